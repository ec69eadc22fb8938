#include "core/model/sample_noise.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace triadcal {
namespace {

// White noise of 2 mV on a 1000-mV swing of 6 s sampled at 50 Hz, with a few
// spikes and a gap: the estimate is the noise, not the motion or the spikes.
TEST(SampleNoise, SecondDifferencesGiveTheWhiteNoiseWithoutAModel) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 2.0);
  std::vector<double> x;
  for (int k = 0; k < 20000; ++k) {
    const double t = (k < 10000 ? k : k + 7) / 50.0;  // a 7-sample gap
    x.push_back(1000.0 * std::sin(2.0 * M_PI * t / 6.0) + g(rng));
  }
  for (int k = 500; k < 20000; k += 2000) x[k] += 300.0;  // spikes
  EXPECT_NEAR(SecondDifferenceNoise(x), 2.0, 0.05);
  // Without the noise the motion alone reads as far below it.
  std::vector<double> clean;
  for (int k = 0; k < 20000; ++k) clean.push_back(1000.0 * std::sin(2.0 * M_PI * k / 50.0 / 6.0));
  EXPECT_LT(SecondDifferenceNoise(clean), 0.2);  // 1000 (2 pi dt / T)^2 / sqrt(12): 0.13
  EXPECT_EQ(SecondDifferenceNoise({1.0, 2.0}), 0.0);
}

}  // namespace
}  // namespace triadcal
