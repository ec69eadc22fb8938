// Simulate -> fit recovery of every registered effect (effects.cpp): each
// effect is injected at its catalogue typical size into a short run of the
// paper's profile and fitted by the batch solver with that effect declared,
// over a few seeds. Judged by error / sigma: over the seeds and the effect's
// estimated parameters, sum z^2 must pass a chi-square test (p > 1e-3) and no
// |z| may exceed 4.5. A parameter the run cannot carry is held by the solver's
// auto-hold and is then reported, not judged; at least one parameter of every
// effect must be estimated.
//
// Short runs (40 s at 100 Hz, 1 mV) keep this at about a second per effect;
// at 50 Hz and 2 mV axis_nonintersection.d (sigma ~4 mm against a 10-mm prior)
// falls below the auto-hold's information threshold and is held.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "solvers/estimation/batch_solver.h"
#include "solvers/statistics/statistics.h"
#include "tests/sim_fixtures.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

constexpr int kSeeds = 3;

Scenario InjectTypical(const EffectSpec& e, std::uint64_t seed) {
  // A drift's curvature needs minutes to be determined (its signal grows as
  // the square of the span: on 40 s it is not determined, and not estimated).
  const bool slow = e.id == Effect::kThermalDriftQuadratic;
  Scenario s = PaperScenario(slow ? 20.0 : 100.0, slow ? 300.0 : 40.0, 1.0, 15.0, seed);
  s.truth_layout = ParameterLayout({e.id});
  Eigen::VectorXd t = Eigen::VectorXd::Zero(s.truth_layout.size());
  t.head(kNumBaseParams) = s.truth;
  const double k_nom = s.run.scale_mV_per_g.cwiseAbs().maxCoeff();
  const int o = s.truth_layout.offset(e.id);
  for (size_t j = 0; j < e.params.size(); ++j) {
    t[o + j] = TypicalValue(e, e.params[j], k_nom) * e.params[j].si_per_unit;
  }
  s.truth = t;
  if (e.needs.temp_C) {
    s.write_temp = true;
    s.temp_rate_C_per_h = 30.0;
  }
  return s;
}

TEST(EffectRecovery, EveryRegisteredEffectIsRecoveredWithinItsSigma) {
  for (const EffectSpec& e : EffectCatalogue()) {
    // The gyro's effects need a run with a gyro: gyro_term_test.cpp
    // (FitRecoversEachGyroEffect).
    if (e.stage == EffectStage::kGyro) continue;
    SCOPED_TRACE("effect " + e.name);
    double sum_z2 = 0.0, worst = 0.0;
    int n = 0;
    std::ostringstream detail;
    for (int seed = 1; seed <= kSeeds; ++seed) {
      const Scenario s = InjectTypical(e, 100 + seed);
      const RunData data = Simulate(s);
      const BatchResult r = SolveBatch(s.run, data, s.truth_layout, BatchOptions{});
      const int o = s.truth_layout.offset(e.id);
      for (size_t j = 0; j < e.params.size(); ++j) {
        const int i = o + static_cast<int>(j);
        const std::string& name = s.truth_layout.info(i).name;
        if (!IsEstimated(r, name)) {
          detail << " " << name << " not estimated(seed " << seed << ")";
          continue;
        }
        const double z = (r.estimate.theta[i] - s.truth[i]) / std::sqrt(r.estimate.cov(i, i));
        detail << " " << name << " z=" << z;
        sum_z2 += z * z;
        worst = std::max(worst, std::abs(z));
        ++n;
      }
    }
    std::printf("[ recovery ] %-26s %d estimates, sum z^2 %.2f, worst |z| %.2f:%s\n",
                e.name.c_str(), n, sum_z2, worst, detail.str().c_str());
    EXPECT_GT(n, 0) << "no parameter of the effect is estimable on this run:" << detail.str();
    if (n > 0) {
      EXPECT_GT(ChiSquareSurvival(sum_z2, n), 1e-3) << detail.str();
    }
    EXPECT_LT(worst, 4.5) << detail.str();
  }
}

// `fit --effects NAME` on a noise-free simulated run without temp_C or a
// gyro, for every catalogue effect `pick` names: exit 2, no output, and the
// error line `why(effect)`. Returns how many effects were tried.
int ExpectEffectsRefused(const std::string& folder, bool (*pick)(const EffectSpec&),
                         const std::string& why) {
  namespace fs = std::filesystem;
  const fs::path dir = testing_fixtures::OwnTempDir(folder);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string bin = TRIADCAL_BIN;
  const std::string scen = std::string(TRIADCAL_SOURCE_DIR) + "/examples/noise-free/scenario.yaml";
  EXPECT_EQ(
      std::system(
          (bin + " simulate " + scen + " -o " + (dir / "run").string() + " > /dev/null").c_str()),
      0);
  int tested = 0;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (!pick(e)) continue;
    ++tested;
    const std::string cmd = bin + " fit " + (dir / "run" / "run.yaml").string() + " -o " +
                            (dir / "out.json").string() + " --effects " + e.name + " 2> " +
                            (dir / "err.txt").string() + " > /dev/null";
    EXPECT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 2) << e.name;
    EXPECT_FALSE(fs::exists(dir / "out.json"));
    std::ifstream in(dir / "err.txt");
    const std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(err, "triadcal: error: --effects: " + e.name + why + "\n");
  }
  return tested;
}

// What an effect needs (EffectSpec::needs) is checked before any fit: every
// effect whose entry needs temp_C is refused on a run without it, with one
// line, exit 2 and no output.
TEST(EffectNeeds, FitRefusesAnEffectWhoseDataTheRunLacks) {
  EXPECT_GT(ExpectEffectsRefused(
                "effect_needs", [](const EffectSpec& e) { return e.needs.temp_C; },
                " needs a temp_C column, which this run does not have (columns.temp_C in "
                "run.yaml)"),
            0);
}

// The gyro's effects on a run without a gyro: one line, exit 2, no output.
TEST(EffectNeeds, FitRefusesAGyroEffectOnARunWithoutAGyro) {
  EXPECT_EQ(ExpectEffectsRefused(
                "effect_needs_gyro",
                [](const EffectSpec& e) { return e.stage == EffectStage::kGyro; },
                " acts on the gyro, which this run does not have (gx gy gz columns and a "
                "gyro block in run.yaml)"),
            2);
}

}  // namespace
}  // namespace triadcal
