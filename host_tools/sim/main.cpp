// gyrochar-sim: a simulated ring laser gyro with known IEEE-952 parameters, faster than real time:
// writes pulse counts per tau0 (one per line) for gyrochar-analyze, the firmware's fakes or a test.
// With --can it is also the gyro's readout electronics: it sends the same counts as CounterInput
// frames (docs/protocol.md, section 8) on a SocketCAN interface, paced at tau0 (or --speed times
// faster), for gyrochard's can-counter source.
#include <CLI/CLI.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hal/linux/can_interface.hpp"
#include "gyro_sim.hpp"
#include "sim_truth.hpp"
#include "gyrochar/wire/protocol.hpp"
#include "hal/program/command_line.hpp"
#include "hal/program/exit_codes.hpp"
#include "hal/linux/socketcan.hpp"

namespace {

using namespace gyrochar;

constexpr const char* program = "gyrochar-sim";

// The readout electronics: frame k carries the pulses accumulated over the first k intervals
// (modulo 2^32) and Seq = k mod 256, sent at start + k tau0 / speed on CLOCK_MONOTONIC. Frame 0
// (Count 0) marks the start, so a board that receives every frame derives exactly the simulated
// counts. A full TX queue is waited out (1 ms steps, up to 1 s); a frame the interface refuses
// because it is down is lost, as on a real bus, and counted.
class CounterInputSender {
 public:
  CounterInputSender(const std::string& interface, std::uint8_t node, double interval_s)
      : bus_(interface), node_(node), interval_ns_(static_cast<long long>(std::llround(interval_s * 1e9))) {
    clock_gettime(CLOCK_MONOTONIC, &start_);
  }

  void send_next(std::int64_t count) {
    accumulated_ += static_cast<std::uint32_t>(count);  // two's complement: wraps like the electronics
    wait_until_due();
    protocol::CounterInputMsg msg;
    msg.count = accumulated_;
    msg.seq = static_cast<std::uint8_t>(frames_);
    CanFrame frame;
    if (protocol::encode(msg, node_, frame) != protocol::ProtocolError::none)
      throw std::logic_error("CounterInput frame refused by the codec");
    ++frames_;
    for (int attempt = 0; attempt < 1000; ++attempt) {
      switch (bus_.send(frame)) {
        case hal::SendResult::sent: return;
        case hal::SendResult::bus_down: ++lost_down_; return;
        case hal::SendResult::queue_full:
          ++queue_full_waits_;
          sleep_ns(1000000);
          break;
      }
    }
    ++lost_queue_full_;
  }

  std::string summary() const {
    return std::to_string(frames_) + " CounterInput frames from node " + std::to_string(node_) + ", " +
           std::to_string(late_) + " sent late, " + std::to_string(queue_full_waits_) + " waits for a full TX queue, " +
           std::to_string(lost_down_) + " lost (interface down), " + std::to_string(lost_queue_full_) +
           " lost (TX queue full for 1 s)";
  }

 private:
  static void sleep_ns(long long ns) {
    const timespec t{static_cast<time_t>(ns / 1000000000LL), static_cast<long>(ns % 1000000000LL)};
    nanosleep(&t, nullptr);
  }

  void wait_until_due() {
    const long long due_ns = static_cast<long long>(frames_) * interval_ns_ + start_.tv_nsec;
    timespec due{start_.tv_sec + static_cast<time_t>(due_ns / 1000000000LL), static_cast<long>(due_ns % 1000000000LL)};
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (now.tv_sec > due.tv_sec || (now.tv_sec == due.tv_sec && now.tv_nsec > due.tv_nsec + 1000000)) ++late_;
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &due, nullptr) == EINTR) {
    }
  }

  hal::SocketCan bus_;
  std::uint8_t node_;
  long long interval_ns_;
  timespec start_{};
  std::uint32_t accumulated_ = 0;
  std::uint64_t frames_ = 0, late_ = 0, queue_full_waits_ = 0, lost_down_ = 0, lost_queue_full_ = 0;
};

constexpr const char* footer =
    R"(Parameters are in the units gyro data sheets use; the quantization noise follows from the pulse
weight (Q = pulse weight / sqrt(12), white only when the angle moves at random by a pulse or more
per sample, or a dither moves it). Bias instability is flicker rate noise (ADEV floor 0.664 B)
over the band from 1/(2 pi --bias-time) up to 0.34 / tau0. docs/metrology.md gives each term's
model and its Allan deviation.

--markov SIGMA,TC adds a first-order Gauss-Markov (exponentially correlated) rate: SIGMA is the
STATIONARY standard deviation of the rate in deg/h, TC the correlation time in s. The rate over
sample k (its mean over the tau0 interval) is y_k = phi y_{k-1} + SIGMA sqrt(1 - phi^2) e_k,
phi = exp(-tau0/TC), e_k standard normal, y_0 drawn from the stationary N(0, SIGMA^2); the angle
added over the interval is y_k tau0. The driving noise of the continuous model (IEEE 952 q_c) is
SIGMA sqrt(2/TC); the ADEV peaks at 0.618 SIGMA near tau = 1.89 TC (TC many tau0).
--sinusoid AMP,FREQ adds a sinusoidal rate AMP sin(2 pi FREQ t + phi0), AMP in deg/h, FREQ in Hz
below the Nyquist frequency 1/(2 tau0), phi0 uniform from the seed, integrated exactly over each
interval (ADEV AMP sin^2(pi FREQ tau)/(pi FREQ tau), at most 0.725 AMP near tau = 0.371/FREQ).
Both repeat, up to 4 of each, last for the whole run, are listed on the truth line, and draw from
their own random stream: the other terms' noise is the same with or without them.

--segment T:NAME=VALUE[,NAME=VALUE...] changes the gyro from T seconds on (repeatable, in time
order): NAME is rate (deg/h), white-angle (arcsec), arw (deg/sqrt(h)) or rrw (deg/h/sqrt(h)); the
other parameters stay, and nothing restarts (the angle and the noise processes carry over). The
truth line then has format 2 and lists the segments.

Range: the counts are exact integers while the angle stays within 2^53 pulses. Parameters whose
angle could pass it over the run (the rate and ramp as given, the noise terms at 10 standard
deviations, e.g. --rate 1e9 --pulse-weight 1e-9) are refused up front, naming the largest term;
a run that passes it all the same stops with an error, never a wrapped count.

Output: two '#' header lines, then one count per line. The first describes the run; the second,
"# gyrochar-sim truth: key=value ...", repeats every parameter and the IEEE-952 truth (Q arcsec,
N deg/sqrt(h), B deg/h, K deg/h/sqrt(h), R deg/h/h, Q_white yes/no) and, when there are some, the
Gauss-Markov and sinusoidal terms (markov_terms=M markov1_sigma_deg_per_h=... markov1_tc_s=...,
sinusoid_terms=S sinusoid1_amplitude_deg_per_h=... sinusoid1_frequency_hz=...) for programs to read.

With --can the counts also go out as CounterInput frames (0x0CFF50xx, docs/protocol.md section 8)
from node --can-node, one per tau0 interval, paced on the monotonic clock at tau0 / --speed; the
first frame carries Count 0 and marks the start, so a board receiving every frame derives exactly
the counts written to --out. With --can, --out writes nothing unless given. A summary of what was
sent goes to stderr at the end.

Examples:
  gyrochar-sim --duration 7200 --tau0 0.01 --arw 0.002 --rrw 0.01 > counts.txt
  gyrochar-sim --duration 3600 --arw 0.002 | gyrochar-analyze --type counts --tau0 0.01 --pulse-weight 1 -
  gyrochar-sim --duration 60 --tau0 0.01 --arw 0.003 --can vcan0 --can-node 128 --speed 4 --out counts.txt
  gyrochar-sim --duration 7200 --arw 0.002 --segment 3600:arw=0.004 > doubling.txt   # N doubles halfway
  gyrochar-sim --duration 36000 --tau0 0.1 --arw 0.002 --markov 0.05,300 --sinusoid 0.02,0.01 > bumps.txt

)";

// The command line's values.
struct SimCli {
  SimOptions o;
  std::string out = "-";
  std::vector<std::string> segments, markov, sinusoids;
  std::string can_interface;
  unsigned can_node = 0x80;
  double speed = 1.0;
};

void add_options(CLI::App& app, SimCli& c) {
  app.add_option("--duration", c.o.duration_s, "simulated time in seconds")->capture_default_str();
  app.add_option("--tau0", c.o.tau0_s, "sample interval in seconds")->capture_default_str();
  app.add_option("--pulse-weight", c.o.pulse_arcsec, "angle per pulse in arcsec")->capture_default_str();
  app.add_option("--rate", c.o.rate_deg_per_h, "input rate in deg/h (earth rate by default)")->capture_default_str();
  app.add_option("--white-angle", c.o.white_angle_arcsec, "white angle noise beyond quantization, arcsec")
      ->capture_default_str();
  app.add_option("--arw", c.o.arw_deg_per_sqrt_h, "angle random walk N in deg/sqrt(h)")->capture_default_str();
  app.add_option("--rrw", c.o.rrw_deg_per_h_sqrt_h, "rate random walk K in deg/h/sqrt(h)")->capture_default_str();
  app.add_option("--bias-instability", c.o.bias_deg_per_h, "bias instability B in deg/h (flicker rate noise)")
      ->capture_default_str();
  app.add_option("--bias-time", c.o.bias_time_s, "the flicker band reaches down to 1/(2 pi BIAS_TIME), seconds")
      ->capture_default_str();
  app.add_option("--ramp", c.o.ramp_deg_per_h2, "rate ramp R in deg/h/h")->capture_default_str();
  app.add_option("--dither", c.o.dither_arcsec, "dither amplitude in arcsec")->capture_default_str();
  app.add_option("--dither-hz", c.o.dither_hz, "dither frequency in Hz")->capture_default_str();
  // CLI11 would wrap "-1" to 2^64 - 1: only plain decimal digits are a seed.
  app.add_option("--seed", c.o.seed, "random seed 0..2^64-1 (runs are reproducible)")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](const std::string& text) {
            const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
            return digits && (text.size() < 20 || (text.size() == 20 && text <= "18446744073709551615"))
                       ? std::string()
                       : "must be an integer 0..2^64-1, not '" + text + "'";
          },
          "SEED"));
  app.add_option("--segment", c.segments, "from T seconds on, change parameters: T:NAME=VALUE[,NAME=VALUE...]")
      ->option_text("T:NAME=VALUE");
  app.add_option("--markov", c.markov, "Gauss-Markov rate: stationary sigma in deg/h, correlation time in s (up to 4)")
      ->option_text("SIGMA,TC");
  app.add_option("--sinusoid", c.sinusoids,
                 "sinusoidal rate: amplitude in deg/h, frequency in Hz below 1/(2 tau0) (up to 4)")
      ->option_text("AMP,FREQ");
  app.add_option("--out", c.out, "output file, '-' for standard output")->capture_default_str();
  app.add_option("--can", c.can_interface, "also send the counts as CounterInput frames on this SocketCAN interface")
      ->option_text("IF");
  app.add_option("--can-node", c.can_node, "with --can: address of the simulated electronics, 0..253")
      ->capture_default_str();
  app.add_option("--speed", c.speed, "with --can: frames every tau0 / SPEED seconds (1: real time)")->capture_default_str();
}

// The options CLI11 took, checked in this order; the exit code when one is refused (said on
// stderr), nothing when the run goes on. Fills c.o's segments and terms; without --out, --can
// writes no counts.
std::optional<int> check_options(const CLI::App& app, SimCli& c) {
  auto bad = [](const char* what, const char* why) {
    print_error(program, what, why);
    return exit_code::bad_input;
  };
  // The repeatable options' arguments, in order; `why` says what is wrong with the first bad one.
  const auto read_each = [](const std::vector<std::string>& texts, auto parse, auto& list, std::string& why) {
    for (const std::string& text : texts) {
      const auto item = parse(text, why);
      if (!item) return false;
      list.push_back(*item);
    }
    return true;
  };
  std::string why;
  if (!read_each(c.segments, parse_segment_option, c.o.segments, why)) return bad("--segment", why.c_str());
  if (!read_each(c.markov, parse_markov_option, c.o.markov, why)) return bad("--markov", why.c_str());
  if (!read_each(c.sinusoids, parse_sinusoid_option, c.o.sinusoids, why)) return bad("--sinusoid", why.c_str());
  if (const auto problem = check_parameters(c.o)) return bad(problem->what, problem->why.c_str());
  if (c.can_node > protocol::max_node_address) return bad("--can-node", "must be an address 0..253");
  if (!(c.speed > 0) || !std::isfinite(c.speed)) return bad("--speed", "must be positive");
  if (c.can_interface.empty() && (app.count("--can-node") || app.count("--speed")))
    return bad("--can-node, --speed", "only apply with --can");
  if (!c.can_interface.empty())  // a name no interface can have is bad input; a missing one is hardware
    if (const std::string problem = interface_name_problem(c.can_interface); !problem.empty())
      exit_with(exit_code::bad_input, program, "--can", "'" + c.can_interface + "': " + problem);
  if (!c.can_interface.empty() && !app.count("--out")) c.out.clear();  // frames only
  return std::nullopt;
}

// The counts of the run to `f` (may be null) and `sender` (may be null); stops early when `f`
// fails (its close says so).
void simulate(const SimOptions& o, FILE* f, CounterInputSender* sender) {
  SimRun sim(o);
  if (sender) sender->send_next(0);  // the start: Count 0
  for (std::uint64_t k = 0; k < sim.samples(); ++k) {
    std::int64_t count = 0;
    try {
      count = sim.next_count();
    } catch (const std::overflow_error& e) {  // beyond what check_parameters allowed for (> 10 sigma)
      if (f != nullptr && f != stdout) std::fclose(f);
      exit_with(exit_code::bad_input, program, "counts", std::string(e.what()) + "; the output stops before it");
    }
    if (f != nullptr) {
      std::fprintf(f, "%lld\n", static_cast<long long>(count));
      if ((k & 0xFFFF) == 0 && std::ferror(f)) break;  // the output is lost: stop now, say so below
    }
    if (sender) sender->send_next(count);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gyrochar-sim: pulse counts of a simulated ring laser gyro with known parameters.", "gyrochar-sim"};
  app.footer(std::string(footer) + std::string(exit_code::help));
  SimCli c;
  add_options(app, c);
  if (const auto code = parse_command_line(app, argc, argv, program)) return finish(program, *code);
  if (const auto code = check_options(app, c)) return *code;
  const SimOptions& o = c.o;
  const std::string& out = c.out;
  const GyroParameters p = gyro_parameters(o);
  std::unique_ptr<CounterInputSender> sender;
  if (!c.can_interface.empty()) {
    try {
      sender = std::make_unique<CounterInputSender>(c.can_interface, static_cast<std::uint8_t>(c.can_node),
                                                    p.tau0_s / c.speed);
    } catch (const std::exception& e) {
      exit_with(exit_code::no_hardware, program, e.what());  // "vcan0: why": the interface first
    }
  }
  FILE* f = out.empty() ? nullptr : out == "-" ? stdout : std::fopen(out.c_str(), "w");
  if (!out.empty() && f == nullptr) exit_with(exit_code::output_failed, program, out, std::strerror(errno));
  const std::string output_name = out == "-" ? "standard output" : out;
  if (f != nullptr)  // the description, then the machine-readable truth (sim_truth.hpp)
    std::fprintf(f, "%s\n%s\n", format_sim_description_line(o).c_str(), format_sim_truth_line(o).c_str());
  simulate(o, f, sender.get());
  if (sender) std::fprintf(stderr, "gyrochar-sim: %s: %s\n", c.can_interface.c_str(), sender->summary().c_str());
  if (f != nullptr && f != stdout && !close_output(f, program, output_name)) return exit_code::output_failed;
  return finish(program, exit_code::ok);
}
