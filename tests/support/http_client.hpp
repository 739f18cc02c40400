#pragma once
// A bare HTTP client for the live page's tests: raw bytes over a loopback TCP socket, so that the
// tests can send what no browser would (garbage, HTTP/0.9, endless headers) and can stop reading.
// Every wait is bounded (poll with a limit); nothing is ever sent off this machine.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

namespace gyrochar::test {

/// A TCP connection to 127.0.0.1:port, blocking; -1 when refused.
inline int connect_local(std::uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

inline bool send_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n <= 0) return false;
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

/// Reads until the peer closes, `until` appears, or `limit_s` passes; what came.
inline std::string receive(int fd, double limit_s = 10.0, std::string_view until = {}) {
  std::string in;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
  char buffer[65536];
  while (std::chrono::steady_clock::now() < end) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    in.append(buffer, static_cast<std::size_t>(n));
    if (!until.empty() && in.find(until) != std::string::npos) break;
  }
  return in;
}

/// Sends `request` as it is on a new connection and returns the whole answer ("" if refused).
inline std::string ask(std::uint16_t port, std::string_view request, double limit_s = 10.0) {
  const int fd = connect_local(port);
  if (fd < 0) return {};
  send_all(fd, request);
  std::string answer = receive(fd, limit_s);
  ::close(fd);
  return answer;
}

inline std::string get(std::uint16_t port, std::string_view path) {
  return ask(port, "GET " + std::string(path) + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
}

/// The status code of an answer ("HTTP/1.1 404 ..." -> 404), 0 for none.
inline int status_of(std::string_view answer) {
  if (answer.size() < 12 || !answer.starts_with("HTTP/1.")) return 0;
  return std::stoi(std::string(answer.substr(9, 3)));
}

/// The body of an answer: what follows the empty line.
inline std::string body_of(const std::string& answer) {
  const auto end = answer.find("\r\n\r\n");
  return end == std::string::npos ? std::string() : answer.substr(end + 4);
}

}  // namespace gyrochar::test
