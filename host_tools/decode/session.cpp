#include "session.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "node_report.hpp"

namespace gyrochar::decoding {

// ---------------------------------------------------------------------------------------------
// LineReader

LineReader::LineReader(int fd, std::size_t max_line_bytes)
    : fd_(fd), max_line_(max_line_bytes), buffer_(std::max<std::size_t>(max_line_bytes + 2, std::size_t{1} << 16)) {}

LineReader::Result LineReader::next(std::string_view& line) {
  for (bool have_read = false;; have_read = true) {
    if (skipping_) {  // the rest of an overlong line, up to its '\n': dropped
      const auto* newline = static_cast<const char*>(std::memchr(buffer_.data() + begin_, '\n', end_ - begin_));
      skipping_ = newline == nullptr;
      begin_ = newline != nullptr ? static_cast<std::size_t>(newline - buffer_.data()) + 1 : end_;
    }
    const char* begin = buffer_.data() + begin_;
    const std::size_t available = end_ - begin_;
    const std::size_t whole = max_line_ + 1;  // a line and its '\n'
    const auto* newline = static_cast<const char*>(std::memchr(begin, '\n', std::min(available, whole)));
    const bool overlong = newline == nullptr && available > max_line_;
    if (!skipping_ && (newline != nullptr || overlong || (eof_ && available > 0))) {
      const std::size_t length = newline != nullptr ? static_cast<std::size_t>(newline - begin)
                                 : overlong         ? whole
                                                    : available;
      line = std::string_view(begin, length);
      if (!overlong && !line.empty() && line.back() == '\r') line.remove_suffix(1);
      begin_ += newline != nullptr ? length + 1 : length;
      skipping_ = overlong;
      return Result::line;
    }
    if (eof_) return Result::end;
    if (have_read) return Result::again;  // one read() per call: the caller may poll() in between
    std::memmove(buffer_.data(), begin, available);
    begin_ = 0;
    end_ = available;
    const ssize_t n = ::read(fd_, buffer_.data() + end_, buffer_.size() - end_);
    if (n > 0) {
      end_ += static_cast<std::size_t>(n);
    } else if (n == 0) {
      eof_ = true;
    } else if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
      return Result::again;
    } else {
      return Result::error;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Session

namespace {

std::vector<Verdict> verdicts_of(const std::vector<Decision>& decisions) {
  std::vector<Verdict> v;
  for (const Decision& d : decisions) v.push_back(d.verdict);
  return v;
}

}  // namespace

Session::Session(const SessionOptions& options)
    : options_(options),
      intervals_(options.confidence),
      csv_(!options.csv ? nullptr
           : judging()  ? std::make_unique<CsvWriter>(options.csv, options.confidence, verdict_csv_header(*options.limits),
                                                     verdict_csv_columns(*options.limits))
                        : std::make_unique<CsvWriter>(options.csv, options.confidence)),
      jsonl_(options.jsonl ? std::make_unique<JsonlWriter>(options.jsonl, options.confidence) : nullptr),
      decoder_([this](DecoderEvent e, const NodeView& node, std::uint8_t seq) { on_event(e, node, seq); }) {}

bool Session::feed_line(std::string_view line, std::string& why) {
  ++input_.lines;
  if (!parse_candump_line(line, parsed_, why)) {
    ++input_.malformed_lines;
    return false;
  }
  if (parsed_.remote) {  // a request for data, not data: its DLC is not a payload to decode
    ++input_.remote_frames;
    return true;
  }
  feed(parsed_.frame, parsed_.time_s);
  return true;
}

void Session::feed(const CanFrame& frame, double t_s) {
  if (!input_.started) {
    input_.started = true;
    input_.first_s = input_.now_s = t_s;
  }
  if (t_s < input_.now_s) {
    ++input_.time_backwards;
  } else {
    input_.now_s = t_s;
  }
  ++input_.frames;
  decoder_.feed(frame, input_.now_s);
}

void Session::tick(double t_s) {
  if (t_s <= input_.now_s) return;
  input_.now_s = t_s;
  decoder_.tick(t_s);
}

void Session::finish() {
  decoder_.flush();
  if (!jsonl_) return;
  if (judging())
    for (const auto& [address, node] : decoder_.nodes()) {
      if (!options_.shown[address]) continue;
      decisions_ = node_decisions(node, *options_.limits);
      write_acceptance(input_.now_s, node, true);
    }
  jsonl_->summary(decoder_, input_, options_.shown);
}

void Session::write_acceptance(double time_s, const NodeView& node, bool final) {
  nlohmann::json j = acceptance_record(time_s, node, *options_.limits, decisions_);
  j["final"] = final;
  jsonl_->line(j.dump());
  verdicts_written_[node.address] = verdicts_of(decisions_);
}

void Session::on_event(DecoderEvent e, const NodeView& node, std::uint8_t seq) {
  const bool record = options_.shown[node.address];
  if (e == DecoderEvent::report_closed && record && (csv_ || jsonl_ || options_.on_report)) {
    const Decoder::Report& report = *decoder_.report(node.address);  // the slot table of the report just closed
    const Units units = units_for(node, options_.rate_unit);
    rows_.clear();
    tau_rows(node, report, units, intervals_, rows_);
    const bool judged = judging() && (csv_ || jsonl_);
    if (judged) decisions_ = node_decisions(node, *options_.limits);
    for (const TauRow& row : rows_) {
      if (csv_) csv_->row(row, units, judged ? verdict_csv_fields(*options_.limits, decisions_, node, row.tau_index) : "");
      if (jsonl_) jsonl_->row(row, units);
    }
    if (jsonl_) jsonl_->report(report.start_s, node, seq, units);
    if (jsonl_ && judged) {  // a record when a verdict changed: a watcher sees pass or fail once decided
      const auto written = verdicts_written_.find(node.address);
      if (written == verdicts_written_.end() || written->second != verdicts_of(decisions_))
        write_acceptance(report.start_s, node, false);
    }
    if (options_.on_report) options_.on_report(node, rows_, units);
  }
  if (e == DecoderEvent::window_complete && record && (csv_ || jsonl_) && node.current_window()) {
    const Units units = units_for(node, options_.rate_unit);
    window_rows_.clear();
    window_rows(node, node.windows.at(*node.current_window()), input_.now_s, seq, units, window_rows_);
    for (const WindowRow& row : window_rows_) {
      if (csv_) csv_->row(row, units);
      if (jsonl_) jsonl_->row(row, units);
    }
  }
  const bool noteworthy = e == DecoderEvent::restart || e == DecoderEvent::offline || e == DecoderEvent::online ||
                          e == DecoderEvent::duplicate || e == DecoderEvent::unknown_version;
  if (noteworthy && record && jsonl_) jsonl_->event(input_.now_s, e, node);
}

}  // namespace gyrochar::decoding
