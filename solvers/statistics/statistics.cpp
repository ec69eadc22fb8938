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

namespace {

// The largest prime factor of n (n >= 1).
std::size_t LargestPrimeFactor(std::size_t n) {
  std::size_t largest = 1;
  for (std::size_t p = 2; p * p <= n; ++p) {
    while (n % p == 0) {
      largest = p;
      n /= p;
    }
  }
  return std::max(largest, n);
}

}  // namespace

std::vector<std::complex<double>> Dft(const std::vector<double>& x) {
  const std::size_t N = x.size();
  std::vector<std::complex<double>> X;
  Eigen::FFT<double> fft;
  // Kiss FFT's radices are 2, 3, 4 and 5; any other prime factor p of N takes
  // O(N p) (the gyro's residual series of the real fast roll run, 14000
  // intervals with a prime factor of some thousands: 2 s of a 10-s fit).
  if (N <= 1) return std::vector<std::complex<double>>(x.begin(), x.end());
  if (LargestPrimeFactor(N) <= 5) {
    fft.fwd(X, x);
    return X;
  }
  // Bluestein: X_k = w_k sum_n (x_n w_n) conj(w_{k-n}), w_n = exp(-i pi n^2 / N),
  // a circular convolution of length M >= 2N - 1 (a power of 2) by three FFTs.
  std::size_t M = 1;
  while (M < 2 * N - 1) M *= 2;
  const double pi = 3.14159265358979323846;
  std::vector<std::complex<double>> w(N), a(M), b(M);
  for (std::size_t n = 0; n < N; ++n) {
    // n^2 mod 2N keeps the angle exact for long series.
    const std::size_t q = static_cast<std::size_t>((static_cast<unsigned long long>(n) * n) %
                                                   (2ULL * N));
    w[n] = std::polar(1.0, -pi * static_cast<double>(q) / static_cast<double>(N));
    a[n] = x[n] * w[n];
    b[n] = std::conj(w[n]);
    if (n > 0) b[M - n] = b[n];
  }
  std::vector<std::complex<double>> A, B, c;
  fft.fwd(A, a);
  fft.fwd(B, b);
  for (std::size_t k = 0; k < M; ++k) A[k] *= B[k];
  fft.inv(c, A);  // scaled by 1 / M
  X.resize(N);
  for (std::size_t k = 0; k < N; ++k) X[k] = w[k] * c[k];
  return X;
}

Spectrum Periodogram(const std::vector<double>& x, double dt_s) {
  const std::vector<double> c = Centered(x);
  const std::vector<std::complex<double>> X = Dft(c);
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
