#pragma once
// The pipeline of gyrochar-decode without its I/O: candump log lines or frames go in with their
// times, the Decoder follows the nodes, and every closed report becomes CSV / JSON lines rows, as
// every window of a node's dynamic Allan deviation does once its last frame has come.
// The program (host_tools/decode/main.cpp) adds the sources, the terminal view and the plot.
#include <cstddef>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "candump.hpp"
#include "limits.hpp"
#include "recording.hpp"
#include "decoder.hpp"

namespace gyrochar::decoding {

/// Reads lines from a file descriptor it does not own, in large blocks (no per-line system call).
class LineReader {
 public:
  /// `fd` open for reading; `max_line_bytes` is the longest line returned whole: a longer one
  /// comes out once, as its first max_line_bytes + 1 bytes (so the caller sees it is too long),
  /// and the rest of it up to its '\n' is skipped, never held. Allocates the buffer once.
  explicit LineReader(int fd, std::size_t max_line_bytes = max_candump_line_bytes);
  enum class Result { line, again, end, error };
  /// The next line, without its '\n' (and '\r'). `line` stays valid until the next call. Calls
  /// read() at most once, so that the caller can poll() or check a stop flag in between:
  /// again: no complete line yet (after one read(), on EAGAIN or on EINTR); end: end of input (a
  /// last line without '\n' is returned first); error: read() failed, errno says why.
  /// O(line length) amortized.
  Result next(std::string_view& line);

 private:
  int fd_;
  std::size_t max_line_;
  std::vector<char> buffer_;
  std::size_t begin_ = 0, end_ = 0;
  bool eof_ = false;
  bool skipping_ = false;  // inside an overlong line, after its first part
};

struct SessionOptions {
  DisplayRate rate_unit = gyrochar::rate_unit("deg/h");  // empty: native
  double confidence = 0.683;
  NodeFilter shown = NodeFilter{}.set();  // nodes recorded (the decoder follows all of them)
  std::FILE* csv = nullptr;               // not owned; null: no CSV
  std::FILE* jsonl = nullptr;             // not owned; null: no JSON lines
  /// Given the rows of every closed report of a recorded node, the CSV's rows (the live web page
  /// keeps them: live_feed.hpp). May be empty.
  std::function<void(const NodeView&, const std::vector<TauRow>&, const Units&)> on_report;
  /// Acceptance limits (--limits; not owned, null or empty: none). With them the CSV gains the
  /// verdict columns (node_report.hpp), and the JSON lines get a node's record of type
  /// "acceptance" ("final": false) at each closed report where one of its verdicts differs from
  /// the record written before (the first closed report always), and one per node at the end
  /// ("final": true), before the summary.
  const std::vector<Limit>* limits = nullptr;
};

/// Decodes one bus. Not copyable or movable (the decoder's listener points at it).
class Session {
 public:
  explicit Session(const SessionOptions& options);
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  /// One candump log line, decoded at its own timestamp. A malformed line is counted and skipped:
  /// returns false and says why. A remote request (RTR) frame is counted and skipped. Allocates nothing per line once warmed up (rows are reused).
  bool feed_line(std::string_view line, std::string& why);
  /// One frame at t_s (seconds). A time earlier than the latest is counted and decoded at the
  /// latest (the decoder's time never goes backwards). Amortized O(1) per frame plus O(taus) per
  /// closed report.
  void feed(const CanFrame& frame, double t_s);
  /// Advances time without a frame (live input): silent nodes go offline.
  void tick(double t_s);
  /// End of input: closes every open report and writes the final acceptance records and the JSON
  /// lines summary.
  void finish();

  const Decoder& decoder() const { return decoder_; }
  const InputCounters& input() const { return input_; }
  InputCounters& input() { return input_; }
  ConfidenceIntervals& intervals() { return intervals_; }
  const SessionOptions& options() const { return options_; }

 private:
  void on_event(DecoderEvent e, const NodeView& node, std::uint8_t seq);
  bool judging() const { return options_.limits != nullptr && !options_.limits->empty(); }
  void write_acceptance(double time_s, const NodeView& node, bool final);  // of decisions_

  SessionOptions options_;
  ConfidenceIntervals intervals_;
  std::unique_ptr<CsvWriter> csv_;
  std::unique_ptr<JsonlWriter> jsonl_;
  InputCounters input_;
  CandumpLine parsed_;
  std::vector<TauRow> rows_;
  std::vector<WindowRow> window_rows_;
  std::vector<Decision> decisions_;                                // of the node whose report closed last
  std::map<std::uint8_t, std::vector<Verdict>> verdicts_written_;  // per node, in its last acceptance record
  Decoder decoder_;                                                // last: its listener uses the members above
};

}  // namespace gyrochar::decoding
