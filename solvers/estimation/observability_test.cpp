// Observability, experiment design and Monte Carlo (solvers/estimation/observability.h,
// experiment_design.h, monte_carlo.h) and their commands: the inner-axis
// rotation named without the paper's constraint and nothing unobservable with
// it, the CRB against docs/method.md, 1/sqrt(T), what a static test cannot
// determine, the real single-axis runs, a small Monte Carlo, and bad input.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include <ceres/jet.h>
#include <Eigen/QR>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/model/errors.h"
#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "solvers/analysis/experiment_design.h"
#include "solvers/analysis/monte_carlo.h"
#include "solvers/estimation/observability.h"
#include "tests/sim_fixtures.h"
#include "core/io/run_description_io.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::PaperScenario;

// The paper's experiment 3 at the docs/method.md noise level (2 mV at 20 Hz,
// 15" angles), analysed without noise in the data at the truth, with 0.2-s
// epochs (the figures below were set with them; the default 0.5-s epochs
// carry a little less B2 information, and the constrained problem's smallest
// eigenvalue drops to 96, just under the weak threshold of 100).
DesignOptions PaperOptions() {
  DesignOptions o;
  o.epoch_s = 0.2;
  return o;
}

ObservabilityResult PaperObservability(double rate_hz, double duration_s,
                                       bool at_nominal = false) {
  const Scenario s = PaperScenario(rate_hz, duration_s, 2.0, 15.0, 1);
  const ParameterLayout layout;
  ObservabilityResult r = AnalyseScenario(s, layout, PaperOptions());
  if (at_nominal) {
    const Scenario q = NoiseFreeScenario(s);
    const RunData data = Simulate(q);
    const RunProblem p = BuildRunProblem(q.run, data, layout, 0.2, {});
    r = AnalyseObservability(q.run, p, NominalTheta(q.run, layout));
  }
  return r;
}

double Weight(const WeakDirection& d, const std::string& name) {
  for (const auto& [n, w] : d.weights) {
    if (n == name) return w;
  }
  return 0.0;
}

double Sigma(const ObservabilityVariant& v, int i) {
  return std::sqrt(v.cov(i, i)) / ParameterLayout().info(i).si_per_unit;
}

TEST(Observability, InnerAxisRotationNamedWithoutTheConstraintOnly) {
  for (const bool nominal : {false, true}) {
    const ObservabilityResult r = PaperObservability(20.0, 90.0, nominal);
    SCOPED_TRACE(nominal ? "at nominal" : "at truth");
    // Without the paper's constraint: exactly one direction, the common
    // rotation about the inner axis, with equal weights in prior units.
    ASSERT_EQ(r.without_constraints.unobservable.size(), 1u);
    const WeakDirection& d = r.without_constraints.unobservable[0].named;
    for (const char* name : {"dlambda2", "gamma_y", "gamma_z"}) {
      EXPECT_NEAR(std::abs(Weight(d, name)), 1.0 / std::sqrt(3.0), 0.02) << name;
    }
    EXPECT_EQ(d.weights.size(), 3u);
    EXPECT_NE(d.description.find("inner bench axis"), std::string::npos) << d.description;
    // The data carry (next to) nothing along it: a structural null; at the
    // nominal values (K_ij = 0) it is zero to rounding.
    EXPECT_LT(d.data_information, nominal ? 1e-4 : 0.05);
    // Each "without" variant of the one constraint is the same.
    ASSERT_EQ(r.without_each.size(), 1u);
    EXPECT_EQ(r.without_each[0].dropped, "dpsi - dlambda2");
    EXPECT_EQ(r.without_each[0].unobservable.size(), 1u);
    // With it nothing is unobservable, and nothing weakly observable either.
    EXPECT_TRUE(r.with_constraints.unobservable.empty());
    EXPECT_TRUE(r.with_constraints.weak.empty());
    EXPECT_GT(r.with_constraints.eigenvalues[0], 100.0);
    // The direction leaves dlambda2, gamma_y, gamma_z at about their prior sigma.
    EXPECT_GT(Sigma(r.without_constraints, kDlambda2), 0.5 * 180.0);
    EXPECT_LT(Sigma(r.with_constraints, kDlambda2), 2.0);
  }
}

// docs/method.md: with 2 mV white noise at 20 Hz over 90 s the CRB is roughly
// scale 0.08-0.13 mV/g, bias 0.07-0.14 mV, angles 1.3-3.3', K_ij 0.8-1.7e-3 /g,
// dpsi/dtheta_c/dlambda2 1.3-1.5', dR 3-5 mm. "Roughly": our ranges may reach
// 15 % below the low ends (measured: 0.88 of it at worst, Kx and W0z).
TEST(Observability, CrbAgreesWithSpecSection4) {
  const ObservabilityResult r = PaperObservability(20.0, 90.0);
  struct Range {
    std::vector<int> members;
    double lo, hi;
  };
  const std::vector<Range> ranges = {
      {{kKx, kKy, kKz}, 0.08, 0.13},
      {{kW0x, kW0y, kW0z}, 0.07, 0.14},
      {{kAlphaX, kAlphaY, kBetaX, kBetaZ, kGammaY, kGammaZ}, 1.3, 3.3},
      {{kKxx, kKxy, kKxz, kKyx, kKyy, kKyz, kKzx, kKzy, kKzz}, 0.8e-3, 1.7e-3},
      {{kDpsi, kDthetaC, kDlambda2}, 1.3, 1.5},
      {{kDx2, kDy2, kDz2}, 3.0, 5.0},
  };
  for (const Range& g : ranges) {
    for (int i : g.members) {
      const double s = Sigma(r.with_constraints, i);
      std::printf("%-9s %.3g (quoted %.3g-%.3g)\n", ParameterLayout().info(i).name.c_str(), s, g.lo,
                  g.hi);
      EXPECT_GE(s, 0.85 * g.lo) << ParameterLayout().info(i).name;
      EXPECT_LE(s, 1.02 * g.hi) << ParameterLayout().info(i).name;
    }
  }
}

// sigma shrinks as 1/sqrt(samples) (docs/method.md), up to the trapezoid
// weights of B1: an interval of m sample steps carries the noise of m - 1/2
// samples (its end samples count half), so sigma goes as sqrt(m - 1/2) / m
// and 4x the rate gives 1.90 at 20 -> 80 Hz, 1.98 at 100 -> 400 Hz (m = 20 -> 80
// steps of the 0.2-s epochs).
TEST(Observability, SigmaFallsAsOneOverSqrtSamples) {
  for (const double rate : {20.0, 100.0}) {
    const Scenario s1 = PaperScenario(rate, 30.0, 2.0, 15.0, 1);
    const Scenario s4 = PaperScenario(4 * rate, 30.0, 2.0, 15.0, 1);
    const ObservabilityResult a = AnalyseScenario(s1, ParameterLayout(), PaperOptions());
    const ObservabilityResult b = AnalyseScenario(s4, ParameterLayout(), PaperOptions());
    const double m1 = PaperOptions().epoch_s * rate, m4 = 4 * m1;
    const double expected = (std::sqrt(m1 - 0.5) / m1) / (std::sqrt(m4 - 0.5) / m4);
    for (int i : {kKx, kW0y, kAlphaX, kKxy, kDthetaC, kDx2}) {
      const double ratio = Sigma(a.with_constraints, i) / Sigma(b.with_constraints, i);
      EXPECT_NEAR(ratio, expected, 0.01 * expected) << ParameterLayout().info(i).name << " " << rate;
    }
  }
}

// The information is the batch solver's: the CRB at a noise-free fit is the
// fit's own covariance (the declared noise, every parameter estimated).
TEST(Observability, DataInformationPlusPriorsIsTheBatchCovariance) {
  const Scenario s = NoiseFreeScenario(PaperScenario(20.0, 30.0, 2.0, 15.0, 1));
  const RunData data = Simulate(s);
  const ParameterLayout layout;
  BatchOptions opt;
  opt.epoch_s = 0.2;
  opt.estimate_noise = false;
  opt.holding.auto_hold = false;
  opt.sigma = "white";
  const BatchResult fit = SolveBatch(s.run, data, layout, opt);
  ASSERT_TRUE(fit.converged) << fit.termination;
  const RunProblem p = BuildRunProblem(s.run, data, layout, 0.2, {});
  const ObservabilityResult r = AnalyseObservability(s.run, p, fit.estimate.theta);
  for (int i = 0; i < layout.size(); ++i) {
    EXPECT_NEAR(std::sqrt(r.with_constraints.cov(i, i)), std::sqrt(fit.estimate.cov(i, i)),
                1e-6 * std::sqrt(fit.estimate.cov(i, i)))
        << layout.info(i).name;
  }
}

TEST(Observability, UnsupportedDirectionsForFitAndFilter) {
  Scenario s = NoiseFreeScenario(PaperScenario(20.0, 30.0, 2.0, 15.0, 1));
  s.run.constraints.clear();
  const RunData data = Simulate(s);
  const ParameterLayout layout;
  const RunProblem p = BuildRunProblem(s.run, data, layout, 0.2, {});
  const Eigen::VectorXd theta = TruthInLayout(s, layout);
  const std::vector<WeakDirection> a = UnsupportedDirections(p, theta);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_NE(a[0].description.find("inner bench axis"), std::string::npos);
  // From an estimator's covariance: the same direction.
  const ObservabilityResult r = AnalyseObservability(s.run, p, theta);
  const std::vector<WeakDirection> b =
      UnsupportedDirections(layout, r.with_constraints.cov, p.prior.sigma);
  ASSERT_EQ(b.size(), 1u);
  for (const char* name : {"dlambda2", "gamma_y", "gamma_z"}) {
    EXPECT_NEAR(Weight(a[0], name), Weight(b[0], name), 1e-3) << name;
  }
}

// Exact nulls share one eigenvalue, so the eigensolver's basis of them turns
// with rounding; the directions come out in the layout's order of their main
// parameter, whatever basis the null space is given in.
TEST(Observability, NullDirectionsInTheLayoutsOrder) {
  const ParameterLayout layout;
  const int n = layout.size();
  const Eigen::VectorXd sigma = Eigen::VectorXd::LinSpaced(n, 1.0, 3.0);
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(n, 4);  // in prior units
  N(kDy2, 0) = 1.0;
  N(kKyy, 1) = 1.0;  // with a little of Ky, as on the real roll runs
  N(kKy, 1) = 0.012;
  N.col(1).normalize();
  N(kDthetaC, 2) = N(kBetaX, 2) = std::sqrt(0.5);
  N(kKy, 3) = 1.0;
  // An orthonormal basis of the null space (N's columns are not orthogonal).
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(N).householderQ() *
                            Eigen::MatrixXd::Identity(n, 4);
  for (int turn = 0; turn < 3; ++turn) {
    // The same null space, its basis turned.
    const Eigen::MatrixXd R =
        Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd::Random(4, 4)).householderQ();
    const Eigen::MatrixXd B = turn == 0 ? Q : Eigen::MatrixXd(Q * R);
    const Eigen::MatrixXd in_prior_units =
        1e4 * (Eigen::MatrixXd::Identity(n, n) - B * B.transpose());
    const Eigen::MatrixXd information =
        sigma.cwiseInverse().asDiagonal() * in_prior_units * sigma.cwiseInverse().asDiagonal();
    std::vector<Direction> nulls;
    ClassifyDirections(layout, information, sigma, ObservabilityThresholds{}, &nulls, nullptr);
    ASSERT_EQ(nulls.size(), 4u) << "turn " << turn;
    EXPECT_EQ(nulls[0].named.weights[0].first, "Ky") << "turn " << turn;
    EXPECT_GT(std::abs(Weight(nulls[1].named, "beta_x")), 0.5) << "turn " << turn;
    EXPECT_GT(std::abs(Weight(nulls[1].named, "dtheta_c")), 0.5) << "turn " << turn;
    EXPECT_EQ(nulls[2].named.weights[0].first, "Kyy") << "turn " << turn;
    EXPECT_EQ(nulls[3].named.weights[0].first, "dy2") << "turn " << turn;
  }
}

// The real single-axis runs: one moving axis, so much is held; named.
class ObservabilityRealData : public ::testing::TestWithParam<const char*> {};

TEST_P(ObservabilityRealData, SingleAxisRunNamesWhatIsHeld) {
  const std::string name = GetParam();
  const std::string yaml =
      std::string(TRIADCAL_SOURCE_DIR) + "/examples/single-axis-roll/" + name + ".yaml";
  const std::string mat =
      ResolveDataPath(yaml, "shared:data/real/single-axis-encoder/raw_roll_" + name + ".mat");
  if (mat.empty() || !fs::exists(mat)) GTEST_SKIP() << "shared data folder absent";
  const RunDescription run = LoadRunDescription(yaml);
  RunWarnings warnings;
  const RunData data = LoadRunData(run, &warnings);
  const ParameterLayout layout;
  const RunProblem p = BuildRunProblem(run, data, layout, 0.2, {});
  const ObservabilityResult r = AnalyseObservability(run, p, NominalTheta(run, layout));
  std::set<std::string> held, descriptions;
  for (const Direction& d : r.with_constraints.unobservable) {
    for (const auto& [n, w] : d.named.weights) held.insert(n);
    descriptions.insert(d.named.description);
    std::printf("%s: UNOBSERVABLE %s\n", name.c_str(), d.named.description.c_str());
  }
  // Along the only rotation axis (platform y) the lever arm does nothing; the
  // rotations of the triad about either bench axis are its misalignment.
  for (const char* n : {"dy2", "dtheta_c", "beta_x", "beta_z", "dlambda2", "gamma_y", "gamma_z"}) {
    EXPECT_TRUE(held.count(n)) << n;
  }
  auto named = [&](const std::string& prefix) {
    for (const std::string& d : descriptions) {
      if (d.rfind(prefix, 0) == 0) return true;
    }
    return false;
  };
  EXPECT_TRUE(named("common rotation of the triad about the outer bench axis (dtheta_c with beta_x"));
  EXPECT_TRUE(named("common rotation of the triad about the inner bench axis (dlambda2 with gamma_"));
  EXPECT_TRUE(named("lever-arm error dy2 (acts only through rotations about axes across it"));
  // What the motion does determine: the x and z channels swing through +-1 g.
  for (const char* n : {"Kx", "Kz", "W0x", "W0z", "alpha_x", "dx2", "dz2"}) {
    EXPECT_FALSE(held.count(n)) << n;
  }
  EXPECT_TRUE(r.without_each.empty());  // constraints: []
}

INSTANTIATE_TEST_SUITE_P(Observability, ObservabilityRealData,
                         ::testing::Values("slow", "medium", "fast"));

// ---------------------------------------------------------------------------
// Experiment design

TEST(Design, SigmaFallsAsOneOverSqrtDuration) {
  const Scenario s = PaperScenario(20.0, 90.0, 2.0, 15.0, 1);
  const ParameterLayout layout;
  HarmonicProfile p = s.profile;
  p.duration_s = 120.0;
  const DesignPoint a = EvaluateProfile(s, p, layout, {});
  p.duration_s = 480.0;
  const DesignPoint b = EvaluateProfile(s, p, layout, {});
  for (int i : {kKx, kKz, kW0x, kAlphaY, kBetaZ, kKxx, kKzy, kDpsi, kDthetaC, kDx2, kDz2}) {
    const double slope = std::log(b.sigma[i] / a.sigma[i]) / std::log(4.0);
    EXPECT_NEAR(slope, -0.5, 0.03) << layout.info(i).name;
  }
  // The constrained rotation levels off at the constraint's 30".
  EXPECT_GT(b.sigma[kDlambda2], 0.45 * kArcminToRad);
  EXPECT_TRUE(a.unobservable.empty());
}

// J of the static model against central differences of PredictReadings_mV.
TEST(Design, StaticInformationMatchesNumericDerivatives) {
  const Scenario s = PaperScenario(20.0, 90.0, 2.0, 0.0, 1);
  const ParameterLayout layout;
  const Eigen::VectorXd theta = TruthInLayout(s, layout);
  const std::array<double, 2> pos = {0.7, -0.4};
  const double T = 100.0, rate = 20.0;
  const Eigen::MatrixXd I = StaticTestInformation(s.run, layout, theta, {pos}, T, rate);
  const ModelConfig cfg = MakeModelConfig(s.run, layout);
  BenchAngles<double> b;
  b.axis[0].angle = pos[0];
  b.axis[1].angle = pos[1];
  Eigen::MatrixXd J(3, layout.size());
  for (int i = 0; i < layout.size(); ++i) {
    const double h = 1e-6 * std::max(1.0, std::abs(theta[i]));
    Eigen::VectorXd tp = theta, tm = theta;
    tp[i] += h;
    tm[i] -= h;
    J.col(i) = (PredictReadings_mV(cfg, tp.data(), b, {}) - PredictReadings_mV(cfg, tm.data(), b, {})) /
               (2 * h);
  }
  const Eigen::MatrixXd I_num = J.transpose() * J * (T * rate) / (s.run.noise_mV * s.run.noise_mV);
  EXPECT_LT((I - I_num).norm(), 1e-5 * I_num.norm());
}

TEST(Design, StaticTestCannotDetermineTheLeverArm) {
  const Scenario s = PaperScenario(100.0, 90.0, 2.0, 15.0, 1);
  const ParameterLayout layout;
  const ObservabilityThresholds t;
  const DesignPoint twelve = EvaluateStatic(s, layout, StaticPositions(12), 2400.0, t);
  const std::set<std::string> held12(twelve.unobservable.begin(), twelve.unobservable.end());
  EXPECT_EQ(held12, (std::set<std::string>{"dx2", "dy2", "dz2"}));
  ASSERT_EQ(twelve.directions.size(), 3u);
  EXPECT_NE(twelve.directions[0].description.find("lever-arm error"), std::string::npos);
  // Six positions (each axis up and down) never excite the cross-coupling
  // products W_i W_j, nor separate the outer-axis rotation.
  const DesignPoint six = EvaluateStatic(s, layout, StaticPositions(6), 2400.0, t);
  const std::set<std::string> held6(six.unobservable.begin(), six.unobservable.end());
  for (const char* n : {"dx2", "dy2", "dz2", "Kxy", "Kyz", "Kzy"}) EXPECT_TRUE(held6.count(n)) << n;
  for (const char* n : {"Kx", "Ky", "Kz", "W0y", "Kyy", "Kzz"}) EXPECT_FALSE(held6.count(n)) << n;
  // The positioning error (15" per position) stops sigma falling as
  // 1/sqrt(T): 16 x the time gains the zero offsets far less than 4 x.
  const DesignPoint longer = EvaluateStatic(s, layout, StaticPositions(12), 16 * 2400.0, t);
  EXPECT_GT(longer.sigma[kW0x] / twelve.sigma[kW0x], 0.5);
  EXPECT_THROW(StaticPositions(7), InputError);
}

TEST(Design, DurationForTargetIsTheShortestThatReachesIt) {
  const Scenario s = PaperScenario(20.0, 90.0, 2.0, 15.0, 1);
  const ParameterLayout layout;
  const std::vector<int> K = TargetIndices(layout, "K");
  ASSERT_EQ(K.size(), 3u);
  const double target = 0.2;  // mV/g
  const TargetResult r = DurationForTarget(s, layout, K, target, 5.0, 600.0, {}, 0.02);
  ASSERT_TRUE(r.reached);
  EXPECT_LE(r.sigma_at_duration, target);
  HarmonicProfile p = s.profile;
  p.duration_s = r.duration_s / 1.05;
  const DesignPoint before = EvaluateProfile(s, p, layout, {});
  EXPECT_GT(std::max({before.sigma[kKx], before.sigma[kKy], before.sigma[kKz]}), target);
  EXPECT_LT(r.evaluations, 16);
  const TargetResult never = DurationForTarget(s, layout, K, 1e-6, 5.0, 30.0, {});
  EXPECT_FALSE(never.reached);
  EXPECT_THROW(TargetIndices(layout, "Q"), InputError);
}

// ---------------------------------------------------------------------------
// Monte Carlo

TEST(MonteCarlo, SmallRunHasSaneStatistics) {
  // 60 s at 50 Hz: short enough for a test, long enough that the batch
  // solver holds no parameter (at 25 Hz it holds dx2, BatchResult::held).
  Scenario s = PaperScenario(50.0, 60.0, 2.0, 15.0, 1);
  s.truth_spread = {{kDlambda2, 30.0 * kArcsecToRad}};
  MonteCarloOptions opt;
  opt.runs = 12;
  opt.threads = 2;
  const MonteCarloResult r = RunMonteCarlo(s, opt);
  ASSERT_EQ(r.estimators.size(), 3u);
  EXPECT_EQ(r.estimators[0].name, "ekf");
  EXPECT_EQ(r.estimators[2].name, "batch");
  for (const EstimatorStats& st : r.estimators) {
    EXPECT_EQ(st.runs, 12) << st.name;
    EXPECT_EQ(st.failures, 0) << st.first_failure;
    EXPECT_EQ(st.held_runs.sum(), 0) << st.name;
    // 12 runs x 27 parameters: the pooled rms of z within ~25 % of 1.
    EXPECT_GT(st.pooled_rms_z, 0.75) << st.name;
    EXPECT_LT(st.pooled_rms_z, 1.3) << st.name;
  }
  const EstimatorStats& batch = r.estimators[2];
  for (int i = 0; i < kNumBaseParams; ++i) {
    // The batch's own sigma (at its estimate) is the CRB (at the truth).
    EXPECT_NEAR(batch.mean_sigma[i] / r.crb[i], 1.0, 0.1) << r.layout.info(i).name;
    // 12 runs: the scatter is within a factor ~2 of the CRB.
    EXPECT_GT(batch.scatter[i] / r.crb[i], 0.4) << r.layout.info(i).name;
    EXPECT_LT(batch.scatter[i] / r.crb[i], 1.9) << r.layout.info(i).name;
  }
  // The same numbers with one thread.
  opt.runs = 3;
  opt.estimators = {"batch"};
  const MonteCarloResult a = RunMonteCarlo(s, opt);
  opt.threads = 1;
  const MonteCarloResult b = RunMonteCarlo(s, opt);
  EXPECT_EQ(a.estimators[0].scatter, b.estimators[0].scatter);
  opt.estimators = {"kalman"};
  EXPECT_THROW(RunMonteCarlo(s, opt), InputError);
}

// ---------------------------------------------------------------------------
// The commands

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

const char* kSmallScenario = R"(
profile: {amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0], duration_s: 30, rate_hz: 25}
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, gamma_y: 140, gamma_z: 64,
        Kxx: 0.002, dpsi: -33, dtheta_c: 43, dlambda2: -33, dx2: -7, dy2: 16, dz2: 4}
truth_spread: {dlambda2: 0.5}
noise: {accel_mV: 2.0, angle_arcsec: 15}
run:
  bench: {lever_arm_mm: [138, 20, 20]}
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
)";

struct Cli {
  fs::path dir;
  explicit Cli(const std::string& name) : dir(testing_fixtures::OwnTempDir(name)) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "scen.yaml") << kSmallScenario;
  }
  std::string Path(const std::string& f) const { return (dir / f).string(); }
  // Runs `triadcal ARGS`, stdout and stderr to files; returns the exit status.
  int Run(const std::string& args) const {
    return std::system((std::string(TRIADCAL_BIN) + " " + args + " > " + Path("out.txt") +
                        " 2> " + Path("err.txt"))
                           .c_str());
  }
  std::string Err() const { return Slurp(Path("err.txt")); }
};

TEST(ObservabilityCommand, WritesCrbCorrelationAndEachVariant) {
  const Cli c("obs_cmd");
  ASSERT_EQ(c.Run("observability " + c.Path("scen.yaml") + " -o " + c.Path("o.json")), 0)
      << c.Err();
  const nlohmann::json o = nlohmann::json::parse(Slurp(c.Path("o.json")));
  for (const char* key : {"crb", "correlation", "unobservable", "weakly_observable", "parameters",
                          "with_constraints", "without_constraints", "without_each_constraint",
                          "evaluated_at", "units"}) {
    EXPECT_TRUE(o.contains(key)) << key;
  }
  EXPECT_EQ(o["crb"].size(), static_cast<std::size_t>(kNumBaseParams));
  EXPECT_EQ(o["correlation"]["matrix"].size(), static_cast<std::size_t>(kNumBaseParams));
  EXPECT_NEAR(o["correlation"]["matrix"][3][3].get<double>(), 1.0, 1e-12);
  EXPECT_TRUE(o["unobservable"].empty());
  EXPECT_EQ(o["evaluated_at"], "truth");
  const nlohmann::json& u = o["without_constraints"]["unobservable"];
  ASSERT_EQ(u.size(), 1u);
  EXPECT_TRUE(u[0]["parameters"].contains("dlambda2"));
  EXPECT_TRUE(u[0]["parameters"].contains("gamma_y"));
  EXPECT_TRUE(u[0]["parameters"].contains("gamma_z"));
  EXPECT_NE(u[0]["description"].get<std::string>().find("inner bench axis"), std::string::npos);
  EXPECT_EQ(o["without_each_constraint"]["dpsi - dlambda2"]["unobservable"].size(), 1u);
  EXPECT_TRUE(o["parameters"]["dlambda2"]["estimable"].get<bool>());
  EXPECT_NE(Slurp(c.Path("out.txt")).find("UNOBSERVABLE: common rotation"), std::string::npos);

  // A recorded run, evaluated at a truth file: the same CRB, its readings
  // predicted there for the recorded motion (15" of angle noise moves the
  // attitude and the angles' derivatives a little: 0.07 % at most; 0.3 % with
  // the recorded readings in the Jacobian).
  ASSERT_EQ(c.Run("simulate " + c.Path("scen.yaml") + " -o " + c.Path("sim")), 0) << c.Err();
  ASSERT_EQ(c.Run("observability " + c.Path("sim/run.yaml") + " -o " + c.Path("r.json") +
                  " --at " + c.Path("sim/truth.json")),
            0)
      << c.Err();
  const nlohmann::json rr = nlohmann::json::parse(Slurp(c.Path("r.json")));
  EXPECT_EQ(rr["source"], "run");
  for (const char* n : {"Kx", "W0z", "alpha_y", "Kxy", "dtheta_c", "dz2"}) {
    EXPECT_NEAR(rr["crb"][n].get<double>() / o["crb"][n].get<double>(), 1.0, 0.005) << n;
  }

  // Bad input: one line, non-zero, no OUT.
  auto fails = [&](const std::string& args, const std::string& message) {
    fs::remove(c.Path("bad.json"));
    EXPECT_NE(c.Run(args + " -o " + c.Path("bad.json")), 0) << args;
    EXPECT_EQ(c.Err(), "triadcal: error: " + message + "\n") << args;
    EXPECT_FALSE(fs::exists(c.Path("bad.json"))) << args;
  };
  fails("observability " + c.Path("none.yaml"),
        c.Path("none.yaml") + ": cannot read (no such file or not readable)");
  std::ofstream(c.Path("broken.json")) << "{\"parameters\": {\"Kx\": \"big\"}}";
  fails("observability " + c.Path("scen.yaml") + " --at " + c.Path("broken.json"),
        c.Path("broken.json") + ": parameters.Kx: expected a number or {\"value\": number}");
  std::ofstream(c.Path("empty.json")) << "{}";
  fails("observability " + c.Path("scen.yaml") + " --at " + c.Path("empty.json"),
        c.Path("empty.json") +
            ": parameters: missing (expected a fit or filter OUT, or truth.json)");
  fails("observability " + c.Path("scen.yaml") + " --weak-below 0.5",
        "--unobservable-below, --weak-below: expected 0 < unobservable <= weak");
  std::ofstream(c.Path("typo.yaml")) << "profile: {duration_s: 30, rate_hz: 25}\nnoise: {acel_mV: 2}\n";
  fs::remove(c.Path("bad.json"));
  EXPECT_NE(c.Run("observability " + c.Path("typo.yaml") + " -o " + c.Path("bad.json")), 0);
  EXPECT_NE(c.Err().find(c.Path("typo.yaml") + ": noise"), std::string::npos) << c.Err();
  EXPECT_FALSE(fs::exists(c.Path("bad.json")));
}

// A recorded run's Fisher information is that of the readings the model
// predicts for its recorded attitude (as the fit's decision takes it), not of
// its recorded readings: two recordings of one profile that differ only in
// their reading noise (20 mV, 0.11 g; the angles exact) give one CRB. With
// the recorded readings in the Jacobian their noise was taken for specific
// force (the CRBs then differ by percents).
TEST(ObservabilityCommand, TheReadingNoiseOfARecordedRunIsNoInformation) {
  const Cli c("obs_reading_noise");
  std::string scenario = kSmallScenario;
  const std::string noise = "noise: {accel_mV: 2.0, angle_arcsec: 15}";
  ASSERT_NE(scenario.find(noise), std::string::npos);
  scenario.replace(scenario.find(noise), noise.size(), "noise: {accel_mV: 20.0, angle_arcsec: 0}");
  std::ofstream(c.Path("noisy.yaml")) << scenario;
  nlohmann::json crb[2];
  for (int seed = 1; seed <= 2; ++seed) {
    const std::string sim = c.Path("sim" + std::to_string(seed));
    ASSERT_EQ(c.Run("simulate " + c.Path("noisy.yaml") + " --seed " + std::to_string(seed) +
                    " -o " + sim),
              0)
        << c.Err();
    const std::string out = c.Path("o" + std::to_string(seed) + ".json");
    ASSERT_EQ(c.Run("observability " + sim + "/run.yaml -o " + out), 0) << c.Err();
    crb[seed - 1] = nlohmann::json::parse(Slurp(out))["crb"];
  }
  ASSERT_EQ(crb[0].size(), static_cast<std::size_t>(kNumBaseParams));
  for (const auto& [name, sigma] : crb[0].items()) {
    EXPECT_NEAR(crb[1][name].get<double>() / sigma.get<double>(), 1.0, 1e-9) << name;
  }
}

TEST(ObservabilityCommand, ARunsFileOfOneRunHasThatRunsCramerRaoBound) {
  // Joint and single alike: the information of the readings predicted for
  // the recorded motion (with the readings predicted at rest, the joint
  // CRB was up to 1.2 % off the single run's on a paper run).
  const Cli c("obs_joint_one");
  const std::string sim = c.Path("sim");
  ASSERT_EQ(c.Run("simulate " + c.Path("scen.yaml") + " --seed 3 -o " + sim), 0) << c.Err();
  ASSERT_EQ(c.Run("observability " + sim + "/run.yaml -o " + c.Path("single.json")), 0) << c.Err();
  std::ofstream(c.Path("runs.yaml")) << "runs:\n  - {run: sim/run.yaml, name: a}\n";
  ASSERT_EQ(c.Run("observability " + c.Path("runs.yaml") + " -o " + c.Path("joint.json")), 0)
      << c.Err();
  const nlohmann::json crb = nlohmann::json::parse(Slurp(c.Path("single.json")))["crb"];
  const nlohmann::json joint = nlohmann::json::parse(Slurp(c.Path("joint.json")))["parameters"];
  int compared = 0;
  for (const auto& [name, sigma] : crb.items()) {
    if (!joint.contains(name)) continue;  // a run's own parameters are name@run there
    ASSERT_TRUE(joint[name]["crb_sigma"].is_number()) << name;
    EXPECT_NEAR(joint[name]["crb_sigma"].get<double>() / sigma.get<double>(), 1.0, 1e-6) << name;
    ++compared;
  }
  EXPECT_EQ(compared, 21);  // the triad's: K, W0, the angles and K_ij
}

TEST(DesignCommand, WritesTablePlotAndTargets) {
  const Cli c("design_cmd");
  ASSERT_EQ(c.Run("design " + c.Path("scen.yaml") + " -o " + c.Path("d.json") +
                  " --durations 30,60,120 --periods 30:12,15:6 --amplitudes 360:90 "
                  "--target K=0.3,dx2=2 --static-duration 600 --report " + c.Path("d.html")),
            0)
      << c.Err();
  const nlohmann::json d = nlohmann::json::parse(Slurp(c.Path("d.json")));
  for (const char* key : {"duration", "profiles", "targets", "comparison", "units"}) {
    EXPECT_TRUE(d.contains(key)) << key;
  }
  EXPECT_EQ(d["duration"]["durations_s"].size(), 3u);
  EXPECT_EQ(d["duration"]["quasi_harmonic"]["sigma"]["Kx"].size(), 3u);
  EXPECT_EQ(d["profiles"].size(), 2u);
  ASSERT_EQ(d["targets"].size(), 2u);
  EXPECT_EQ(d["targets"][0]["unit"], "mV/g");
  EXPECT_TRUE(d["targets"][0]["reached"].get<bool>());
  const nlohmann::json& cmp = d["comparison"];
  EXPECT_EQ(cmp["static_not_determined"], (nlohmann::json{"dx2", "dy2", "dz2"}));
  EXPECT_TRUE(cmp["quasi_harmonic_not_determined"].empty());
  // The curves the HTML report draws (its browser test: tests/report_browser_test.cpp).
  EXPECT_EQ(d["duration"]["groups"].size(), 6u);
  EXPECT_EQ(d["duration"]["groups"][0]["unit"], "mV/g");
  const std::string html = Slurp(c.Path("d.html"));
  EXPECT_NE(html.find("\"command\":\"design\""), std::string::npos);
  const std::string table = Slurp(c.Path("out.txt"));
  EXPECT_NE(table.find("static 12-position method"), std::string::npos);

  auto fails = [&](const std::string& args, const std::string& message) {
    fs::remove(c.Path("bad.json"));
    fs::remove(c.Path("bad.html"));
    EXPECT_NE(c.Run("design " + c.Path("scen.yaml") + " -o " + c.Path("bad.json") + " --report " +
                    c.Path("bad.html") + " " + args),
              0);
    EXPECT_EQ(c.Err(), "triadcal: error: " + message + "\n") << args;
    EXPECT_FALSE(fs::exists(c.Path("bad.json")));
    EXPECT_FALSE(fs::exists(c.Path("bad.html")));
  };
  fails("--target Q=1", "--target: unknown parameter or group 'Q' (a parameter name or K, W0, "
                        "angles, K_ij, bench, dR)");
  fails("--target K", "--target: expected NAME=SIGMA (file units) such as K=0.5, got 'K'");
  fails("--durations 30,-5", "--durations: expected a positive number, got '-5'");
  fails("--periods 30", "--periods: expected OUTER:INNER pairs such as 30:12, got '30'");
  fails("--static-positions 7", "--static-positions: expected 6, 12 or 18, got 7");
}

TEST(MonteCarloCommand, WritesStatisticsPerParameterAndEstimator) {
  const Cli c("mc_cmd");
  ASSERT_EQ(c.Run("montecarlo " + c.Path("scen.yaml") + " -n 6 -o " + c.Path("m.json") +
                  " --per-seed"),
            0)
      << c.Err();
  const nlohmann::json m = nlohmann::json::parse(Slurp(c.Path("m.json")));
  for (const char* key : {"parameters", "crb", "pooled", "scatter_over_crb", "per_seed",
                          "sampling_error_relative"}) {
    EXPECT_TRUE(m.contains(key)) << key;
  }
  EXPECT_EQ(m["runs"], 6);
  const nlohmann::json& kx = m["parameters"]["Kx"];
  for (const char* est : {"ekf", "rts", "batch"}) {
    ASSERT_TRUE(kx.contains(est)) << est;
    for (const char* key : {"scatter", "mean_sigma", "rms_normalised_error", "scatter_over_crb",
                            "mean_error"}) {
      EXPECT_TRUE(kx[est].contains(key)) << est << " " << key;
    }
    EXPECT_EQ(m["pooled"][est]["failures"], 0);
  }
  EXPECT_GT(kx["crb"].get<double>(), 0.0);
  EXPECT_EQ(m["per_seed"]["runs"].size(), 6u);
  EXPECT_NE(Slurp(c.Path("out.txt")).find("sampling error"), std::string::npos);

  fs::remove(c.Path("bad.json"));
  EXPECT_NE(c.Run("montecarlo " + c.Path("scen.yaml") + " -n 2 --estimators ekf,lsq -o " +
                  c.Path("bad.json")),
            0);
  EXPECT_EQ(c.Err(), "triadcal: error: --estimators: unknown estimator 'lsq' (ekf, rts, batch)\n");
  EXPECT_FALSE(fs::exists(c.Path("bad.json")));
  EXPECT_NE(c.Run("montecarlo " + c.Path("scen.yaml") + " -n 0 -o " + c.Path("bad.json")), 0);
  EXPECT_EQ(c.Err(), "triadcal: error: -n: at least 1 run, got 0\n");
  EXPECT_FALSE(fs::exists(c.Path("bad.json")));
}

}  // namespace
}  // namespace triadcal
