#pragma once
// The live web page of a decoding session (gyrochar-decode --http, gyrochar-demo --http): the
// feed that turns the session into snapshots (live_feed.hpp) and the server that sends them
// (http_server.hpp), with the pace between them. The program's thread only builds a snapshot
// every refresh and hands it over; the server's thread does all the talking.
#include <memory>
#include <string>

#include "http_server.hpp"
#include "live_feed.hpp"

namespace gyrochar::decoding {

class LiveWeb {
 public:
  /// Listens on `address` (throws web::ListenError naming the address and the reason).
  LiveWeb(const web::ListenAddress& address, std::string program, double refresh_s, double confidence,
          const TrueTermsByNode* truth = nullptr, web::ServerLimits limits = {});
  /// The SessionOptions::on_report hook that keeps each report's rows for the page.
  std::function<void(const NodeView&, const std::vector<TauRow>&, const Units&)> hook();
  /// Gives each node's verdicts under `limits` on the page (null: none); they must outlive this.
  void judge(const std::vector<Limit>* limits) { feed_.judge(limits); }
  /// Publishes a snapshot of `session` once refresh_s of wall-clock time has passed since the
  /// last one (`force`: now). O(1) when not due; else the snapshot's cost (live_feed.hpp).
  void update(Session& session, bool force = false);
  std::string url() const { return server_->url(); }
  const web::HttpServer& server() const { return *server_; }

 private:
  LiveFeed feed_;
  double refresh_s_;
  double last_s_ = -1e300;
  std::unique_ptr<web::HttpServer> server_;
};

}  // namespace gyrochar::decoding
