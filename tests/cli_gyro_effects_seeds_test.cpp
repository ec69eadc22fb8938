// The gyro's effects over seeds (docs/method.md section 11): for each
// gyro-stage effect of the catalogue, ten seeds of a two-axis run with a gyro
// and that effect in its readings (`simulate`, every kind of gyro parameter
// non-zero), each fitted by `fit --effects EFFECT` as a user would: every
// parameter the fit estimates -- the effect's and the gyro's 21 -- within 4
// sigma of the truth, and the RMS of error / sigma over the seeds within
// 0.7-1.3 for the effect's parameters and for the gyro's base parameters.
//
// The run is the paper's (50 Hz, 90 s, accelerometer 2 mV, angles 15",
// gyro 0.05 deg/s). The hold rule keeps k2_y and k2_z of gyro_nonlinearity
// there, not k2_x, the inner axis's: its rate is one sine, whose cube is 0.95
// correlated with itself; the fit considers it at nominal, its prior carried
// into gyro.Kx's sigma, and the test counts it as not estimated and prints
// so (at least two of an effect's three parameters must be estimated in
// every seed). dlambda2's truth is drawn per seed around the constraint dpsi
// - dlambda2 = 0 +- 30" (truth_spread), as on a real bench.
//
// Statistical: 20 simulations and fits (label `statistical`, left out of the
// sanitizer stage; about 8 s of CPU in the release build).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "core/io/file_util.h"
#include "core/model/effects.h"
#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

using testing_fixtures::RunTriadcal;

constexpr int kSeeds = 10;

// The scenario with `effects` (a scenario's effects: block) in the gyro's
// readings.
std::string GyroScenario(const std::string& effects) {
  return "truth_spread: {dlambda2: 0.5}\n"
         "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 90, "
         "rate_hz: 50}\n"
         "truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3,\n"
         "        alpha_x: 16, alpha_y: -32, beta_x: 11, beta_z: 26, gamma_y: 140, gamma_z: 64,\n"
         "        Kxx: 0.002, Kyz: -0.001, Kzy: 0.0015, dpsi: -33, dtheta_c: 43, dlambda2: -33,\n"
         "        dx2: -7, dy2: 16, dz2: 4,\n"
         "        gyro.Kx: 1.004, gyro.Ky: 0.997, gyro.Kz: 1.002,\n"
         "        gyro.W0x: 0.31, gyro.W0y: -0.52, gyro.W0z: 0.12,\n"
         "        gyro.alpha_x: 12, gyro.alpha_y: -20, gyro.beta_x: 8, gyro.beta_z: 15,\n"
         "        gyro.gamma_y: -9, gyro.gamma_z: 25,\n"
         "        gyro.Gxx: 0.05, gyro.Gyz: -0.08, gyro.Gzy: 0.03}\n"
         "noise: {accel_mV: 2, angle_arcsec: 15, gyro_dps: 0.05}\n" +
         effects +
         "run:\n"
         "  bench: {lever_arm_mm: [138, 20, 20]}\n"
         "  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}\n"
         "  gyro: {noise_dps: 0.05}\n"
         "  constraints: [{expr: \"dpsi - dlambda2\", value_arcmin: 0, sigma_arcsec: 30}]\n";
}

// truth.json's value of parameter `name` (an effect's key carries its unit:
// "gyro_nonlinearity.k2_x_ppm_per_(deg_per_s)^2").
double TruthOf(const nlohmann::json& truth, const std::string& name) {
  for (auto it = truth.begin(); it != truth.end(); ++it) {
    if (it.key() == name || it.key().rfind(name + "_", 0) == 0) return it.value().get<double>();
  }
  ADD_FAILURE() << "no truth for " << name;
  return 0.0;
}

class CliGyroEffectsSeeds : public testing_fixtures::TempDirTest {};

TEST_F(CliGyroEffectsSeeds, EachGyroEffectOverTenSeeds) {
  // Per effect: its parameters' truth in file units.
  const std::map<std::string, std::string> truths = {
      {"gyro_scale_asymmetry", "{dKx: 3000, dKy: -2000, dKz: 1000}"},
      {"gyro_nonlinearity", "{k2_x: 0.02, k2_y: -0.03, k2_z: 0.025}"}};
  int effects = 0;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kGyro) continue;
    ++effects;
    SCOPED_TRACE(e.name);
    ASSERT_EQ(truths.count(e.name), 1u) << "give the new gyro effect a truth here";
    const std::string scenario =
        WriteText(e.name + ".yaml", GyroScenario("effects: {" + e.name + ": " +
                                                 truths.at(e.name) + "}\n"));
    // Sum of z^2 and count per parameter; per group (effect, gyro base).
    std::map<std::string, double> ss;
    std::map<std::string, int> n, not_estimated;
    double ss_effect = 0.0, ss_base = 0.0;
    int n_effect = 0, n_base = 0;
    for (int seed = 1; seed <= kSeeds; ++seed) {
      const std::string dir = Path(e.name + "_" + std::to_string(seed));
      const std::string err = Path("err.txt");
      auto r = RunTriadcal("simulate " + scenario + " --seed " + std::to_string(seed) + " -o " +
                               dir,
                           err);
      ASSERT_EQ(r.status, 0) << r.err;
      r = RunTriadcal("fit " + dir + "/run.yaml --effects " + e.name + " -o " + dir + "/fit.json",
                      err);
      ASSERT_EQ(r.status, 0) << r.err;
      const nlohmann::json truth =
          nlohmann::json::parse(ReadFile(dir + "/truth.json"))["parameters"];
      const nlohmann::json fit = nlohmann::json::parse(ReadFile(dir + "/fit.json"));
      ASSERT_EQ(fit["converged"], true) << "seed " << seed;
      for (auto it = fit["parameters"].begin(); it != fit["parameters"].end(); ++it) {
        const std::string& name = it.key();
        const bool of_effect = name.rfind(e.name + ".", 0) == 0;
        if (!of_effect && name.rfind("gyro.", 0) != 0) continue;
        const nlohmann::json& p = it.value();
        if (!p.value("determined", false) || p.value("considered", false)) {
          ++not_estimated[name];
          continue;
        }
        const double z = (p["value"].get<double>() - TruthOf(truth, name)) /
                         p["sigma"].get<double>();
        EXPECT_LT(std::abs(z), 4.0) << name << " seed " << seed;
        ss[name] += z * z;
        ++n[name];
        (of_effect ? ss_effect : ss_base) += z * z;
        ++(of_effect ? n_effect : n_base);
      }
    }
    std::printf("%s, %d seeds (fit --effects %s):\n", e.name.c_str(), kSeeds, e.name.c_str());
    for (const auto& [name, s] : ss) {
      std::printf("  %-28s RMS z %.2f over %d\n", name.c_str(), std::sqrt(s / n[name]), n[name]);
    }
    for (const auto& [name, k] : not_estimated) {
      std::printf("  %-28s not estimated in %d of %d seeds (held or considered)\n", name.c_str(),
                  k, kSeeds);
    }
    const double rms_effect = std::sqrt(ss_effect / std::max(1, n_effect));
    const double rms_base = std::sqrt(ss_base / std::max(1, n_base));
    const double rms_all = std::sqrt((ss_effect + ss_base) / std::max(1, n_effect + n_base));
    std::printf("  effect's parameters RMS z %.3f over %d; gyro base RMS z %.3f over %d; all %.3f\n",
                rms_effect, n_effect, rms_base, n_base, rms_all);
    // The gyro's 21 estimated in every seed, and at least two of the
    // effect's three (gyro_nonlinearity's k2_x is not: above).
    EXPECT_GE(n_effect, 2 * kSeeds);
    EXPECT_EQ(n_base, 21 * kSeeds);
    for (double rms : {rms_effect, rms_base, rms_all}) {
      EXPECT_GT(rms, 0.7);
      EXPECT_LT(rms, 1.3);
    }
  }
  EXPECT_GE(effects, 2);
}

}  // namespace
}  // namespace triadcal
