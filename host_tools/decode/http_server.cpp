#include "http_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <vector>

namespace gyrochar::web {

namespace {

double steady_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

const char* reason(int status) {
  switch (status) {
    case 200: return "OK";
    case 400: return "Bad Request";
    case 403: return "Forbidden";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 408: return "Request Timeout";
    case 414: return "URI Too Long";
    case 431: return "Request Header Fields Too Large";
    case 503: return "Service Unavailable";
    case 505: return "HTTP Version Not Supported";
  }
  return "Error";
}

// What every answer says: nothing cached, nothing sniffed, nothing loaded from elsewhere (the page
// reaches only its own server), never framed.
constexpr std::string_view common_headers =
    "Cache-Control: no-store\r\n"
    "X-Content-Type-Options: nosniff\r\n"
    "X-Frame-Options: DENY\r\n"
    "Referrer-Policy: no-referrer\r\n"
    "Content-Security-Policy: default-src 'none'; script-src 'self'; style-src 'self'; connect-src 'self'; "
    "img-src 'self' data:; base-uri 'none'; form-action 'none'; frame-ancestors 'none'\r\n";

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return std::tolower(x) == std::tolower(y); });
}

// The host name of a Host header names this machine (a page of a server bound to loopback answers
// no other name: another site's page cannot reach it through a name it points here).
bool local_host_name(std::string_view host) {
  std::string_view name = host;
  if (!name.empty() && name.front() == '[') {
    name = name.substr(1, name.find(']') == std::string_view::npos ? 0 : name.find(']') - 1);
  } else if (const auto colon = name.find(':'); colon != std::string_view::npos) {
    name = name.substr(0, colon);
  }
  return iequals(name, "localhost") || name.starts_with("127.") || name == "::1";
}

void set_nonblocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK); }

// 'text' for a message (built by appending: GCC 12 at -O3 warns wrongly of overlapping copies in
// "'" + std::string).
std::string quoted(std::string_view text) { return std::string(1, '\'').append(text).append(1, '\''); }

}  // namespace

std::optional<ListenAddress> parse_listen_address(std::string_view text, std::string& why) {
  ListenAddress a;
  std::string_view port = text;
  if (const auto colon = text.rfind(':'); colon != std::string_view::npos) {
    std::string_view host = text.substr(0, colon);
    port = text.substr(colon + 1);
    if (host.starts_with('[') != host.ends_with(']') || (host.starts_with('[') && host.size() < 3)) {
      why = quoted(text) + ": an IPv6 address goes in brackets, e.g. [::1]:8080";
      return std::nullopt;
    }
    if (host.starts_with('[')) host = host.substr(1, host.size() - 2);
    if (host.empty()) {
      why = quoted(text) + ": no address before ':' (give PORT alone for 127.0.0.1)";
      return std::nullopt;
    }
    if (host.find(':') != std::string_view::npos && !text.starts_with('[')) {
      why = quoted(text) + ": an IPv6 address goes in brackets, e.g. [::1]:8080";
      return std::nullopt;
    }
    a.host = host;
    in6_addr scratch{};
    if (a.host != "localhost" && ::inet_pton(AF_INET, a.host.c_str(), &scratch) != 1 &&
        ::inet_pton(AF_INET6, a.host.c_str(), &scratch) != 1) {
      why = "'" + a.host + "' is not a numeric IPv4 or IPv6 address or localhost";
      return std::nullopt;
    }
  }
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc{} || end != port.data() + port.size() || value > 65535) {
    why = "port '" + std::string(port) + "' is not a number 0..65535";
    return std::nullopt;
  }
  a.port = static_cast<std::uint16_t>(value);
  return a;
}

// ---------------------------------------------------------------------------------------------
// A connection: the request as it arrives, the output queued (pieces that share the snapshot's
// text instead of copying it), and where it stands.

struct HttpServer::Connection {
  int fd = -1;
  double opened_s = 0, progress_s = 0, event_s = 0;
  std::string in;  // the request head, at most max_request_bytes + 1
  struct Piece {
    std::shared_ptr<const std::string> owner;  // null: static storage
    std::string_view text;
  };
  std::vector<Piece> out;
  std::size_t out_offset = 0;  // sent of out.front()
  bool answered = false;       // a response is queued: no more requests read
  bool stream = false;         // an event stream: kept open, fed every snapshot
  bool draining = false;       // answered and sent: write side shut, waiting for the client's close
  bool peer_closed = false;    // the client shut its side (it may still read the answer)
  std::uint64_t version_sent = 0;

  bool pending() const { return !out.empty(); }
  void push(std::shared_ptr<const std::string> owner, std::string_view text) { out.push_back({std::move(owner), text}); }
  void push(std::string text) {
    auto owned = std::make_shared<const std::string>(std::move(text));
    const std::string_view view = *owned;
    out.push_back({std::move(owned), view});
  }
};

HttpServer::HttpServer(const ListenAddress& address, std::span<const Asset> assets, ServerLimits limits)
    : assets_(assets), limits_(limits), host_(address.host) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV | (address.host == "localhost" ? 0 : AI_NUMERICHOST);
  addrinfo* found = nullptr;
  const std::string where = (address.host.find(':') != std::string::npos ? "[" + address.host + "]" : address.host) + ":" +
                            std::to_string(address.port);
  if (const int e = ::getaddrinfo(address.host.c_str(), std::to_string(address.port).c_str(), &hints, &found); e != 0)
    throw ListenError(where + ": " + ::gai_strerror(e));
  std::unique_ptr<addrinfo, void (*)(addrinfo*)> list(found, ::freeaddrinfo);
  int error = 0;
  for (const addrinfo* ai = found; ai != nullptr && listen_fd_ < 0; ai = ai->ai_next) {
    const int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) {
      error = errno;
      continue;
    }
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (::bind(fd, ai->ai_addr, ai->ai_addrlen) != 0 || ::listen(fd, SOMAXCONN) != 0) {
      error = errno;
      ::close(fd);
      continue;
    }
    sockaddr_storage bound{};
    socklen_t length = sizeof bound;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&bound), &length);
    if (bound.ss_family == AF_INET) {
      const auto& v4 = reinterpret_cast<const sockaddr_in&>(bound);
      port_ = ntohs(v4.sin_port);
      loopback_ = (ntohl(v4.sin_addr.s_addr) >> 24) == 127;
    } else {
      const auto& v6 = reinterpret_cast<const sockaddr_in6&>(bound);
      port_ = ntohs(v6.sin6_port);
      loopback_ = IN6_IS_ADDR_LOOPBACK(&v6.sin6_addr);
    }
    listen_fd_ = fd;
  }
  if (listen_fd_ < 0) throw ListenError(where + ": " + std::strerror(error));
  if (::pipe2(wake_, O_NONBLOCK | O_CLOEXEC) != 0) {
    ::close(listen_fd_);
    throw ListenError(where + ": " + std::strerror(errno));
  }
  thread_ = std::thread([this] { run(); });
}

HttpServer::~HttpServer() {
  stop_ = true;
  const char byte = 's';
  [[maybe_unused]] const auto n = ::write(wake_[1], &byte, 1);
  thread_.join();
  ::close(listen_fd_);
  ::close(wake_[0]);
  ::close(wake_[1]);
}

std::string HttpServer::url() const {
  const std::string host = host_.find(':') != std::string::npos ? "[" + host_ + "]" : host_;
  return "http://" + host + ":" + std::to_string(port_) + "/";
}

void HttpServer::publish(std::string json) {
  auto text = std::make_shared<const std::string>(std::move(json));
  {
    const std::lock_guard lock(mutex_);
    snapshot_ = std::move(text);
    ++version_;
  }
  const char byte = 'p';
  [[maybe_unused]] const auto n = ::write(wake_[1], &byte, 1);  // a full pipe already wakes it
}

// ---------------------------------------------------------------------------------------------
// The thread

void HttpServer::queue_snapshot(Connection& c) {
  if (!c.stream || c.pending() || c.version_sent == current_version_ || !current_) return;
  c.push(nullptr, "data: ");
  c.push(current_, *current_);
  c.push(nullptr, "\n\n");
  c.version_sent = current_version_;
  ++counters_.events_sent;
}

void HttpServer::respond(Connection& c, int status, std::string_view type, std::string_view body, bool head,
                         std::string_view extra_headers) {
  std::string h = "HTTP/1.1 " + std::to_string(status) + " " + reason(status) + "\r\n";
  h += common_headers;
  h += extra_headers;
  h += "Content-Type: ";
  h += type;
  h += "\r\nContent-Length: " + std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n";
  c.push(std::move(h));
  if (!head && !body.empty()) c.push(nullptr, body);  // assets, reason texts: static storage
  c.answered = true;
  ++counters_.requests;
  if (status >= 400) ++counters_.errors;
}

void HttpServer::serve(Connection& c, double now) {
  const auto error = [&](int status, std::string_view extra = {}) {
    respond(c, status, "text/plain; charset=utf-8", reason(status), false, extra);
  };
  const std::size_t line_end = c.in.find('\n');
  if (line_end == std::string::npos) {
    if (c.in.size() > limits_.max_request_bytes) return error(414);
    if (now - c.opened_s > limits_.request_timeout_s) {
      ++counters_.timed_out;
      return error(408);
    }
    return;  // wait for more
  }
  std::string_view line(c.in.data(), line_end);
  if (line.ends_with('\r')) line.remove_suffix(1);
  std::string_view parts[3];
  std::size_t count = 0;
  for (std::size_t start = 0; start <= line.size() && count < 4;) {
    const std::size_t space = std::min(line.find(' ', start), line.size());
    if (count == 3) return error(400);  // a fourth part
    parts[count++] = line.substr(start, space - start);
    start = space + 1;
  }
  const auto token = [](std::string_view t) {
    return !t.empty() && std::all_of(t.begin(), t.end(), [](char ch) { return ch >= 'A' && ch <= 'Z'; });
  };
  if (count != 3 || !token(parts[0])) return error(400);  // HTTP/0.9 ("GET /") among them
  const std::string_view method = parts[0], target = parts[1], version = parts[2];
  if (version != "HTTP/1.1" && version != "HTTP/1.0") return error(version.starts_with("HTTP/") ? 505 : 400);
  if (target.empty() || target.front() != '/' ||
      !std::all_of(target.begin(), target.end(), [](char ch) { return ch > 0x20 && ch < 0x7f; }))
    return error(400);
  if (method != "GET" && method != "HEAD") return error(405, "Allow: GET, HEAD\r\n");
  // The head ends at an empty line.
  std::size_t head_end = c.in.find("\r\n\r\n");
  if (head_end == std::string::npos) head_end = c.in.find("\n\n");
  if (head_end == std::string::npos) {
    if (c.in.size() > limits_.max_request_bytes) return error(431);
    if (now - c.opened_s > limits_.request_timeout_s) {
      ++counters_.timed_out;
      return error(408);
    }
    return;
  }
  std::optional<std::string_view> host;
  for (std::size_t start = line_end + 1; start < head_end;) {
    const std::size_t end = std::min(c.in.find('\n', start), head_end);
    std::string_view field(c.in.data() + start, end - start);
    if (field.ends_with('\r')) field.remove_suffix(1);
    const std::size_t colon = field.find(':');
    if (colon == std::string_view::npos || colon == 0) return error(400);
    if (iequals(field.substr(0, colon), "host")) {
      if (host) return error(400);  // two Host headers
      std::string_view value = field.substr(colon + 1);
      while (!value.empty() && (value.front() == ' ' || value.front() == '\t')) value.remove_prefix(1);
      while (!value.empty() && (value.back() == ' ' || value.back() == '\t')) value.remove_suffix(1);
      host = value;
    }
    start = end + 1;
  }
  if (!host && version == "HTTP/1.1") return error(400);
  if (host && loopback_ && !local_host_name(*host)) return error(403);
  const bool head = method == "HEAD";
  const std::string_view path = target.substr(0, target.find('?'));
  if (path == "/events") {
    std::string h = "HTTP/1.1 200 OK\r\n";
    h += common_headers;
    h += "Content-Type: text/event-stream\r\nConnection: keep-alive\r\n\r\nretry: 1000\n\n";
    c.push(std::move(h));
    c.answered = true;
    c.stream = !head;
    c.event_s = now;
    ++counters_.requests;
    queue_snapshot(c);
    return;
  }
  if (path == "/data.json") {
    std::string h = "HTTP/1.1 200 OK\r\n";
    h += common_headers;
    const std::size_t size = current_ ? current_->size() : 4;
    h += "Content-Type: application/json\r\nContent-Length: " + std::to_string(size) + "\r\nConnection: close\r\n\r\n";
    c.push(std::move(h));
    if (!head) current_ ? c.push(current_, *current_) : c.push(nullptr, "null");
    c.answered = true;
    ++counters_.requests;
    return;
  }
  for (const Asset& a : assets_)
    if (a.path == path) {
      respond(c, 200, a.content_type, a.body, head);
      return;
    }
  return error(404);
}

void HttpServer::accept_all() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;  // EAGAIN, or out of descriptors: tried again at the next wake-up
    if (counters_.open >= limits_.max_connections) {
      static constexpr std::string_view busy =
          "HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\nConnection: close\r\nRetry-After: 5\r\n\r\n";
      [[maybe_unused]] const auto n = ::send(fd, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      ::close(fd);
      ++counters_.refused;
      continue;
    }
    ++counters_.accepted;
    ++counters_.open;
    set_nonblocking(fd);
    auto c = std::make_unique<Connection>();
    c->fd = fd;
    c->opened_s = c->progress_s = steady_s();
    connections_.push_back(std::move(c));
  }
}

void HttpServer::run() {
  std::vector<pollfd> fds;
  char scratch[4096];
  while (!stop_) {
    fds.clear();
    fds.push_back({wake_[0], POLLIN, 0});
    fds.push_back({listen_fd_, POLLIN, 0});
    for (const auto& c : connections_) {
      short events = c->pending() ? POLLOUT : 0;
      if (!c->answered || c->stream || c->draining) events |= POLLIN;
      fds.push_back({c->fd, events, 0});
    }
    ::poll(fds.data(), fds.size(), 250);
    const double now = steady_s();
    if (fds[0].revents & POLLIN) {
      while (::read(wake_[0], scratch, sizeof scratch) > 0) {
      }
      const std::lock_guard lock(mutex_);
      current_ = snapshot_;
      current_version_ = version_;
    }
    if (fds[1].revents & POLLIN) accept_all();
    for (std::size_t i = 0; i < connections_.size(); ++i) {
      Connection& c = *connections_[i];
      const short revents = i + 2 < fds.size() ? fds[i + 2].revents : 0;
      bool keep = true;
      if (revents & POLLIN) {
        // Before the answer, read no more than the limit + 1 bytes (enough to know the request is too
        // long); after it, read and drop (an event stream's client says nothing).
        const std::size_t room = c.answered ? sizeof scratch : limits_.max_request_bytes + 1 - c.in.size();
        const ssize_t n = ::recv(c.fd, scratch, std::min(room, sizeof scratch), 0);
        if (n > 0 && !c.answered) c.in.append(scratch, static_cast<std::size_t>(n));
        if (n == 0) c.peer_closed = true;
        if (n < 0 && errno != EAGAIN && errno != EINTR) keep = false;
      } else if (revents & (POLLERR | POLLNVAL)) {
        keep = false;
      }
      if (keep && !c.answered) serve(c, now);
      if (c.peer_closed && (!c.answered || c.stream || c.draining)) keep = false;
      if (keep && c.stream) {
        queue_snapshot(c);
        if (!c.pending() && now - c.event_s > limits_.keepalive_s) c.push(nullptr, ": keep-alive\n\n");
      }
      if (keep && c.pending() && (revents & POLLOUT || c.answered)) {
        iovec io[16];
        int pieces = 0;
        for (std::size_t k = 0; k < c.out.size() && pieces < 16; ++k, ++pieces) {
          const std::string_view t = c.out[k].text.substr(k == 0 ? c.out_offset : 0);
          io[pieces] = {const_cast<char*>(t.data()), t.size()};
        }
        msghdr m{};
        m.msg_iov = io;
        m.msg_iovlen = static_cast<std::size_t>(pieces);
        const ssize_t n = ::sendmsg(c.fd, &m, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n > 0) {
          c.progress_s = c.event_s = now;
          auto left = static_cast<std::size_t>(n);
          while (left > 0) {
            const std::size_t rest = c.out.front().text.size() - c.out_offset;
            if (left < rest) {
              c.out_offset += left;
              break;
            }
            left -= rest;
            c.out.erase(c.out.begin());
            c.out_offset = 0;
          }
          if (c.stream) queue_snapshot(c);  // the latest snapshot, if one came while this was queued
        } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
          keep = false;
        }
      }
      if (keep && c.pending() && now - c.progress_s > limits_.write_stall_s) {
        ++counters_.dropped_slow;  // a client that does not read
        keep = false;
      }
      if (keep && c.answered && !c.stream && !c.pending()) {
        if (!c.draining) {  // sent: let the client see the end, then close (no reset over the answer)
          ::shutdown(c.fd, SHUT_WR);
          c.draining = true;
          c.progress_s = now;
        } else if (now - c.progress_s > 2.0) {
          keep = false;
        }
      }
      if (!keep) {
        ::close(c.fd);
        connections_[i].reset();
        --counters_.open;
      }
    }
    std::erase(connections_, nullptr);
  }
  for (const auto& c : connections_) ::close(c->fd);
  connections_.clear();
}

}  // namespace gyrochar::web
