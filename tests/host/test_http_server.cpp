// The live page's web server under hostile requests: it serves only its own page and data, answers
// every malformed, oversized, slow or foreign request with the status HTTP names for it, holds no
// more than its limits, drops clients that never read, and stays responsive throughout (a normal
// request after each attack is answered with the latest snapshot). Oracle: RFC 9110/9112 status
// codes (400 bad syntax, 403 refused, 404 no such resource, 405 + Allow for other methods, 408
// request timeout, 414 URI too long, 431 header fields too large, 503 overloaded, 505 version) and
// the server's documented limits (http_server.hpp).
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <array>
#include <string>
#include <thread>
#include <vector>

#include "http_server.hpp"
#include "support/http_client.hpp"
#include "web_assets.hpp"

namespace gyrochar::web {
namespace {

using namespace gyrochar::test;

// Short limits so that the slow attacks end quickly; the defaults are tested by the programs.
ServerLimits quick_limits() {
  ServerLimits l;
  l.request_timeout_s = 1.0;
  l.write_stall_s = 1.0;
  return l;
}

class Server : public ::testing::Test {
 protected:
  Server() : server(ListenAddress{"127.0.0.1", 0}, page_assets(), quick_limits()) { server.publish(R"({"snapshot":1})"); }
  // The server still answers a normal request with the latest snapshot.
  void expect_responsive(const std::string& snapshot = R"({"snapshot":1})") {
    const std::string answer = get(server.port(), "/data.json");
    EXPECT_EQ(status_of(answer), 200) << answer;
    EXPECT_EQ(body_of(answer), snapshot);
  }
  HttpServer server;
};

TEST_F(Server, ServesItsPageItsDataAndNothingElse) {
  const std::string page = get(server.port(), "/");
  EXPECT_EQ(status_of(page), 200);
  EXPECT_NE(page.find("Content-Type: text/html; charset=utf-8\r\n"), std::string::npos);
  EXPECT_NE(page.find("<script src=\"app.js\""), std::string::npos);
  EXPECT_NE(page.find("Content-Security-Policy: default-src 'none'"), std::string::npos);
  for (const char* path : {"/app.js", "/style.css", "/chart.js"})
    EXPECT_EQ(status_of(get(server.port(), path)), 200) << path;
  // The plotting library is served from the page's own origin, before the page's script: Chart.js
  // as Debian's libjs-chart.js installs it (oracle: the banner that file begins with).
  EXPECT_LT(page.find("<script src=\"chart.js\""), page.find("<script src=\"app.js\""));
  const std::string library = get(server.port(), "/chart.js");
  EXPECT_NE(library.find("Content-Type: text/javascript; charset=utf-8\r\n"), std::string::npos);
  EXPECT_NE(body_of(library).find(" * Chart.js v"), std::string::npos);
  expect_responsive();
  const std::string head = ask(server.port(), "HEAD /app.js HTTP/1.1\r\nHost: localhost\r\n\r\n");
  EXPECT_EQ(status_of(head), 200);
  EXPECT_EQ(body_of(head), "") << "HEAD has no body";
  EXPECT_EQ(status_of(get(server.port(), "/index.html.bak")), 404);
}

TEST_F(Server, PathTraversalFindsNothing) {
  for (const char* path : {"/../../../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/app.js/../../etc/passwd",
                           "//etc/passwd", "/..%2f..%2fetc%2fpasswd", "/./app.js/..", "/events/../../etc/shadow",
                           "/data.json%00.html", "/\\..\\..\\etc\\passwd"}) {
    const std::string answer = get(server.port(), path);
    EXPECT_EQ(status_of(answer), 404) << path;
    EXPECT_EQ(answer.find("root:"), std::string::npos) << path;
  }
  EXPECT_EQ(status_of(ask(server.port(), "GET ../etc/passwd HTTP/1.1\r\nHost: localhost\r\n\r\n")), 400);
  EXPECT_EQ(status_of(ask(server.port(), "GET http://example.org/ HTTP/1.1\r\nHost: localhost\r\n\r\n")), 400);
  expect_responsive();
}

TEST_F(Server, OtherMethodsAre405WithAllow) {
  for (const char* method : {"POST", "PUT", "DELETE", "PATCH", "OPTIONS", "TRACE", "CONNECT", "PROPFIND"}) {
    const std::string answer = ask(server.port(),
                                   std::string(method) + " / HTTP/1.1\r\nHost: localhost\r\nContent-Length: 3\r\n\r\nabc");
    EXPECT_EQ(status_of(answer), 405) << method;
    EXPECT_NE(answer.find("Allow: GET, HEAD\r\n"), std::string::npos) << method;
  }
  expect_responsive();
}

TEST_F(Server, GarbageHttp09AndUnknownVersionsAreRefused) {
  EXPECT_EQ(status_of(ask(server.port(), "GET /\r\n")), 400) << "HTTP/0.9";
  EXPECT_EQ(status_of(ask(server.port(), "GET / HTTP/2.0\r\nHost: localhost\r\n\r\n")), 505);
  EXPECT_EQ(status_of(ask(server.port(), "get / HTTP/1.1\r\nHost: localhost\r\n\r\n")), 400);
  EXPECT_EQ(status_of(ask(server.port(), "GET / HTTP/1.1\r\n\r\n")), 400) << "HTTP/1.1 without Host";
  EXPECT_EQ(status_of(ask(server.port(), "GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n")), 400);
  EXPECT_EQ(status_of(ask(server.port(), "GET / HTTP/1.1\r\nno colon here\r\n\r\n")), 400);
  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage += static_cast<char>((i * 7919) % 256);
  EXPECT_EQ(status_of(ask(server.port(), garbage + "\r\n\r\n")), 400);
  EXPECT_EQ(status_of(ask(server.port(), std::string("\0\0\0\0\r\n\r\n", 8))), 400);
  // A TLS hello has no line end: it waits for one until the request timeout (1 s here).
  EXPECT_EQ(status_of(ask(server.port(), std::string("\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03", 11))), 408);
  expect_responsive();
}

TEST_F(Server, HugeRequestsAreCutAtTheLimit) {
  const std::string long_uri = "GET /" + std::string(100000, 'a') + " HTTP/1.1\r\nHost: localhost\r\n\r\n";
  EXPECT_EQ(status_of(ask(server.port(), long_uri)), 414);
  std::string big = "GET / HTTP/1.1\r\nHost: localhost\r\n";
  for (int i = 0; i < 2000; ++i) big += "X-Filler-" + std::to_string(i) + ": " + std::string(64, 'x') + "\r\n";
  EXPECT_EQ(status_of(ask(server.port(), big + "\r\n")), 431);
  expect_responsive();
}

// A page of another site, through a host name pointed at 127.0.0.1, gets nothing (DNS rebinding).
TEST_F(Server, ForeignHostNamesAreRefusedOnLoopback) {
  EXPECT_EQ(status_of(ask(server.port(), "GET /data.json HTTP/1.1\r\nHost: evil.example:8080\r\n\r\n")), 403);
  for (const char* host : {"localhost", "LOCALHOST:1", "127.0.0.1", "127.1.2.3:80", "[::1]:8080"})
    EXPECT_EQ(status_of(ask(server.port(), std::string("GET / HTTP/1.1\r\nHost: ") + host + "\r\n\r\n")), 200) << host;
}

TEST_F(Server, SlowlorisGets408AndOthersAreServedMeanwhile) {
  std::vector<int> slow;
  for (int i = 0; i < 50; ++i) {
    slow.push_back(connect_local(server.port()));
    send_all(slow.back(), "GET / HTTP/1.1\r\nHost: local");  // and never the rest
  }
  expect_responsive();  // while they wait
  for (const int fd : slow) {
    EXPECT_EQ(status_of(receive(fd, 10.0)), 408);
    ::close(fd);
  }
  EXPECT_GE(server.counters().timed_out.load(), 50u);
  expect_responsive();
}

TEST_F(Server, ThousandConnectionsAreHeldToTheLimitAndTheRestRefused) {
  rlimit files{};
  ::getrlimit(RLIMIT_NOFILE, &files);
  if (files.rlim_cur < 1100) {
    files.rlim_cur = std::min<rlim_t>(files.rlim_max, 1100);
    ::setrlimit(RLIMIT_NOFILE, &files);
  }
  if (files.rlim_cur < 1100) GTEST_SKIP() << "needs 1100 open files (RLIMIT_NOFILE " << files.rlim_cur << ")";
  std::vector<int> idle;
  for (int i = 0; i < 1000; ++i) idle.push_back(connect_local(server.port()));
  const auto& c = server.counters();
  for (int wait = 0; wait < 200 && c.accepted.load() + c.refused.load() < 1000; ++wait)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  // Oracle: max_connections = 256 (ServerLimits' default): that many held, the other 744 answered
  // 503 and closed at once.
  EXPECT_EQ(c.accepted.load(), 256u);
  EXPECT_EQ(c.refused.load(), 744u);
  EXPECT_EQ(c.open.load(), 256u);
  int busy = 0;
  for (const int fd : idle) {
    pollfd p{fd, POLLIN, 0};
    if (fd >= 0 && ::poll(&p, 1, 0) == 1 && status_of(receive(fd, 1.0)) == 503) ++busy;
  }
  EXPECT_EQ(busy, 744);
  for (const int fd : idle) ::close(fd);
  // Once they are gone, new clients are served again.
  for (int attempt = 0; attempt < 100 && status_of(get(server.port(), "/data.json")) != 200; ++attempt)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  expect_responsive();
}

TEST_F(Server, ClientsThatNeverReadAreDroppedAndPublishNeverWaits) {
  std::vector<int> deaf;
  for (int i = 0; i < 20; ++i) {
    const int fd = connect_local(server.port());
    const int small = 4096;
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    send_all(fd, "GET /events HTTP/1.1\r\nHost: localhost\r\n\r\n");
    deaf.push_back(fd);  // and never read
  }
  // Snapshots of 1 MB, more than the socket buffers hold: the server queues one per client at most.
  std::string last;
  for (int k = 0; k < 150 && server.counters().dropped_slow.load() < deaf.size(); ++k) {
    last = "{\"k\":" + std::to_string(k) + ",\"pad\":\"" + std::string(1 << 20, 'x') + "\"}";
    server.publish(last);  // returns at once whatever the clients do
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(server.counters().dropped_slow.load(), deaf.size()) << "write_stall_s = 1 s: each deaf client dropped";
  expect_responsive(last);
  for (const int fd : deaf) ::close(fd);
}

TEST_F(Server, EventStreamSendsEverySnapshotAsOneDataLine) {
  const int fd = connect_local(server.port());
  send_all(fd, "GET /events HTTP/1.1\r\nHost: localhost\r\n\r\n");
  const std::string first = receive(fd, 5.0, "data: {\"snapshot\":1}\n\n");
  EXPECT_EQ(status_of(first), 200);
  EXPECT_NE(first.find("Content-Type: text/event-stream\r\n"), std::string::npos);
  EXPECT_NE(first.find("data: {\"snapshot\":1}\n\n"), std::string::npos) << first;
  server.publish(R"({"snapshot":2})");
  EXPECT_NE(receive(fd, 5.0, "\n\n").find("data: {\"snapshot\":2}\n\n"), std::string::npos);
  ::close(fd);
}

TEST(ListenAddress, ParsesPortAndAddress) {
  std::string why;
  const auto port = parse_listen_address("8080", why);
  ASSERT_TRUE(port);
  EXPECT_EQ(port->host, "127.0.0.1") << "localhost unless told otherwise";
  EXPECT_EQ(port->port, 8080);
  const auto any = parse_listen_address("0.0.0.0:80", why);
  ASSERT_TRUE(any);
  EXPECT_EQ(any->host, "0.0.0.0");
  const auto v6 = parse_listen_address("[::1]:0", why);
  ASSERT_TRUE(v6);
  EXPECT_EQ(v6->host, "::1");
  EXPECT_EQ(v6->port, 0);
  const std::array<std::pair<const char*, const char*>, 8> bad{{
      {"", "port '' is not a number 0..65535"},
      {"http", "port 'http' is not a number 0..65535"},
      {"65536", "port '65536' is not a number 0..65535"},
      {"-1", "port '-1' is not a number 0..65535"},
      {":8080", "':8080': no address before ':' (give PORT alone for 127.0.0.1)"},
      {"::1:8080", "'::1:8080': an IPv6 address goes in brackets, e.g. [::1]:8080"},
      {"[::1:8080", "'[::1:8080': an IPv6 address goes in brackets, e.g. [::1]:8080"},
      {"gyro.example:8080", "'gyro.example' is not a numeric IPv4 or IPv6 address or localhost"},
  }};
  for (const auto& [text, message] : bad) {
    EXPECT_FALSE(parse_listen_address(text, why)) << text;
    EXPECT_EQ(why, message) << text;
  }
}

TEST(ListenAddress, APortInUseIsAnErrorNamingIt) {
  HttpServer first(ListenAddress{"127.0.0.1", 0}, page_assets());
  try {
    HttpServer second(ListenAddress{"127.0.0.1", first.port()}, page_assets());
    FAIL() << "two servers on one port";
  } catch (const ListenError& e) {
    EXPECT_EQ(std::string(e.what()), "127.0.0.1:" + std::to_string(first.port()) + ": Address already in use");
  }
}

}  // namespace
}  // namespace gyrochar::web
