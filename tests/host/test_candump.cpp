// candump log parser: every line form candump -l writes, and malformed lines rejected with a
// reason. Oracle: the format of can-utils' lib.c (sprint_canframe / parse_canframe) as documented
// in the design brief section 5.
#include <gtest/gtest.h>

#include "candump.hpp"

namespace gyrochar {
namespace {

CandumpLine parse_ok(const std::string& line) {
  CandumpLine out;
  std::string why;
  EXPECT_TRUE(parse_candump_line(line, out, why)) << line << ": " << why;
  return out;
}

std::string parse_error(const std::string& line) {
  CandumpLine out;
  std::string why;
  EXPECT_FALSE(parse_candump_line(line, out, why)) << line;
  return why;
}

TEST(Candump, ClassicExtendedFrame) {
  const auto l = parse_ok("(1436509052.249713) can0 18FF4101#0102030405060708");
  EXPECT_DOUBLE_EQ(l.time_s, 1436509052.249713);
  EXPECT_EQ(l.interface, "can0");
  EXPECT_TRUE(l.frame.extended);
  EXPECT_EQ(l.frame.id, 0x18FF4101u);
  ASSERT_EQ(l.frame.len, 8);
  EXPECT_EQ(l.frame.data[0], 1);
  EXPECT_EQ(l.frame.data[7], 8);
}

TEST(Candump, StandardRemoteEmptyAndFd) {
  const auto s = parse_ok("(0.000001) vcan0 123#");
  EXPECT_FALSE(s.frame.extended);
  EXPECT_EQ(s.frame.id, 0x123u);
  EXPECT_EQ(s.frame.len, 0);
  const auto r = parse_ok("(1.5) can1 123#R");
  EXPECT_TRUE(r.remote);
  const auto fd = parse_ok("(2.0) can0 18FF4101##1" + std::string(24, 'A'));
  EXPECT_TRUE(fd.frame.fd);
  EXPECT_EQ(fd.frame.len, 12);
  EXPECT_EQ(fd.frame.data[11], 0xAA);
}

TEST(Candump, ErrorFrame) {
  const auto e = parse_ok("(3.0) can0 20000004#0004000000000000");
  EXPECT_TRUE(e.frame.error);
  EXPECT_EQ(e.frame.id, 0x4u);  // CAN_ERR_CRTL
}

TEST(Candump, RoundTripThroughFormatter) {
  CanFrame f;
  f.id = 0x14FF4007;
  f.extended = true;
  f.len = 5;
  for (int i = 0; i < 5; ++i) f.data[i] = static_cast<std::uint8_t>(0x10 * i + 1);
  const std::string line = format_candump_line(12.25, "can0", f);
  EXPECT_EQ(line, "(12.250000) can0 14FF4007#0111213141");
  const auto back = parse_ok(line);
  EXPECT_EQ(back.frame.id, f.id);
  EXPECT_EQ(back.frame.len, f.len);
  EXPECT_EQ(back.frame.data, f.data);
}

TEST(Candump, MalformedLinesAreRejectedWithAReason) {
  EXPECT_FALSE(parse_error("").empty());
  EXPECT_FALSE(parse_error("18FF4101#00").empty());                                    // no timestamp
  EXPECT_FALSE(parse_error("(1.0 can0 18FF4101#00").empty());                          // unterminated
  EXPECT_FALSE(parse_error("(abc) can0 18FF4101#00").empty());                         // bad timestamp
  EXPECT_FALSE(parse_error("(1.0) can0").empty());                                     // no frame
  EXPECT_FALSE(parse_error("(1.0) can0 18FF4101").empty());                            // no '#'
  EXPECT_FALSE(parse_error("(1.0) can0 18FF41#00").empty());                           // 6-digit id
  EXPECT_FALSE(parse_error("(1.0) can0 18FG4101#00").empty());                         // not hex
  EXPECT_FALSE(parse_error("(1.0) can0 18FF4101#0").empty());                          // odd digits
  EXPECT_FALSE(parse_error("(1.0) can0 18FF4101#001122334455667788").empty());         // 9 bytes classic
  EXPECT_FALSE(parse_error("(1.0) can0 800#00").empty());                              // 11-bit id > 0x7FF
  EXPECT_FALSE(parse_error("(1.0) can0 18FF4101##").empty());                          // FD without flags
  EXPECT_FALSE(parse_error("(1.0) can0 18FF4101##1" + std::string(26, '0')).empty());  // 13 bytes FD
  EXPECT_FALSE(parse_error(std::string("(1.0) ca\0n0 18FF4101#00", 23)).empty());      // NUL in the name
  EXPECT_FALSE(parse_error("(1.0) averyveryverylongname 18FF4101#00").empty());        // > 15 characters
  EXPECT_FALSE(parse_error("(1e300) can0 18FF4101#00").empty());                       // absurd time
}

TEST(Candump, RemoteRequestsCarryALengthAndNoData) {
  const auto r = parse_ok("(1.5) can0 14FF4010#R8");  // the issue's reproducer: a DLC, no data
  EXPECT_TRUE(r.remote);
  EXPECT_EQ(r.frame.len, 8);
  EXPECT_TRUE(r.frame.extended);
  EXPECT_FALSE(parse_ok("(1.5) can0 14FF4010#0000000000000000").remote);
}

// A line longer than max_candump_line_bytes is malformed whatever it holds (here a valid frame
// and trailing spaces); one of exactly the limit is parsed.
TEST(Candump, LinesLongerThanTheLimitAreRejected) {
  const std::string frame = "(1.0) can0 18FF4101#00";
  EXPECT_EQ(parse_error(frame + std::string(max_candump_line_bytes + 1 - frame.size(), ' ')), "longer than 1024 bytes");
  parse_ok(frame + std::string(max_candump_line_bytes - frame.size(), ' '));
}

}  // namespace
}  // namespace gyrochar
