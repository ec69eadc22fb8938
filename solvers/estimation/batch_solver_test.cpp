// The batch solver: cost-function Jacobians against numeric derivatives, the
// Schur covariance against Ceres's, noise-free recovery, bad starts, the
// relinearised increments against exact ones, normalised errors over seeds,
// and the fit/compare commands.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "solvers/estimation/batch_costs.h"
#include "solvers/estimation/state_space_model.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/observability.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

BatchResult Fit(const Scenario& s, const RunData& data, BatchOptions opt = {}) {
  return SolveBatch(s.run, data, ParameterLayout(), opt);
}

double MaxAbsZ(const BatchResult& r, const Eigen::VectorXd& truth, std::string* worst) {
  double m = 0.0;
  for (int i = 0; i < kNumBaseParams; ++i) {
    const double z = (r.estimate.theta[i] - truth[i]) / std::sqrt(r.estimate.cov(i, i));
    if (std::abs(z) > m) {
      m = std::abs(z);
      *worst = ParameterLayout().info(i).name;
    }
  }
  return m;
}

// The Ceres costs (state-space model residuals) against numeric derivatives,
// with every parameter free and with some held (absent from theta_free).
TEST(BatchCosts, JacobiansMatchNumericDerivatives) {
  const Scenario s = PaperScenario(100.0, 6.0, 2.0, 15.0, 1);
  const RunData data = Simulate(s);
  for (const bool some_held : {false, true}) {
    RunProblem p = BuildRunProblem(s.run, data, ParameterLayout(), 0.2, {});
    p.theta_held = s.truth;
    if (some_held) p.Hold({kDlambda2, kKxy, kDz2});
    const StateSpaceModel model(p);
    const Eigen::VectorXd theta_free = model.Free(s.truth);
    const ProcessStep step = model.Process(3, s.truth, true);
    ASSERT_EQ(step.U.cols(), model.num_free());
    Mat6 cov = Mat6::Identity() * 1e-6;
    cov(0, 3) = cov(3, 0) = 3e-7;
    const Mat6 L = WhiteningOf(cov);
    EXPECT_LT((L.transpose() * L - cov.inverse()).norm(), 1e-6 * cov.inverse().norm());

    std::vector<double> xa = {0.1, -0.2, 0.05, 0.13, 0.02, 0.03};
    std::vector<double> xb = {0.12, -0.19, 0.04, 0.15, 0.01, 0.02};
    Eigen::VectorXd th = theta_free;
    th[0] += 1e-3;
    th[5] += 1e-3;
    ceres::NumericDiffOptions nd;
    nd.relative_step_size = 1e-7;
    for (const bool exact : {false, true}) {
      ProcessCost cost(&step, &theta_free, &model, exact, 3);
      ceres::GradientChecker checker(&cost, static_cast<const std::vector<const ceres::Manifold*>*>(nullptr), nd);
      ceres::GradientChecker::ProbeResults results;
      std::vector<const double*> params = {xa.data(), xb.data(), th.data()};
      EXPECT_TRUE(checker.Probe(params.data(), 1e-6, &results)) << results.error_log;
    }
    MeasurementCost mcost(&model, 5, L);
    ceres::GradientChecker mchecker(&mcost, static_cast<const std::vector<const ceres::Manifold*>*>(nullptr), nd);
    ceres::GradientChecker::ProbeResults mres;
    std::vector<const double*> mparams = {xa.data(), th.data()};
    EXPECT_TRUE(mchecker.Probe(mparams.data(), 1e-6, &mres)) << mres.error_log;
  }
}

TEST(BatchSolver, SchurCovarianceEqualsCeresCovariance) {
  const Scenario s = PaperScenario(50.0, 30.0, 2.0, 15.0, 2);
  const RunData data = Simulate(s);
  BatchOptions a, b;
  b.covariance_method = "ceres";
  const BatchResult ra = Fit(s, data, a), rb = Fit(s, data, b);
  // The Schur path works on the normal equations, whose condition number is
  // the square of the Jacobian's (~1e5 here, the priors against the um/s
  // trajectory): agreement to ~1e-16 * 1e10 = 1e-6 relative is what double
  // precision allows, so 1e-5 is the test.
  for (int i = 0; i < kNumBaseParams; ++i) {
    for (int j = 0; j < kNumBaseParams; ++j) {
      const double scale = std::sqrt(rb.estimate.cov(i, i) * rb.estimate.cov(j, j));
      EXPECT_NEAR(ra.estimate.cov(i, j), rb.estimate.cov(i, j), 1e-5 * scale);
    }
  }
}

TEST(BatchSolver, NoiseFreeDataRecoveredFarBelowSigma) {
  Scenario s = PaperScenario(50.0, 90.0, 0.0, 0.0, 1);
  s.run.noise_mV = 2.0;  // declared: sets sigma
  s.run.angle_noise_rad = 15.0 * kArcsecToRad;
  const RunData data = Simulate(s);
  // sigma from the declared noise (the yardstick here): with the noise
  // estimated from these noise-free residuals sigma would shrink to the
  // model's numerical floor (NoiseIsEstimatedFromTheResiduals checks that).
  BatchOptions opt;
  opt.estimate_noise = false;
  const BatchResult r = Fit(s, data, opt);
  EXPECT_TRUE(r.converged);
  // Not exactly 0: the weak priors pull by (sigma / sigma_prior)^2 * (truth -
  // nominal) / sigma, ~0.01 sigma for dy2 and gamma_y here, and the trapezoid
  // rule at 50 Hz leaves ~0.005 sigma. Anything model-related would be >> 0.05.
  std::string worst;
  EXPECT_LT(MaxAbsZ(r, s.truth, &worst), 0.05) << worst;
}

// From the nominal values with the truth 3 deg away in misalignment and
// levelling, the lever arm 20 mm off and the scale 5 % off.
TEST(BatchSolver, ConvergesFromABadStart) {
  Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, 4);
  SetFromFileUnits(s.truth_layout,
                   {{"Kx", 174.0 * 0.95}, {"Ky", 174 * 1.05}, {"alpha_x", 180}, {"beta_z", -180},
                    {"gamma_y", 180}, {"dtheta_c", 180}, {"dpsi", -180}, {"dlambda2", -180},
                    {"dx2", 20}, {"dy2", -20}, {"dz2", 20}},
                   &s.truth);
  const RunData data = Simulate(s);
  BatchOptions opt;
  opt.init = BatchInit::kNominal;
  const BatchResult r = Fit(s, data, opt);
  EXPECT_TRUE(r.converged);
  std::string worst;
  EXPECT_LT(MaxAbsZ(r, s.truth, &worst), 4.0) << worst;
  EXPECT_NEAR(r.chi2_per_dof, 1.0, 4.0 * std::sqrt(2.0 / r.degrees_of_freedom));
  // The same answer as from the smoother's start.
  const BatchResult r2 = Fit(s, data);
  for (int i = 0; i < kNumBaseParams; ++i) {
    EXPECT_NEAR(r.estimate.theta[i], r2.estimate.theta[i], 0.01 * std::sqrt(r2.estimate.cov(i, i)))
        << ParameterLayout().info(i).name;
  }
}

// The relinearised increments reach the optimum of the exact problem.
TEST(BatchSolver, RelinearisedEqualsExactIncrements) {
  const Scenario s = PaperScenario(25.0, 30.0, 2.0, 15.0, 6);
  const RunData data = Simulate(s);
  const BatchResult lin = Fit(s, data);
  BatchOptions opt;
  opt.exact_increments = true;
  opt.init = BatchInit::kGiven;
  opt.init_theta = lin.estimate.theta;
  opt.compute_covariance = false;
  const BatchResult ex = Fit(s, data, opt);
  for (int i = 0; i < kNumBaseParams; ++i) {
    EXPECT_NEAR(ex.estimate.theta[i], lin.estimate.theta[i],
                0.01 * std::sqrt(lin.estimate.cov(i, i)))
        << ParameterLayout().info(i).name;
  }
  EXPECT_NEAR(ex.final_cost, lin.final_cost, 1e-3 * lin.final_cost);
}

TEST(BatchSolver, NormalisedErrorsOverSeeds) {
  double sum = 0.0;
  int count = 0;
  for (int seed = 11; seed <= 18; ++seed) {
    Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, seed);
    s.truth_spread = {{kDlambda2, 30.0 * kArcsecToRad}};  // the constraint's own spread
    SampleTruth(&s);
    const RunData data = Simulate(s);
    const BatchResult r = Fit(s, data);
    // chi2/dof has standard deviation sqrt(2 / dof): allow 4 of them.
    EXPECT_NEAR(r.chi2_per_dof, 1.0, 4.0 * std::sqrt(2.0 / r.degrees_of_freedom));
    for (int i = 0; i < kNumBaseParams; ++i) {
      const double z = (r.estimate.theta[i] - s.truth[i]) / std::sqrt(r.estimate.cov(i, i));
      EXPECT_LT(std::abs(z), 4.5) << ParameterLayout().info(i).name << " seed " << seed;
      sum += z * z;
      ++count;
    }
  }
  const double rms = std::sqrt(sum / count);
  EXPECT_GT(rms, 0.8);
  EXPECT_LT(rms, 1.2);
}

// A drift in the data, estimated with the thermal_drift effect.
TEST(BatchSolver, EstimatesAnEffect) {
  Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, 9);
  s.truth_layout = ParameterLayout({Effect::kThermalDrift});
  Eigen::VectorXd t(s.truth_layout.size());
  t << s.truth, 0.5 / 60.0, -0.3 / 60.0, 0.2 / 60.0;  // mV/min -> mV/s
  s.truth = t;
  const RunData data = Simulate(s);
  const BatchResult r = SolveBatch(s.run, data, s.truth_layout, {});
  for (int i = 0; i < s.truth_layout.size(); ++i) {
    const double z = (r.estimate.theta[i] - s.truth[i]) / std::sqrt(r.estimate.cov(i, i));
    EXPECT_LT(std::abs(z), 4.5) << s.truth_layout.info(i).name;
  }
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A vertical shaft: only the inner axis turns (lambda1 = 0), so gravity stays
// on x and y, z see the bench's ~1 % g tilt and a few mg of motion. The scale
// factors then lie along flat directions (K_y, K_z against the tilts, K_x
// against W0x). The first-order increments let a scale step cancel the
// readings' noise, and every K ran to the 5x bound with sigma ~2 mV/g
// (state_space_model.h, c_e); now no scale factor leaves its nominal value
// by more than its honest sigma, the fit converges with chi2/dof ~1, and the
// analysis of its covariance names every scale factor and zero offset as
// not determined by this motion.
TEST(BatchSolver, VerticalShaftScaleFactorsStayAtThePriorAndAreNamed) {
  const ParameterLayout layout;
  for (const unsigned seed : {2u, 7u, 11u}) {
    SCOPED_TRACE(seed);
    Scenario s = PaperScenario(50.0, 60.0, 2.0, 15.0, seed);
    s.profile.amplitude_rad[0] = 0.0;
    const RunData data = Simulate(s);
    BatchOptions opt;
    opt.estimate_noise = false;  // the declared noise is right: chi2/dof judges the fit
    const BatchResult r = SolveBatch(s.run, data, layout, opt);
    EXPECT_TRUE(r.converged);
    EXPECT_GT(r.chi2_per_dof, 0.8);
    EXPECT_LT(r.chi2_per_dof, 1.25);
    const Eigen::VectorXd nominal = NominalTheta(s.run, layout);
    for (int i = kKx; i <= kKz; ++i) {
      const double sigma = std::sqrt(r.estimate.cov(i, i));
      ASSERT_GT(sigma, 0.0) << layout.info(i).name;
      EXPECT_LT(std::abs(r.estimate.theta[i] - nominal[i]), sigma) << layout.info(i).name;
      // Determined by the prior, not by the data: sigma near the prior's.
      EXPECT_GT(sigma, 0.5 * r.prior.sigma[i]) << layout.info(i).name;
    }
    const std::vector<std::string> named =
        ParametersIn(UnsupportedDirections(layout, r.estimate.cov, r.prior.sigma));
    for (const char* p : {"Kx", "Ky", "Kz", "W0x", "W0y", "W0z"}) {
      EXPECT_NE(std::find(named.begin(), named.end(), p), named.end()) << p;
    }
  }
}

TEST(FitCommand, FitAndCompareWriteTheirOutputs) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(testing::TempDir()) / "fit_cmd";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string bin = TRIADCAL_BIN;
  const std::string scen =
      std::string(TRIADCAL_SOURCE_DIR) + "/examples/paper-experiment3/scenario.yaml";
  ASSERT_EQ(std::system((bin + " simulate " + scen + " -o " + (dir / "run").string() +
                         " > /dev/null").c_str()),
            0);
  const std::string run = (dir / "run" / "run.yaml").string();
  ASSERT_EQ(std::system((bin + " fit " + run + " -o " + (dir / "fit.json").string() +
                         " > " + (dir / "fit.txt").string()).c_str()),
            0);
  const nlohmann::json fit = nlohmann::json::parse(Slurp((dir / "fit.json").string()));
  for (const char* key : {"parameters", "final_cost", "residual_rms", "iterations", "time_s",
                          "verdict", "chi2_per_dof", "unobservable"}) {
    EXPECT_TRUE(fit.contains(key)) << key;
  }
  EXPECT_EQ(fit["parameters"].size(), static_cast<size_t>(kNumBaseParams));
  EXPECT_EQ(fit["parameters"]["gamma_z"]["unit"], "arcmin");
  EXPECT_TRUE(fit["converged"].get<bool>());

  ASSERT_EQ(std::system((bin + " compare " + run + " -o " + (dir / "cmp.json").string() +
                         " > " + (dir / "cmp.txt").string()).c_str()),
            0);
  const nlohmann::json cmp = nlohmann::json::parse(Slurp((dir / "cmp.json").string()));
  for (const char* key : {"ekf", "rts", "batch", "differences_in_sigma"}) {
    EXPECT_TRUE(cmp.contains(key)) << key;
  }
  EXPECT_TRUE(cmp["ekf"]["parameters"].contains("Kx"));
  // The batch optimum and the iterated smoother agree (docs/method.md).
  EXPECT_LT(cmp["largest_batch_minus_rts"]["sigma"].get<double>(), 0.05);
  const std::string table = Slurp((dir / "cmp.txt").string());
  EXPECT_NE(table.find("RTS-EKF"), std::string::npos);
  EXPECT_NE(table.find("gamma_y"), std::string::npos);

  // Bad option: one line, non-zero, no output.
  EXPECT_NE(std::system((bin + " fit " + run + " --init sideways -o " +
                         (dir / "bad.json").string() + " 2> " + (dir / "err.txt").string() +
                         " > /dev/null").c_str()),
            0);
  EXPECT_FALSE(fs::exists(dir / "bad.json"));
  EXPECT_EQ(Slurp((dir / "err.txt").string()),
            "triadcal: error: --init: expected rts or nominal, got 'sideways'\n");
}

// A held parameter anchors the other members of its weak direction
// (relative_to); a pinned one does not: its uncertainty goes into their sigma.
// Single-axis run: dtheta_c with beta_x, beta_z.
TEST(HoldDecision, APinIsNoAnchorOfRelativeTo) {
  Scenario s = PaperScenario(50.0, 30.0, 2.0, 15.0, 4);
  s.profile.amplitude_rad[1] = 0.0;
  const RunData data = Simulate(s);
  HoldPolicy held;
  held.hold = {"dtheta_c"};
  const HoldDecision h = ChooseHeldParameters(s.run, data, ParameterLayout(), held, 0.5, {});
  ASSERT_TRUE(h.relative_to.count("beta_x"));
  EXPECT_EQ(h.relative_to.at("beta_x"), std::vector<std::string>{"dtheta_c"});
  HoldPolicy pinned;
  pinned.pinned = {"dtheta_c"};
  const HoldDecision p = ChooseHeldParameters(s.run, data, ParameterLayout(), pinned, 0.5, {});
  EXPECT_NE(std::find(p.held.begin(), p.held.end(), "dtheta_c"), p.held.end());
  EXPECT_FALSE(p.relative_to.count("beta_x"));
  EXPECT_FALSE(p.relative_to.count("beta_z"));
}

// The sensitivity of the consider model (BatchResult::pinned_sensitivity)
// is how the estimates follow the pinned value: dz2 pinned 20 mm (one prior
// sigma) further -- the nominal lever arm moved by that, dz2 held at 0 --
// moves the other estimates by up to 1.2 sigma, S times 20 mm. S is taken at
// the hold decision's linearisation (the nominal values), as the added
// covariance is: it predicts the change within 0.13 sigma (alpha_y -0.37
// for -0.50). The fit's own information, at its estimate, predicts it within
// 0.03 sigma (the regression on dz2 in the covariance of the fit with dz2
// free): what S misses is the linearisation point, not the algebra.
TEST(BatchSolver, PinnedSensitivityPredictsTheEstimatesAtAnotherPinnedValue) {
  const ParameterLayout layout;
  Scenario s = PaperScenario(50.0, 10.0, 2.0, 15.0, 3);
  s.run.prior_sigma["dz2"] = 20.0;
  const RunData data = Simulate(s);
  BatchOptions opt;
  opt.estimate_noise = false;
  opt.sigma = "white";
  opt.holding.hold = {"dz2"};
  BatchResult r = Fit(s, data, opt);
  ASSERT_TRUE(r.converged);
  ASSERT_EQ(r.information_at_start.rows(), layout.size());
  r.pinned = {PinnedExcursion{"dz2", 0.0, 0.0}};
  AddPinnedUncertainty(layout, &r);
  ASSERT_EQ(r.pinned_sensitivity.cols(), 1);
  BatchOptions free_opt = opt;
  free_opt.holding.hold = {};
  free_opt.holding.pin_weak_excursions = false;
  const BatchResult free_fit = Fit(s, data, free_opt);
  const double delta = 0.02;
  Scenario moved = s;
  moved.run.lever_arm0_m.z() += delta;
  const BatchResult r_moved = Fit(moved, data, opt);
  double miss_nominal = 0.0, miss_estimate = 0.0, largest = 0.0;
  for (int i = 0; i < kNumBaseParams; ++i) {
    if (i == kDz2 || r.cov_given_pinned(i, i) <= 0.0) continue;
    const double sigma = std::sqrt(r.cov_given_pinned(i, i));
    const double change = (r_moved.estimate.theta[i] - r.estimate.theta[i]) / sigma;
    const double by_s = r.pinned_sensitivity(i, 0) * delta / sigma;
    const double by_fit =
        free_fit.estimate.cov(i, kDz2) / free_fit.estimate.cov(kDz2, kDz2) * delta / sigma;
    miss_nominal = std::max(miss_nominal, std::abs(change - by_s));
    miss_estimate = std::max(miss_estimate, std::abs(change - by_fit));
    largest = std::max(largest, std::abs(change));
  }
  std::printf("largest change %.2f sigma; missed by S %.3f sigma, by the fit's own %.3f sigma\n",
              largest, miss_nominal, miss_estimate);
  EXPECT_GT(largest, 1.0);  // the test has teeth
  EXPECT_LT(miss_nominal, 0.15);
  EXPECT_LT(miss_estimate, 0.03);
}

// A parameter the data know less than twice its prior that the fit moves
// beyond 3 prior sigma is pinned at nominal and the run refitted; what its
// uncertainty does to the others is added to their covariance, so their sigma
// stay those of the fit with it free. A 10-s paper run at 2 mV with a 20-mm
// prior on dz2 knows it at about 0.6 of that prior; a lever arm 250 mm off
// (12.5 prior sigma, the model is linear in it) draws the estimate to about
// 0.6 / 1.6 of that, beyond 3 prior sigma (a nominal value this wrong is the
// price of the rule, docs/method.md).
TEST(BatchSolver, WeakParameterMovedFarIsPinnedAndItsUncertaintyKept) {
  const ParameterLayout layout;
  Scenario s = PaperScenario(50.0, 10.0, 2.0, 15.0, 3);
  s.run.prior_sigma["dz2"] = 20.0;
  s.truth[kDz2] = 0.25;
  const RunData data = Simulate(s);
  // The model's sigma, compared between fits whose misfit differs (the held
  // fits miss 250 mm of lever arm): no noise estimate, no HAC.
  BatchOptions pin_opt;
  pin_opt.estimate_noise = false;
  pin_opt.sigma = "white";
  BatchOptions free_opt = pin_opt;
  free_opt.holding.pin_weak_excursions = false;
  const BatchResult free_fit = Fit(s, data, free_opt);
  ASSERT_TRUE(free_fit.converged);
  // The progress of the fit and its refit only climbs, to 1.
  std::vector<double> fractions;
  BatchOptions watched = pin_opt;
  watched.fraction = [&fractions](double x) { fractions.push_back(x); };
  const BatchResult pinned = Fit(s, data, watched);
  ASSERT_TRUE(pinned.converged);
  ASSERT_FALSE(fractions.empty());
  for (std::size_t i = 1; i < fractions.size(); ++i) {
    EXPECT_GE(fractions[i], fractions[i - 1]) << i;
  }
  EXPECT_EQ(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
  BatchOptions hold_opt = free_opt;
  hold_opt.holding.hold = {"dz2"};
  const BatchResult held = Fit(s, data, hold_opt);

  const double z_free = free_fit.estimate.theta[kDz2] / free_fit.prior.sigma[kDz2];
  std::printf("free dz2 %.4f m (%.1f prior sigma), information %.3f\n",
              free_fit.estimate.theta[kDz2], z_free, MarginalInformationAtStart(layout, free_fit)[kDz2]);
  ASSERT_GT(z_free, 3.0);
  ASSERT_LT(MarginalInformationAtStart(layout, free_fit)[kDz2], 2.0);
  EXPECT_TRUE(WeakExcursions(layout, free_fit, HoldPolicy{}).size() >= 1);
  ASSERT_FALSE(pinned.pinned.empty());
  EXPECT_EQ(pinned.pinned[0].name, "dz2");
  EXPECT_NEAR(pinned.pinned[0].z, z_free, 1e-6 * std::abs(z_free));
  EXPECT_NE(std::find(pinned.held.begin(), pinned.held.end(), "dz2"), pinned.held.end());
  EXPECT_EQ(pinned.estimate.theta[kDz2], 0.0);
  // The estimate is the held fit's; the sigma are the free fit's (to the
  // linearisation), not the held fit's.
  double worst_free = 0.0, most_shrunk = 1.0;
  std::string shrunk;
  for (int i = 0; i < kNumBaseParams; ++i) {
    if (i == kDz2 || pinned.estimate.cov(i, i) <= 0.0) continue;
    EXPECT_NEAR(pinned.estimate.theta[i], held.estimate.theta[i],
                1e-6 * std::sqrt(held.estimate.cov(i, i)))
        << layout.info(i).name;
    const double s_pin = std::sqrt(pinned.estimate.cov(i, i));
    const double s_free = std::sqrt(free_fit.estimate.cov(i, i));
    const double s_held = std::sqrt(held.estimate.cov(i, i));
    // Given the pinned value, the sigma are the held fit's.
    EXPECT_NEAR(std::sqrt(pinned.cov_given_pinned(i, i)), s_held, 1e-3 * s_held)
        << layout.info(i).name;
    worst_free = std::max(worst_free, std::abs(std::log(s_pin / s_free)));
    if (s_held / s_free < most_shrunk) {
      most_shrunk = s_held / s_free;
      shrunk = layout.info(i).name;
    }
  }
  std::printf("sigma / sigma of the free fit: pinned within %.3f (log), held down to %.3f (%s)\n",
              worst_free, most_shrunk, shrunk.c_str());
  EXPECT_LT(most_shrunk, 0.8) << shrunk;  // holding alone would hide the uncertainty
  EXPECT_LT(worst_free, std::log(1.1));

  // The consider model behind the added covariance: S P S^T is what was
  // added (PinnedSensitivityPredictsTheEstimatesAtAnotherPinnedValue checks S).
  const Eigen::MatrixXd& S = pinned.pinned_sensitivity;
  ASSERT_EQ(S.rows(), layout.size());
  ASSERT_EQ(S.cols(), 1);
  ASSERT_EQ(pinned.pinned_cov.rows(), 1);
  const Eigen::MatrixXd added = pinned.estimate.cov - pinned.cov_given_pinned;
  const Eigen::MatrixXd consider = S * pinned.pinned_cov * S.transpose();
  for (int i = 0; i < kNumBaseParams; ++i) {
    if (pinned.estimate.cov(i, i) <= 0.0) continue;
    for (int j = 0; j < kNumBaseParams; ++j) {
      if (pinned.estimate.cov(j, j) <= 0.0) continue;
      const double scale = std::sqrt(pinned.estimate.cov(i, i) * pinned.estimate.cov(j, j));
      EXPECT_NEAR(consider(i, j), added(i, j), 1e-9 * scale)
          << layout.info(i).name << " " << layout.info(j).name;
    }
  }
  EXPECT_EQ(S(kDz2, 0), 0.0);  // held: no row

  // Named free, it is not pinned.
  BatchOptions keep = pin_opt;
  keep.holding.free = {"dz2"};
  EXPECT_TRUE(Fit(s, data, keep).pinned.empty());
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// A missing output folder is reported before any work, in one line.
TEST(FitCommand, MissingOutputFolderFailsFirst) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(testing::TempDir()) / "fit_outdir";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string bin = TRIADCAL_BIN;
  const std::string scen = std::string(TRIADCAL_SOURCE_DIR) + "/examples/noise-free/scenario.yaml";
  ASSERT_EQ(std::system((bin + " simulate " + scen + " -o " + (dir / "run").string() + " > /dev/null").c_str()), 0);
  const std::string out = (dir / "no" / "out.json").string();
  for (const char* cmd : {"fit", "filter", "compare", "diagnose"}) {
    EXPECT_NE(std::system((bin + " " + cmd + " " + (dir / "run" / "run.yaml").string() + " -o " +
                           out + " 2> " + (dir / "err.txt").string() + " > /dev/null").c_str()),
              0);
    EXPECT_EQ(Slurp((dir / "err.txt").string()),
              "triadcal: error: " + out + ": cannot write (folder missing or not writable)\n")
        << cmd;
  }
}

}  // namespace
}  // namespace triadcal
