// Greenhall & Riley (2003) EDF: the generalized autocovariance sw of the phase noise (eq. 7), the
// filters sx (eq. 8) and sz (eq. 9), the BasicSum (eq. 10), and the large-M approximations with
// the paper's Tables 1-3 (coefficients as published in the paper and NIST SP 1065).
#include "gyrochar/greenhall_edf.hpp"

#include <cmath>
#include <limits>

namespace gyrochar {
namespace {

constexpr double infinity = std::numeric_limits<double>::infinity();
constexpr double j_max = 100.0;

// sw(t) for alpha = 2 .. -4 (log terms vanish at t = 0).
double sw(double t, int alpha) {
  const double a = std::fabs(t);
  switch (alpha) {
    case 2: return -a;
    case 1: return t == 0 ? 0.0 : t * t * std::log(a);
    case 0: return a * a * a;
    case -1: return t == 0 ? 0.0 : std::pow(t, 4) * std::log(a);
    case -2: return std::pow(a, 5);
    case -3: return t == 0 ? 0.0 : std::pow(t, 6) * std::log(a);
    case -4: return std::pow(a, 7);
    default: return 0.0;
  }
}

// sx: the averaging filter of length 1/F (F = infinity: no averaging, sw of alpha + 2).
double sx(double t, double F, int alpha) {
  if (std::isinf(F)) return sw(t, alpha + 2);
  return F * F * (2.0 * sw(t, alpha) - sw(t - 1.0 / F, alpha) - sw(t + 1.0 / F, alpha));
}

// sz: the d-th difference filter (binomial coefficients with alternating signs).
double sz(double t, double F, int alpha, int d) {
  static constexpr double c2[] = {6, -4, 1};
  static constexpr double c3[] = {20, -15, 6, -1};
  const double* c = d == 2 ? c2 : c3;
  double s = c[0] * sx(t, F, alpha);
  for (int k = 1; k <= d; ++k) s += c[k] * (sx(t - k, F, alpha) + sx(t + k, F, alpha));
  return s;
}

double basic_sum(double J, double M, double S, double F, int alpha, int d) {
  const double z0 = sz(0, F, alpha, d);
  double sum = z0 * z0;
  const double zj = sz(J / S, F, alpha, d);
  sum += (1.0 - J / M) * zj * zj;
  for (double j = 1; j < J; j += 1) {
    const double z = sz(j / S, F, alpha, d);
    sum += 2.0 * (1.0 - j / M) * z * z;
  }
  return sum;
}

struct Coefficients {
  double a0, a1;
};
// Table 1 (modified variances) and Table 2 (unmodified), rows alpha = 2 .. -4, columns d = 1 .. 3;
// {0, 0} where alpha + 2d <= 1.
constexpr Coefficients table1[7][3] = {
    {{2.0 / 3, 1.0 / 3}, {7.0 / 9, 1.0 / 2}, {22.0 / 25, 2.0 / 3}},
    {{0.840, 0.345}, {0.997, 0.616}, {1.141, 0.843}},
    {{1.079, 0.368}, {1.033, 0.607}, {1.184, 0.848}},
    {{0, 0}, {1.048, 0.534}, {1.180, 0.816}},
    {{0, 0}, {1.302, 0.535}, {1.175, 0.777}},
    {{0, 0}, {0, 0}, {1.194, 0.703}},
    {{0, 0}, {0, 0}, {1.489, 0.702}},
};
constexpr Coefficients table2[7][3] = {
    {{3.0 / 2, 1.0 / 2}, {35.0 / 18, 1.0}, {231.0 / 100, 3.0 / 2}},
    {{78.6, 25.2}, {790.0, 410.0}, {9950.0, 6520.0}},
    {{2.0 / 3, 1.0 / 6}, {2.0 / 3, 1.0 / 3}, {7.0 / 9, 1.0 / 2}},
    {{0, 0}, {0.852, 0.375}, {0.997, 0.617}},
    {{0, 0}, {1.079, 0.368}, {1.033, 0.607}},
    {{0, 0}, {0, 0}, {1.053, 0.553}},
    {{0, 0}, {0, 0}, {1.302, 0.535}},
};
// Table 3 (unmodified, flicker PM): sz(0) ~ b0 + b1 ln m, columns d = 1 .. 3.
constexpr Coefficients table3[3] = {{6.0, 4.0}, {15.23, 12.0}, {47.8, 40.0}};

double binomial(int n, int k) {
  double r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

}  // namespace

double edf_basic_sum_inverse(int alpha, int d, double m, double F, double S, double N) {
  const double L = m / F + m * d;
  if (N < L) return 0.0;
  const double M = 1 + std::floor(S * (N - L) / m);
  const double J = std::fmin(M, (d + 1) * S);
  const double z0 = sz(0, F, alpha, d);
  return basic_sum(J, M, S, F, alpha, d) / (z0 * z0 * M);
}

double edf_greenhall(const EdfQuery& q) {
  const int alpha = q.alpha, d = q.d;
  if ((d != 2 && d != 3) || alpha > 2 || alpha < -4 || alpha + 2 * d <= 1) return 0.0;
  const double m = q.m, S = q.S, N = q.N;
  const double F = q.modified ? 1.0 : m;
  if (!(m >= 1) || !(S >= 1) || !(S <= m) || !(N >= 0)) return 0.0;
  const double L = m / F + m * d;
  if (N < L) return 0.0;
  const double M = 1 + std::floor(S * (N - L) / m);
  const double J = std::fmin(M, (d + 1) * S);
  const double r = M / S;
  const Coefficients t1 = table1[2 - alpha][d - 1];
  const Coefficients t2 = table2[2 - alpha][d - 1];
  double inverse = 0.0;
  if (q.modified) {  // case 1: modified variances, any alpha
    if (J <= j_max) {
      const double z0 = sz(0, 1, alpha, d);
      inverse = basic_sum(J, M, S, 1, alpha, d) / (z0 * z0 * M);
    } else if (r > d + 1) {
      inverse = (t1.a0 - t1.a1 / r) / r;
    } else {
      const double z0 = sz(0, 1, alpha, d);
      inverse = basic_sum(j_max, j_max, j_max / r, 1, alpha, d) / (z0 * z0 * j_max);
    }
  } else if (alpha <= 0) {  // case 2: unmodified, alpha <= 0
    if (J <= j_max) {
      const double Fp = m * (d + 1) <= j_max ? m : infinity;
      const double z0 = sz(0, Fp, alpha, d);
      inverse = basic_sum(J, M, S, Fp, alpha, d) / (z0 * z0 * M);
    } else if (r > d + 1) {
      inverse = (t2.a0 - t2.a1 / r) / r;
    } else {
      const double z0 = sz(0, infinity, alpha, d);
      inverse = basic_sum(j_max, j_max, j_max / r, infinity, alpha, d) / (z0 * z0 * j_max);
    }
  } else if (alpha == 1) {  // case 3: unmodified, flicker PM
    const Coefficients t3 = table3[d - 1];
    if (J <= j_max) {
      const double z0 = sz(0, m, 1, d);
      inverse = basic_sum(J, M, S, m, 1, d) / (z0 * z0 * M);
    } else if (r > d + 1) {
      const double b = t3.a0 + t3.a1 * std::log(m);
      inverse = (t2.a0 - t2.a1 / r) / (b * b * r);
    } else {
      const double b = t3.a0 + t3.a1 * std::log(m);
      const double mp = j_max / r;
      inverse = basic_sum(j_max, j_max, mp, mp, 1, d) / (b * b * j_max);
    }
  } else {  // case 4: unmodified, white PM
    if (std::ceil(r) > d) {
      inverse = (binomial(4 * d, 2 * d) / (binomial(2 * d, d) * binomial(2 * d, d)) - (d / 2.0) / r) / M;
    } else {  // few terms: the BasicSum itself (J <= (d+1) S is small here)
      const double z0 = sz(0, m, 2, d);
      inverse = basic_sum(J, M, S, m, 2, d) / (z0 * z0 * M);
    }
  }
  return inverse > 0 ? 1.0 / inverse : 0.0;
}

}  // namespace gyrochar
