// libFuzzer target: the CAN frame decoder. Any frame must decode or be rejected with a reason, and
// every accepted frame must re-encode bit for bit (the codec's canonical-form contract).
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "gyrochar/wire/protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 5) return 0;
  gyrochar::CanFrame frame;
  std::uint32_t id = 0;
  std::memcpy(&id, data, 4);
  frame.id = id & 0x1FFFFFFFu;
  frame.extended = (data[4] & 1) != 0;
  frame.fd = (data[4] & 2) != 0;
  frame.error = (data[4] & 4) != 0;
  const std::size_t len = size - 5 > 64 ? 64 : size - 5;
  frame.len = static_cast<std::uint8_t>(len);
  std::memcpy(frame.data.data(), data + 5, len);
  const gyrochar::protocol::Decoded d = gyrochar::protocol::decode(frame);
  if (d.error != gyrochar::protocol::ProtocolError::none) return 0;
  gyrochar::CanFrame again;
  if (gyrochar::protocol::encode(d.message, d.node, again) != gyrochar::protocol::ProtocolError::none) std::abort();
  if (again.id != frame.id || again.len != frame.len || std::memcmp(again.data.data(), frame.data.data(), len) != 0)
    std::abort();
  return 0;
}
