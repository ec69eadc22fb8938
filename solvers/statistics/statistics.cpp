#include "solvers/statistics/statistics.h"

#include <unsupported/Eigen/FFT>
#include <unsupported/Eigen/SpecialFunctions>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numeric>

namespace triadcal {

double ChiSquareSurvival(double x, double k) {
  if (!(x > 0.0)) return 1.0;
  return Eigen::numext::igammac(0.5 * k, 0.5 * x);
}

double ChiSquareUpperQuantile(double p, double k) {
  // Bisection on the survival function (monotone in x); 200 halvings reach
  // double precision from any bracket below.
  double lo = 0.0, hi = k + 10.0;
  while (ChiSquareSurvival(hi, k) > p) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ChiSquareSurvival(mid, k) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double FSurvival(double f, double d1, double d2) {
  if (!(f > 0.0)) return 1.0;
  return Eigen::numext::betainc(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f));
}

double HotellingSurvival(double w, double k, double nu) {
  if (!std::isfinite(nu)) return ChiSquareSurvival(w, k);
  if (!(nu > k - 1.0)) return 1.0;
  return FSurvival(w * (nu - k + 1.0) / (k * nu), k, nu - k + 1.0);
}

double NoncentralChiSquareSurvival(double x, double k, double lambda) {
  // Poisson mixture of central chi-squares: sum_j Pois(j; lambda/2) Q(x; k + 2j).
  if (lambda <= 0.0) return ChiSquareSurvival(x, k);
  const double m = 0.5 * lambda;
  const int j_max = static_cast<int>(m + 12.0 * std::sqrt(m) + 40.0);
  double sum = 0.0;
  for (int j = 0; j <= j_max; ++j) {
    const double log_pois = -m + j * std::log(m) - std::lgamma(j + 1.0);
    sum += std::exp(log_pois) * ChiSquareSurvival(x, k + 2.0 * j);
  }
  return std::min(1.0, sum);
}

double NoncentralityForPower(double alpha, double k, double power) {
  const double crit = ChiSquareUpperQuantile(alpha, k);
  double lo = 0.0, hi = 1.0;
  while (NoncentralChiSquareSurvival(crit, k, hi) < power) hi *= 2.0;
  for (int i = 0; i < 100 && hi - lo > 1e-9 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (NoncentralChiSquareSurvival(crit, k, mid) < power ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {
std::vector<double> Centered(const std::vector<double>& x) {
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / std::max<std::size_t>(1, x.size());
  std::vector<double> c(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) c[i] = x[i] - mean;
  return c;
}
}  // namespace

double Autocorrelation(const std::vector<double>& x, int lag) {
  const std::vector<double> c = Centered(x);
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < c.size(); ++i) den += c[i] * c[i];
  for (std::size_t i = static_cast<std::size_t>(lag); i < c.size(); ++i) num += c[i] * c[i - lag];
  return den > 0.0 ? num / den : 0.0;
}

WhitenessTest LjungBox(const std::vector<double>& x, int lags,
                       const std::vector<double>* expected_rho) {
  WhitenessTest t;
  const double N = static_cast<double>(x.size());
  t.lags = std::max(1, std::min(lags, static_cast<int>(x.size()) / 4));
  for (int k = 1; k <= t.lags; ++k) {
    double r = Autocorrelation(x, k);
    const double expected =
        expected_rho && static_cast<int>(expected_rho->size()) >= k ? (*expected_rho)[k - 1] : 0.0;
    r -= expected;
    if (k == 1) {
      t.rho1 = r;
      t.rho1_expected = expected;
    }
    t.q += r * r / (N - k);
  }
  t.q *= N * (N + 2.0);
  t.p_value = ChiSquareSurvival(t.q, t.lags);
  return t;
}

double Correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::vector<double> ca = Centered(a), cb = Centered(b);
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (std::size_t i = 0; i < ca.size(); ++i) {
    ab += ca[i] * cb[i];
    aa += ca[i] * ca[i];
    bb += cb[i] * cb[i];
  }
  return aa > 0.0 && bb > 0.0 ? ab / std::sqrt(aa * bb) : 0.0;
}

Spectrum Periodogram(const std::vector<double>& x, double dt_s) {
  const std::vector<double> c = Centered(x);
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> X;
  fft.fwd(X, c);
  Spectrum s;
  const std::size_t N = c.size();
  for (std::size_t k = 0; k <= N / 2; ++k) {
    s.freq_hz.push_back(k / (N * dt_s));
    s.power.push_back(std::norm(X[k]) / N);
  }
  return s;
}

double DominantFrequency(const std::vector<double>& x, double dt_s) {
  const Spectrum s = Periodogram(x, dt_s);
  std::size_t best = 1;
  for (std::size_t k = 1; k < s.power.size(); ++k) {
    if (s.power[k] > s.power[best]) best = k;
  }
  return s.freq_hz.size() > 1 ? s.freq_hz[best] : 0.0;
}

}  // namespace triadcal
