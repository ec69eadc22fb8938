// The gyro triad's term of the batch problem (gyro_term.h): the increment
// residual's Jacobian against central differences, the noise at its maximum
// against a scan of the likelihood, and the fit of a simulated paper run with
// a gyro against its truth, judged by error / sigma over seeds.
#include <cmath>
#include <cstdlib>
#include <functional>
#include <random>
#include <set>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "core/model/gyro_model.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/gyro_term.h"
#include "solvers/estimation/observability.h"
#include "tests/gyro_fixtures.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

// Column c of the gyro pass's Jacobian against central differences of step h:
// the largest difference and the largest numeric derivative over the intervals.
void CentralDifference(const RunProblem& p, const Eigen::VectorXd& th, const GyroPass& pass,
                       int c, double h, double* worst, double* scale) {
  Eigen::VectorXd tp = th, tm = th;
  tp[c] += h;
  tm[c] -= h;
  const GyroPass a = EvaluateGyroPass(p, tp, false, 1);
  const GyroPass b = EvaluateGyroPass(p, tm, false, 1);
  for (std::size_t e = 0; e < pass.r.size(); ++e) {
    const Eigen::Vector3d num = (a.r[e] - b.r[e]) / (2.0 * h);
    *worst = std::max(*worst, (num - pass.J[e].col(c)).cwiseAbs().maxCoeff());
    *scale = std::max(*scale, num.cwiseAbs().maxCoeff());
  }
}


using testing_fixtures::GyroRun;
using testing_fixtures::MakeGyroRun;
using testing_fixtures::PaperScenario;

TEST(GyroTerm, ModelInvertsExactly) {
  const ParameterLayout layout({}, true);
  ModelConfig cfg;
  cfg.layout = layout;
  Eigen::VectorXd th = Eigen::VectorXd::Zero(layout.size());
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < layout.size(); ++i) th[i] = 0.01 * u(rng);
  for (int i = 0; i < 3; ++i) th[layout.gyro_offset() + kGKx + i] = 1.0 + 0.05 * u(rng);
  const Eigen::Vector3d w(0.7, -1.3, 0.2), W(0.3, -0.9, 0.1);
  const Eigen::Vector3d G = GyroReadings<double>(cfg, th.data(), w, W);
  EXPECT_LT((GyroRateFromReadings<double>(cfg, th.data(), G, W) - w).norm(), 1e-14);
}

// d r / d theta of every interval against central differences of r (the
// gyro's parameters, dlambda2, and the accelerometer's through W).
TEST(GyroTerm, JacobianMatchesCentralDifferences) {
  const GyroRun g = MakeGyroRun(50.0, 10.0, 0.05, 1);
  const RunProblem p = BuildRunProblem(g.s.run, g.data, g.layout, 0.5, {});
  Eigen::VectorXd th = g.truth;
  th[g.layout.gyro_offset() + kGKy] *= 1.01;  // away from the truth
  th[kDlambda2] += 1e-3;
  const GyroPass pass = EvaluateGyroPass(p, th, true, 1);
  const int go = g.layout.gyro_offset();
  // The accelerometer's readings-model parameters reach the gyro through W
  // of the g-sensitivity.
  std::vector<int> cols = {kDlambda2, kKx, kW0y, kAlphaX, kGammaZ, kKxy};
  for (int j = 0; j < kNumGyroParams; ++j) cols.push_back(go + j);
  for (int c : cols) {
    const double h = 1e-6 * std::max(1.0, std::abs(th[c]));
    double worst = 0.0, scale = 0.0;
    CentralDifference(p, th, pass, c, h, &worst, &scale);
    EXPECT_LE(worst, 1e-6 * scale + 1e-12) << g.layout.info(c).name;
  }
}

// The information's scale-factor and angle columns (the readings' form, with
// the bench's rate from the angles) agree with the residual's own at the
// truth, where the readings hold the rate and little else.
TEST(GyroTerm, InformationColumnsAreTheResidualsAtTheTruth) {
  const GyroRun g = MakeGyroRun(50.0, 20.0, 0.05, 6);
  const RunProblem p = BuildRunProblem(g.s.run, g.data, g.layout, 0.5, {});
  const GyroPass pass = EvaluateGyroPass(p, g.truth, true, 1);
  const int go = g.layout.gyro_offset();
  for (int i = 0; i < 9; ++i) {
    const int c = go + (i < 3 ? kGKx + i : kGAlphaX + i - 3);
    double diff = 0.0, norm = 0.0;
    for (std::size_t e = 0; e < pass.r.size(); ++e) {
      diff += (pass.J_info[e].col(i) - pass.J[e].col(c)).squaredNorm();
      norm += pass.J[e].col(c).squaredNorm();
    }
    EXPECT_LT(std::sqrt(diff / norm), 0.02) << g.layout.info(c).name;
  }
}

// The gradient of -log L profiled over the noise (the weights follow the
// scale factors: the gradient carries their derivative) against central
// differences of the profile.
TEST(GyroTerm, ProfiledGradientMatchesCentralDifferences) {
  const GyroRun g = MakeGyroRun(50.0, 20.0, 0.05, 4);
  const RunProblem p = BuildRunProblem(g.s.run, g.data, g.layout, 0.5, {});
  const int go = g.layout.gyro_offset();
  Eigen::VectorXd th = g.truth;
  th[go + kGKx] *= 1.002;  // away from the optimum
  th[go + kGW0z] += 2e-4;
  th[go + kGAlphaY] += 3e-4;
  const Eigen::Vector3d start = Eigen::Vector3d::Constant(0.05 * kDegToRad);
  const GyroReduction at = ReduceGyroAtBestNoise(EvaluateGyroPass(p, th, true, 1), start, 21, true);
  for (int j : {kGKx, kGKy, kGKz, kGW0x, kGW0z, kGAlphaY, kGBetaZ, kGGammaZ, kGGxy}) {
    SCOPED_TRACE(g.layout.info(go + j).name);
    const int c = go + j;
    const double h = 1e-6 * std::max(1.0, std::abs(th[c]));
    Eigen::VectorXd tp = th, tm = th;
    tp[c] += h;
    tm[c] -= h;
    const double fp = ReduceGyroAtBestNoise(EvaluateGyroPass(p, tp, false, 1), start, 21, false).neg_log_l;
    const double fm = ReduceGyroAtBestNoise(EvaluateGyroPass(p, tm, false, 1), start, 21, false).neg_log_l;
    const double num = (fp - fm) / (2.0 * h);
    // Agreement to 1e-4 of a gradient of one sigma's offset (sqrt of the information).
    EXPECT_NEAR(at.gradient[c], num, 1e-4 * (std::abs(num) + std::sqrt(at.information(c, c))))
        << g.layout.info(c).name << " analytic " << at.gradient[c] << " numeric " << num;
  }
}

// A 20-s gyro run at 50 Hz and theta away from the noise weights' reference
// values (the prior means): gyro scale factor `scale` times `factor`, gyro
// misalignment `angle` moved by `add` rad.
struct OffReference {
  GyroRun g;
  RunProblem p;
  Eigen::VectorXd th;
};

OffReference MakeOffReference(int seed, int scale, double factor, int angle, double add) {
  OffReference o{MakeGyroRun(50.0, 20.0, 0.05, seed), {}, {}};
  o.p = BuildRunProblem(o.g.s.run, o.g.data, o.g.layout, 0.5, {});
  const int go = o.g.layout.gyro_offset();
  o.th = o.g.truth;
  o.th[go + scale] *= factor;
  o.th[go + angle] += add;
  return o;
}

// At a fixed noise (what the minimiser measures its curvature with) the
// gradient carries the weights' derivatives too: against central differences
// of -log L at that noise.
TEST(GyroTerm, GradientAtFixedNoiseMatchesCentralDifferences) {
  const OffReference o = MakeOffReference(4, kGKx, 1.002, kGAlphaY, 3e-4);
  const GyroRun& g = o.g;
  const RunProblem& p = o.p;
  const Eigen::VectorXd& th = o.th;
  const int go = g.layout.gyro_offset();
  const Eigen::Vector3d noise(0.04 * kDegToRad, 0.06 * kDegToRad, 0.05 * kDegToRad);
  const double rho = 0.97;
  const GyroReduction at = ReduceGyroAtNoise(EvaluateGyroPass(p, th, true, 1), noise, rho);
  for (int j : {kGKx, kGKy, kGW0z, kGAlphaY, kGBetaZ, kGGammaZ, kGGxy}) {
    const int c = go + j;
    SCOPED_TRACE(g.layout.info(c).name);
    const double h = 1e-6 * std::max(1.0, std::abs(th[c]));
    Eigen::VectorXd tp = th, tm = th;
    tp[c] += h;
    tm[c] -= h;
    const double fp = ReduceGyro(EvaluateGyroPass(p, tp, false, 1), noise, rho, false).neg_log_l;
    const double fm = ReduceGyro(EvaluateGyroPass(p, tm, false, 1), noise, rho, false).neg_log_l;
    const double num = (fp - fm) / (2.0 * h);
    EXPECT_NEAR(at.gradient[c], num, 1e-4 * (std::abs(num) + std::sqrt(at.information(c, c))));
  }
}

// The gradient of -log L by the log of each channel's noise (the cost's
// and the reference log-determinant's parts) against central differences,
// away from the scale factors' and misalignment's reference values.
TEST(GyroTerm, NoiseGradientMatchesCentralDifferences) {
  const OffReference o = MakeOffReference(3, kGKy, 0.997, kGGammaZ, 4e-4);
  const GyroPass pass = EvaluateGyroPass(o.p, o.th, false, 1);
  const Eigen::Vector3d noise(0.03 * kDegToRad, 0.07 * kDegToRad, 0.05 * kDegToRad);
  const double rho = 0.95;
  Eigen::Vector3d grad;
  const GyroReduction at = ReduceGyroWithNoiseGradient(pass, noise, rho, &grad);
  EXPECT_NEAR(at.neg_log_l, ReduceGyro(pass, noise, rho, false).neg_log_l, 1e-9 * std::abs(at.neg_log_l));
  for (int i = 0; i < 3; ++i) {
    const double h = 1e-5;
    Eigen::Vector3d up = noise, down = noise;
    up[i] *= std::exp(h);
    down[i] *= std::exp(-h);
    const double num = (ReduceGyro(pass, up, rho, false).neg_log_l -
                        ReduceGyro(pass, down, rho, false).neg_log_l) / (2.0 * h);
    EXPECT_NEAR(grad[i], num, 1e-6 * (std::abs(num) + pass.r.size())) << "channel " << i;
  }
}

// The profiled noise is the maximum of the restricted likelihood: a step of
// 1 % either way in any channel does not lower -log L; and it is within 4 sd
// of the truth, the sd from the curvature of -log L in log sigma there (the
// inner-axis channel shares its residual with the angle noise, so its figure
// is the least determined).
TEST(GyroTerm, NoiseIsAtTheLikelihoodMaximum) {
  const GyroRun g = MakeGyroRun(50.0, 30.0, 0.05, 2);
  const RunProblem p = BuildRunProblem(g.s.run, g.data, g.layout, 0.5, {});
  const GyroPass pass = EvaluateGyroPass(p, g.truth, false, 1);
  const GyroReduction best = ReduceGyroAtBestNoise(pass, Eigen::Vector3d::Constant(1e-3), 21, false);
  auto f = [&](const Eigen::Vector3d& s) {
    return ReduceGyro(pass, s.array().exp(), best.rho, false).neg_log_l;
  };
  const Eigen::Vector3d s0 = best.noise_rad_s.array().log();
  const double h = 1e-2;
  Eigen::Matrix3d H;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Eigen::Vector3d pp = s0, pm = s0, mp = s0, mm = s0;
      pp[i] += h, pp[j] += h;
      pm[i] += h, pm[j] -= h;
      mp[i] -= h, mp[j] += h;
      mm[i] -= h, mm[j] -= h;
      H(i, j) = (f(pp) - f(pm) - f(mp) + f(mm)) / (4.0 * h * h);
    }
  }
  const Eigen::Vector3d sd_log = H.inverse().diagonal().cwiseSqrt();
  for (int i = 0; i < 3; ++i) {
    std::printf("channel %d: %.4f deg/s, sd %.1f %%\n", i, best.noise_rad_s[i] / kDegToRad,
                100.0 * sd_log[i]);
    EXPECT_LT(std::abs(s0[i] - std::log(0.05 * kDegToRad)), 4.0 * sd_log[i]) << i;
    for (double fct : {0.99, 1.01}) {
      Eigen::Vector3d s = best.noise_rad_s;
      s[i] *= fct;
      EXPECT_GE(ReduceGyro(pass, s, best.rho, false).neg_log_l, best.neg_log_l - 1e-9) << i;
    }
  }
  // From starts 90 times too small and 60 times too large (the common scale's
  // jump, then Newton's steps): the same maximum.
  for (double start : {1e-5, 5e-2}) {
    const GyroReduction far =
        ReduceGyroAtBestNoise(pass, Eigen::Vector3d::Constant(start), 21, false);
    const double rel = ((far.noise_rad_s - best.noise_rad_s).array() / best.noise_rad_s.array())
                           .abs()
                           .maxCoeff();
    EXPECT_LT(rel, 1e-6) << "start " << start;
  }
}

// The Cramer-Rao bound of the gyro's parameters from its readings model alone
// (SPEC section 10), the input rate and W known exactly at every sample: the
// information sum_k J_k^T J_k / sigma^2, J_k = dG_k / d theta_gyro.
Eigen::VectorXd ReadingsModelBound(const GyroRun& g, const Eigen::Vector3d& noise_rad_s) {
  using J = ceres::Jet<double, kNumGyroParams>;
  const ModelConfig cfg = MakeModelConfig(g.s.run, g.layout, g.data);
  std::vector<J> th(g.truth.size());
  for (int i = 0; i < g.truth.size(); ++i) th[i] = J(g.truth[i]);
  for (int j = 0; j < kNumGyroParams; ++j) th[g.layout.gyro_offset() + j].v[j] = 1.0;
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(kNumGyroParams, kNumGyroParams);
  for (std::size_t k = 0; k < g.data.size(); ++k) {
    const BenchAngles<J> b = CastAngles<J>(g.s.profile.At(g.data.t_s[k]));
    const Vec3<J> G = PredictGyroReadings<J>(cfg, th.data(), b);
    for (int i = 0; i < 3; ++i) info += G[i].v * G[i].v.transpose() / std::pow(noise_rad_s[i], 2);
  }
  return info.inverse().diagonal().cwiseSqrt();
}

// fit on the paper's profile with a gyro: every gyro parameter within 4 sigma
// of its truth on every seed; sigma within 0.85-1.2 of the readings model's
// Cramer-Rao bound at the noise the fit estimated (the angle noise, 15'',
// costs the increments a little). The bound knows the input rate, so the
// fit's sigma is taken given dlambda2 (the common rotation of both triads
// about the inner axis: the gyro's gamma_y, gamma_z are as good as dlambda2).
TEST(GyroTerm, FitRecoversTheGyroWithinItsSigma) {
  for (std::uint64_t seed : {11, 12, 13}) {
    const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, seed);
    BatchOptions opt;
    const BatchResult r = SolveBatch(g.s.run, g.data, g.layout, opt);
    ASSERT_TRUE(r.converged) << r.termination;
    ASSERT_TRUE(r.gyro.present);
    EXPECT_NEAR(r.gyro.noise_rad_s.maxCoeff() / kDegToRad, 0.05, 0.01);
    const int go = g.layout.gyro_offset();
    const Eigen::VectorXd crb = ReadingsModelBound(g, r.gyro.noise_rad_s);
    const Eigen::VectorXd c_l = r.estimate.cov.col(kDlambda2);
    const Eigen::MatrixXd cov_given_l2 = r.estimate.cov - c_l * c_l.transpose() / c_l[kDlambda2];
    std::printf("seed %d noise %.4f %.4f %.4f deg/s sigma %s\n", static_cast<int>(seed),
                r.gyro.noise_rad_s[0] / kDegToRad, r.gyro.noise_rad_s[1] / kDegToRad,
                r.gyro.noise_rad_s[2] / kDegToRad, r.sigma_method.c_str());
    for (int j = 0; j < kNumGyroParams; ++j) {
      const int i = go + j;
      const std::string& name = g.layout.info(i).name;
      ASSERT_TRUE(IsEstimated(r, name)) << name << " seed " << seed;
      const double sigma = std::sqrt(r.estimate.cov(i, i));
      ASSERT_GT(sigma, 0.0) << name;
      const double sigma_given = std::sqrt(cov_given_l2(i, i));
      std::printf("%-16s sigma %.4g given dlambda2 %.4g crb %.4g ratio %.3f\n", name.c_str(), sigma,
                  sigma_given, crb[j], sigma_given / crb[j]);
      EXPECT_GT(sigma_given / crb[j], 0.85) << name;
      EXPECT_LT(sigma_given / crb[j], 1.2) << name;
      EXPECT_LT(std::abs(r.estimate.theta[i] - g.truth[i]) / sigma, 4.0)
          << name << " seed " << seed << " value " << r.estimate.theta[i] << " truth "
          << g.truth[i] << " sigma " << sigma;
    }
  }
}

// The increment's quadrature: on a fast profile at a low rate (50 Hz, the
// paper's amplitudes doubled and its periods halved: the inner axis at a 6-s
// period, 188 deg/s peak) the trapezoid rule alone integrated the inner
// axis's rate 3.7e-5 short, and the fit took it into gyro.Kx: 6-7 sigma on
// every seed. With its Euler-Maclaurin end correction gyro.Kx is within its
// sigma's spread.
TEST(GyroTerm, FastTurnsAtALowRateLeaveTheScaleUnbiased) {
  double sum_z2 = 0.0;
  const std::vector<std::uint64_t> seeds = {61, 62, 63, 64};
  for (std::uint64_t seed : seeds) {
    const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, seed, {}, {}, [](Scenario* s) {
      for (int i = 0; i < 2; ++i) {
        s->profile.amplitude_rad[i] *= 2.0;
        s->profile.period_s[i] *= 0.5;
      }
    });
    const BatchResult r = SolveBatch(g.s.run, g.data, g.layout, BatchOptions{});
    ASSERT_TRUE(r.converged) << r.termination;
    const int i = g.layout.gyro_offset() + kGKx;
    const double sigma = std::sqrt(r.estimate.cov(i, i));
    const double z = (r.estimate.theta[i] - g.truth[i]) / sigma;
    std::printf("seed %d gyro.Kx %.7f +- %.2g (truth %.7f) z %.2f\n", static_cast<int>(seed),
                r.estimate.theta[i], sigma, g.truth[i], z);
    EXPECT_LT(std::abs(z), 4.0) << "seed " << seed;
    sum_z2 += z * z;
  }
  EXPECT_LT(std::sqrt(sum_z2 / seeds.size()), 2.0);
}

// `observability` carries the gyro (DataInformation): on the paper's profile
// each gyro parameter's Cramer-Rao bound within 0.85-1.2 of the readings
// model's (given dlambda2, as the fit's sigma above); with the outer axis
// still, the inner axis turns frame 2 about its x alone, so gyro.Kx is
// determined and gyro.Ky, gyro.Kz are named in unobservable directions.
TEST(GyroTerm, ObservabilityBoundsTheGyroAndNamesWhatASingleAxisLeaves) {
  const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, 31);
  const RunProblem p = BuildRunProblem(g.s.run, g.data, g.layout, kDefaultEpoch_s, {});
  const ObservabilityResult r = AnalyseObservability(g.s.run, p, g.truth);
  const Eigen::MatrixXd& C = r.with_constraints.cov;
  ASSERT_EQ(C.rows(), g.layout.size());
  const Eigen::VectorXd c_l = C.col(kDlambda2);
  const Eigen::MatrixXd given_l2 = C - c_l * c_l.transpose() / c_l[kDlambda2];
  const Eigen::VectorXd crb = ReadingsModelBound(g, g.s.run.gyro->noise_rad_s);
  const int go = g.layout.gyro_offset();
  for (int j = 0; j < kNumGyroParams; ++j) {
    const std::string& name = g.layout.info(go + j).name;
    const double ratio = std::sqrt(given_l2(go + j, go + j)) / crb[j];
    EXPECT_GT(ratio, 0.85) << name;
    EXPECT_LT(ratio, 1.2) << name;
  }

  const GyroRun one = MakeGyroRun(50.0, 90.0, 0.05, 32, {}, {},
                                  [](Scenario* s) { s->profile.amplitude_rad[0] = 0.0; });
  const RunProblem p1 = BuildRunProblem(one.s.run, one.data, one.layout, kDefaultEpoch_s, {});
  const ObservabilityResult r1 = AnalyseObservability(one.s.run, p1, one.truth);
  std::set<std::string> named;
  for (const Direction& d : r1.with_constraints.unobservable) {
    for (const auto& [name, weight] : d.named.weights) {
      if (std::abs(weight) >= 0.2) named.insert(name);
    }
  }
  EXPECT_TRUE(named.count("gyro.Ky")) << "gyro.Ky not named";
  EXPECT_TRUE(named.count("gyro.Kz")) << "gyro.Kz not named";
  EXPECT_FALSE(named.count("gyro.Kx")) << "gyro.Kx named";
  const int kx = one.layout.IndexOf("gyro.Kx");
  EXPECT_LT(std::sqrt(r1.with_constraints.cov(kx, kx)), 0.01 * r1.prior.sigma[kx]);
}

// The angles lag the bench by 8 ms (angle_latency, in the data of both
// triads): declared, it is one time offset between the angles and both
// triads, estimated with the gyro's parameters; each within 4 sigma.
TEST(GyroTerm, SharedTimeOffsetIsEstimated) {
  const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, 21, {Effect::kAngleLatency},
                                {{"angle_latency.tau", 8.0}});
  const RunProblem p = BuildRunProblem(g.s.run, g.data, g.layout, 0.5, {});
  // The residual's Jacobian by tau against central differences.
  const int tau = g.layout.offset(Effect::kAngleLatency);
  const GyroPass pass = EvaluateGyroPass(p, g.truth, true, 1);
  Eigen::VectorXd tp = g.truth, tm = g.truth;
  const double h = 1e-6;
  tp[tau] += h;
  tm[tau] -= h;
  const GyroPass a = EvaluateGyroPass(p, tp, false, 1), b = EvaluateGyroPass(p, tm, false, 1);
  double worst = 0.0, scale = 0.0;
  for (std::size_t e = 0; e < pass.r.size(); ++e) {
    const Eigen::Vector3d num = (a.r[e] - b.r[e]) / (2.0 * h);
    worst = std::max(worst, (num - pass.J[e].col(tau)).cwiseAbs().maxCoeff());
    scale = std::max(scale, num.cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, 1e-5 * scale);
  const BatchResult r = SolveBatch(g.s.run, g.data, g.layout, BatchOptions{});
  ASSERT_TRUE(r.converged) << r.termination;
  for (int i = 0; i < g.layout.size(); ++i) {
    const std::string& name = g.layout.info(i).name;
    if (!g.layout.is_gyro(i) && i != tau) continue;
    ASSERT_TRUE(IsEstimated(r, name)) << name;
    const double z = (r.estimate.theta[i] - g.truth[i]) / std::sqrt(r.estimate.cov(i, i));
    EXPECT_LT(std::abs(z), 4.0) << name << " value " << r.estimate.theta[i] << " truth " << g.truth[i];
  }
}

// The gyro-stage effects (gyro_model.h): d r / d theta by dK, k2 and the
// columns their inverse changes (K, W0, G, the angles) against central
// differences, at values off the truth; then the fit with each effect in the
// data and in the layout recovers it within 4 sigma, and the gyro's residual
// falls against the fit without it.
TEST(GyroTerm, JacobianByTheGyroEffectsMatchesCentralDifferences) {
  const std::vector<Effect> fx = {Effect::kGyroScaleAsymmetry, Effect::kGyroNonlinearity};
  const GyroRun g = MakeGyroRun(50.0, 10.0, 0.05, 2, fx,
                                {{"gyro_scale_asymmetry.dKx", 3000.0},
                                 {"gyro_scale_asymmetry.dKy", -2000.0},
                                 {"gyro_nonlinearity.k2_x", 0.3},
                                 {"gyro_nonlinearity.k2_z", -0.2}});
  const RunProblem p = BuildRunProblem(g.s.run, g.data, g.layout, 0.5, {});
  Eigen::VectorXd th = g.truth;
  const int go = g.layout.gyro_offset();
  const int o_a = g.layout.offset(Effect::kGyroScaleAsymmetry);
  const int o_q = g.layout.offset(Effect::kGyroNonlinearity);
  th[go + kGKy] *= 1.01;
  th[o_a + 2] += 1e-3;
  th[o_q + 1] += 0.5 * g.layout.info(o_q).si_per_unit;
  const GyroPass pass = EvaluateGyroPass(p, th, true, 1);
  std::vector<int> cols = {kDlambda2, kKx, kW0y};
  for (int j = 0; j < kNumGyroParams; ++j) cols.push_back(go + j);
  for (int i = 0; i < 3; ++i) {
    cols.push_back(o_a + i);
    cols.push_back(o_q + i);
  }
  for (int c : cols) {
    const double h = 1e-6 * std::max(std::abs(th[c]), c >= o_q && c < o_q + 3 ? 1e-3 : 1.0);
    double worst = 0.0, scale = 0.0;
    CentralDifference(p, th, pass, c, h, &worst, &scale);
    EXPECT_GT(scale, 0.0) << g.layout.info(c).name;
    EXPECT_LE(worst, 1e-5 * scale + 1e-12) << g.layout.info(c).name;
  }
}

TEST(GyroTerm, FitRecoversEachGyroEffect) {
  struct Case {
    Effect effect;
    NamedValues truth;
  };
  const std::vector<Case> cases = {
      {Effect::kGyroScaleAsymmetry,
       {{"gyro_scale_asymmetry.dKx", 3000.0}, {"gyro_scale_asymmetry.dKy", -2000.0},
        {"gyro_scale_asymmetry.dKz", 1000.0}}},
      {Effect::kGyroNonlinearity,
       {{"gyro_nonlinearity.k2_x", 0.05}, {"gyro_nonlinearity.k2_y", -0.2},
        {"gyro_nonlinearity.k2_z", 0.15}}}};
  for (const Case& c : cases) {
    const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, 41, {c.effect}, c.truth);
    // The hold rule decides at the nominal values with the gyro's declared
    // noise: k2_y and k2_z, whose fitted sigma are 6-9 times below the
    // prior's, are estimated. (With the gyro noise profiled there, the
    // nominal values' misfit took it up and the rule kept none of k2.)
    const BatchResult with = SolveBatch(g.s.run, g.data, g.layout, BatchOptions{});
    const BatchResult without =
        SolveBatch(g.s.run, g.data, g.layout.WithEffects({}), BatchOptions{});
    ASSERT_TRUE(with.converged) << with.termination;
    ASSERT_TRUE(without.converged) << without.termination;
    const EffectSpec& spec = GetEffectSpec(c.effect);
    for (int i = g.layout.offset(c.effect); i < g.layout.offset(c.effect) + 3; ++i) {
      std::printf("  hold rule: %s information left %.3g (prior units, 10 kept)\n",
                  g.layout.info(i).name.c_str(),
                  with.conditional_information.size() ? with.conditional_information[i] : -1.0);
    }
    std::printf("%s: gyro noise %.4f -> %.4f deg/s, whitened rms %.3f -> %.3f, nll %.1f -> %.1f\n",
                spec.name.c_str(), without.gyro.noise_rad_s.maxCoeff() / kDegToRad,
                with.gyro.noise_rad_s.maxCoeff() / kDegToRad, without.gyro.whitened_rms,
                with.gyro.whitened_rms, without.gyro.neg_log_likelihood,
                with.gyro.neg_log_likelihood);
    EXPECT_LT(with.gyro.neg_log_likelihood, without.gyro.neg_log_likelihood - 10.0);
    EXPECT_NEAR(with.gyro.noise_rad_s.maxCoeff() / kDegToRad, 0.05, 0.01);
    const int o = g.layout.offset(c.effect);
    int estimated = 0;
    for (int i = o; i < o + 3; ++i) {
      const std::string& name = g.layout.info(i).name;
      // The inner axis's (x) k2: its rate is one sine (47 deg/s peak), whose
      // cube is 0.95 correlated with itself: not determined on this profile
      // (considered at nominal, within its prior).
      if (!IsEstimated(with, name)) {
        std::printf("  %-26s not determined on this profile\n", name.c_str());
        EXPECT_EQ(name, "gyro_nonlinearity.k2_x");
        continue;
      }
      ++estimated;
      const double sigma = std::sqrt(with.estimate.cov(i, i));
      const double f = g.layout.info(i).si_per_unit;
      std::printf("  %-26s %9.4g +- %.3g (truth %.4g) %s, z %.2f\n", name.c_str(),
                  with.estimate.theta[i] / f, sigma / f, g.truth[i] / f,
                  g.layout.info(i).unit.c_str(), (with.estimate.theta[i] - g.truth[i]) / sigma);
      EXPECT_LT(std::abs(with.estimate.theta[i] - g.truth[i]) / sigma, 4.0) << name;
    }
    EXPECT_GE(estimated, 2);
  }
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// SPEC section 10's figure: 20 seeds of the paper run (50 Hz, 90 s, gyro noise
// 0.05 deg/s): every gyro parameter within 4 sigma, RMS of error / sigma per
// group within 0.85-1.15; the accelerometer's estimates as without the gyro
// (the gyro shares only dlambda2 with them) to 0.1 sigma.
TEST(GyroTerm, NormalisedErrorsOverTwentySeeds) {
  const char* groups[4] = {"scale", "bias", "misalignment", "g-sensitivity"};
  auto group_of = [](int j) { return j <= kGKz ? 0 : j <= kGW0z ? 1 : j <= kGGammaZ ? 2 : 3; };
  double ss[4] = {0, 0, 0, 0};
  int count[4] = {0, 0, 0, 0};
  double worst_acc = 0.0;
  std::vector<double> per(kNumGyroParams, 0.0);
  Eigen::Vector3d noise_sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_tied = Eigen::Vector3d::Zero();  // accelerometer gamma_y, gamma_z, dlambda2
  const char* env = std::getenv("TRIADCAL_GYRO_SEEDS");
  const int seeds = env ? std::atoi(env) : 20;
  const char* first = std::getenv("TRIADCAL_GYRO_FIRST_SEED");
  const std::uint64_t seed0 = first ? std::atoi(first) : 100;
  for (std::uint64_t seed = seed0; seed < seed0 + static_cast<std::uint64_t>(seeds); ++seed) {
    const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, seed);
    BatchOptions bo;
    if (std::getenv("TRIADCAL_GYRO_VERBOSE")) {
      bo.progress = [](const std::string& l) { std::printf("  %s\n", l.c_str()); };
    }
    const BatchResult r = SolveBatch(g.s.run, g.data, g.layout, bo);
    ASSERT_TRUE(r.converged) << r.termination << " seed " << seed;
    const int go = g.layout.gyro_offset();
    for (int j = 0; j < kNumGyroParams; ++j) {
      const int i = go + j;
      const double z = (r.estimate.theta[i] - g.truth[i]) / std::sqrt(r.estimate.cov(i, i));
      EXPECT_LT(std::abs(z), 4.0) << g.layout.info(i).name << " seed " << seed;
      ss[group_of(j)] += z * z;
      per[j] += z * z / seeds;
      ++count[group_of(j)];
    }
    noise_sum += r.gyro.noise_rad_s / kDegToRad / seeds;
    for (int q = 0; q < 3; ++q) {
      const int i = q == 0 ? kGammaY : q == 1 ? kGammaZ : kDlambda2;
      const double z = (r.estimate.theta[i] - g.truth[i]) / std::sqrt(r.estimate.cov(i, i));
      acc_tied[q] += z * z / seeds;
    }
    RunDescription without = g.s.run;
    without.gyro.reset();
    const BatchResult a = SolveBatch(without, g.data, ParameterLayout(), BatchOptions{});
    for (int i = 0; i < kNumBaseParams; ++i) {
      if (!(a.estimate.cov(i, i) > 0.0)) continue;
      worst_acc = std::max(worst_acc, std::abs(r.estimate.theta[i] - a.estimate.theta[i]) /
                                          std::sqrt(a.estimate.cov(i, i)));
    }
  }
  for (int j = 0; j < kNumGyroParams; ++j) {
    std::printf("  %-16s RMS z %.2f\n", ParameterLayout({}, true).info(kNumBaseParams + j).name.c_str(),
                std::sqrt(per[j]));
  }
  std::printf("accelerometer gamma_y gamma_z dlambda2: RMS z %.2f %.2f %.2f\n",
              std::sqrt(acc_tied[0]), std::sqrt(acc_tied[1]), std::sqrt(acc_tied[2]));
  std::printf("mean noise estimate %.4f %.4f %.4f deg/s\n", noise_sum[0], noise_sum[1], noise_sum[2]);
  for (int k = 0; k < 4; ++k) {
    const double rms = std::sqrt(ss[k] / count[k]);
    std::printf("%-14s RMS z %.3f over %d\n", groups[k], rms, count[k]);
    EXPECT_GT(rms, 0.85) << groups[k];
    EXPECT_LT(rms, 1.15) << groups[k];
  }
  std::printf("accelerometer: largest change with the gyro %.3f sigma\n", worst_acc);
  EXPECT_LT(worst_acc, 0.1);
}

}  // namespace
}  // namespace triadcal
