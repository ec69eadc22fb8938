// The analytic Jacobian of block B1 against automatic differentiation of the
// templated model and against central differences.
#include "core/model/b1_jacobian.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <functional>
#include <random>

namespace triadcal {
namespace {

// The sensor's and the bench's parameters drawn about a typical triad (174
// mV/g, 1500 mV), the effects' at twice their typical size where `away`,
// else at zero.
Eigen::VectorXd RandomTheta(const ParameterLayout& layout, std::mt19937_64& rng,
                            const std::function<bool(Effect)>& away) {
  std::normal_distribution<double> nrm(0.0, 1.0);
  Eigen::VectorXd th = Eigen::VectorXd::Zero(layout.size());
  for (int i = 0; i < 3; ++i) th[kKx + i] = 174 + 5 * nrm(rng);
  for (int i = 0; i < 3; ++i) th[kW0x + i] = 1500 + 20 * nrm(rng);
  for (int i = kAlphaX; i <= kGammaZ; ++i) th[i] = 0.02 * nrm(rng);
  for (int i = kKxx; i <= kKzz; ++i) th[i] = 0.005 * nrm(rng);
  for (int i = kDpsi; i <= kDlambda2; ++i) th[i] = 0.02 * nrm(rng);
  for (Effect e : layout.effects()) {
    const EffectSpec& spec = GetEffectSpec(e);
    for (std::size_t q = 0; q < spec.params.size(); ++q) {
      const ParamSpec& p = spec.params[q];
      const double size = p.typical * p.si_per_unit * (spec.scale_relative ? th[kKx] : 1.0);
      th[layout.offset(e) + q] = away(e) ? 2.0 * size * nrm(rng) : 0.0;
    }
  }
  return th;
}

// Each column of J (3 x layout.size()) against the central difference of f.
void ExpectCentralDifferences(const ParameterLayout& layout, const Eigen::VectorXd& th,
                              const Eigen::MatrixXd& J, double tolerance,
                              const std::function<Eigen::Vector3d(const Eigen::VectorXd&)>& f) {
  for (int c = 0; c < layout.size(); ++c) {
    const double h = 1e-6 * std::max(1.0, std::abs(th[c]));
    Eigen::VectorXd tp = th, tm = th;
    tp[c] += h;
    tm[c] -= h;
    const Eigen::Vector3d d = (f(tp) - f(tm)) / (2 * h);
    EXPECT_LT((d - J.col(c)).norm(), tolerance * (1 + d.norm())) << layout.info(c).name;
  }
}

TEST(B1Jacobian, AnalyticMatchesAutomaticAndNumeric) {
  constexpr int N = 64;
  using J = ceres::Jet<double, N>;
  std::mt19937_64 rng(17);
  std::normal_distribution<double> nrm(0.0, 1.0);
  // The base model; the whole catalogue at once, every effect away from zero;
  // the whole catalogue with the effects at zero, as the score tests of
  // diagnose linearise; and every effect but the size effect away from zero
  // (the size effect's columns at r = 0 are written out apart from the rest);
  // then the size effect away from zero with the angle stage, the axis
  // non-intersection d and the non-perpendicularity eps, through which frame
  // 2's motion moves (SizeEffectAwayFromZero).
  // (The gyro stage does not act on the accelerometers: left out.)
  std::vector<Effect> all;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kGyro) all.push_back(e.id);
  }
  const std::vector<std::vector<Effect>> size_layouts = {
      {Effect::kSizeEffect, Effect::kAngleLatency},
      {Effect::kSizeEffect, Effect::kEncoderHarmonic, Effect::kAxisNonintersection},
      {Effect::kSizeEffect, Effect::kAngleLatency, Effect::kEncoderHarmonic,
       Effect::kAxisNonperpendicularity}};
  for (int variant = 0; variant < 7; ++variant) {
    ModelConfig cfg;
    if (variant > 0) cfg.layout = ParameterLayout(all);
    if (variant >= 4) cfg.layout = ParameterLayout(size_layouts[variant - 4]);
    cfg.temp_ref_C = 20.0;
    ASSERT_TRUE(B1HasAnalyticJacobian(cfg.layout));
    const int n = cfg.layout.size();
    ASSERT_LE(n, N);
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd th = RandomTheta(cfg.layout, rng, [&](Effect e) {
        return variant == 1 || variant >= 4 || (variant == 3 && e != Effect::kSizeEffect);
      });
      BenchAngles<double> rec;
      for (int i = 0; i < 2; ++i) {
        rec.axis[i].angle = (3 - i) * nrm(rng);
        rec.axis[i].rate = nrm(rng);
        rec.axis[i].accel = nrm(rng);
      }
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
      ExpectCentralDifferences(
          cfg.layout, th, Ja, 1e-6, [&](const Eigen::VectorXd& t) -> Eigen::Vector3d {
            return AccelerationFromReadings_L<double>(cfg, t.data(), rec, z, ctx);
          });
    }
  }
}

// The specific force from the readings and its Jacobian (the gyro's
// g-sensitivity acts through it) against automatic differentiation and
// central differences: the whole catalogue and the gyro block (87 parameters,
// more than AccelerationWithJacobian's 64), every effect away from zero, both
// signs of the readings against the offsets (the scale asymmetry's branch).
TEST(B1Jacobian, SpecificForceMatchesAutomaticAndNumeric) {
  constexpr int N = 96;
  using J = ceres::Jet<double, N>;
  std::mt19937_64 rng(23);
  std::normal_distribution<double> nrm(0.0, 1.0);
  std::vector<Effect> all;
  for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
  ModelConfig cfg;
  cfg.layout = ParameterLayout(all, true);
  cfg.temp_ref_C = 20.0;
  const int n = cfg.layout.size();
  ASSERT_LE(n, N);
  ASSERT_GT(n, 64);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd th = RandomTheta(cfg.layout, rng, [](Effect) { return true; });
    const Eigen::Vector3d z(1500 + 150 * nrm(rng), 1500 + 150 * nrm(rng), 1500 + 150 * nrm(rng));
    const SampleContext ctx{40.0 * std::abs(nrm(rng)), 20 + 5 * nrm(rng)};
    Eigen::Vector3d W;
    Eigen::MatrixXd dW(3, n);
    SpecificForceWithJacobian(cfg, th.data(), z, ctx, &W, dW);
    std::vector<J> thj(N);
    for (int i = 0; i < N; ++i) thj[i] = J(i < n ? th[i] : 0.0, i);
    const Vec3<J> wj = SpecificForceFromReadings_g<J>(cfg, thj.data(), z.cast<J>(), ctx);
    for (int r = 0; r < 3; ++r) {
      EXPECT_NEAR(W[r], wj[r].a, 1e-14);
      for (int c = 0; c < n; ++c) {
        EXPECT_NEAR(dW(r, c), wj[r].v[c], 1e-10 * (1 + std::abs(wj[r].v[c])))
            << cfg.layout.info(c).name;
      }
    }
    ExpectCentralDifferences(
        cfg.layout, th, dW, 1e-7, [&](const Eigen::VectorXd& t) -> Eigen::Vector3d {
          return SpecificForceFromReadings_g<double>(cfg, t.data(), z, ctx);
        });
  }
}

TEST(B1Jacobian, TheWholeCatalogueIsWrittenOut) {
  EXPECT_TRUE(B1HasAnalyticJacobian(ParameterLayout()));
  EXPECT_TRUE(B1HasAnalyticJacobian(ParameterLayout({Effect::kAxisNonperpendicularity})));
  // The angle stage's Jets are 8 wide: the whole catalogue has 7 such parameters.
  int angle = 0;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage == EffectStage::kAngle) angle += static_cast<int>(e.params.size());
  }
  EXPECT_LE(angle, 8);
}

}  // namespace
}  // namespace triadcal
