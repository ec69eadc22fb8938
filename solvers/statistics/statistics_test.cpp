#include "solvers/statistics/statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>
#include <vector>

namespace triadcal {
namespace {

// The DFT by its definition, O(N^2), with the angle reduced exactly (k n mod N).
std::vector<std::complex<double>> NaiveDft(const std::vector<double>& x) {
  const std::size_t N = x.size();
  const double pi = 3.14159265358979323846;
  std::vector<std::complex<double>> X(N);
  for (std::size_t k = 0; k < N; ++k) {
    for (std::size_t n = 0; n < N; ++n) {
      X[k] += x[n] * std::polar(1.0, -2.0 * pi * static_cast<double>((k * n) % N) / N);
    }
  }
  return X;
}

// Kiss FFT's own lengths (factors 2, 3, 5), prime lengths and lengths with a
// large prime factor (Bluestein), and the smallest ones: the definition.
TEST(Dft, IsTheDefinitionForAnyLength) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  for (std::size_t N : {1u, 2u, 3u, 7u, 240u, 997u, 1009u, 2 * 997u, 3 * 5 * 7 * 11u}) {
    std::vector<double> x(N);
    for (double& v : x) v = normal(rng);
    const std::vector<std::complex<double>> X = Dft(x), ref = NaiveDft(x);
    ASSERT_EQ(X.size(), N);
    double scale = 0.0, worst = 0.0;
    for (std::size_t k = 0; k < N; ++k) scale = std::max(scale, std::abs(ref[k]));
    for (std::size_t k = 0; k < N; ++k) worst = std::max(worst, std::abs(X[k] - ref[k]));
    EXPECT_LT(worst, 1e-11 * scale) << "N = " << N;
  }
  EXPECT_TRUE(Dft({}).empty());
}

// A sine on a bin of a prime-length series peaks there.
TEST(Dft, PeriodogramOfAPrimeLengthSinePeaksAtItsFrequency) {
  const std::size_t N = 14009;  // prime
  const double dt = 0.01, f = 123.0 / (N * dt);
  std::vector<double> x(N);
  for (std::size_t n = 0; n < N; ++n) x[n] = std::sin(2.0 * 3.14159265358979323846 * f * n * dt);
  EXPECT_NEAR(DominantFrequency(x, dt), f, 1e-12);
  const Spectrum s = Periodogram(x, dt);
  ASSERT_EQ(s.power.size(), N / 2 + 1);
  // All the power in one bin: N/4 for a unit sine (|X_k| = N/2).
  EXPECT_NEAR(s.power[123], N / 4.0, 1e-6 * N);
}

}  // namespace
}  // namespace triadcal
