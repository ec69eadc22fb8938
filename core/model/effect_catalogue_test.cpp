// One test per property, looped over every registered effect (effects.cpp), so
// that a new effect is tested by registering it:
//   - its catalogue entry is complete and consistent;
//   - the derivatives of blocks B1 and B2 (Jets of the templated model, and the
//     analytic B1 Jacobian where the entry claims it) match central differences;
//   - sensor-stage effects: readings model -> exact inverse gives W back;
//   - angle-stage effects: EncoderReading -> BenchAnglesFromRecorded gives the
//     bench angles back (latency: to second order in tau).
// The simulate -> fit recovery over seeds is in
// solvers/diagnosis/effect_recovery_test.cpp (it needs the estimators).
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "core/model/angle_derivatives.h"
#include "core/model/b1_jacobian.h"
#include "core/model/bench_model.h"

namespace triadcal {
namespace {

constexpr double kNominalScale = 175.0;  // mV/g, for scale_relative sizes

std::string Name(const EffectSpec& e) { return "effect " + e.name; }

TEST(EffectCatalogue, EveryEntryIsCompleteAndConsistent) {
  std::set<std::string> names;
  ASSERT_EQ(static_cast<int>(EffectCatalogue().size()), kNumEffects);
  for (int k = 0; k < kNumEffects; ++k) {
    const EffectSpec& e = EffectCatalogue()[k];
    SCOPED_TRACE(Name(e));
    EXPECT_EQ(static_cast<int>(e.id), k) << "catalogue order must follow the Effect enum";
    EXPECT_TRUE(names.insert(e.name).second) << "duplicate name";
    EXPECT_EQ(EffectFromName(e.name), e.id);
    EXPECT_FALSE(e.description.empty());
    EXPECT_FALSE(e.plausible_reason.empty());
    ASSERT_FALSE(e.params.empty());
    std::set<std::string> pnames;
    for (const ParamSpec& p : e.params) {
      SCOPED_TRACE(p.name);
      EXPECT_TRUE(pnames.insert(p.name).second);
      EXPECT_FALSE(p.unit.empty());
      EXPECT_GT(p.si_per_unit, 0.0);
      const double sigma = DefaultPriorSigma(e, p, kNominalScale);
      const double lo = PlausibleMin(e, p, kNominalScale);
      const double hi = PlausibleMax(e, p, kNominalScale);
      const double typical = TypicalValue(e, p, kNominalScale);
      EXPECT_GT(sigma, 0.0);
      // The effect absent (0) is plausible, and so is its typical size, which
      // the default prior must cover.
      EXPECT_LT(lo, 0.0);
      EXPECT_GT(hi, 0.0);
      EXPECT_NE(typical, 0.0);
      EXPECT_GE(typical, lo);
      EXPECT_LE(typical, hi);
      EXPECT_LE(std::abs(typical), sigma);
    }
    if (e.zero_offset_signal != ZeroOffsetSignal::kNone) {
      // W0_i += theta_i x: one parameter per axis, acting on the sensor.
      EXPECT_EQ(e.stage, EffectStage::kSensor);
      EXPECT_EQ(e.params.size(), 3u);
    }
    const ParameterLayout layout({e.id});
    EXPECT_EQ(B1HasAnalyticJacobian(layout), e.b1_analytic_jacobian);
    EXPECT_TRUE(layout.has_stage(e.stage));
    EXPECT_EQ(NeedsRatesAtEverySample(layout), e.needs.rates_at_every_sample);
  }
}

// A random but plausible operating point: base parameters near a real triad,
// the effect's parameters at +-(0.5..1.5) x their typical size.
struct Point {
  ModelConfig cfg;
  Eigen::VectorXd theta;
  BenchAngles<double> recorded;
  Eigen::Vector3d readings_mV;
  SampleContext ctx;
};

Point RandomPoint(Effect effect, std::mt19937_64& rng) {
  std::normal_distribution<double> nrm(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.5, 1.5);
  Point p;
  p.cfg.layout = ParameterLayout({effect});
  p.cfg.temp_ref_C = 20.0;
  const int n = p.cfg.layout.size();
  Eigen::VectorXd& th = p.theta;
  th = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < 3; ++i) th[kKx + i] = kNominalScale + 5 * nrm(rng);
  for (int i = 0; i < 3; ++i) th[kW0x + i] = 1500 + 20 * nrm(rng);
  for (int i = kAlphaX; i <= kGammaZ; ++i) th[i] = 0.02 * nrm(rng);
  for (int i = kKxx; i <= kKzz; ++i) th[i] = 0.005 * nrm(rng);
  for (int i = kDpsi; i <= kDlambda2; ++i) th[i] = 0.02 * nrm(rng);
  for (int i = kDx2; i <= kDz2; ++i) th[i] = 0.01 * nrm(rng);
  const EffectSpec& e = GetEffectSpec(effect);
  const int o = p.cfg.layout.offset(effect);
  for (size_t j = 0; j < e.params.size(); ++j) {
    const double sign = nrm(rng) < 0 ? -1.0 : 1.0;
    th[o + j] =
        sign * uni(rng) * TypicalValue(e, e.params[j], kNominalScale) * e.params[j].si_per_unit;
  }
  for (int i = 0; i < 2; ++i) {
    p.recorded.axis[i].angle = 3 * nrm(rng);
    p.recorded.axis[i].rate = nrm(rng);
    p.recorded.axis[i].accel = nrm(rng);
  }
  for (int i = 0; i < 3; ++i) p.readings_mV[i] = 1500 + 150 * nrm(rng);
  p.ctx = {40.0 * std::abs(nrm(rng)), 20 + 5 * nrm(rng)};
  return p;
}

// d f / d theta by central differences.
template <typename F>
Eigen::MatrixXd NumericJacobian(const F& f, const Eigen::VectorXd& theta, int rows) {
  Eigen::MatrixXd J(rows, theta.size());
  for (int c = 0; c < theta.size(); ++c) {
    const double h = 1e-6 * std::max(1.0, std::abs(theta[c]));
    Eigen::VectorXd tp = theta, tm = theta;
    tp[c] += h;
    tm[c] -= h;
    J.col(c) = (f(tp) - f(tm)) / (2 * h);
  }
  return J;
}

constexpr int kJetSize = 40;
using Jet = ceres::Jet<double, kJetSize>;

std::vector<Jet> JetTheta(const Eigen::VectorXd& theta) {
  std::vector<Jet> out(kJetSize);
  for (int i = 0; i < kJetSize; ++i) out[i] = Jet(i < theta.size() ? theta[i] : 0.0, i);
  return out;
}

void ExpectColumnsNear(const Eigen::MatrixXd& got, const Eigen::MatrixXd& numeric,
                       const ParameterLayout& layout, const char* what) {
  for (int c = 0; c < got.cols(); ++c) {
    EXPECT_LT((got.col(c) - numeric.col(c)).norm(), 1e-6 * (1 + numeric.col(c).norm()))
        << what << " column " << layout.info(c).name << "\n got " << got.col(c).transpose()
        << "\n numeric " << numeric.col(c).transpose();
  }
}

TEST(EffectCatalogue, BlockJacobiansMatchCentralDifferences) {
  std::mt19937_64 rng(23);
  for (const EffectSpec& e : EffectCatalogue()) {
    SCOPED_TRACE(Name(e));
    for (int trial = 0; trial < 5; ++trial) {
      const Point p = RandomPoint(e.id, rng);
      const int n = p.cfg.layout.size();
      ASSERT_LE(n, kJetSize);
      const std::vector<Jet> thj = JetTheta(p.theta);

      // B1: readings -> acceleration of O in L.
      auto b1 = [&](const Eigen::VectorXd& th) {
        return AccelerationFromReadings_L<double>(p.cfg, th.data(), p.recorded, p.readings_mV,
                                                  p.ctx);
      };
      const Eigen::MatrixXd numeric_b1 = NumericJacobian(b1, p.theta, 3);
      const Vec3<Jet> aj =
          AccelerationFromReadings_L<Jet>(p.cfg, thj.data(), p.recorded, p.readings_mV, p.ctx);
      Eigen::MatrixXd jet_b1(3, n);
      for (int r = 0; r < 3; ++r) jet_b1.row(r) = aj[r].v.head(n).transpose();
      ExpectColumnsNear(jet_b1, numeric_b1, p.cfg.layout, "B1 (Jets)");
      if (e.b1_analytic_jacobian) {
        Eigen::Vector3d a;
        Eigen::MatrixXd J(3, n);
        AccelerationWithJacobian(p.cfg, p.theta.data(), p.recorded, p.readings_mV, p.ctx, &a, J);
        EXPECT_LT((a - b1(p.theta)).norm(), 1e-12);
        ExpectColumnsNear(J, numeric_b1, p.cfg.layout, "B1 (analytic)");
      }

      // B2: the reference position and velocity of O from the angles.
      auto b2 = [&](const Eigen::VectorXd& th) {
        const PointMotion<double> m = ReferenceMotion<double>(p.cfg, th.data(), p.recorded);
        Eigen::Matrix<double, 6, 1> out;
        out << m.p_L, m.v_L;
        return out;
      };
      const Eigen::MatrixXd numeric_b2 = NumericJacobian(b2, p.theta, 6);
      const PointMotion<Jet> mj = ReferenceMotion<Jet>(p.cfg, thj.data(), p.recorded);
      Eigen::MatrixXd jet_b2(6, n);
      for (int r = 0; r < 3; ++r) {
        jet_b2.row(r) = mj.p_L[r].v.head(n).transpose();
        jet_b2.row(3 + r) = mj.v_L[r].v.head(n).transpose();
      }
      ExpectColumnsNear(jet_b2, numeric_b2, p.cfg.layout, "B2 (Jets)");
    }
  }
}

TEST(EffectCatalogue, SensorStageModelAndInverseRoundTrip) {
  std::mt19937_64 rng(29);
  std::normal_distribution<double> nrm(0.0, 1.0);
  int tested = 0;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kSensor) continue;
    SCOPED_TRACE(Name(e));
    ++tested;
    for (int trial = 0; trial < 50; ++trial) {
      const Point p = RandomPoint(e.id, rng);
      const Vec3<double> W(1.5 * nrm(rng), 1.5 * nrm(rng), 1.5 * nrm(rng));  // both signs
      const Vec3<double> z = Readings_mV(p.cfg, p.theta.data(), W, p.ctx);
      const Vec3<double> back = SpecificForceFromReadings_g(p.cfg, p.theta.data(), z, p.ctx);
      EXPECT_LT((back - W).norm(), 1e-12) << W.transpose();
      // And the effect is really applied: the readings differ without it.
      Eigen::VectorXd off = p.theta;
      off.tail(p.theta.size() - kNumBaseParams).setZero();
      EXPECT_GT((Readings_mV(p.cfg, off.data(), W, p.ctx) - z).norm(), 1e-6);
    }
  }
  EXPECT_GT(tested, 0);
}

// Angle stage: the recorded angles of a smooth motion, generated forward
// (bench(t - tau) through the encoder error, as the simulator does), are
// turned back into the bench angles at t. Exact for the encoder error (to the
// fixed-point iteration), second order in tau for the latency.
TEST(EffectCatalogue, AngleStageForwardAndInverseRoundTrip) {
  std::mt19937_64 rng(31);
  int tested = 0;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kAngle) continue;
    SCOPED_TRACE(Name(e));
    ++tested;
    for (int trial = 0; trial < 20; ++trial) {
      const Point p = RandomPoint(e.id, rng);
      const double tau = AngleLatency_s(p.cfg, p.theta.data());
      // Bench motion lambda_i(t) = A_i sin(w_i t + phi_i), at t = 1 s.
      const double A[2] = {1.2, 0.8}, w[2] = {0.9, 1.3}, phi[2] = {0.3, -0.7};
      auto bench_at = [&](double t) {
        BenchAngles<double> b;
        for (int i = 0; i < 2; ++i) {
          b.axis[i].angle = A[i] * std::sin(w[i] * t + phi[i]);
          b.axis[i].rate = A[i] * w[i] * std::cos(w[i] * t + phi[i]);
          b.axis[i].accel = -A[i] * w[i] * w[i] * std::sin(w[i] * t + phi[i]);
        }
        return b;
      };
      const BenchAngles<double> recorded =
          EncoderReading(p.cfg, p.theta.data(), bench_at(1.0 - tau));
      const BenchAngles<double> back =
          BenchAnglesFromRecorded<double>(p.cfg, p.theta.data(), recorded);
      const BenchAngles<double> truth = bench_at(1.0);
      // Taylor remainders of the latency step (angle to tau^2, rate to tau):
      // jerk tau^3 / 6 and jerk tau^2 / 2, with |lambda'''| <= jerk = max A w^3.
      const double jerk = std::max(A[0] * std::pow(w[0], 3), A[1] * std::pow(w[1], 3));
      const double t = std::abs(tau);
      for (int i = 0; i < 2; ++i) {
        EXPECT_NEAR(back.axis[i].angle, truth.axis[i].angle, 1e-12 + 1.01 * jerk * t * t * t / 6);
        EXPECT_NEAR(back.axis[i].rate, truth.axis[i].rate, 1e-11 + 1.01 * jerk * t * t / 2);
      }
    }
  }
  EXPECT_GT(tested, 0);
}

}  // namespace
}  // namespace triadcal
