// The local polynomial fit of the bench angles' derivatives: exact on
// polynomials it can represent (cubic angles, quadratic rates), at every
// sample including the run's ends and irregular time stamps; and the noise
// gain RateNoiseGain states against the fit's own weights.
#include "core/model/angle_derivatives.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "core/model/errors.h"

namespace triadcal {
namespace {

// Time stamps at about rate_hz with jitter and a gap, as real recorders give.
RunData IrregularRun(double rate_hz, double span_s, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  RunData d;
  const double dt = 1.0 / rate_hz;
  for (double t = 0.0; t <= span_s; t += dt) {
    if (t > 0.4 * span_s && t < 0.4 * span_s + 3 * dt) continue;  // a gap
    d.t_s.push_back(t + jitter(rng) * dt);
  }
  return d;
}

TEST(AngleDerivatives, CubicAnglesAreDifferentiatedExactlyAtEverySample) {
  RunData d = IrregularRun(200.0, 3.0, 5);
  // lambda_i(t) = a + b t + c t^2 + e t^3
  const double co[2][4] = {{0.3, -1.2, 0.8, -0.25}, {-0.1, 0.7, -0.4, 0.15}};
  for (int i = 0; i < 2; ++i) {
    for (double t : d.t_s) {
      d.lambda_rad[i].push_back(co[i][0] + t * (co[i][1] + t * (co[i][2] + t * co[i][3])));
    }
  }
  for (double h : {0.02, 0.1, 0.5}) {
    const std::vector<BenchAngles<double>> b = EstimateAngleDerivatives(d, {h});
    ASSERT_EQ(b.size(), d.size());
    for (std::size_t k = 0; k < d.size(); ++k) {
      const double t = d.t_s[k];
      for (int i = 0; i < 2; ++i) {
        const double rate = co[i][1] + t * (2 * co[i][2] + 3 * t * co[i][3]);
        const double accel = 2 * co[i][2] + 6 * t * co[i][3];
        EXPECT_EQ(b[k].axis[i].angle, d.lambda_rad[i][k]);
        EXPECT_NEAR(b[k].axis[i].rate, rate, 1e-8) << "h " << h << " k " << k;
        EXPECT_NEAR(b[k].axis[i].accel, accel, 1e-6) << "h " << h << " k " << k;
      }
    }
  }
}

TEST(AngleDerivativesWithRates, RecordedRatesAreKeptAndQuadraticRatesDifferentiatedExactly) {
  RunData d = IrregularRun(100.0, 2.0, 9);
  const double co[2][3] = {{0.5, -0.9, 0.35}, {-1.5, 0.2, -0.6}};
  for (int i = 0; i < 2; ++i) {
    for (double t : d.t_s) {
      d.lambda_rad[i].push_back(std::sin(t + i));  // not used for the derivatives
      d.rate_rad_s[i].push_back(co[i][0] + t * (co[i][1] + t * co[i][2]));
    }
  }
  const std::vector<BenchAngles<double>> b = EstimateAngleDerivatives(d, {0.1});
  for (std::size_t k = 0; k < d.size(); ++k) {
    for (int i = 0; i < 2; ++i) {
      EXPECT_EQ(b[k].axis[i].rate, d.rate_rad_s[i][k]);
      EXPECT_NEAR(b[k].axis[i].accel, co[i][1] + 2 * co[i][2] * d.t_s[k], 1e-8) << k;
    }
  }
}

TEST(AngleDerivatives, AtTheListedSamplesOnly) {
  RunData d = IrregularRun(100.0, 1.0, 3);
  for (int i = 0; i < 2; ++i) {
    for (double t : d.t_s) d.lambda_rad[i].push_back(0.4 * t * t);
  }
  const std::vector<std::size_t> only = {0, 17, d.size() - 1};
  const std::vector<BenchAngles<double>> b = EstimateAngleDerivativesAt(d, {0.1}, only);
  const std::vector<BenchAngles<double>> every = EstimateAngleDerivatives(d, {0.1});
  ASSERT_EQ(b.size(), only.size());
  for (std::size_t j = 0; j < only.size(); ++j) {
    const std::size_t k = only[j];
    EXPECT_NEAR(b[j].axis[0].rate, 0.8 * d.t_s[k], 1e-9) << k;
    EXPECT_NEAR(b[j].axis[1].accel, 0.8, 1e-7) << k;
    for (int i = 0; i < 2; ++i) {  // the same numbers as at every sample
      EXPECT_EQ(b[j].axis[i].angle, every[k].axis[i].angle) << k;
      EXPECT_EQ(b[j].axis[i].rate, every[k].axis[i].rate) << k;
      EXPECT_EQ(b[j].axis[i].accel, every[k].axis[i].accel) << k;
    }
  }
}

TEST(AngleDerivatives, RateNoiseGainMatchesTheScatterOfTheEstimatedRate) {
  // Uniform 100 Hz, white angle noise of 1e-4 rad on a still bench: the rate's
  // scatter at interior samples is RateNoiseGain x the angle noise.
  const double dt = 0.01, sigma = 1e-4;
  RunData d;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> nrm(0.0, sigma);
  for (int k = 0; k < 20000; ++k) {
    d.t_s.push_back(k * dt);
    for (int i = 0; i < 2; ++i) d.lambda_rad[i].push_back(nrm(rng));
  }
  const AngleDerivativeOptions opt{0.1};
  const std::vector<BenchAngles<double>> b = EstimateAngleDerivatives(d, opt);
  double sum2 = 0.0;
  int n = 0;
  for (std::size_t k = 100; k + 100 < d.size(); k += 25) {  // nearly independent windows
    sum2 += b[k].axis[0].rate * b[k].axis[0].rate;
    ++n;
  }
  const double expected = RateNoiseGain(dt, opt) * sigma;
  // 795 samples: the scatter's own relative sampling error is about 2.5 %.
  EXPECT_NEAR(std::sqrt(sum2 / n) / expected, 1.0, 0.1);
}

// RateNoiseGain from one normal matrix equals |w| of the slope's weights
// computed the slow way: one least-squares cubic per unit vector.
TEST(AngleDerivatives, RateNoiseGainEqualsTheWeightsOfTheSlope) {
  for (const double dt : {0.01, 0.002, 0.05}) {
    for (const double h : {0.02, 0.1, 0.5}) {
      const int half = std::max(2, static_cast<int>(std::floor(h / dt + 1e-9)));
      const int n = 2 * half + 1;
      Eigen::MatrixXd P(n, 4);
      for (int j = 0; j < n; ++j) {
        const double s = (j - half) * dt / h;
        P.row(j) << 1.0, s, s * s, s * s * s;
      }
      double sum2 = 0.0;
      for (int j = 0; j < n; ++j) {
        const Eigen::VectorXd e = Eigen::VectorXd::Unit(n, j);
        const double w = P.colPivHouseholderQr().solve(e)[1] / h;
        sum2 += w * w;
      }
      EXPECT_NEAR(RateNoiseGain(dt, AngleDerivativeOptions{h}), std::sqrt(sum2),
                  1e-9 * std::sqrt(sum2))
          << dt << " " << h;
    }
  }
}

// A window of 0, NaN or 1e6 s is a setting error naming the field (it made the
// fit divide by zero, or span the whole run for every sample).
TEST(AngleDerivatives, WindowOutsideItsBoundsIsAnOptionError) {
  RunData d;
  for (int k = 0; k < 50; ++k) {
    d.t_s.push_back(0.01 * k);
    for (int i = 0; i < 2; ++i) d.lambda_rad[i].push_back(0.0);
  }
  for (const double h : {0.0, -0.1, std::nan(""), 1e6, HUGE_VAL}) {
    const AngleDerivativeOptions opt{h};
    try {
      EstimateAngleDerivatives(d, opt);
      ADD_FAILURE() << h;
    } catch (const OptionError& e) {
      EXPECT_EQ(e.option(), "half_window_s");
      EXPECT_NE(e.problem().find("is outside [0.001, 2] s"), std::string::npos) << e.problem();
    }
    EXPECT_THROW(RateNoiseGain(0.01, opt), OptionError) << h;
  }
  EXPECT_EQ(std::string(OptionError("half_window_s", "x").what()), "half_window_s: x");
  EXPECT_NO_THROW(EstimateAngleDerivatives(d, AngleDerivativeOptions{0.001}));
  EXPECT_NO_THROW(EstimateAngleDerivatives(d, AngleDerivativeOptions{2.0}));
}

}  // namespace
}  // namespace triadcal
