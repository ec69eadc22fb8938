// Several runs of one IMU as one problem: the mounting map against the model,
// one run against its own fit, two single-axis runs with different shafts,
// runs at several temperatures, a run whose mounting changed, and bad input.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <random>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "core/model/bench_model.h"
#include "core/model/errors.h"
#include "core/model/gyro_model.h"
#include "core/model/mounting.h"
#include "solvers/multirun/joint_layout.h"
#include "solvers/multirun/joint_solver.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

void SetMounting(RunDescription* run, const int source[3], const double sign[3]) {
  for (int i = 0; i < 3; ++i) {
    run->axis_source[i] = source[i];
    run->axis_sign[i] = sign[i];
  }
}

// The platform readings of a mounted triad are the IMU's readings of the
// specific force in its own axes, remapped: W_p = P^T-rotated, u_p = P u.
TEST(MountingMap, ReadingsOfTheMappedParametersAreTheRemappedReadings) {
  const ParameterLayout layout(
      {Effect::kScaleAsymmetry, Effect::kThermalDrift, Effect::kCrossQuadratic});
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  const int sources[3][3] = {{1, 0, 2}, {2, 1, 0}, {1, 2, 0}};
  const double signs[3][3] = {{1, 1, -1}, {-1, 1, 1}, {-1, -1, 1}};
  for (int m = 0; m < 3; ++m) {
    RunDescription run;
    SetMounting(&run, sources[m], signs[m]);
    const ModelConfig cfg = MakeModelConfig(run, layout);
    Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
    for (int i = 0; i < 3; ++i) P(i, sources[m][i]) = signs[m][i];
    Eigen::VectorXd imu = Eigen::VectorXd::Zero(layout.size());
    for (int i = 0; i < layout.size(); ++i) imu[i] = 1e-3 * gauss(rng);
    for (int i = 0; i < 3; ++i) {
      imu[kKx + i] = 170.0 + i;
      imu[kW0x + i] = 1500.0 + 3.0 * i;
      imu[layout.offset(Effect::kScaleAsymmetry) + i] = 2.0 + i;
      imu[layout.offset(Effect::kThermalDrift) + i] = 0.01 * (i + 1);
    }
    const Eigen::VectorXd platform = MountingMap(run, layout) * imu;
    for (int k = 0; k < 5; ++k) {
      const Eigen::Vector3d W(gauss(rng), gauss(rng), gauss(rng));
      const SampleContext ctx{12.0, 25.0};
      const Eigen::Vector3d up = Readings_mV(cfg, platform.data(), W, ctx);
      const Eigen::Vector3d ui = Readings_mV(cfg, imu.data(), Eigen::Vector3d(P.transpose() * W), ctx);
      EXPECT_LT((up - P * ui).cwiseAbs().maxCoeff(), 1e-9) << "mounting " << m;
    }
  }
}

// The gyro shares the IMU's axes (SPEC section 10): the gyro readings of the
// mapped parameters are the IMU's gyro readings of the rate and specific force
// in its own axes, remapped.
TEST(MountingMap, GyroReadingsOfTheMappedParametersAreTheRemappedReadings) {
  const ParameterLayout layout({Effect::kThermalDrift}, /*gyro=*/true);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> gauss;
  const int sources[3][3] = {{1, 0, 2}, {2, 1, 0}, {1, 2, 0}};
  const double signs[3][3] = {{1, 1, -1}, {-1, 1, 1}, {-1, -1, 1}};
  const int g = layout.gyro_offset();
  for (int m = 0; m < 3; ++m) {
    RunDescription run;
    SetMounting(&run, sources[m], signs[m]);
    const ModelConfig cfg = MakeModelConfig(run, layout);
    Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
    for (int i = 0; i < 3; ++i) P(i, sources[m][i]) = signs[m][i];
    Eigen::VectorXd imu = Eigen::VectorXd::Zero(layout.size());
    for (int i = 0; i < layout.size(); ++i) imu[i] = 1e-2 * gauss(rng);
    for (int i = 0; i < 3; ++i) {
      imu[kKx + i] = 170.0 + i;
      imu[g + kGKx + i] = (i == 1 ? -1.0 : 1.0) + 0.01 * i;
    }
    const Eigen::VectorXd platform = MountingMap(run, layout) * imu;
    for (int k = 0; k < 5; ++k) {
      const Eigen::Vector3d W(gauss(rng), gauss(rng), gauss(rng));
      const Eigen::Vector3d w(gauss(rng), gauss(rng), gauss(rng));
      const Eigen::Vector3d gp = GyroReadings(cfg, platform.data(), w, W);
      const Eigen::Vector3d gi = GyroReadings(cfg, imu.data(), Eigen::Vector3d(P.transpose() * w),
                                              Eigen::Vector3d(P.transpose() * W));
      EXPECT_LT((gp - P * gi).cwiseAbs().maxCoeff(), 1e-12) << "mounting " << m;
    }
  }
}

JointRun MakeRun(const std::string& name, const Scenario& s) {
  JointRun r;
  r.name = name;
  r.source = name;
  r.run = s.run;
  r.run.yaml_path = name + ".yaml";
  r.run.data_path = name + ".csv";
  r.data = Simulate(s);
  r.temperature_C = 20.0;
  return r;
}

JointOptions Options() {
  JointOptions o;
  o.batch.threads = 2;
  return o;
}

TEST(JointFit, OneRunGivesItsOwnFit) {
  const Scenario s = PaperScenario(50.0, 40.0, 2.0, 15.0, 11);
  const std::vector<JointRun> runs = {MakeRun("a", s)};
  const JointLayout jl(runs, ParameterLayout(), {}, "test");
  const JointResult r = SolveJoint(runs, jl, Options());
  ASSERT_TRUE(r.converged);
  const BatchResult& alone = r.runs[0].alone;
  for (int j = 0; j < jl.size(); ++j) {
    const int i = jl.param(j).base;
    const double sigma = std::sqrt(alone.estimate.cov(i, i));
    EXPECT_NEAR((r.phi[j] - alone.estimate.theta[i]) / sigma, 0.0, 0.05) << jl.param(j).name;
    EXPECT_NEAR(std::sqrt(r.cov(j, j)) / sigma, 1.0, 0.02) << jl.param(j).name;
  }
  EXPECT_TRUE(r.runs[0].consistency.consistent);
  EXPECT_LT(r.runs[0].consistency.chi2, 1.0);
}

// Two runs of one IMU whose scale factor Kx differs by 20 of its sigma (a
// turn-on change, or a run that is not what it claims): the joint fit names
// Kx, and its sigma carries the spread (half the difference for two equal
// runs: the joint value sits between them) instead of shrinking by sqrt(2);
// the parameters on which the runs agree keep their sigma.
TEST(JointFit, SpreadBetweenDisagreeingRunsIsCarriedInTheSigmaAndNamed) {
  const Scenario a = PaperScenario(50.0, 40.0, 2.0, 15.0, 31);
  Scenario b = a;
  b.seed = 32;
  const std::vector<JointRun> one = {MakeRun("a", a)};
  const JointLayout jl1(one, ParameterLayout(), {}, "test");
  const JointResult r1 = SolveJoint(one, jl1, Options());
  const double single = std::sqrt(r1.cov(jl1.IndexOf("Kx"), jl1.IndexOf("Kx")));
  const double delta = 20.0 * single;
  b.truth[kKx] += delta;
  const std::vector<JointRun> runs = {MakeRun("a", a), MakeRun("b", b)};
  const JointLayout jl(runs, ParameterLayout(), {}, "test");
  const JointResult r = SolveJoint(runs, jl, Options());
  ASSERT_TRUE(r.converged);
  const int kx = jl.IndexOf("Kx");
  const BetweenRuns* between_kx = nullptr;
  int flagged = 0;
  for (const BetweenRuns& bt : r.between) {
    if (bt.index == kx) {
      between_kx = &bt;
    } else {
      // At between_alpha 0.05 over 19 agreeing unknowns about one is flagged
      // by chance (seeds 31, 32: Kz, Q 4.8 for 1, p 0.03).
      if (bt.disagree) ++flagged;
    }
  }
  EXPECT_LE(flagged, 1);
  ASSERT_NE(between_kx, nullptr);
  EXPECT_TRUE(between_kx->disagree);
  EXPECT_EQ(between_kx->runs, 2);
  EXPECT_NEAR(between_kx->tau / delta, 1.0 / std::sqrt(2.0), 0.15);
  const double joint = std::sqrt(r.cov(kx, kx));
  EXPECT_GT(joint, 0.4 * delta);
  EXPECT_GT(joint, 0.5 * single);
  // Each run's truth within 2 sigma of the joint value.
  EXPECT_LT(std::abs(r.phi[kx] - a.truth[kKx]) / joint, 2.0);
  EXPECT_LT(std::abs(r.phi[kx] - b.truth[kKx]) / joint, 2.0);
}

// --hold with a per-run parameter's bare name holds it in every run, jointly
// and in each run's fit alone; "NAME@RUN" in that run only; an unknown name is
// refused before any run is fitted (the runs alone of real 25-min runs take
// minutes each).
TEST(JointFit, HoldByBareNameHoldsInEveryRunAndInEachFitAlone) {
  const std::vector<JointRun> runs = {MakeRun("a", PaperScenario(50.0, 20.0, 2.0, 15.0, 21)),
                                      MakeRun("b", PaperScenario(50.0, 20.0, 2.0, 15.0, 22))};
  const JointLayout jl(runs, ParameterLayout(), {}, "test");
  JointOptions o = Options();
  o.batch.holding.hold = {"dpsi", "dx2@b"};
  const JointResult r = SolveJoint(runs, jl, o);
  std::set<std::string> held;
  for (int j : r.held) held.insert(jl.param(j).name);
  EXPECT_TRUE(held.count("dpsi@a"));
  EXPECT_TRUE(held.count("dpsi@b"));
  EXPECT_TRUE(held.count("dx2@b"));
  EXPECT_FALSE(held.count("dx2@a"));
  auto has = [](const std::vector<std::string>& v, const std::string& n) {
    return std::find(v.begin(), v.end(), n) != v.end();
  };
  EXPECT_TRUE(has(r.runs[0].alone.held, "dpsi"));
  EXPECT_FALSE(has(r.runs[0].alone.held, "dx2"));
  EXPECT_TRUE(has(r.runs[1].alone.held, "dpsi"));
  EXPECT_TRUE(has(r.runs[1].alone.held, "dx2"));

  o.batch.holding.hold = {"dpsy"};
  int progress_lines = 0;
  o.batch.progress = [&](const std::string&) { ++progress_lines; };
  try {
    SolveJoint(runs, jl, o);
    ADD_FAILURE() << "an unknown --hold name was accepted";
  } catch (const OptionError& e) {
    EXPECT_EQ(std::string(e.what()),
              "hold: unknown parameter 'dpsy' in this joint fit (a shared parameter such as "
              "Kx, a per-run one such as dpsi@RUN, or dpsi for every run)");
  }
  EXPECT_EQ(progress_lines, 0) << "refused only after work on the runs had begun";
}

// A single-axis run: the outer axis (platform y) turns, the inner stays at 0.
Scenario SingleAxis(std::uint64_t seed) {
  Scenario s = PaperScenario(50.0, 60.0, 2.0, 15.0, seed);
  s.profile.amplitude_rad[0] = 360.0 * kDegToRad;
  s.profile.amplitude_rad[1] = 0.0;
  return s;
}

// Run a: shaft along the IMU's y. Run b: the IMU turned so that its x lies
// along the shaft, platform (x, y, z) = IMU (+y, +x, -z), with its own set-up
// errors. truth_a is also the IMU's truth (run a has no mounting).
std::vector<JointRun> TwoShaftRuns(std::uint64_t seed_a, std::uint64_t seed_b,
                                   Eigen::VectorXd* truth_a, Eigen::VectorXd* truth_b) {
  Scenario a = SingleAxis(seed_a);
  Scenario b = SingleAxis(seed_b);
  const int src[3] = {1, 0, 2};
  const double sgn[3] = {1, 1, -1};
  SetMounting(&b.run, src, sgn);
  const Eigen::MatrixXd mount = MountingMap(b.run, ParameterLayout());
  b.truth = mount * a.truth;
  b.truth[kDpsi] = b.truth[kDlambda2] = 12.0 * kArcminToRad;
  b.truth[kDthetaC] = -20.0 * kArcminToRad;
  b.run.scale_mV_per_g = mount.block<3, 3>(kKx, kKx) * a.run.scale_mV_per_g;
  b.run.bias_mV = mount.block<3, 3>(kW0x, kW0x) * a.run.bias_mV;
  *truth_a = a.truth;
  *truth_b = b.truth;
  return {MakeRun("a", a), MakeRun("b", b)};
}

TEST(JointFit, TwoSingleAxisRunsWithDifferentShaftsDetermineWhatNeitherDoesAlone) {
  const ParameterLayout layout;
  double sum_z2 = 0.0;
  int count = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Eigen::VectorXd imu_truth, truth_b;
    const std::vector<JointRun> runs = TwoShaftRuns(seed, seed + 100, &imu_truth, &truth_b);
    const JointLayout jl(runs, layout, {}, "test");
    const JointResult r = SolveJoint(runs, jl, Options());
    ASSERT_TRUE(r.converged) << "seed " << seed;
    // Alone, each holds the nonlinearity of the axis along its shaft (it
    // never sees gravity) and the tilt about it: Kyy (platform) is IMU Kyy
    // in run a and IMU Kxx in run b, so each is estimated by one run. The
    // tilts need the misalignments the other run fixes: estimated only
    // together.
    for (const JointRunResult& rr : r.runs) {
      EXPECT_FALSE(IsEstimated(rr.alone, "Kyy")) << rr.name << " seed " << seed;
      EXPECT_FALSE(IsEstimated(rr.alone, "dtheta_c")) << rr.name << " seed " << seed;
    }
    // Together they determine all but what neither run excites: the
    // cross-coupling of the two shaft axes (W_x W_y: no run has both
    // non-zero) and each run's lever arm along its own shaft.
    const std::set<std::string> neither = {"Kxy", "Kyx", "dy2@a", "dy2@b"};
    for (int j : r.held) {
      EXPECT_TRUE(neither.count(jl.param(j).name)) << jl.param(j).name << " seed " << seed;
    }
    for (const char* name : {"dtheta_c@a", "dtheta_c@b"}) {
      EXPECT_TRUE(std::find(r.jointly_only.begin(), r.jointly_only.end(), name) !=
                  r.jointly_only.end())
          << name << " seed " << seed;
    }
    // Run a sees gravity on its y axis only through the bench's tilt (Ky is
    // not determined there); run b turns the IMU's y axis through gravity.
    const int ky = jl.IndexOf("Ky");
    EXPECT_FALSE(IsEstimated(r.runs[0].alone, "Ky"));
    EXPECT_LT(std::sqrt(r.cov(ky, ky)), 0.2 * r.runs[0].alone.prior.sigma[kKy]);
    for (int j = 0; j < jl.size(); ++j) {
      if (jl.param(j).run >= 0 || r.cov(j, j) <= 0.0) continue;
      const double z = (r.phi[j] - imu_truth[jl.param(j).base]) / std::sqrt(r.cov(j, j));
      EXPECT_LT(std::abs(z), 4.5) << jl.param(j).name << " seed " << seed;
      sum_z2 += z * z;
      ++count;
    }
    for (const JointRunResult& rr : r.runs) EXPECT_TRUE(rr.consistency.consistent) << rr.name;
  }
  const double rms = std::sqrt(sum_z2 / count);
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 1.4);
}

// Two runs about the same shaft leave undetermined what one run does; what
// follows a considered unknown one for one comes out at about its prior
// sigma, and the result names it as determined only with that unknown at
// nominal (as a single fit does), never as a value with its sigma alone.
TEST(JointFit, WhatFollowsAConsideredUnknownIsNamedSo) {
  const std::vector<JointRun> runs = {MakeRun("a", SingleAxis(1)), MakeRun("b", SingleAxis(2))};
  const JointLayout jl(runs, ParameterLayout(), {}, "test");
  const JointResult r = SolveJoint(runs, jl, Options());
  ASSERT_TRUE(r.converged);
  ASSERT_FALSE(r.consider.empty());
  // Ky (its sigma 3.7 times its prior's), dpsi of both runs and dlambda2 of
  // one follow considered unknowns.
  EXPECT_GE(r.with_considered.size(), 2u);
  for (int j = 0; j < jl.size(); ++j) {
    if (r.cov(j, j) <= 0.0) continue;
    if (std::sqrt(r.cov(j, j)) > 0.5 * jl.param(j).prior_sigma) {
      EXPECT_TRUE(r.with_considered.count(j)) << jl.param(j).name;
    }
  }
  for (const auto& [j, with] : r.with_considered) {
    ASSERT_FALSE(with.empty()) << jl.param(j).name;
    for (int c : with) {
      EXPECT_NE(std::find(r.consider.begin(), r.consider.end(), c), r.consider.end())
          << jl.param(j).name << " with " << jl.param(c).name;
    }
  }
}

// Four runs at -20, 0, 20, 40 degC with zero offsets and scale factors linear
// in temperature.
std::vector<JointRun> TemperatureRuns(std::uint64_t seed, Eigen::VectorXd* truth_coef,
                                      double rotation_arcmin_of_run_3) {
  const double temps[4] = {-20.0, 0.0, 20.0, 40.0};
  truth_coef->resize(6);
  *truth_coef << 0.05, -0.08, 0.03, 0.01, -0.02, 0.015;  // mV/degC (W0), mV/g/degC (K)
  std::vector<JointRun> runs;
  for (int k = 0; k < 4; ++k) {
    Scenario s = PaperScenario(50.0, 60.0, 2.0, 15.0, 1000 * seed + k);
    for (int i = 0; i < 3; ++i) {
      s.truth[kW0x + i] += (*truth_coef)[i] * (temps[k] - 20.0);
      s.truth[kKx + i] += (*truth_coef)[3 + i] * (temps[k] - 20.0);
    }
    if (k == 3) {
      s.truth[kAlphaX] += rotation_arcmin_of_run_3 * kArcminToRad;
      s.truth[kAlphaY] += rotation_arcmin_of_run_3 * kArcminToRad;
    }
    JointRun r = MakeRun("T" + std::to_string(k), s);
    r.temperature_C = temps[k];
    r.has_temperature = true;
    runs.push_back(std::move(r));
  }
  return runs;
}

JointSpec LinearInTemperature() {
  JointSpec spec;
  for (const char* name : {"W0x", "W0y", "W0z", "Kx", "Ky", "Kz"}) spec.temperature_degree[name] = 1;
  spec.temperature_ref_C = 20.0;
  return spec;
}

TEST(JointFit, RecoversLinearTemperatureCoefficients) {
  double sum_z2 = 0.0;
  int count = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Eigen::VectorXd coef;
    const std::vector<JointRun> runs = TemperatureRuns(seed, &coef, 0.0);
    const JointLayout jl(runs, ParameterLayout(), LinearInTemperature(), "test");
    const JointResult r = SolveJoint(runs, jl, Options());
    ASSERT_TRUE(r.converged);
    const char* names[6] = {"W0x.t1", "W0y.t1", "W0z.t1", "Kx.t1", "Ky.t1", "Kz.t1"};
    for (int c = 0; c < 6; ++c) {
      const int j = jl.IndexOf(names[c]);
      ASSERT_GE(j, 0) << names[c];
      EXPECT_EQ(jl.param(j).unit, c < 3 ? "mV/degC" : "mV/g/degC");
      const double z = (r.phi[j] - coef[c]) / std::sqrt(r.cov(j, j));
      EXPECT_LT(std::abs(z), 4.0) << names[c];
      sum_z2 += z * z;
      ++count;
    }
    for (const JointRunResult& rr : r.runs) EXPECT_TRUE(rr.consistency.consistent) << rr.name;
  }
  const double rms = std::sqrt(sum_z2 / count);
  EXPECT_GT(rms, 0.5);
  EXPECT_LT(rms, 1.5);
}

TEST(JointFit, NamesTheRunWhoseMountingChanged) {
  Eigen::VectorXd coef;
  // Run T3 was remounted 10 arcmin turned about z: its misalignments moved.
  const std::vector<JointRun> runs = TemperatureRuns(4, &coef, 10.0);
  const JointLayout jl(runs, ParameterLayout(), LinearInTemperature(), "test");
  const JointResult r = SolveJoint(runs, jl, Options());
  const RunConsistency& odd = r.runs[3].consistency;
  EXPECT_FALSE(odd.consistent);
  for (int k = 0; k < 3; ++k) EXPECT_LT(r.runs[k].consistency.chi2, odd.chi2);
  ASSERT_FALSE(odd.pulls.empty());
  EXPECT_TRUE(odd.pulls[0].first == "alpha_x" || odd.pulls[0].first == "alpha_y")
      << odd.pulls[0].first;
}

// Without fitting: two runs of the same profile halve the variance of the
// shared parameters; of two single-axis runs with different shafts, each
// alone would hold its shaft's Kyy and tilt, and the tilts are determined
// only together (as the joint fit finds, above).
TEST(JointInformation, TwoRunsHalveTheVarianceAndNameWhatOnlyTogetherDetermine) {
  const Scenario s = PaperScenario(50.0, 40.0, 2.0, 15.0, 21);
  const std::vector<JointRun> one = {MakeRun("a", s)};
  Scenario s2 = s;
  s2.seed = 22;
  const std::vector<JointRun> two = {MakeRun("a", s), MakeRun("b", s2)};
  const JointLayout jl1(one, ParameterLayout(), {}, "test"), jl2(two, ParameterLayout(), {}, "test");
  const JointInformation i1 = JointInformationAtNominal(one, jl1, Options());
  const JointInformation i2 = JointInformationAtNominal(two, jl2, Options());
  for (int i = 0; i < kDpsi; ++i) {
    const std::string name = ParameterLayout().info(i).name;
    const double ratio = std::sqrt(i2.cov(jl2.IndexOf(name), jl2.IndexOf(name)) /
                                   i1.cov(jl1.IndexOf(name), jl1.IndexOf(name)));
    EXPECT_NEAR(ratio, 1.0 / std::sqrt(2.0), 0.03) << name;
    EXPECT_NEAR(i2.share(0, jl2.IndexOf(name)), 0.5, 0.05) << name;
  }
  Eigen::VectorXd ta, tb;
  const std::vector<JointRun> shafts = TwoShaftRuns(1, 101, &ta, &tb);
  const JointLayout jl(shafts, ParameterLayout(), {}, "test");
  const JointInformation info = JointInformationAtNominal(shafts, jl, Options());
  const std::set<std::string> neither = {"Kxy", "Kyx", "dy2@a", "dy2@b"};
  for (int j : info.held) EXPECT_TRUE(neither.count(jl.param(j).name)) << jl.param(j).name;
  for (int r = 0; r < 2; ++r) {
    const auto& h = info.held_alone[r];
    EXPECT_TRUE(std::find(h.begin(), h.end(), "Kyy") != h.end()) << r;
    EXPECT_TRUE(std::find(h.begin(), h.end(), "dtheta_c") != h.end()) << r;
  }
  for (const char* name : {"dtheta_c@a", "dtheta_c@b"}) {
    EXPECT_TRUE(std::find(info.jointly_only.begin(), info.jointly_only.end(), name) !=
                info.jointly_only.end())
        << name;
  }
}

TEST(JointLayoutErrors, RejectsRunsOfAnotherImuARunListedTwiceAndUnknownNames) {
  const Scenario s = PaperScenario(50.0, 10.0, 2.0, 15.0, 1);
  JointRun a = MakeRun("a", s), b = MakeRun("b", s);
  const ParameterLayout layout;
  auto message = [&](const std::vector<JointRun>& runs, const JointSpec& spec) {
    try {
      JointLayout jl(runs, layout, spec, "runs.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  JointRun other = b;
  other.run.scale_mV_per_g[1] = 300.0;
  EXPECT_EQ(message({a, other}, {}),
            "runs.yaml: run 'b' (b.yaml) declares another IMU: its triad in the IMU's own axes "
            "(mounting undone) has scale_mV_per_g [174, 300, 174] and bias_mV [1500, 1500, "
            "1500], run 'a' has [174, 174, 174] and [1500, 1500, 1500] (runs of one IMU declare "
            "the same nominal triad)");
  JointRun twice = a;
  twice.name = "a2";
  twice.source = "a2";
  EXPECT_EQ(message({a, twice}, {}),
            "runs.yaml: run 'a2' (a2) is run 'a' (a) again: the same data a.csv (a run listed "
            "twice)");
  JointSpec spec;
  spec.per_run = {"W0q"};
  EXPECT_EQ(message({a, b}, spec),
            "runs.yaml: per_run: 'W0q' is not a parameter (see `triadcal params`)");
  spec.per_run = {"dpsi"};
  EXPECT_EQ(message({a, b}, spec),
            "runs.yaml: per_run: 'dpsi' belongs to each run already (bench set-up and angle- "
            "or geometry-stage effects are per run unless listed under shared)");
  spec = {};
  spec.temperature_degree["W0x"] = 1;
  EXPECT_EQ(message({a, b}, spec),
            "runs.yaml: run 'a' has no temperature for the temperature model (give "
            "temperature_C in the runs file or a temp_C column)");
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// The criteria over many seeds (bench/multirun_accuracy.sh runs these:
// they take minutes). Each prints its figures; the assertions are the
// targets.
int BenchSeeds() {
  const char* env = std::getenv("TRIADCAL_BENCH_SEEDS");
  return env ? std::max(1, std::atoi(env)) : 20;
}

TEST(JointFitBench, DISABLED_TwoShaftsOverManySeeds) {
  const ParameterLayout layout;
  const int seeds = BenchSeeds();
  double sum_z2 = 0.0;
  int count = 0, inconsistent = 0, max_held_jointly = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    Eigen::VectorXd truth_a, truth_b;
    const std::vector<JointRun> runs = TwoShaftRuns(seed, seed + 1000, &truth_a, &truth_b);
    const JointLayout jl(runs, layout, {}, "bench");
    const JointResult r = SolveJoint(runs, jl, Options());
    max_held_jointly = std::max(max_held_jointly, static_cast<int>(r.held.size()));
    for (const JointRunResult& rr : r.runs) inconsistent += !rr.consistency.consistent;
    for (int j = 0; j < jl.size(); ++j) {
      if (r.cov(j, j) <= 0.0) continue;
      const JointParam& p = jl.param(j);
      const Eigen::VectorXd& truth = p.run == 1 ? truth_b : truth_a;
      const double z = (r.phi[j] - truth[p.base]) / std::sqrt(r.cov(j, j));
      sum_z2 += z * z;
      ++count;
    }
  }
  const double rms = std::sqrt(sum_z2 / count);
  std::printf("two single-axis runs (shaft along IMU y, then x), %d seeds: RMS z %.3f over %d "
              "estimates (all joint unknowns); most held jointly %d; runs named inconsistent "
              "%d of %d\n",
              seeds, rms, count, max_held_jointly, inconsistent, 2 * seeds);
  EXPECT_GT(rms, 0.85);
  EXPECT_LT(rms, 1.15);
}

TEST(JointFitBench, DISABLED_TemperatureOverManySeeds) {
  const int seeds = BenchSeeds();
  double sum_z2 = 0.0, sum_z2_all = 0.0;
  int count = 0, count_all = 0, inconsistent = 0, named = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    Eigen::VectorXd coef;
    const std::vector<JointRun> runs = TemperatureRuns(seed, &coef, 0.0);
    const JointLayout jl(runs, ParameterLayout(), LinearInTemperature(), "bench");
    const JointResult r = SolveJoint(runs, jl, Options());
    const char* names[6] = {"W0x.t1", "W0y.t1", "W0z.t1", "Kx.t1", "Ky.t1", "Kz.t1"};
    for (int c = 0; c < 6; ++c) {
      const int j = jl.IndexOf(names[c]);
      const double z = (r.phi[j] - coef[c]) / std::sqrt(r.cov(j, j));
      sum_z2 += z * z;
      ++count;
    }
    for (int j = 0; j < jl.size(); ++j) {
      const JointParam& p = jl.param(j);
      if (p.degree != 0 || p.run >= 0 || r.cov(j, j) <= 0.0) continue;
      // The truth at the reference temperature is the paper truth.
      const double z = (r.phi[j] - PaperScenario(50.0, 60.0, 2.0, 15.0, 1).truth[p.base]) /
                       std::sqrt(r.cov(j, j));
      sum_z2_all += z * z;
      ++count_all;
    }
    for (const JointRunResult& rr : r.runs) inconsistent += !rr.consistency.consistent;
    // The same runs with T3 remounted 10 arcmin turned about z.
    const std::vector<JointRun> moved = TemperatureRuns(seed, &coef, 10.0);
    const JointResult m = SolveJoint(moved, jl, Options());
    bool odd_worst = !m.runs[3].consistency.consistent;
    for (int k = 0; k < 3; ++k) odd_worst = odd_worst && m.runs[k].consistency.chi2 < m.runs[3].consistency.chi2;
    named += odd_worst;
  }
  const double rms = std::sqrt(sum_z2 / count), rms_all = std::sqrt(sum_z2_all / count_all);
  std::printf("four runs at -20, 0, 20, 40 degC, %d seeds: RMS z of the 6 temperature "
              "coefficients %.3f (%d), of the 21 shared parameters at 20 degC %.3f (%d); "
              "clean runs named inconsistent %d of %d; remounted run named (and worst) in %d "
              "of %d\n",
              seeds, rms, count, rms_all, count_all, inconsistent, 4 * seeds, named, seeds);
  EXPECT_GT(rms, 0.85);
  EXPECT_LT(rms, 1.15);
  EXPECT_EQ(named, seeds);
}

}  // namespace
}  // namespace triadcal
