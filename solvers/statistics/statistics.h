// Small statistics for residual diagnosis: chi-square tail probabilities, the
// Ljung-Box portmanteau test of whiteness, correlation, and the periodogram.
#pragma once

#include <complex>
#include <vector>

namespace triadcal {

// P(X > x) for X ~ chi-square with k degrees of freedom.
double ChiSquareSurvival(double x, double k);

// x with P(X > x) = p for X ~ chi-square with k degrees of freedom.
double ChiSquareUpperQuantile(double p, double k);

// P(F > f) for F ~ Fisher's F with d1 and d2 degrees of freedom.
double FSurvival(double f, double d1, double d2);

// P(W > w) for a Wald (or Hotelling) statistic W = v^T C^-1 v over k
// components whose covariance C is itself estimated with nu degrees of
// freedom: W (nu - k + 1) / (k nu) ~ F(k, nu - k + 1) (Hotelling's T^2). As
// nu grows it is ChiSquareSurvival(w, k); with nu <= k - 1 the estimate
// cannot test k components, and the p-value is 1.
double HotellingSurvival(double w, double k, double nu);

// P(X > x) for X ~ noncentral chi-square, k degrees of freedom, noncentrality
// lambda (the distribution of a test statistic when the tested effect is there).
double NoncentralChiSquareSurvival(double x, double k, double lambda);

// The noncentrality lambda0 at which a chi-square test with k degrees of
// freedom at level alpha detects with the given power (Baarda's lambda0:
// 17.08 for alpha 0.001, power 0.8, k 1).
double NoncentralityForPower(double alpha, double k, double power);

// Sample autocorrelation at lag (mean removed).
double Autocorrelation(const std::vector<double>& x, int lag);

// Ljung-Box: Q = N (N + 2) sum_{k=1..h} rho_k^2 / (N - k) ~ chi2(h) for white x.
struct WhitenessTest {
  int lags = 0;
  double q = 0.0;
  double p_value = 1.0;
  double rho1 = 0.0;           // lag-1 autocorrelation (its excess over expected_rho when given)
  double rho1_expected = 0.0;  // what the model leaves at lag 1 (subtracted from rho1)
};
// expected_rho (lags 1..), when given, is the autocorrelation the series has
// under the model even when the model holds (a least-squares fit's residuals
// are r = (I - H) w, so rho_k = -sum_t H(t, t+k) / sum_t (1 - H(t, t)) for
// smooth regressors, e.g. -0.05 at lag 1 for 9 parameters over 180 epochs):
// the test is on the excess, and rho1 is the excess at lag 1.
WhitenessTest LjungBox(const std::vector<double>& x, int lags,
                       const std::vector<double>* expected_rho = nullptr);

// Pearson correlation of two equally long series.
double Correlation(const std::vector<double>& a, const std::vector<double>& b);

// The discrete Fourier transform X_k = sum_n x_n exp(-2 pi i k n / N), k = 0
// .. N-1, in O(N log N) for any N (Bluestein's algorithm where N has a prime
// factor above 5).
std::vector<std::complex<double>> Dft(const std::vector<double>& x);

// One-sided periodogram of a uniformly sampled series (mean removed): power at
// frequencies k / (N dt), k = 0 .. N/2. Power is |X_k|^2 / N (same units^2).
struct Spectrum {
  std::vector<double> freq_hz, power;
};
Spectrum Periodogram(const std::vector<double>& x, double dt_s);

// Dominant frequency of a series (the periodogram peak above 0 Hz) [Hz].
double DominantFrequency(const std::vector<double>& x, double dt_s);

}  // namespace triadcal
