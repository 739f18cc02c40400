#include "candump.hpp"

#include <charconv>
#include <fmt/format.h>

namespace gyrochar {
namespace {

constexpr std::uint32_t can_err_flag = 0x20000000u;  // linux/can.h CAN_ERR_FLAG

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool parse_bytes(std::string_view hex, CanFrame& frame, std::size_t max_len, std::string& why) {
  if (hex.size() % 2 != 0) {
    why = "odd number of data hex digits";
    return false;
  }
  if (hex.size() / 2 > max_len) {
    why = "more than " + std::to_string(max_len) + " data bytes";
    return false;
  }
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    const int hi = hex_value(hex[i]), lo = hex_value(hex[i + 1]);
    if (hi < 0 || lo < 0) {
      why = "data is not hexadecimal";
      return false;
    }
    frame.data[i / 2] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  frame.len = static_cast<std::uint8_t>(hex.size() / 2);
  return true;
}

}  // namespace

bool parse_candump_line(std::string_view line, CandumpLine& out, std::string& why) {
  out = CandumpLine{};
  if (line.size() > max_candump_line_bytes) {
    why = fmt::format("longer than {} bytes", max_candump_line_bytes);
    return false;
  }
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  if (line.size() < 3 || line.front() != '(') {
    why = "does not start with a '(timestamp)'";
    return false;
  }
  const auto close = line.find(')');
  if (close == std::string_view::npos) {
    why = "unterminated timestamp";
    return false;
  }
  const std::string_view stamp = line.substr(1, close - 1);
  const auto [end, ec] = std::from_chars(stamp.data(), stamp.data() + stamp.size(), out.time_s);
  if (ec != std::errc() || end != stamp.data() + stamp.size() || !(out.time_s >= 0 && out.time_s < 1e11)) {
    why = "bad timestamp '" + std::string(stamp) + "'";
    return false;
  }
  std::string_view rest = line.substr(close + 1);
  if (rest.empty() || rest.front() != ' ') {
    why = "missing interface";
    return false;
  }
  rest.remove_prefix(1);
  const auto space = rest.find(' ');
  if (space == std::string_view::npos || space == 0) {
    why = "missing frame after the interface";
    return false;
  }
  const std::string_view name = rest.substr(0, space);
  if (name.size() > 15) {
    why = "interface name longer than 15 characters";
    return false;
  }
  for (const char c : name) {
    if (c <= ' ' || c > '~') {
      why = "interface name has a non-printable character";
      return false;
    }
  }
  out.interface = std::string(name);
  std::string_view text = rest.substr(space + 1);
  const auto hash = text.find('#');
  if (hash == std::string_view::npos) {
    why = "frame has no '#'";
    return false;
  }
  const std::string_view id_text = text.substr(0, hash);
  if (id_text.size() != 3 && id_text.size() != 8) {
    why = "identifier must have 3 or 8 hex digits";
    return false;
  }
  std::uint32_t id = 0;
  for (const char c : id_text) {
    const int v = hex_value(c);
    if (v < 0) {
      why = "identifier is not hexadecimal";
      return false;
    }
    id = id * 16 + static_cast<std::uint32_t>(v);
  }
  CanFrame& f = out.frame;
  f.extended = id_text.size() == 8;
  if (f.extended && (id & can_err_flag)) {
    f.error = true;
    id &= ~can_err_flag;
  }
  if (id > 0x1FFFFFFFu || (!f.extended && id > 0x7FFu)) {
    why = "identifier out of range";
    return false;
  }
  f.id = id;
  std::string_view payload = text.substr(hash + 1);
  if (!payload.empty() && payload.front() == '#') {  // CAN FD: flags nibble, then data
    if (payload.size() < 2 || hex_value(payload[1]) < 0) {
      why = "CAN FD frame without its flags digit";
      return false;
    }
    f.fd = true;
    return parse_bytes(payload.substr(2), f, CanFrame::max_fd_len, why) &&
           (f.len <= 8 || f.len == 12 || f.len == 16 || f.len == 20 || f.len == 24 || f.len == 32 || f.len == 48 ||
            f.len == 64 || (why = "CAN FD length is not a valid DLC size", false));
  }
  if (!payload.empty() && (payload.front() == 'R' || payload.front() == 'r')) {
    out.remote = true;
    if (payload.size() == 2 && payload[1] >= '0' && payload[1] <= '8') f.len = static_cast<std::uint8_t>(payload[1] - '0');
    else if (payload.size() != 1) {
      why = "bad remote request length";
      return false;
    }
    return true;
  }
  if (const auto underscore = payload.find('_'); underscore != std::string_view::npos)
    payload = payload.substr(0, underscore);  // classic frame with raw DLC 9..15: data is 8 bytes
  return parse_bytes(payload, f, CanFrame::max_classic_len, why);
}

std::string format_candump_line(double time_s, std::string_view interface, const CanFrame& frame) {
  const std::uint32_t id = frame.id | (frame.error ? can_err_flag : 0u);
  std::string line = (frame.extended || frame.error) ? fmt::format("({:.6f}) {} {:08X}#", time_s, interface, id)
                                                     : fmt::format("({:.6f}) {} {:03X}#", time_s, interface, id);
  if (frame.fd) line += "#0";
  static constexpr char digits[] = "0123456789ABCDEF";
  for (std::size_t i = 0; i < frame.len; ++i) {
    line += digits[frame.data[i] >> 4];
    line += digits[frame.data[i] & 15];
  }
  return line;
}

}  // namespace gyrochar
