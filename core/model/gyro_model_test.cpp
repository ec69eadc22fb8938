// Tests of the gyro's physics (core/model/gyro_model.h): the readings model
// against its exact inverse at random parameters, the input rate's magnitude
// against the bench's two angle rates (what the input check of the gyro's unit
// relies on), and Earth's rate on a still bench.
#include "core/model/gyro_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace triadcal {
namespace {

// A layout with the gyro block (after two effects, so its offset is not the
// base size) and random parameters: scale factors 0.5 to 1.5 of either sign,
// biases of 10 deg/s, angles of 3 deg and g-sensitivities of 1 (deg/s)/g.
struct GyroSetup {
  ModelConfig cfg;
  Eigen::VectorXd theta;
};

GyroSetup RandomGyro(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  GyroSetup s;
  s.cfg.layout = ParameterLayout({Effect::kAngleLatency, Effect::kEncoderHarmonic}, true);
  s.theta = Eigen::VectorXd::Zero(s.cfg.layout.size());
  s.theta[kDlambda2] = 30 * kArcminToRad * n(rng);
  const int o = s.cfg.layout.gyro_offset();
  for (int i = 0; i < 3; ++i) s.theta[o + kGKx + i] = (n(rng) < 0 ? -1.0 : 1.0) * u(rng);
  for (int i = 0; i < 3; ++i) s.theta[o + kGW0x + i] = 10.0 * kDegToRad * n(rng);
  for (int i = kGAlphaX; i <= kGGammaZ; ++i) s.theta[o + i] = 3.0 * kDegToRad * n(rng);
  for (int i = kGGxx; i <= kGGzz; ++i) s.theta[o + i] = 1.0 * kDegToRad * n(rng);
  return s;
}

TEST(GyroModel, RateFromReadingsInvertsReadingsAtRandomParameters) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const GyroSetup s = RandomGyro(rng);
    const Eigen::Vector3d w_2(300 * kDegToRad * n(rng), 300 * kDegToRad * n(rng),
                              300 * kDegToRad * n(rng));  // rad/s
    const Eigen::Vector3d W_g(n(rng), n(rng), n(rng));
    const Eigen::Vector3d g = GyroReadings(s.cfg, s.theta.data(), w_2, W_g);
    const Eigen::Vector3d back = GyroRateFromReadings(s.cfg, s.theta.data(), g, W_g);
    EXPECT_LT((back - w_2).cwiseAbs().maxCoeff(), 1e-12) << trial;
    // ... and the other way round.
    const Eigen::Vector3d again = GyroReadings(
        s.cfg, s.theta.data(), GyroRateFromReadings(s.cfg, s.theta.data(), g, W_g), W_g);
    EXPECT_LT((again - g).cwiseAbs().maxCoeff(), 1e-12) << trial;
  }
}

// The gyro-stage effects (scale asymmetry up to 3 % of |K|, k2 up to 0.05 of
// scale at 1000 deg/s, either sign): the inverse's Newton steps reach the
// forward model's input rate to rounding, both ways, on both signs of every
// axis's rate.
TEST(GyroModel, RateFromReadingsInvertsReadingsWithGyroEffects) {
  std::mt19937_64 rng(12);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    GyroSetup s = RandomGyro(rng);
    s.cfg.layout = ParameterLayout({Effect::kAngleLatency, Effect::kGyroScaleAsymmetry,
                                    Effect::kEncoderHarmonic, Effect::kGyroNonlinearity},
                                   true);
    const Eigen::VectorXd g_block = s.theta.tail(kNumGyroParams);
    s.theta = Eigen::VectorXd::Zero(s.cfg.layout.size());
    s.theta.tail(kNumGyroParams) = g_block;
    const int o_a = s.cfg.layout.offset(Effect::kGyroScaleAsymmetry);
    const int o_q = s.cfg.layout.offset(Effect::kGyroNonlinearity);
    const double m_max = 1000 * kDegToRad;
    for (int i = 0; i < 3; ++i) {
      s.theta[o_a + i] = 0.03 * std::abs(g_block[kGKx + i]) * u(rng);
      s.theta[o_q + i] = 0.05 / (m_max * m_max) * u(rng);
    }
    const Eigen::Vector3d w_2(300 * kDegToRad * n(rng), 300 * kDegToRad * n(rng),
                              300 * kDegToRad * n(rng));  // rad/s
    const Eigen::Vector3d W_g(n(rng), n(rng), n(rng));
    const Eigen::Vector3d g = GyroReadings(s.cfg, s.theta.data(), w_2, W_g);
    const Eigen::Vector3d back = GyroRateFromReadings(s.cfg, s.theta.data(), g, W_g);
    EXPECT_LT((back - w_2).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, w_2.norm())) << trial;
    const Eigen::Vector3d again = GyroReadings(
        s.cfg, s.theta.data(), GyroRateFromReadings(s.cfg, s.theta.data(), g, W_g), W_g);
    EXPECT_LT((again - g).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, g.norm())) << trial;
  }
}

// Each effect alone, at one axis: the scale is K + dK for a positive rate and
// K - dK for a negative one; with k2 it is K (1 + k2 m^2).
TEST(GyroModel, GyroEffectsGiveTheirScales) {
  ModelConfig cfg;
  cfg.layout = ParameterLayout({Effect::kGyroScaleAsymmetry, Effect::kGyroNonlinearity}, true);
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  const int go = cfg.layout.gyro_offset();
  for (int i = 0; i < 3; ++i) th[go + kGKx + i] = 1.0;
  SetFromFileUnits(cfg.layout,
                   {{"gyro_scale_asymmetry.dKx", 2000.0}, {"gyro_nonlinearity.k2_y", 0.01}}, &th);
  const Eigen::Vector3d W = Eigen::Vector3d::Zero();
  const double r = 100 * kDegToRad;
  EXPECT_NEAR(GyroReadings<double>(cfg, th.data(), Eigen::Vector3d(r, 0, 0), W).x() / r, 1.002,
              1e-12);
  EXPECT_NEAR(GyroReadings<double>(cfg, th.data(), Eigen::Vector3d(-r, 0, 0), W).x() / -r, 0.998,
              1e-12);
  EXPECT_NEAR(GyroReadings<double>(cfg, th.data(), Eigen::Vector3d(0, -r, 0), W).y() / -r,
              1.0 + 0.01e-6 * 100 * 100, 1e-12);
}

// With a nominal gyro (scale 1, nothing else) and no Earth's rate the
// readings are the input rate, whose magnitude is sqrt(lambda1'^2 +
// lambda2'^2) and whose x component is lambda2', whatever the angles.
TEST(GyroModel, NominalReadingsAreTheBenchRates) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  ModelConfig cfg;
  cfg.layout = ParameterLayout({}, true);
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(cfg.layout.size());
  for (int i = 0; i < 3; ++i) theta[cfg.layout.gyro_offset() + kGKx + i] = 1.0;
  for (int trial = 0; trial < 50; ++trial) {
    theta[kDlambda2] = 30 * kArcminToRad * n(rng);
    BenchAngles<double> b;
    for (int i = 0; i < 2; ++i) {
      b.axis[i].angle = 3.0 * n(rng);
      b.axis[i].rate = n(rng);
      b.axis[i].accel = n(rng);
    }
    const Eigen::Vector3d g = PredictGyroReadings(cfg, theta.data(), b);
    EXPECT_NEAR(g.norm(), std::hypot(b.axis[0].rate, b.axis[1].rate), 1e-14) << trial;
    EXPECT_NEAR(g.x(), b.axis[1].rate, 1e-15) << trial;
  }
}

// A still bench reads Earth's rate, 7.292115e-5 rad/s, whatever its angles
// and heading; its component along L's x (up) is Omega_E sin(latitude).
TEST(GyroModel, StillBenchReadsEarthsRate) {
  ModelConfig cfg;
  cfg.layout = ParameterLayout({}, true);
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(cfg.layout.size());
  for (int i = 0; i < 3; ++i) theta[cfg.layout.gyro_offset() + kGKx + i] = 1.0;
  for (double lat_deg : {-60.0, 0.0, 48.15, 90.0}) {
    for (double heading_deg : {0.0, 37.0, -120.0}) {
      cfg.earth_rate_L = EarthRateInL(lat_deg * kDegToRad, heading_deg * kDegToRad);
      EXPECT_NEAR(cfg.earth_rate_L.x(), kEarthRate_rad_s * std::sin(lat_deg * kDegToRad), 1e-20);
      BenchAngles<double> b;
      b.axis[0].angle = 0.7;
      b.axis[1].angle = -2.1;
      const Eigen::Vector3d g = PredictGyroReadings(cfg, theta.data(), b);
      EXPECT_NEAR(g.norm(), kEarthRate_rad_s, 1e-18) << lat_deg << " " << heading_deg;
    }
  }
}

}  // namespace
}  // namespace triadcal
