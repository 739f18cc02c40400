#pragma once
// The live page's web server (gyrochar-decode --http, gyrochar-demo --http): plain POSIX sockets,
// one thread of its own, read-only. The program publishes a snapshot (a JSON text) whenever it
// likes; the server only reads the latest one, so the CAN reception never waits for a browser.
// It answers GET and HEAD of its compiled-in assets, /data.json (the latest snapshot) and /events
// (server-sent events: every snapshot as one `data:` line); anything else is 404, 405, 400, 414,
// 431 or 505, and it never touches the file system. Every resource a client can make it hold is
// bounded (ServerLimits): connections, request bytes, the time to send a request, and the output
// queued for a client that does not read (one snapshot at most; a client that takes nothing for
// write_stall_s is dropped).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace gyrochar::web {

/// Where to listen: a numeric IPv4 or IPv6 address (or "localhost") and a port (0: any free port).
struct ListenAddress {
  std::string host = "127.0.0.1";
  std::uint16_t port = 0;
};

/// Parses the --http value "[ADDR:]PORT": "8080", "0.0.0.0:8080", "[::1]:8080", "localhost:8080".
/// Without ADDR the server listens on 127.0.0.1 only. Nothing with `why` (e.g. "port 'x' is not a
/// number 0..65535") for a value that cannot be one. O(length).
std::optional<ListenAddress> parse_listen_address(std::string_view text, std::string& why);

/// One file of the page, compiled into the program (web_assets.hpp).
struct Asset {
  std::string_view path;          // "/", "/app.js"
  std::string_view content_type;  // "text/html; charset=utf-8"
  std::string_view body;
};

struct ServerLimits {
  std::size_t max_connections = 256;     // more are answered 503 and closed at once
  std::size_t max_request_bytes = 8192;  // request line and headers: 414 / 431 beyond
  double request_timeout_s = 5.0;        // the whole request head must arrive within (slowloris): 408
  double write_stall_s = 10.0;           // queued output and nothing taken for that long: dropped
  double keepalive_s = 15.0;             // an idle event stream gets a comment line this often
};

/// What the server has done, for the tests and the benchmark (read while it runs).
struct ServerCounters {
  std::atomic<std::uint64_t> accepted{0};      // connections taken
  std::atomic<std::uint64_t> refused{0};       // answered 503: max_connections open
  std::atomic<std::uint64_t> requests{0};      // requests answered (any status)
  std::atomic<std::uint64_t> errors{0};        // answered 4xx or 5xx
  std::atomic<std::uint64_t> timed_out{0};     // request head not complete in time (408)
  std::atomic<std::uint64_t> dropped_slow{0};  // clients that took nothing for write_stall_s
  std::atomic<std::uint64_t> events_sent{0};   // snapshots queued to event streams
  std::atomic<std::uint64_t> open{0};          // connections open now
};

/// Thrown by the constructor when the address cannot be listened on; what() names the address and
/// the system's reason ("127.0.0.1:8080: Address already in use").
struct ListenError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class HttpServer {
 public:
  /// Binds and listens on `address` (throws ListenError), then serves from a thread of its own.
  /// `assets` must outlive the server.
  HttpServer(const ListenAddress& address, std::span<const Asset> assets, ServerLimits limits = {});
  /// Stops the thread and closes every connection.
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// The port listened on (the one the system chose for port 0).
  std::uint16_t port() const { return port_; }
  /// "http://127.0.0.1:8080/" (IPv6 in brackets).
  std::string url() const;
  /// Makes `json` (one line, no '\n') the snapshot served from now on and sends it to every event
  /// stream. Never blocks on a client: O(1) under a mutex the server thread holds only to copy a
  /// pointer, plus one write() to a pipe.
  void publish(std::string json);
  const ServerCounters& counters() const { return counters_; }

 private:
  struct Connection;
  void run();
  void accept_all();
  void serve(Connection& c, double now);  // answers the request once its head is complete
  void respond(Connection& c, int status, std::string_view type, std::string_view body, bool head,
               std::string_view extra_headers = {});
  void queue_snapshot(Connection& c);

  std::span<const Asset> assets_;
  ServerLimits limits_;
  std::string host_;
  bool loopback_ = true;
  std::uint16_t port_ = 0;
  int listen_fd_ = -1;
  int wake_[2] = {-1, -1};  // self-pipe: publish() and the destructor wake the thread
  std::mutex mutex_;
  std::shared_ptr<const std::string> snapshot_;  // guarded by mutex_
  std::uint64_t version_ = 0;                    // guarded by mutex_
  std::atomic<bool> stop_{false};
  ServerCounters counters_;
  // The server thread's own: its connections and its copy of the latest snapshot.
  std::vector<std::unique_ptr<Connection>> connections_;
  std::shared_ptr<const std::string> current_;
  std::uint64_t current_version_ = 0;
  std::thread thread_;
};

}  // namespace gyrochar::web
