// Tests of the physics in core/model/bench_model.h: kinematics against finite
// differences of S(t), gravity projection in static positions, the readings
// model against its inverse, the angle stage against its inverse, and the
// automatic derivatives against numeric ones.
#include <cmath>
#include <random>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "core/model/bench_model.h"

namespace triadcal {
namespace {

// A harmonic bench profile written here independently of the simulator.
BenchAngles<double> Harmonic(double t) {
  const double A[2] = {360 * kDegToRad, 90 * kDegToRad}, T[2] = {30.0, 12.0},
               phi[2] = {0.3, -1.1};
  BenchAngles<double> b;
  for (int i = 0; i < 2; ++i) {
    const double w = 2 * kPi / T[i];
    b.axis[i].angle = A[i] * std::sin(w * t + phi[i]);
    b.axis[i].rate = A[i] * w * std::cos(w * t + phi[i]);
    b.axis[i].accel = -A[i] * w * w * std::sin(w * t + phi[i]);
  }
  return b;
}

Eigen::VectorXd RandomTheta(const ParameterLayout& layout, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd th = Eigen::VectorXd::Zero(layout.size());
  for (int i = 0; i < 3; ++i) th[kKx + i] = 174.0 + 3.0 * n(rng);
  for (int i = 0; i < 3; ++i) th[kW0x + i] = 1500.0 + 5.0 * n(rng);
  for (int i = kAlphaX; i <= kGammaZ; ++i) th[i] = 60 * kArcminToRad * n(rng);
  for (int i = kKxx; i <= kKzz; ++i) th[i] = 2e-3 * n(rng);
  for (int i = kDpsi; i <= kDlambda2; ++i) th[i] = 40 * kArcminToRad * n(rng);
  for (int i = kDx2; i <= kDz2; ++i) th[i] = 0.01 * n(rng);
  for (int i = kNumBaseParams; i < layout.size(); ++i) {
    th[i] = 0.3 * n(rng) * layout.info(i).si_per_unit;  // 0.3 file units
    // Second-order coefficients (cross_quadratic) at 1.5 prior sigma: 0.3 /g
    // is three times their plausible bound, where the inverse's Newton from
    // M^-1 u no longer converges in its 8 steps.
    if (layout.info(i).unit == "1/g") th[i] = 0.03 * n(rng);
  }
  return th;
}

// Every effect that acts on the accelerometers (the gyro stage does not: gyro_model_test.cpp).
ParameterLayout AllEffects() {
  std::vector<Effect> all;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kGyro) all.push_back(e.id);
  }
  return ParameterLayout(all);
}

// v and a of every point against central differences of its position p(t).
TEST(BenchModel, KinematicsMatchFiniteDifferencesOfPosition) {
  std::mt19937_64 rng(7);
  ModelConfig cfg;
  cfg.layout = AllEffects();
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd th = RandomTheta(cfg.layout, rng);
    const Vec3<double> r = LeverArm_m(cfg, th.data());
    const double t = 0.37 + 4.1 * trial, h = 1e-4;
    auto pos = [&](double tt) {
      return MotionOfPoint(ComputeBenchMotion(cfg, th.data(), Harmonic(tt)), r).p_L;
    };
    const PointMotion<double> pm =
        MotionOfPoint(ComputeBenchMotion(cfg, th.data(), Harmonic(t)), r);
    const Vec3<double> v_fd = (pos(t + h) - pos(t - h)) / (2 * h);
    const Vec3<double> a_fd = (pos(t + h) - 2 * pos(t) + pos(t - h)) / (h * h);
    EXPECT_LT((pm.p_L - pos(t)).norm(), 1e-15);
    // Truncation O(h^2 * |p'''|) ~ 1e-8 * 0.2 * 1e3; rounding ~ 1e-16 / h^2 for a.
    EXPECT_LT((pm.v_L - v_fd).norm(), 1e-6) << "trial " << trial;
    EXPECT_LT((pm.a_L - a_fd).norm(), 2e-4 * (1.0 + pm.a_L.norm())) << "trial " << trial;
  }
}

// The rotation chain of docs/method.md written out directly.
TEST(BenchModel, RotationChainIsSpecOrder) {
  ModelConfig cfg;
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  th[kDpsi] = 0.01;
  th[kDthetaC] = -0.02;
  th[kDlambda2] = 0.03;
  BenchAngles<double> b;
  b.axis[0].angle = 0.7;
  b.axis[1].angle = -1.3;
  const Mat3<double> C = ComputeBenchMotion(cfg, th.data(), b).C_L2;
  Mat3<double> Rz_, Ry_, Rx_;
  const double z = 0.01, y = 0.7 - 0.02, x = -1.3 + 0.03;
  Rz_ << std::cos(z), -std::sin(z), 0, std::sin(z), std::cos(z), 0, 0, 0, 1;
  Ry_ << std::cos(y), 0, std::sin(y), 0, 1, 0, -std::sin(y), 0, std::cos(y);
  Rx_ << 1, 0, 0, 0, std::cos(x), -std::sin(x), 0, std::sin(x), std::cos(x);
  EXPECT_LT((C - Rz_ * Ry_ * Rx_).norm(), 1e-15);
}

// Specific force of an ideal triad at the bench centre in static positions.
Vec3<double> StaticW(double l1_deg, double l2_deg) {
  ModelConfig cfg;
  cfg.lever_arm0_m.setZero();
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  BenchAngles<double> b;
  b.axis[0].angle = l1_deg * kDegToRad;
  b.axis[1].angle = l2_deg * kDegToRad;
  const BenchMotion<double> m = ComputeBenchMotion(cfg, th.data(), b);
  return SpecificForceAtAxes_g(cfg, th.data(), m).col(0);
}

TEST(BenchModel, GravityProjectionInStaticPositions) {
  // Level: x up reads +1 g.
  EXPECT_LT((StaticW(0, 0) - Vec3<double>(1, 0, 0)).norm(), 1e-15);
  // Turning the inner axis (x) does not move x away from up.
  EXPECT_LT((StaticW(0, 90) - Vec3<double>(1, 0, 0)).norm(), 1e-15);
  // Outer axis +90 deg about y: Ry(90) maps z2 onto x_L, so z is up.
  EXPECT_LT((StaticW(90, 0) - Vec3<double>(0, 0, 1)).norm(), 1e-15);
  EXPECT_LT((StaticW(-90, 0) - Vec3<double>(0, 0, -1)).norm(), 1e-15);
  EXPECT_LT((StaticW(180, 0) - Vec3<double>(-1, 0, 0)).norm(), 1e-15);
  // l1 = 90, l2 = 90: C_L2 = Ry(90) Rx(90); up in frame 2 = C_L2^T e_x.
  // Rx(90)^T Ry(90)^T e_x = Rx(90)^T (0, 0, 1) = (0, 1, 0): y is up.
  EXPECT_LT((StaticW(90, 90) - Vec3<double>(0, 1, 0)).norm(), 1e-15);
  EXPECT_LT((StaticW(90, -90) - Vec3<double>(0, -1, 0)).norm(), 1e-15);
  // General: W = (cos l1, sin l1 sin l2, sin l1 cos l2).
  const double l1 = 0.4, l2 = -2.2;
  EXPECT_LT((StaticW(l1 / kDegToRad, l2 / kDegToRad) -
             Vec3<double>(std::cos(l1), std::sin(l1) * std::sin(l2), std::sin(l1) * std::cos(l2)))
                .norm(),
            1e-15);
}

TEST(BenchModel, SetUpErrorSigns) {
  ModelConfig cfg;
  cfg.lever_arm0_m.setZero();
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  BenchAngles<double> b;  // level
  const double e = 1e-3;
  // dtheta_c tilts about y like lambda1: W = (cos e, 0, sin e).
  th[kDthetaC] = e;
  Vec3<double> W = SpecificForceAtAxes_g(cfg, th.data(), ComputeBenchMotion(cfg, th.data(), b)).col(0);
  EXPECT_NEAR(W.z(), std::sin(e), 1e-15);
  // dpsi rotates about the vertical-to-level z axis of L: x tips towards -y_2.
  th.setZero();
  th[kDpsi] = e;
  W = SpecificForceAtAxes_g(cfg, th.data(), ComputeBenchMotion(cfg, th.data(), b)).col(0);
  EXPECT_NEAR(W.y(), -std::sin(e), 1e-15);
  // dlambda2 does nothing while x is up, but at l1 = 90 it acts like lambda2.
  th.setZero();
  th[kDlambda2] = e;
  b.axis[0].angle = kPi / 2;
  W = SpecificForceAtAxes_g(cfg, th.data(), ComputeBenchMotion(cfg, th.data(), b)).col(0);
  EXPECT_NEAR(W.y(), std::sin(e), 1e-15);
}

// A constant rotation about the outer axis at rate w: centripetal acceleration
// of a point at distance r from the axis is w^2 r towards the axis.
TEST(BenchModel, CentripetalAndTangentialTerms) {
  ModelConfig cfg;
  cfg.lever_arm0_m = Eigen::Vector3d(0.2, 0.0, 0.0);  // along x2
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  BenchAngles<double> b;
  b.axis[0].rate = 2.0;
  b.axis[0].accel = 3.0;
  const BenchMotion<double> m = ComputeBenchMotion(cfg, th.data(), b);
  const PointMotion<double> pm = MotionOfPoint(m, LeverArm_m(cfg, th.data()));
  // At l1 = 0 the point is at x_L = 0.2; w = 2 e_y; alpha = 3 e_y.
  // a = alpha x r + w x (w x r) = 3 e_y x 0.2 e_x + (-4 * 0.2 e_x) = (-0.8, 0, -0.6)
  EXPECT_LT((pm.a_L - Vec3<double>(-0.8, 0.0, -0.6)).norm(), 1e-15);
  EXPECT_LT((pm.v_L - Vec3<double>(0.0, 0.0, -0.4)).norm(), 1e-15);
  // Coriolis: inner axis turning at rate 1 while the outer turns at rate 2,
  // point at 0.1 e_y: v_rel = 1 e_x x 0.1 e_y = 0.1 e_z; 2 w1 x v_rel = 2*2*0.1 e_x.
  cfg.lever_arm0_m = Eigen::Vector3d(0.0, 0.1, 0.0);
  b.axis[0].accel = 0.0;
  b.axis[1].rate = 1.0;
  const BenchMotion<double> m2 = ComputeBenchMotion(cfg, th.data(), b);
  const PointMotion<double> p2 = MotionOfPoint(m2, LeverArm_m(cfg, th.data()));
  // Total: w = (1, 2, 0); a = w1 x w12 x r-term + w x (w x r) with r = 0.1 e_y:
  // w x r = (0,0,0.1); w x (0,0,0.1) = (0.2,-0.1,0); dw = w1 x w12 = (0,0,-2),
  // dw x r = (0.2, 0, 0). Sum (0.4, -0.1, 0): centripetal (0.2,-0.1,0) plus the
  // Coriolis-type term 0.2 e_x.
  EXPECT_LT((p2.a_L - Vec3<double>(0.4, -0.1, 0.0)).norm(), 1e-15);
}

// The paper's block B2: V_DU = C(dpsi) [(l1' + C(l1) l2') x (C(l1) C(l2) R)].
TEST(BenchModel, VelocityMatchesPaperBlockB2) {
  std::mt19937_64 rng(3);
  ModelConfig cfg;
  const Eigen::VectorXd th = RandomTheta(cfg.layout, rng);
  const BenchAngles<double> b = Harmonic(5.3);
  const BenchMotion<double> m = ComputeBenchMotion(cfg, th.data(), b);
  const Vec3<double> R = LeverArm_m(cfg, th.data());
  const Mat3<double> C1 = Ry(b.axis[0].angle + th[kDthetaC]);
  const Mat3<double> C2 = Rx(b.axis[1].angle + th[kDlambda2]);
  const Vec3<double> w = Vec3<double>(0, b.axis[0].rate, 0) + C1 * Vec3<double>(b.axis[1].rate, 0, 0);
  const Vec3<double> v_du = Rz(th[kDpsi]) * w.cross(C1 * C2 * R);
  EXPECT_LT((MotionOfPoint(m, R).v_L - v_du).norm(), 1e-15);
}

TEST(BenchModel, ReadingsInverseRoundTripWithNonlinearity) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.3, 1.3);
  for (const bool effects : {false, true}) {
    ModelConfig cfg;
    if (effects) {
      cfg.layout = ParameterLayout(
          {Effect::kThermalDrift, Effect::kThermalDriftTemp, Effect::kScaleAsymmetry});
    }
    cfg.temp_ref_C = 21.0;
    // Up to ~1e-2 /g, and up to ~0.1 /g, where the chord steps from W = u
    // converge slowly enough to form J again (SpecificForceFromReadings_g).
    for (const double k_scale : {5.0, 50.0}) {
      for (int trial = 0; trial < 200; ++trial) {
        Eigen::VectorXd th = RandomTheta(cfg.layout, rng);
        for (int i = kKxx; i <= kKzz; ++i) th[i] *= k_scale;
        const Vec3<double> W(u(rng), u(rng), u(rng));
        const SampleContext ctx{37.0, 24.5};
        const Vec3<double> z = Readings_mV(cfg, th.data(), W, ctx);
        const Vec3<double> W_back = SpecificForceFromReadings_g(cfg, th.data(), z, ctx);
        EXPECT_LT((W - W_back).norm(), 1e-13) << "trial " << trial << " K x" << k_scale;
      }
    }
  }
}

// Where the readings model has no inverse (W + 0.5 W^2 = u has no real root
// for u < -0.5), W is not a number, not the last iterate.
TEST(BenchModel, ReadingsInverseIsNotANumberWhereTheModelDoesNotInvert) {
  ModelConfig cfg;
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  for (int i = 0; i < 3; ++i) th[kKx + i] = 1.0;
  th[kKxx] = th[kKyy] = th[kKzz] = 0.5;
  const SampleContext ctx{0.0, 20.0};
  Mat3<double> J_inv;
  const Vec3<double> bad =
      SpecificForceFromReadings_g(cfg, th.data(), Vec3<double>(-2.0, 0.1, 0.2), ctx, &J_inv);
  EXPECT_TRUE(std::isnan(bad.x()) && std::isnan(bad.y()) && std::isnan(bad.z()));
  EXPECT_TRUE(J_inv.hasNaN());
  // Within its range the same model inverts.
  const Vec3<double> W(-0.9, 0.1, 0.2);
  const Vec3<double> z = Readings_mV(cfg, th.data(), W, ctx);
  EXPECT_LT((SpecificForceFromReadings_g(cfg, th.data(), z, ctx) - W).norm(), 1e-13);
}

TEST(BenchModel, ReadingsModelIsEquationOne) {
  ModelConfig cfg;
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  th[kKx] = 170;
  th[kKy] = 175;
  th[kKz] = 180;
  th[kW0x] = 1;
  th[kW0y] = 2;
  th[kW0z] = 3;
  th[kAlphaY] = 0.01;  // Wx picks up -alpha_y Wy
  th[kGammaY] = 0.02;  // Wz picks up +gamma_y Wy
  th[kKxy] = 0.1;      // Wx picks up Kxy Wx Wy
  const Vec3<double> W(0.5, 0.8, -0.2);
  const Vec3<double> z = Readings_mV(cfg, th.data(), W, SampleContext{});
  EXPECT_NEAR(z.x(), 170 * (0.5 - 0.01 * 0.8 + 0.1 * 0.5 * 0.8) + 1, 1e-12);
  EXPECT_NEAR(z.y(), 175 * 0.8 + 2, 1e-12);
  EXPECT_NEAR(z.z(), 180 * (-0.2 + 0.02 * 0.8) + 3, 1e-12);
}

TEST(BenchModel, AngleStageInvertsEncoderHarmonicAndLatency) {
  ModelConfig cfg;
  cfg.layout = ParameterLayout({Effect::kAngleLatency, Effect::kEncoderHarmonic});
  Eigen::VectorXd th = Eigen::VectorXd::Zero(cfg.layout.size());
  const int o = cfg.layout.offset(Effect::kEncoderHarmonic);
  th[o + 0] = 3 * kArcminToRad;
  th[o + 1] = -2 * kArcminToRad;
  th[o + 2] = 1 * kArcminToRad;
  th[o + 3] = 4 * kArcminToRad;
  const double tau = 2e-3;
  th[cfg.layout.offset(Effect::kAngleLatency)] = tau;
  for (double t : {0.1, 3.3, 17.0, 44.4}) {
    // What the sensors report at t: the encoder reading of the bench at t - tau.
    const BenchAngles<double> rec = EncoderReading(cfg, th.data(), Harmonic(t - tau));
    const BenchAngles<double> back = BenchAnglesFromRecorded<double>(cfg, th.data(), rec);
    const BenchAngles<double> truth = Harmonic(t);
    for (int i = 0; i < 2; ++i) {
      // Latency is undone to second order: error ~ tau^3 l'''/6 ~ 1e-8 rad.
      EXPECT_NEAR(back.axis[i].angle, truth.axis[i].angle, 5e-8);
      EXPECT_NEAR(back.axis[i].rate, truth.axis[i].rate, 1e-5);
      EXPECT_NEAR(back.axis[i].accel, truth.axis[i].accel, 1e-2);
    }
  }
  // Encoder alone inverts exactly.
  cfg.layout = ParameterLayout({Effect::kEncoderHarmonic});
  Eigen::VectorXd th2 = th.head(cfg.layout.size());
  th2.tail(4) = th.segment(o, 4);
  const BenchAngles<double> truth = Harmonic(8.8);
  const BenchAngles<double> back =
      BenchAnglesFromRecorded<double>(cfg, th2.data(), EncoderReading(cfg, th2.data(), truth));
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(back.axis[i].angle, truth.axis[i].angle, 1e-14);
    EXPECT_NEAR(back.axis[i].rate, truth.axis[i].rate, 1e-13);
    EXPECT_NEAR(back.axis[i].accel, truth.axis[i].accel, 1e-12);
  }
}

// Ceres Jets through the whole forward chain and the inverse agree with central
// differences for every parameter, with every effect switched on.
TEST(BenchModel, AutomaticDerivativesMatchNumeric) {
  constexpr int N = 64;
  using J = ceres::Jet<double, N>;
  ModelConfig cfg;
  cfg.layout = AllEffects();
  cfg.temp_ref_C = 20.0;
  ASSERT_LE(cfg.layout.size(), N);
  std::mt19937_64 rng(5);
  const SampleContext ctx{12.0, 23.0};
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd th = RandomTheta(cfg.layout, rng);
    const BenchAngles<double> rec = Harmonic(2.0 + 7.0 * trial);
    std::vector<J> thj(cfg.layout.size());
    for (int i = 0; i < cfg.layout.size(); ++i) thj[i] = J(th[i], i);
    auto forward = [&](const auto* p) {
      using T = std::remove_const_t<std::remove_pointer_t<decltype(p)>>;
      const BenchAngles<T> b = BenchAnglesFromRecorded<T>(cfg, p, rec);
      return PredictReadings_mV<T>(cfg, p, b, ctx);
    };
    const Vec3<J> zj = forward(thj.data());
    const Vec3<double> z0 = forward(th.data());
    const Vec3<J> Wj = SpecificForceFromReadings_g<J>(cfg, thj.data(), z0.cast<J>(), ctx);
    for (int i = 0; i < cfg.layout.size(); ++i) {
      const double h = 1e-6 * std::max(1.0, std::abs(th[i]));
      Eigen::VectorXd tp = th, tm = th;
      tp[i] += h;
      tm[i] -= h;
      const Vec3<double> dz = (forward(tp.data()) - forward(tm.data())) / (2 * h);
      const Vec3<double> dW =
          (SpecificForceFromReadings_g<double>(cfg, tp.data(), z0, ctx) -
           SpecificForceFromReadings_g<double>(cfg, tm.data(), z0, ctx)) /
          (2 * h);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(zj[k].v[i], dz[k], 1e-6 * (1.0 + std::abs(dz[k])))
            << cfg.layout.info(i).name << " channel " << k;
        EXPECT_NEAR(Wj[k].v[i], dW[k], 1e-7 * (1.0 + std::abs(dW[k])))
            << cfg.layout.info(i).name << " channel " << k;
      }
    }
  }
}

TEST(Parameters, FileUnitsRoundTripAndNames) {
  const ParameterLayout layout({Effect::kAngleLatency});
  EXPECT_EQ(layout.size(), kNumBaseParams + 1);
  EXPECT_EQ(layout.info(kGammaZ).name, "gamma_z");
  EXPECT_EQ(layout.info(kGammaZ).unit, "arcmin");
  EXPECT_EQ(layout.info(kNumBaseParams).name, "angle_latency.tau");
  EXPECT_EQ(layout.info(kNumBaseParams).unit, "ms");
  EXPECT_EQ(layout.IndexOf("dz2"), kDz2);
  EXPECT_EQ(layout.IndexOf("nope"), -1);
  Eigen::VectorXd th = Eigen::VectorXd::Zero(layout.size());
  SetFromFileUnits(layout, {{"dpsi", -33.0}, {"dx2", -7.0}, {"angle_latency.tau", 2.0}}, &th);
  EXPECT_NEAR(th[kDpsi], -33.0 * kArcminToRad, 1e-18);
  EXPECT_NEAR(th[kDx2], -0.007, 1e-18);
  EXPECT_NEAR(th[kNumBaseParams], 0.002, 1e-18);
  const NamedValues back = ToFileUnits(layout, th);
  EXPECT_NEAR(back.at("dpsi"), -33.0, 1e-12);
  EXPECT_EQ(UnitSuffixedKey(GetEffectSpec(Effect::kThermalDrift).params[0]), "rate_x_mV_per_min");
  EXPECT_THROW(EffectFromName("wobble"), std::invalid_argument);
}

}  // namespace
}  // namespace triadcal
