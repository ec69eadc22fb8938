// The EKF + RTS smoother against simulated truth: normalised errors over seeds,
// the unseparable case, and the command's handling of a bad run.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "solvers/estimation/observability.h"
#include "solvers/estimation/kalman_smoother.h"
#include "solvers/estimation/separability.h"
#include "tests/sim_fixtures.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

FilterResult Filter(const Scenario& s, const RunData& data, int iterations = 2) {
  FilterOptions opt;
  opt.smoother_iterations = iterations;
  return RunFilterSmoother(s.run, data, ParameterLayout(), opt);
}

// Over several seeds the smoothed estimates scatter about the truth as their
// sigma says: RMS of (estimate - truth) / sigma near 1 for every parameter
// group, and no parameter beyond 4.5 sigma. The truth satisfies the constraint
// exactly, so dlambda2, gamma_y, gamma_z (known to ~30") are left out of the RMS.
TEST(KalmanSmoother, NormalisedErrorsOverSeeds) {
  const int kSeeds = 8;
  double sum_z2 = 0.0;
  int count = 0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, seed);
    const RunData data = Simulate(s);
    const FilterResult r = Filter(s, data);
    for (int i = 0; i < kNumBaseParams; ++i) {
      const double z = (r.rts.theta[i] - s.truth[i]) / std::sqrt(r.rts.cov(i, i));
      EXPECT_LT(std::abs(z), 4.5) << "seed " << seed << " " << ParameterLayout().info(i).name;
      if (i == kDlambda2 || i == kGammaY || i == kGammaZ) continue;
      sum_z2 += z * z;
      ++count;
    }
    EXPECT_GT(r.mean_nis, 4.5);
    EXPECT_LT(r.mean_nis, 7.5);
  }
  const double rms = std::sqrt(sum_z2 / count);
  EXPECT_GT(rms, 0.75);
  EXPECT_LT(rms, 1.25);
}

// The smoother's sigma equals the final filter sigma of the same linearisation
// (no process noise on theta); with one pass the two coincide.
TEST(KalmanSmoother, SmootherSigmaEqualsFilterSigmaForConstantParameters) {
  const Scenario s = PaperScenario(50.0, 30.0, 2.0, 15.0, 3);
  const RunData data = Simulate(s);
  const FilterResult r = Filter(s, data, 1);
  for (int i = 0; i < kNumBaseParams; ++i) {
    const double se = std::sqrt(r.ekf.cov(i, i)), sr = std::sqrt(r.rts.cov(i, i));
    EXPECT_LE(sr, se * (1.0 + 1e-6)) << ParameterLayout().info(i).name;
    EXPECT_NEAR(r.rts.theta[i], r.ekf.theta[i], 1e-6 * se) << ParameterLayout().info(i).name;
  }
}

// Noise-free data: the filter lands on the truth to far below the sigma that the
// declared noise implies.
TEST(KalmanSmoother, NoiseFreeRecoversTruth) {
  Scenario s = PaperScenario(50.0, 90.0, 0.0, 0.0, 1);
  s.run.noise_mV = 2.0;  // declared noise: the sigma scale to compare with
  s.run.angle_noise_rad = 15.0 * kArcsecToRad;
  const RunData data = Simulate(s);
  const FilterResult r = Filter(s, data);
  for (int i = 0; i < kNumBaseParams; ++i) {
    const double z = (r.rts.theta[i] - s.truth[i]) / std::sqrt(r.rts.cov(i, i));
    EXPECT_LT(std::abs(z), 0.05) << ParameterLayout().info(i).name;
  }
}

// Without the paper's constraint the rotation about the inner axis is named.
TEST(KalmanSmoother, UnseparableWithoutConstraint) {
  Scenario s = PaperScenario(20.0, 90.0, 2.0, 15.0, 5);
  const RunData data = Simulate(s);
  s.run.constraints.clear();
  const FilterResult r = Filter(s, data);
  const std::vector<WeakDirection> weak =
      UnsupportedDirections(ParameterLayout(), r.rts.cov, r.prior.sigma);
  ASSERT_EQ(weak.size(), 1u);
  std::vector<std::string> names = ParametersIn(weak);
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"dlambda2", "gamma_y", "gamma_z"}));
  EXPECT_NE(weak[0].description.find("inner bench axis"), std::string::npos);
  // With the constraint nothing is unseparable.
  s.run.constraints = PaperScenario(20.0, 90.0, 2.0, 15.0, 5).run.constraints;
  const FilterResult rc = Filter(s, data);
  EXPECT_TRUE(UnsupportedDirections(ParameterLayout(), rc.rts.cov, rc.prior.sigma).empty());
}

// Memory: what the smoother stores grows with the epochs, not the samples.
TEST(KalmanSmoother, EpochsFollowEpochInterval) {
  RunData d;
  for (int k = 0; k < 1001; ++k) d.t_s.push_back(k * 0.001);
  EXPECT_EQ(ChooseEpochs(d, 0.2).size(), 6u);  // 0, 0.2, ..., 1.0
  EXPECT_EQ(ChooseEpochs(d, 0.2).back(), 1000u);
}

int RunCommand(const std::string& args, std::string* err) {
  const std::string errfile = (testing_fixtures::OwnTempDir("filter_cmd") / "err.txt").string();
  std::filesystem::create_directories(testing_fixtures::OwnTempDir("filter_cmd"));
  const int rc = std::system((std::string(TRIADCAL_BIN) + " " + args + " 2> " + errfile +
                              " > /dev/null").c_str());
  std::ifstream in(errfile);
  err->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return rc;
}

TEST(FilterCommand, BadRunFileGivesOneLineAndNoOutput) {
  namespace fs = std::filesystem;
  const fs::path dir = testing_fixtures::OwnTempDir("filter_bad");
  fs::create_directories(dir);
  const fs::path yaml = dir / "run.yaml";
  std::ofstream(yaml) << "data: missing.csv\n";
  const fs::path out = dir / "out.json";
  std::string err;
  EXPECT_NE(RunCommand("filter " + yaml.string() + " -o " + out.string(), &err), 0);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("missing.csv"), std::string::npos) << err;

  // A bad key in run.yaml: named, and still no output.
  std::ofstream(yaml) << "data: run.csv\ntriad: {scale_mV_per_g: [174, 174]}\n";
  EXPECT_NE(RunCommand("filter " + yaml.string() + " -o " + out.string(), &err), 0);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_NE(err.find("triad.scale_mV_per_g"), std::string::npos) << err;
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// The command says plainly what it cannot separate: by default it holds
// dlambda2 and names the direction; without holding it names all three.
TEST(FilterCommand, NamesTheInnerAxisRotationWithoutTheConstraint) {
  namespace fs = std::filesystem;
  const fs::path dir = testing_fixtures::OwnTempDir("filter_nc");
  fs::remove_all(dir);
  const std::string bin = TRIADCAL_BIN;
  const std::string scen = std::string(TRIADCAL_SOURCE_DIR) + "/examples/paper-experiment3/scenario.yaml";
  ASSERT_EQ(std::system((bin + " simulate " + scen + " -o " + dir.string() + " > /dev/null").c_str()), 0);
  std::string yaml;
  {
    std::ifstream in(dir / "run.yaml");
    yaml.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::ofstream(dir / "run.yaml") << yaml.substr(0, yaml.find("constraints:")) << "constraints: []\n";
  auto run = [&](const std::string& extra) {
    const std::string out = (dir / "out.txt").string();
    EXPECT_EQ(std::system((bin + " filter " + (dir / "run.yaml").string() + " -o " +
                           (dir / "f.json").string() + extra + " > " + out).c_str()),
              0);
    std::ifstream in(out);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const std::string held = run("");
  EXPECT_NE(held.find("NOT DETERMINED, held at nominal (this run's motion does not determine them): dlambda2"),
            std::string::npos)
      << held;
  EXPECT_NE(held.find("common rotation of the triad about the inner bench axis"), std::string::npos);
  const std::string free = run(" --no-auto-hold");
  EXPECT_NE(free.find("NOT SEPARABLE in this run: gamma_y, gamma_z, dlambda2"), std::string::npos)
      << free;
}

}  // namespace
}  // namespace triadcal
