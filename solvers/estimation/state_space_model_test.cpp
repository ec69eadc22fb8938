// The state-space model shared by the estimators: where the model is linear
// in the free parameters, the EKF + RTS smoother and the batch solver must
// reach the same optimum and covariance (they consume the same process,
// measurement, prior and constraint terms); held parameters are absent from
// both problems.
#include "solvers/estimation/state_space_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "solvers/estimation/batch_solver.h"
#include "solvers/analysis/experiment_design.h"
#include "solvers/estimation/inertial_increments.h"
#include "solvers/estimation/kalman_smoother.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

// The reference motion's Jacobian (Jets over the parameters it reads) against
// central differences, with every accelerometer effect of the catalogue away
// from zero: a parameter it reads but does not seed would show here.
TEST(ReferenceMotion, JacobianMatchesCentralDifferencesWithEveryEffect) {
  std::vector<Effect> all;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kGyro) all.push_back(e.id);
  }
  for (const ParameterLayout& layout : {ParameterLayout(), ParameterLayout(all)}) {
    ModelConfig cfg;
    cfg.layout = layout;
    cfg.lever_arm0_m = Eigen::Vector3d(0.05, -0.12, 0.3);
    std::mt19937_64 rng(5);
    std::normal_distribution<double> nrm(0.0, 1.0);
    for (int trial = 0; trial < 10; ++trial) {
      const int n = layout.size();
      Eigen::VectorXd th = Eigen::VectorXd::Zero(n);
      for (int i = 0; i < 3; ++i) th[kKx + i] = 174 + 5 * nrm(rng);
      for (int i = kDpsi; i <= kDlambda2; ++i) th[i] = 0.02 * nrm(rng);
      for (int i = kDx2; i <= kDz2; ++i) th[i] = 0.01 * nrm(rng);
      for (Effect e : layout.effects()) {
        const EffectSpec& spec = GetEffectSpec(e);
        for (std::size_t q = 0; q < spec.params.size(); ++q) {
          const ParamSpec& p = spec.params[q];
          th[layout.offset(e) + q] =
              2.0 * p.typical * p.si_per_unit * (spec.scale_relative ? th[kKx] : 1.0) * nrm(rng);
        }
      }
      BenchAngles<double> rec;
      for (int i = 0; i < 2; ++i) {
        rec.axis[i] = AxisState<double>{(3 - i) * nrm(rng), nrm(rng), nrm(rng)};
      }
      const ReferenceSample ref = EvaluateReference(cfg, th, rec, true);
      ASSERT_EQ(ref.dref_dtheta.cols(), n);
      for (int c = 0; c < n; ++c) {
        const double h = 1e-6 * std::max(1.0, std::abs(th[c]));
        Eigen::VectorXd tp = th, tm = th;
        tp[c] += h;
        tm[c] -= h;
        const ReferenceSample p = EvaluateReference(cfg, tp, rec, false);
        const ReferenceSample m = EvaluateReference(cfg, tm, rec, false);
        Eigen::Matrix<double, 6, 1> d;
        d << (p.v_mps - m.v_mps) / (2 * h), (p.p_m - m.p_m) / (2 * h);
        EXPECT_LT((d - ref.dref_dtheta.col(c)).norm(), 1e-6 * (1 + d.norm()))
            << layout.size() << " " << layout.info(c).name;
      }
    }
  }
}

// Zero offsets enter B1 linearly and the lever arm enters B2 linearly, so with
// everything else held (at its true value) the run is a linear-Gaussian model.
TEST(StateSpaceModel, FilterAndBatchCoincideOnALinearGaussianRun) {
  Scenario s = PaperScenario(50.0, 20.0, 2.0, 15.0, 7);
  const ParameterLayout layout;
  // The truth: scale factors nominal, no misalignment or nonlinearity, bench
  // zeros 0; biases and lever arm off their nominal values.
  s.truth = NominalTheta(s.run, layout);
  SetFromFileUnits(layout, {{"W0x", 1503.1}, {"W0y", 1501.7}, {"W0z", 1498.9},
                            {"dx2", -7}, {"dy2", 16}, {"dz2", 4}}, &s.truth);
  const RunData data = Simulate(s);
  const std::vector<std::string> free = {"W0x", "W0y", "W0z", "dx2", "dy2", "dz2"};
  std::vector<std::string> held;
  for (int i = 0; i < layout.size(); ++i) {
    const std::string& name = layout.info(i).name;
    if (std::find(free.begin(), free.end(), name) == free.end()) held.push_back(name);
  }

  FilterOptions fo;
  fo.held = held;
  fo.smoother_iterations = 2;
  const FilterResult fr = RunFilterSmoother(s.run, data, layout, fo);

  BatchOptions bo;
  bo.init = BatchInit::kNominal;
  bo.estimate_noise = false;  // the filter's declared noise
  bo.holding.auto_hold = false;
  bo.holding.hold = held;
  const BatchResult br = SolveBatch(s.run, data, layout, bo);
  ASSERT_TRUE(br.converged);
  ASSERT_EQ(br.held.size(), held.size());

  for (const std::string& name : free) {
    const int i = layout.IndexOf(name);
    const double sigma = std::sqrt(br.estimate.cov(i, i));
    ASSERT_GT(sigma, 0.0) << name;
    // The same to 1e-4 sigma: the batch takes its noise weights' shape at the
    // nominal values (run_evaluation.h), the filter at its estimate, and the
    // B2 weight follows the lever arm (here 18 mm from nominal): 5e-6 sigma.
    EXPECT_LT(std::abs(fr.rts.theta[i] - br.estimate.theta[i]) / sigma, 1e-4) << name;
    EXPECT_LT(std::abs(std::sqrt(fr.rts.cov(i, i)) / sigma - 1.0), 1e-6) << name;
    // And both recover the truth within their sigma's usual range.
    EXPECT_LT(std::abs(br.estimate.theta[i] - s.truth[i]) / sigma, 4.0) << name;
  }
  // Held parameters are absent: exactly their values, no covariance.
  for (const std::string& name : held) {
    const int i = layout.IndexOf(name);
    EXPECT_EQ(br.estimate.theta[i], s.truth[i]) << name;
    EXPECT_EQ(fr.rts.theta[i], s.truth[i]) << name;
    EXPECT_EQ(br.estimate.cov(i, i), 0.0) << name;
    EXPECT_EQ(fr.rts.cov(i, i), 0.0) << name;
  }
}

// The whitening of a 6 x 6 covariance (its lower-triangular inverse written
// out, LowerInverse) against Eigen's inverse and determinant: W^T W = cov^-1,
// W cov W^T = I, zero above the diagonal, and half the log-determinant; on
// covariances whose diagonal spans eighteen orders of magnitude.
TEST(StateSpaceModel, WhiteningIsTheInverseCholeskyFactor) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    Mat6 A;
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) A(r, c) = n(rng);
    Eigen::Matrix<double, 6, 1> scale;
    for (int r = 0; r < 6; ++r) scale[r] = std::pow(10.0, 6.0 * (r % 3) / 2.0 - 3.0 * (r / 3));
    const Mat6 cov =
        scale.asDiagonal() * (A * A.transpose() + 0.1 * Mat6::Identity()) * scale.asDiagonal();
    double half_log_det = 0.0;
    const Mat6 W = WhiteningOf(cov, &half_log_det);
    for (int r = 0; r < 6; ++r)
      for (int c = r + 1; c < 6; ++c) EXPECT_EQ(W(r, c), 0.0);
    EXPECT_LT((W * cov * W.transpose() - Mat6::Identity()).norm(), 1e-9) << "trial " << trial;
    const Mat6 inv = cov.inverse();
    EXPECT_LT((W.transpose() * W - inv).norm(), 1e-9 * inv.norm()) << "trial " << trial;
    EXPECT_NEAR(half_log_det, 0.5 * std::log(cov.determinant()), 1e-9 * std::abs(half_log_det));
    EXPECT_EQ(WhiteningOf(cov), W);
  }
}

// The rows of priors and constraints over the free parameters: a constraint on
// held parameters only is dropped, held terms move to the right-hand side.
TEST(StateSpaceModel, ThetaRowsOverTheFreeParameters) {
  Scenario s = PaperScenario(20.0, 6.0, 2.0, 15.0, 1);
  const RunData data = Simulate(s);
  RunProblem p = BuildRunProblem(s.run, data, ParameterLayout(), 0.5, {});
  p.theta_held[kDlambda2] = 1e-3;
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  StateSpaceModel(p).ThetaRows(true, &A, &b);
  EXPECT_EQ(A.rows(), p.n + 1);
  EXPECT_EQ(A.cols(), p.n);

  p.Hold({kDlambda2});  // dpsi - dlambda2 = 0: dpsi = 1e-3 +- 30"
  StateSpaceModel(p).ThetaRows(true, &A, &b);
  ASSERT_EQ(A.rows(), p.n);  // n - 1 priors + 1 constraint
  ASSERT_EQ(A.cols(), p.n - 1);
  const double sigma = 30.0 * kArcsecToRad;
  EXPECT_NEAR(A(p.n - 1, kDpsi), 1.0 / sigma, 1e-9 / sigma);
  EXPECT_NEAR(b[p.n - 1], 1e-3 / sigma, 1e-12 / sigma);

  p.Hold({kDlambda2, kDpsi});  // nothing left free in the constraint
  StateSpaceModel(p).ThetaRows(true, &A, &b);
  EXPECT_EQ(A.rows(), p.n - 2);
}

// One set of defaults: every estimator and analysis uses the same epochs
// unless told otherwise.
TEST(StateSpaceModel, EstimatorsShareTheDefaultEpochs) {
  EXPECT_EQ(BatchOptions().epoch_s, kDefaultEpoch_s);
  EXPECT_EQ(FilterOptions().epoch_s, kDefaultEpoch_s);
  EXPECT_EQ(DesignOptions().epoch_s, kDefaultEpoch_s);
}

// And every command that fits or analyses a run offers that default.
TEST(StateSpaceModel, EveryCommandDefaultsToTheSameEpochs) {
  char expected[64];
  std::snprintf(expected, sizeof(expected), "=%g ", kDefaultEpoch_s);
  for (const char* cmd :
       {"fit", "filter", "compare", "diagnose", "observability", "design", "montecarlo"}) {
    const std::string line = std::string(TRIADCAL_BIN) + " " + cmd + " --help";
    FILE* p = popen(line.c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::string help;
    char buf[512];
    while (std::fgets(buf, sizeof(buf), p)) help += buf;
    pclose(p);
    const std::size_t at = help.find("--epoch-s");
    ASSERT_NE(at, std::string::npos) << cmd;
    const std::string option = help.substr(at, help.find('\n', at) - at) + " ";
    EXPECT_NE(option.find(expected), std::string::npos) << cmd << ": " << option;
  }
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// Without the paper's constraint the common rotation about the inner axis is a
// structural null: exactly one of its members is held (removed from the
// problem), the others are estimated relative to it and say so; nothing that
// the data determine is held.
TEST(HoldDecision, HoldsTheStructuralNullOnlyAndNamesWhatIsRelative) {
  Scenario s = testing_fixtures::PaperScenario(50.0, 60.0, 2.0, 15.0, 4);
  s.run.constraints.clear();
  const RunData data = Simulate(s);
  const ParameterLayout layout;
  const HoldDecision d =
      ChooseHeldParameters(s.run, data, layout, HoldPolicy(), kDefaultEpoch_s, {});
  ASSERT_EQ(d.held.size(), 1u);
  const std::string& held = d.held[0];
  const std::set<std::string> rotation = {"dlambda2", "gamma_y", "gamma_z"};
  EXPECT_TRUE(rotation.count(held)) << held;
  for (const std::string& name : rotation) {
    if (name == held) continue;
    ASSERT_TRUE(d.relative_to.count(name)) << name;
    EXPECT_EQ(d.relative_to.at(name), std::vector<std::string>{held}) << name;
  }
  // With the constraint nothing is held.
  Scenario c = testing_fixtures::PaperScenario(50.0, 60.0, 2.0, 15.0, 4);
  const HoldDecision dc = ChooseHeldParameters(c.run, Simulate(c), layout, HoldPolicy(),
                                               kDefaultEpoch_s, {});
  EXPECT_TRUE(dc.held.empty());
  EXPECT_TRUE(dc.relative_to.empty());
}

// Neighbouring intervals share the sample at their common epoch, so their
// process noises are correlated (about -3/(4N) for S given V, N samples an
// interval). Reading noise alone, integrated by the model over many draws:
// whitening each interval on its own leaves a clearly negative lag-1
// correlation in the S components; WhitenProcessSequence (with
// ProcessCrossCovariance) leaves none, and unit variance.
TEST(StateSpaceModel, SequenceWhiteningRemovesTheSharedSampleCorrelation) {
  Scenario s = PaperScenario(50.0, 4.0, 0.0, 0.0, 5);  // noise-free run
  const ParameterLayout layout;
  RunData data = Simulate(s);  // the problem reads it through a pointer
  const RunData clean = data;
  s.run.noise_mV = 2.0;
  s.run.angle_noise_rad = 0.0;
  const RunProblem p = BuildRunProblem(s.run, data, layout, 0.2, AngleDerivativeOptions());
  const StateSpaceModel model(p);
  const Eigen::VectorXd& theta = s.truth;
  const std::size_t first = 3, steps = 8;  // intervals of 10 samples
  std::vector<ProcessStep> st;
  for (std::size_t e = first; e < first + steps; ++e) st.push_back(model.Process(e, theta, false));
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int draws = 2000;
  Mat6 lag_seq = Mat6::Zero(), lag_each = Mat6::Zero(), var_seq = Mat6::Zero();
  int pairs = 0, singles = 0;
  for (int d = 0; d < draws; ++d) {
    for (int c = 0; c < 3; ++c) {
      for (std::size_t k = 0; k < data.t_s.size(); ++k) {
        data.w_mV[c][k] = clean.w_mV[c][k] + 2.0 * n01(rng);
      }
    }
    std::vector<Vec6> r, each;
    for (std::size_t j = 0; j < steps; ++j) {
      const ProcessStep noisy = model.Process(first + j, theta, false);
      r.push_back(noisy.u - st[j].u);
      each.push_back(WhiteningOf(st[j].noise->Q) * r.back());
    }
    const std::vector<Vec6> seq = model.WhitenProcessSequence(st, r, theta);
    for (std::size_t j = 1; j < steps; ++j) {
      lag_seq += seq[j] * seq[j - 1].transpose();
      lag_each += each[j] * each[j - 1].transpose();
      ++pairs;
    }
    for (std::size_t j = 0; j < steps; ++j) {
      var_seq += seq[j] * seq[j].transpose();
      ++singles;
    }
  }
  lag_seq /= pairs;
  lag_each /= pairs;
  var_seq /= singles;
  // Sampling error of each entry: 1/sqrt(14000) = 0.008 (pairs overlap).
  for (int c = 0; c < 6; ++c) {
    EXPECT_NEAR(var_seq(c, c), 1.0, 0.05) << c;
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(lag_seq(c, k), 0.0, 0.035) << c << "," << k;
  }
  for (int c = 3; c < 6; ++c) EXPECT_LT(lag_each(c, c), -0.05) << c;  // -3/(4N) = -0.075
}

}  // namespace
}  // namespace triadcal
