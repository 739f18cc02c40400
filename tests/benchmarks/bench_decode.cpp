// Throughput of gyrochar-decode's pipeline on a big candump log:
//   bench_decode [LINES [LOG]]   (default 10^7 lines; LOG: keep the generated log at this path)
// Writes a log of LINES frames with the codec (4 nodes, 32 taus, one report per second each, lines
// in time order), then times, in this process, reading it in lines, parsing and decoding it, and
// decoding with the CSV and the JSON lines writers (to /dev/null). Prints lines per second of each.
// Time the program itself on the kept log with e.g. `time gyrochar-decode LOG --view none --csv x.csv`.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "candump.hpp"
#include "session.hpp"

namespace {

using namespace gyrochar;
using namespace gyrochar::protocol;

constexpr std::uint8_t taus = 32;
constexpr int nodes = 4;

Message message(std::uint8_t node, std::uint8_t seq, ReportSlot s, std::uint64_t report) {
  const auto value = static_cast<float>(node) / static_cast<float>(1 + s.index) + 1e-3f * static_cast<float>(seq);
  switch (s.slot) {
    case Slot::status: return StatusMsg{seq, NodeState::running, taus, 100 * (report + 1)};
    case Slot::faults: return StatusFaultsMsg{seq, 0, 0, 0, 0};
    case Slot::adev: return TauDevMsg{seq, s.index, DevKind::adev, value, 10.0 + s.index, NoiseType::white_fm, true};
    case Slot::mdev: return TauDevMsg{seq, s.index, DevKind::mdev, value / 2, 9.0 + s.index, NoiseType::white_fm, true};
    case Slot::terms: return TauTermsMsg{seq, s.index, 100 * (report + 1)};
    case Slot::tau_info: return TauInfoMsg{seq, s.index, std::uint64_t{1} << s.index, 0};
    case Slot::sampling: return MetaSamplingMsg{seq, 0.01f, 8};
    case Slot::clock: return MetaClockMsg{seq, 1000 * (report + 1), version};
    case Slot::scale: return MetaScaleMsg{seq, 1.0f, AngleUnit::arcsec, InputSource::simulated};
    case Slot::config: return MetaConfigMsg{seq, 7, 1000};
    case Slot::ieee952:
      if (s.index == ieee952_summary_page) return Ieee952SummaryMsg{seq, Ieee952Status::ok, 0.9f, 15, true, {}};
      return Ieee952Msg{seq, static_cast<Ieee952Term>(s.index), true, 0.01f, 0.1, true};
    case Slot::fit_model: return Ieee952ModelMsg{seq, 1, 0, false, 0, false, 0, 0, false, 0.0f};  // one Markov term
    case Slot::fit_parameter: {
      const FitParameterSlot p = fit_parameter_slot(s.index);
      const bool in_model = p.parameter == FitParameter::markov_sigma || p.parameter == FitParameter::markov_tc;
      return Ieee952ParameterMsg{
          seq, p.parameter, p.index, in_model && p.index == 0, in_model ? value : 0.0f, in_model ? 0.1 : 0.0};
    }
    case Slot::unconstrained: return Ieee952UnconstrainedMsg{seq, static_cast<Ieee952Term>(s.index), 0.01f, 0.001};
    case Slot::window:  // no window taus
    case Slot::window_length:
    case Slot::window_dev: break;
  }
  return {};
}

void write_log(const std::string& path, long lines) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (out == nullptr) {
    std::perror(path.c_str());
    std::exit(2);
  }
  long written = 0;
  std::vector<std::pair<double, std::string>> second;
  for (std::uint64_t report = 0; written < lines; ++report) {
    const auto seq = static_cast<std::uint8_t>(report);
    second.clear();
    for (int n = 0; n < nodes; ++n) {
      const auto node = static_cast<std::uint8_t>(0x10 + n);
      const std::size_t frames = report_frame_count(seq, taus);
      for (std::size_t k = 0; k < frames; ++k) {
        CanFrame f;
        encode(message(node, seq, report_slot(seq, taus, k), report), node, f);
        const double t = 1.7e9 + static_cast<double>(report) +
                         (static_cast<double>(k) + 0.25 * n) / static_cast<double>(frames);
        second.emplace_back(t, format_candump_line(t, "can0", f));
      }
    }
    std::sort(second.begin(), second.end());
    for (const auto& [t, line] : second) {
      if (written++ == lines) break;
      std::fputs(line.c_str(), out);
      std::fputc('\n', out);
    }
  }
  std::fclose(out);
}

// Reads the whole log through a session made by `make` (null: only split it in lines).
template <class Make>
void measure(const char* what, const std::string& path, long lines, Make make) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  const auto start = std::chrono::steady_clock::now();
  {
    decoding::LineReader reader(fd);
    auto session = make();
    std::string_view line;
    std::string why;
    for (;;) {
      const auto r = reader.next(line);
      if (r == decoding::LineReader::Result::end || r == decoding::LineReader::Result::error) break;
      if (r == decoding::LineReader::Result::line && session) session->feed_line(line, why);
    }
    if (session) session->finish();
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ::close(fd);
  std::printf("%-32s %7.2f s  %6.2f M lines/s\n", what, s, static_cast<double>(lines) / s / 1e6);
}

}  // namespace

int main(int argc, char** argv) {
  const long lines = argc > 1 ? std::atol(argv[1]) : 10000000;
  const bool keep = argc > 2;
  const std::string path = keep ? argv[2] : "/tmp/bench_decode_" + std::to_string(getpid()) + ".log";
  write_log(path, lines);
  std::printf("%ld lines, %d nodes x %u taus\n", lines, nodes, taus);
  std::FILE* null = std::fopen("/dev/null", "w");
  using Session = std::unique_ptr<decoding::Session>;
  measure("read lines", path, lines, [] { return Session{}; });
  measure("read, parse, decode", path, lines,
          [] { return std::make_unique<decoding::Session>(decoding::SessionOptions{}); });
  measure("... and write CSV", path, lines, [&] {
    decoding::SessionOptions o;
    o.csv = null;
    return std::make_unique<decoding::Session>(o);
  });
  measure("... and write CSV and JSON lines", path, lines, [&] {
    decoding::SessionOptions o;
    o.csv = null;
    o.jsonl = null;
    return std::make_unique<decoding::Session>(o);
  });
  std::fclose(null);
  if (!keep) std::remove(path.c_str());
  return 0;
}
