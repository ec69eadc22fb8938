// The analytic Jacobian of block B1 against automatic differentiation of the
// templated model and against central differences.
#include <random>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "core/model/b1_jacobian.h"

namespace triadcal {
namespace {

TEST(B1Jacobian, AnalyticMatchesAutomaticAndNumeric) {
  constexpr int N = 40;
  using J = ceres::Jet<double, N>;
  std::mt19937_64 rng(17);
  std::normal_distribution<double> nrm(0.0, 1.0);
  for (const bool effects : {false, true}) {
    ModelConfig cfg;
    if (effects) {
      cfg.layout = ParameterLayout(
          {Effect::kThermalDrift, Effect::kAxisNonintersection, Effect::kThermalDriftTemp});
    }
    cfg.temp_ref_C = 20.0;
    ASSERT_TRUE(B1HasAnalyticJacobian(cfg.layout));
    const int n = cfg.layout.size();
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::VectorXd th = Eigen::VectorXd::Zero(n);
      for (int i = 0; i < 3; ++i) th[kKx + i] = 174 + 5 * nrm(rng);
      for (int i = 0; i < 3; ++i) th[kW0x + i] = 1500 + 20 * nrm(rng);
      for (int i = kAlphaX; i <= kGammaZ; ++i) th[i] = 0.02 * nrm(rng);
      for (int i = kKxx; i <= kKzz; ++i) th[i] = 0.005 * nrm(rng);
      for (int i = kDpsi; i <= kDlambda2; ++i) th[i] = 0.02 * nrm(rng);
      for (int i = kNumBaseParams; i < n; ++i) th[i] = 0.1 * nrm(rng);
      BenchAngles<double> rec;
      rec.axis[0].angle = 3 * nrm(rng);
      rec.axis[1].angle = 2 * nrm(rng);
      const Eigen::Vector3d z(1500 + 150 * nrm(rng), 1500 + 150 * nrm(rng), 1500 + 150 * nrm(rng));
      const SampleContext ctx{40.0 * std::abs(nrm(rng)), 20 + 5 * nrm(rng)};

      Eigen::Vector3d a;
      Eigen::MatrixXd Ja(3, n);
      AccelerationWithJacobian(cfg, th.data(), rec, z, ctx, &a, Ja);

      std::vector<J> thj(N);
      for (int i = 0; i < N; ++i) thj[i] = J(i < n ? th[i] : 0.0, i);
      const Vec3<J> aj = AccelerationFromReadings_L<J>(cfg, thj.data(), rec, z, ctx);
      for (int r = 0; r < 3; ++r) {
        EXPECT_NEAR(a[r], aj[r].a, 1e-12);
        for (int c = 0; c < n; ++c) {
          EXPECT_NEAR(Ja(r, c), aj[r].v[c], 1e-9 * (1 + std::abs(aj[r].v[c])))
              << cfg.layout.info(c).name;
        }
      }
      for (int c = 0; c < n; ++c) {
        const double h = 1e-6 * std::max(1.0, std::abs(th[c]));
        Eigen::VectorXd tp = th, tm = th;
        tp[c] += h;
        tm[c] -= h;
        const Eigen::Vector3d d =
            (AccelerationFromReadings_L<double>(cfg, tp.data(), rec, z, ctx) -
             AccelerationFromReadings_L<double>(cfg, tm.data(), rec, z, ctx)) /
            (2 * h);
        EXPECT_LT((d - Ja.col(c)).norm(), 1e-6 * (1 + d.norm())) << cfg.layout.info(c).name;
      }
    }
  }
}

TEST(B1Jacobian, EffectsOnTheAngleOrSensorStageUseJets) {
  EXPECT_FALSE(B1HasAnalyticJacobian(ParameterLayout({Effect::kAngleLatency})));
  EXPECT_FALSE(B1HasAnalyticJacobian(ParameterLayout({Effect::kSizeEffect})));
  EXPECT_FALSE(B1HasAnalyticJacobian(ParameterLayout({Effect::kScaleAsymmetry})));
  EXPECT_TRUE(B1HasAnalyticJacobian(ParameterLayout()));
}

}  // namespace
}  // namespace triadcal
