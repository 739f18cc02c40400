#pragma once
// gyrochar-sim's parameters and the IEEE Std 952 truth they imply, written as one machine-readable
// comment line at the top of its output and read back by any later program (an analyzer that
// shows the truth beside its fit, a test):
//
//   # gyrochar-sim truth: format=1 duration_s=7200 tau0_s=0.01 ... Q_arcsec=0.288675 ... Q_white=no
//
// Grammar: the prefix "# gyrochar-sim truth:", then key=value tokens separated by blanks, in any
// order, each key once. Values are decimal numbers as std::to_chars writes them (the shortest text
// that reads back to the same double), an unsigned integer for seed and format, yes/no for
// Q_white. Keys carry their unit: the simulator's parameters in the units of its command line
// (format, duration_s, tau0_s, pulse_arcsec, rate_deg_per_h, white_angle_arcsec,
// arw_deg_per_sqrt_h, rrw_deg_per_h_sqrt_h, bias_deg_per_h, bias_time_s, ramp_deg_per_h2,
// dither_arcsec, dither_hz, seed), then the truth in the units of the IEEE-952 fit (Q_arcsec,
// N_deg_per_sqrt_h, B_deg_per_h, K_deg_per_h_sqrt_h, R_deg_per_h2, Q_white). A reader ignores keys
// it does not know: adding keys keeps format=1; only a change in the meaning of a key raises it,
// and a reader refuses a format it does not know.
//
// Gauss-Markov and sinusoidal rate terms (gyrochar-sim --markov, --sinusoid; IEEE Std 952 Annex C's
// exponentially correlated and sinusoidal noise) are written only when there are some:
// `markov_terms=M` followed, for i = 1..M, by markov<i>_sigma_deg_per_h (the stationary standard
// deviation) and markov<i>_tc_s (the correlation time), and `sinusoid_terms=S` followed by
// sinusoid<i>_amplitude_deg_per_h and sinusoid<i>_frequency_hz. They are parameters and truth at
// once (Ieee952Truth carries them in SI); a line without them has none, so older lines read as
// before. They add keys, so the format stays 1 (2 with segments): a reader that predates them
// ignores them, as it ignores the dither, and reads the other terms' truth, which stays true.
//
// A run with segments (gyrochar-sim --segment: the gyro changes during the run, e.g. its angle
// random walk doubles halfway) writes format=2: the keys above then describe the run before the
// first change, and `segments=S` is followed, for i = 1..S, by segment<i>_start_s and the keys of
// the parameters segment i changes (segment<i>_arw_deg_per_sqrt_h=0.004, ...; rate, white angle,
// ARW and RRW may change). Q_white says whether the quantization is white in every segment. A
// format-1 reader refuses such a line rather than take the first segment's truth for the run's.
//
// The data readers skip '#' lines, so the header costs them nothing. The writer (gyrochar-sim) and
// the parser share format_sim_truth_line and the key list below: they cannot drift apart.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gyro_sim.hpp"

namespace gyrochar {

/// A change of the simulated gyro from start_s on (gyrochar-sim --segment T:NAME=VALUE,...): the
/// parameters it names take these values, the others stay. Only levels whose process state carries
/// over unchanged may change: the input rate, the white angle noise, ARW and RRW.
struct SimSegment {
  double start_s = 0;  // seconds since the start of the run; the change applies from the sample
                       // interval that starts at round(start_s / tau0) tau0
  std::optional<double> rate_deg_per_h, white_angle_arcsec, arw_deg_per_sqrt_h, rrw_deg_per_h_sqrt_h;
  bool operator==(const SimSegment&) const = default;
};

/// A Gauss-Markov rate term (gyrochar-sim --markov SIGMA,TC): stationary standard deviation of the
/// rate in deg/h, correlation time in s (gyro_sim.hpp states the convention).
struct SimMarkov {
  double sigma_deg_per_h = 0;
  double tc_s = 0;
  bool operator==(const SimMarkov&) const = default;
};

/// A sinusoidal rate term (gyrochar-sim --sinusoid AMP,FREQ): amplitude in deg/h, frequency in Hz.
struct SimSinusoid {
  double amplitude_deg_per_h = 0;
  double frequency_hz = 0;
  bool operator==(const SimSinusoid&) const = default;
};

/// At most this many Gauss-Markov terms, and as many sinusoids, in a run.
inline constexpr std::size_t max_rate_terms = 4;

/// gyrochar-sim's simulation options, in the units of its command line (defaults included).
struct SimOptions {
  double duration_s = 3600;
  double tau0_s = 0.01;
  double pulse_arcsec = 1.0;
  double rate_deg_per_h = 15.041;  // earth rate
  double white_angle_arcsec = 0;
  double arw_deg_per_sqrt_h = 0;
  double rrw_deg_per_h_sqrt_h = 0;
  double bias_deg_per_h = 0;
  double bias_time_s = 1e5;
  double ramp_deg_per_h2 = 0;
  double dither_arcsec = 0;
  double dither_hz = 0;
  std::uint64_t seed = 1;
  std::vector<SimSegment> segments;    // in increasing start_s; empty: the gyro never changes
  std::vector<SimMarkov> markov;       // Gauss-Markov rate terms, for the whole run
  std::vector<SimSinusoid> sinusoids;  // sinusoidal rate terms, for the whole run
};

/// The options in force in segment i of `o` (0: before the first change, up to o.segments.size()),
/// without segments. O(i).
SimOptions segment_options(const SimOptions& o, std::size_t i);

/// The IEEE-952 truth of a simulation, SI units (rad, s).
struct Ieee952Truth {
  double q_rad = 0;                     // total white angle noise sqrt(q^2 + pulse^2 / 12)
  double n_rad_sqrt_s = 0;              // angle random walk
  double b_rad_s = 0;                   // bias instability (ADEV floor / 0.664)
  double k_rad_s_sqrt_s = 0;            // rate random walk
  double r_rad_s2 = 0;                  // rate ramp
  bool quantization_white = false;      // the pulse quantization is expected to be white (below)
  std::vector<MarkovRate> markov;       // Gauss-Markov rate terms (sigma rad/s, tc s)
  std::vector<SinusoidRate> sinusoids;  // sinusoidal rate terms (amplitude rad/s, frequency Hz)
};

struct SimTruth {
  SimOptions options;  // exactly as written
  Ieee952Truth truth;  // as written, converted to SI
};

/// A parameter gyrochar-sim refuses: `what` names the option ("--tau0", a static string), `why`
/// says why, with the limit.
struct ParameterProblem {
  const char* what = "";
  std::string why;
};

/// The first problem with `o`, or nothing: tau0 > 0; duration >= tau0 and at most 10^12 samples;
/// a finite rate within 10^9 deg/h; pulse weight > 0; noise levels, dither and its frequency
/// finite and >= 0; with bias instability, tau0 < bias_time <= 10^15 tau0; segments starting in
/// increasing order inside the run (tau0 <= start < duration), each changing something, each
/// segment's options as valid; at most max_rate_terms Gauss-Markov terms, each with
/// 0 < sigma <= 10^9 deg/h and 0 < Tc finite, and at most max_rate_terms sinusoids, each with
/// 0 <= amplitude <= 10^9 deg/h and 0 < frequency < 1 / (2 tau0) (the Nyquist frequency); and
/// the pulse total within reach: worst_case_pulses <= max_pulse_total (2^53), the problem then
/// naming the largest contribution's option. O(segments + terms). Allocates the message.
std::optional<ParameterProblem> check_parameters(const SimOptions& o);

/// How far the observed angle of a run of `o` can get from 0, in pulses, term by term, each at
/// its worst over the whole run (every segment's largest level): the input rate |rate| T, the ramp
/// R T^2 / 2, the dither amplitude, and at range_sigmas standard deviations the white angle
/// noise q, the angle random walk N sqrt(T), the rate random walk K T^1.5 / sqrt(3), the bias
/// instability's rate times T (its octave processes' summed variance) and each Gauss-Markov
/// term's, sigma T; each sinusoid's angle amplitude A / (pi f). T = samples x tau0.
struct PulseReach {
  double total = 0;               // the sum of the terms, in pulses
  double largest = 0;             // the largest term, in pulses
  const char* largest_what = "";  // its option ("--rate", "--arw", ...)
};
/// Standard deviations of reach for the random terms: a normal draw exceeds 10 sigma with
/// probability 1.5e-23, so 10^12 samples pass it with probability below 10^-10.
inline constexpr double range_sigmas = 10.0;
PulseReach worst_case_pulses(const SimOptions& o);

/// The simulator's parameters (SI) for `o`. O(1).
GyroParameters gyro_parameters(const SimOptions& o);

/// Whether the quantization error is expected to be white: true when the angle at the sample
/// instants moves at random by at least one pulse between samples, sqrt(N^2 tau0 + 2 q^2) >= pulse
/// (the correlation of two quantization errors is then below 0.61 exp(-2 pi^2) = 2e-9), or when
/// the dither moves it by at least a pulse per sample, 2 A |sin(pi f tau0)| >= pulse (a
/// deterministic whitening: docs/metrology.md gives the residual departures), or when a sinusoidal
/// rate term does, as a dither of angle amplitude A / (2 pi f) would; in every segment. The
/// Gauss-Markov terms, like the rate random walk and the bias instability, are not counted.
/// O(segments + terms).
bool quantization_expected_white(const SimOptions& o);

/// The IEEE-952 truth of `o`: Q = sqrt(q^2 + pulse^2 / 12), N, B, K, R, in SI, before the first
/// segment (segment_options() gives each segment's), and the Gauss-Markov and sinusoidal terms in
/// SI. The dither is not an IEEE-952 term (its AVAR, 4 A^2 sin^4(pi f tau) / tau^2, is not in the
/// truth). O(segments + terms); allocates the terms' lists.
Ieee952Truth ieee952_truth(const SimOptions& o);

/// The human-readable first header line ("# gyrochar-sim counts: tau0 0.01 s, ..."), no newline.
std::string format_sim_description_line(const SimOptions& o);
/// The machine-readable truth line ("# gyrochar-sim truth: format=1 ..."), no newline. Allocates.
std::string format_sim_truth_line(const SimOptions& o);

/// Reads a truth line (trailing blanks, '\r' or '\n' allowed). Nothing when the line is not one:
/// wrong prefix, a token without '=', a repeated key, a value that is not a complete number of its
/// kind (or not finite), a missing key, format other than 1 (2 with segments), a Gauss-Markov or
/// sinusoid key without its count or beyond it, a term missing one of its two keys, or parameters
/// check_parameters refuses. O(line length); allocates nothing beyond the result.
std::optional<SimTruth> parse_sim_truth_line(std::string_view line);

/// Reads one --segment argument, "T:NAME=VALUE[,NAME=VALUE...]" with T in seconds and NAME one of
/// rate (deg/h), white-angle (arcsec), arw (deg/sqrt(h)), rrw (deg/h/sqrt(h)). Nothing, with `why`,
/// when it is not one. O(text length).
std::optional<SimSegment> parse_segment_option(std::string_view text, std::string& why);

/// Reads one --markov argument, "SIGMA,TC" (deg/h, s). Nothing, with `why`, when it is not two
/// finite numbers; their ranges are check_parameters' business. O(text length).
std::optional<SimMarkov> parse_markov_option(std::string_view text, std::string& why);

/// Reads one --sinusoid argument, "AMP,FREQ" (deg/h, Hz), as parse_markov_option does.
std::optional<SimSinusoid> parse_sinusoid_option(std::string_view text, std::string& why);

/// A simulated run as gyrochar-sim makes it: the simulator with the options' segments applied at
/// their samples. Reproducible from the options alone.
class SimRun {
 public:
  explicit SimRun(const SimOptions& o);
  /// Samples in the run: round(duration / tau0).
  std::uint64_t samples() const { return samples_; }
  /// Pulses in the next tau0 interval (segments switch before the interval they start). O(1)
  /// amortized, no allocation.
  std::int64_t next_count();

 private:
  SimOptions options_;
  GyroSimulator gyro_;
  std::uint64_t samples_ = 0, k_ = 0;
  std::size_t next_segment_ = 0;
};

}  // namespace gyrochar
