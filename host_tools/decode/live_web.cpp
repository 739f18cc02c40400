#include "live_web.hpp"

#include <chrono>

#include "web_assets.hpp"

namespace gyrochar::decoding {

LiveWeb::LiveWeb(const web::ListenAddress& address, std::string program, double refresh_s, double confidence,
                 const TrueTermsByNode* truth, web::ServerLimits limits)
    : feed_(std::move(program), refresh_s, confidence, truth),
      refresh_s_(refresh_s),
      server_(std::make_unique<web::HttpServer>(address, web::page_assets(), limits)) {}

std::function<void(const NodeView&, const std::vector<TauRow>&, const Units&)> LiveWeb::hook() {
  return [this](const NodeView& node, const std::vector<TauRow>& rows, const Units& units) {
    feed_.report_closed(node, rows, units);
  };
}

void LiveWeb::update(Session& session, bool force) {
  const double now = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  if (!force && now - last_s_ < refresh_s_) return;
  last_s_ = now;
  server_->publish(feed_.snapshot(session));
}

}  // namespace gyrochar::decoding
