#pragma once
// What the live web page (gyrochar-decode --http, gyrochar-demo --http) is sent: one JSON object
// per refresh, built from what the decoder records. Each node carries
// - "rows": the tau rows of its latest closed report, the JSON lines' `tau` records themselves
//   (the CSV's rows: recording.hpp), and "rows_received_ms", the wall-clock time that report closed;
// - "report": its JSON lines `report` record as of now (state, faults, link health, metadata, the
//   IEEE-952 terms and the fit's summary and model);
// - "plot": the decoder plot's series (plot_data.hpp): the model's lines, the truth's line where a
//   simulation knows it, the notes, the read-off points and the heat map of the dynamic Allan
//   deviation; "truth": the true IEEE-952 terms in the display units, or null;
// - "acceptance": its verdicts under the decoder's --limits as of now (the JSON lines record of
//   type "acceptance", node_report.hpp), or null without limits.
// Top level: program, source, the input's counters, decoder time elapsed, "sent_ms" (wall clock
// at the snapshot, ms since the Unix epoch), refresh_s, ci_level. The keys are the page's
// contract (host_tools/decode/web/app.js reads them; docs/live.md lists them).
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "limits.hpp"
#include "recording.hpp"
#include "session.hpp"

namespace gyrochar::decoding {

/// Wall clock, ms since the Unix epoch (what the page's latency is measured against).
double wall_ms();

class LiveFeed {
 public:
  /// `truth` (may be null) must outlive the feed.
  LiveFeed(std::string program, double refresh_s, double confidence, const TrueTermsByNode* truth = nullptr);
  ~LiveFeed();
  LiveFeed(const LiveFeed&) = delete;
  LiveFeed& operator=(const LiveFeed&) = delete;

  /// Judges every node against `limits` in each snapshot from now on (null: none); they must
  /// outlive the feed.
  void judge(const std::vector<Limit>* limits) { limits_ = limits; }
  /// Keeps the rows of `node`'s report just closed (SessionOptions::on_report). O(rows).
  void report_closed(const NodeView& node, const std::vector<TauRow>& rows, const Units& units);
  /// The snapshot of every recorded node: one line of JSON. O(nodes x (taus + windows x window
  /// taus)); allocates.
  std::string snapshot(Session& session);

 private:
  std::string capture();  // what the JSON lines writer wrote since the last capture, without '\n'

  std::string program_;
  double refresh_s_;
  const TrueTermsByNode* truth_;
  const std::vector<Limit>* limits_ = nullptr;
  char* buffer_ = nullptr;
  std::size_t size_ = 0;
  std::FILE* memory_;  // open_memstream: the JSON lines writer writes here
  JsonlWriter jsonl_;
  struct Latest {
    std::string rows;  // "[{...},{...}]"
    double received_ms = 0;
  };
  std::map<std::uint8_t, Latest> latest_;
};

}  // namespace gyrochar::decoding
