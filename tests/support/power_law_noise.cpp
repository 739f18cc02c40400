#include "power_law_noise.hpp"

#include <fftw3.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <complex>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>

namespace gyrochar::test_support {
namespace {

struct FftwFree {
  void operator()(void* p) const { fftw_free(p); }
};
using RealBuffer = std::unique_ptr<double[], FftwFree>;
using ComplexBuffer = std::unique_ptr<fftw_complex[], FftwFree>;

RealBuffer real_buffer(std::size_t n) {
  RealBuffer b(fftw_alloc_real(n));
  if (!b) throw std::bad_alloc();
  return b;
}
ComplexBuffer complex_buffer(std::size_t n) {
  ComplexBuffer b(fftw_alloc_complex(n));
  if (!b) throw std::bad_alloc();
  return b;
}

// One transform length: the forward and inverse real plans and the transform of the half
// integrator (1 - B)^(-1/2) truncated to the first half of the length. Made under the cache's lock,
// then only read: FFTW's new-array execute functions are thread-safe, its planner is not. The
// buffers passed to them come from fftw_alloc_*, so they have the alignment the plans assume.
struct Transform {
  std::size_t length = 0;  // real points, a power of two
  fftw_plan forward = nullptr;
  fftw_plan inverse = nullptr;
  ComplexBuffer half_integrator;  // length / 2 + 1 bins, scaled by 1 / length (FFTW is unnormalized)
};

class TransformCache {
 public:
  ~TransformCache() {
    for (auto& [length, t] : cache_) {
      fftw_destroy_plan(t->forward);
      fftw_destroy_plan(t->inverse);
    }
    cache_.clear();
    fftw_cleanup();
  }

  const Transform& get(std::size_t length) {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto& slot = cache_[length];
    if (!slot) slot = make(length);
    return *slot;
  }

 private:
  static std::unique_ptr<Transform> make(std::size_t length) {
    auto t = std::make_unique<Transform>();
    t->length = length;
    const std::size_t bins = length / 2 + 1;
    RealBuffer real = real_buffer(length);
    t->half_integrator = complex_buffer(bins);
    const int n = static_cast<int>(length);
    t->forward = fftw_plan_dft_r2c_1d(n, real.get(), t->half_integrator.get(), FFTW_ESTIMATE);
    t->inverse = fftw_plan_dft_c2r_1d(n, t->half_integrator.get(), real.get(), FFTW_ESTIMATE);
    if (!t->forward || !t->inverse) throw std::runtime_error("FFTW could not plan a transform of " + std::to_string(length));
    const std::vector<double> h = kasdin_response(0.5, length / 2);
    std::fill(real.get(), real.get() + length, 0.0);
    std::copy(h.begin(), h.end(), real.get());
    fftw_execute_dft_r2c(t->forward, real.get(), t->half_integrator.get());
    const double scale = 1.0 / static_cast<double>(length);
    for (std::size_t i = 0; i < bins; ++i) {
      t->half_integrator[i][0] *= scale;
      t->half_integrator[i][1] *= scale;
    }
    return t;
  }

  std::mutex mutex_;
  std::map<std::size_t, std::unique_ptr<Transform>> cache_;
};

TransformCache& transforms() {
  static TransformCache cache;
  return cache;
}

void cumulative_sum(std::vector<double>& v) {
  double s = 0.0;
  for (double& e : v) e = s += e;
}

// (2 - alpha) = 2 d, checked.
int twice_d(int alpha, int lowest_alpha) {
  if (alpha < lowest_alpha || alpha > 2)
    throw std::invalid_argument("power-law exponent alpha " + std::to_string(alpha) + " outside " +
                                std::to_string(lowest_alpha) + "..+2");
  return 2 - alpha;
}

// The D-th difference with lag m of the Kasdin response of order e, g_k = sum_i (-1)^i C(D, i)
// q_{k - i m}, summed in squares over k < terms. The D + 1 sequences q_{k - i m} run in lockstep
// by the recurrence, so nothing is stored.
double filter_square_sum(double e, int D, std::uint64_t m, std::uint64_t terms) {
  static constexpr double binomial[4][4] = {{1, 0, 0, 0}, {1, -1, 0, 0}, {1, -2, 1, 0}, {1, -3, 3, -1}};
  double q[4] = {0, 0, 0, 0};
  double sum = 0.0;
  for (std::uint64_t k = 0; k < terms; ++k) {
    double g = 0.0;
    for (int i = 0; i <= D; ++i) {
      const std::uint64_t lag = static_cast<std::uint64_t>(i) * m;
      if (k < lag) break;
      const std::uint64_t j = k - lag;
      q[i] = j == 0 ? 1.0 : q[i] * ((static_cast<double>(j) - 1.0 + e) / static_cast<double>(j));
      g += binomial[D][i] * q[i];
    }
    sum += g * g;
  }
  return sum;
}

struct FilterSpec {
  double e;     // order of the Kasdin response: d (AVAR) or d + 1 (MVAR, phase sums)
  int D;        // difference order: 2 (AVAR) or 3 (MVAR)
  double norm;  // 2 m^2 (AVAR) or 2 m^4 (MVAR)
};

FilterSpec filter_spec(int alpha, Variance v, std::uint64_t m) {
  if (m == 0) throw std::invalid_argument("averaging factor 0");
  const double d = twice_d(alpha, -2) / 2.0;
  const double mm = static_cast<double>(m);
  if (v == Variance::avar) return {d, 2, 2.0 * mm * mm};
  return {d + 1.0, 3, 2.0 * mm * mm * mm * mm};
}

}  // namespace

std::vector<double> kasdin_response(double d, std::size_t n) {
  std::vector<double> h(n);
  if (n == 0) return h;
  h[0] = 1.0;
  for (std::size_t k = 1; k < n; ++k) h[k] = h[k - 1] * ((static_cast<double>(k) - 1.0 + d) / static_cast<double>(k));
  return h;
}

std::size_t burn_in_length(std::size_t n) { return n; }

std::vector<double> power_law_phase(int alpha, std::size_t n, std::uint64_t seed) {
  const int two_d = twice_d(alpha, -4);
  const int sums = two_d / 2;
  const bool half = two_d % 2 != 0;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> x(n);
  if (!half) {
    for (double& v : x) v = normal(rng);
  } else if (n > 0) {
    // y = (1 - B)^(-1/2) w over burn-in + n points by linear convolution: with the transform
    // length at least twice the points, no output below `points` wraps around.
    const std::size_t points = burn_in_length(n) + n;
    const std::size_t length = std::bit_ceil(2 * points);
    const Transform& t = transforms().get(length);
    // Per-thread scratch, kept between calls: fresh multi-megabyte buffers cost more in page
    // faults than the transforms themselves.
    thread_local std::size_t scratch_length = 0;
    thread_local RealBuffer real;
    thread_local ComplexBuffer spectrum;
    if (scratch_length != length) {
      real = real_buffer(length);
      spectrum = complex_buffer(length / 2 + 1);
      scratch_length = length;
    }
    for (std::size_t i = 0; i < points; ++i) real[i] = normal(rng);
    std::fill(real.get() + points, real.get() + length, 0.0);
    fftw_execute_dft_r2c(t.forward, real.get(), spectrum.get());
    for (std::size_t i = 0; i < length / 2 + 1; ++i) {
      const std::complex<double> product = std::complex<double>(spectrum[i][0], spectrum[i][1]) *
                                           std::complex<double>(t.half_integrator[i][0], t.half_integrator[i][1]);
      spectrum[i][0] = product.real();
      spectrum[i][1] = product.imag();
    }
    fftw_execute_dft_c2r(t.inverse, spectrum.get(), real.get());
    std::copy(real.get() + (points - n), real.get() + points, x.begin());
  }
  for (int i = 0; i < sums; ++i) cumulative_sum(x);
  return x;
}

double expected_variance_partial(int alpha, Variance v, std::uint64_t m, std::uint64_t terms) {
  const FilterSpec f = filter_spec(alpha, v, m);
  return filter_square_sum(f.e, f.D, m, terms) / f.norm;
}

double expected_variance(int alpha, Variance v, std::uint64_t m) {
  const FilterSpec f = filter_spec(alpha, v, m);
  if (f.e == std::floor(f.e))  // finite support: g_k = 0 from k = D m + e on (e <= D)
    return filter_square_sum(f.e, f.D, m, static_cast<std::uint64_t>(f.D + 1) * m + 1) / f.norm;
  const std::uint64_t terms = 64 * m + 1024;
  const double sum = filter_square_sum(f.e, f.D, m, terms);
  // Tail k >= terms from g_k ~ m^D A (k - D m / 2 + e / 2)^p, A = (d-1)(d-2)/Gamma(d), p = d - 3: the
  // Kasdin coefficient is Gamma(k + e) / (Gamma(e) Gamma(k + 1)) = (k + e/2)^(e-1) / Gamma(e)
  // (1 + O(k^-2)), its D-th difference with lag m is m^D times the D-th derivative at the
  // middle of the span, and the sum over k >= K is the integral from K - 1/2 (midpoint rule).
  const double d = f.D == 2 ? f.e : f.e - 1.0;
  const double mm = static_cast<double>(m);
  const double A = (d - 1.0) * (d - 2.0) / std::tgamma(d);
  const double p = d - 3.0;
  const double X = static_cast<double>(terms) - 0.5 - f.D * mm / 2.0 + f.e / 2.0;
  const double tail = std::pow(mm, 2.0 * f.D) * A * A * std::pow(X, 2.0 * p + 1.0) / -(2.0 * p + 1.0);
  return (sum + tail) / f.norm;
}

}  // namespace gyrochar::test_support
