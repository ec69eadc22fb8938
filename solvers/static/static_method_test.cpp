// The standard static method (solvers/static/static_method.h, still_intervals.h) and
// what it needs from the readers: header-less text, a text label column,
// rows sorted by time. Simulated positions against their truth (labels, the
// gravity norm, bench angles), the static method next to the quasi-harmonic
// batch on one simulated sensor (the paper's Table 2), the real Ferraris and
// hand-held sessions of the shared folder (skipped without it), and the
// `static` command with its bad inputs.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/model/bench_model.h"
#include "core/io/column_mapping.h"
#include "core/model/errors.h"
#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/simulation/simulator.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/static/static_method.h"
#include "solvers/static/still_intervals.h"
#include "tests/sim_fixtures.h"
#include "core/io/run_description_io.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::PaperScenario;

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("triadcal_" + std::string(info->test_suite_name()) + "_" +
                                        info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(Path(name), std::ios::binary) << text;
    return Path(name);
  }

 private:
  fs::path dir_;
};

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// A run description with no bench: both angles held constant.
RunDescription NoBenchRun(double scale, double bias, double noise) {
  RunDescription run;
  run.yaml_path = "sim.yaml";
  run.scale_mV_per_g.setConstant(scale);
  run.bias_mV.setConstant(bias);
  run.noise_mV = noise;
  run.constraints.clear();
  for (const char* ch : {"lambda1", "lambda2"}) {
    ColumnSource c;
    c.constant = 0.0;
    run.columns[ch] = c;
  }
  return run;
}

// Holds of hold_s at rate_hz with readings z_p + white noise, separated by
// move_s of motion (a linear sweep plus a swing of swing_mV), with the label
// of each hold ("move" while moving) unless every label is empty.
struct Hold {
  Eigen::Vector3d z_mV;
  std::string label;
};

RunData MakeHolds(const std::vector<Hold>& holds, double hold_s, double move_s, double rate_hz,
                  double noise_mV, double swing_mV, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  RunData d;
  std::size_t k = 0;
  bool labelled = false;
  for (const Hold& h : holds) labelled = labelled || !h.label.empty();
  auto push = [&](const Eigen::Vector3d& z, const std::string& label) {
    d.t_s.push_back(static_cast<double>(k++) / rate_hz);
    for (int i = 0; i < 2; ++i) d.lambda_rad[i].push_back(0.0);
    for (int i = 0; i < 3; ++i) d.w_mV[i].push_back(z[i] + noise_mV * normal(rng));
    if (labelled) d.label.push_back(label);
  };
  const std::size_t n_hold = static_cast<std::size_t>(std::lround(hold_s * rate_hz));
  const std::size_t n_move = static_cast<std::size_t>(std::lround(move_s * rate_hz));
  for (std::size_t h = 0; h < holds.size(); ++h) {
    if (h > 0) {
      for (std::size_t j = 0; j < n_move; ++j) {
        const double f = (j + 0.5) / n_move;
        const Eigen::Vector3d z = (1 - f) * holds[h - 1].z_mV + f * holds[h].z_mV +
                                  Eigen::Vector3d::Constant(swing_mV * std::sin(kPi * f));
        push(z, "move");
      }
    }
    for (std::size_t j = 0; j < n_hold; ++j) push(holds[h].z_mV, holds[h].label);
  }
  return d;
}

// The readings of a triad at rest with specific force W (g), from the model.
Eigen::Vector3d ReadingsAt(const Eigen::VectorXd& truth, const Eigen::Vector3d& W) {
  ModelConfig cfg;
  return Readings_mV(cfg, truth.data(), W, SampleContext{});
}

Eigen::VectorXd SensorTruth(double scale, double bias) {
  Eigen::VectorXd t = Eigen::VectorXd::Zero(kNumBaseParams);
  SetFromFileUnits(ParameterLayout(),
                   {{"Kx", scale * 1.01}, {"Ky", scale * 0.99}, {"Kz", scale * 1.02},
                    {"W0x", bias + 12.0}, {"W0y", bias - 7.0}, {"W0z", bias + 3.0},
                    {"alpha_x", 16}, {"alpha_y", -32}, {"beta_x", 11}, {"beta_z", 26},
                    {"gamma_y", 140}, {"gamma_z", 64}, {"Kxx", 2e-3}, {"Kyy", -1.5e-3},
                    {"Kzz", 1e-3}, {"Kxy", 1e-3}, {"Kyz", -1e-3}, {"Kzx", 2e-3}},
                   &t);
  return t;
}

double Z(const StaticResult& r, const Eigen::VectorXd& truth, int i) {
  return (r.theta[i] - truth[i]) / std::sqrt(r.cov(i, i));
}

bool IsHeld(const StaticResult& r, const std::string& name) {
  for (const HeldParameter& h : r.held) {
    if (h.name == name) return true;
  }
  return false;
}

// ---------------------------------------------------------------------------
// Readers: header-less text, a label column, sorting by time.
// ---------------------------------------------------------------------------

TEST(StaticReader, HeaderlessTextWithDataFormatHeader) {
  TempDir dir;
  dir.Write("acc.txt", "# a comment\n  0.00  33100 33330 36430\n 0.01 33101 33331 36431\n");
  std::string rows;
  for (int k = 2; k < 12; ++k) {
    rows += std::to_string(0.01 * k) + " " + std::to_string(33100 + k) + " 33330 36430\n";
  }
  std::ofstream(dir.Path("acc.txt"), std::ios::app) << rows;
  const std::string yaml = dir.Write(
      "run.yaml",
      "data: acc.txt\n"
      "data_format: {header: [time, ax, ay, az]}\n"
      "columns: {t: time, lambda1: {value: 0}, lambda2: {value: 0}, wx: ax, wy: ay, wz: az}\n"
      "triad: {scale_mV_per_g: [4050, 4050, 4050], bias_mV: [32768, 32768, 32768]}\n");
  const RunDescription run = LoadRunDescription(yaml);
  ASSERT_EQ(run.data_header.size(), 4u);
  const RunData d = LoadRunData(run, nullptr);
  ASSERT_EQ(d.size(), 12u);
  EXPECT_EQ(d.t_s[1], 0.01);
  EXPECT_EQ(d.w_mV[0][0], 33100.0);
  EXPECT_EQ(d.w_mV[2][1], 36431.0);
  EXPECT_FALSE(d.has_label());
  // Without data_format.header the first line is taken as the header.
  const std::string plain = dir.Write(
      "plain.yaml", "data: acc.txt\ncolumns: {t: time, lambda1: {value: 0}, lambda2: {value: 0}}\n");
  EXPECT_EQ(ErrorOf([&] { LoadRunData(LoadRunDescription(plain), nullptr); }),
            dir.Path("acc.txt") + ":2: missing column 'time' (for t) (header: 0.00, 33100, 33330, "
                                  "36430)");
  // A header naming too many columns: the error names data_format.header.
  const std::string wide = dir.Write(
      "wide.yaml",
      "data: acc.txt\ndata_format: {header: [time, ax, ay, az, temp]}\n"
      "columns: {t: time, lambda1: {value: 0}, lambda2: {value: 0}, wx: ax, wy: ay, wz: az, "
      "temp_C: temp}\n"
      "triad: {scale_mV_per_g: [4050, 4050, 4050], bias_mV: [32768, 32768, 32768]}\n");
  EXPECT_EQ(ErrorOf([&] { LoadRunData(LoadRunDescription(wide), nullptr); }),
            dir.Path("acc.txt") + ":2: 4 fields, but column 'temp' is field 5 of data_format.header");
}

TEST(StaticReader, LabelColumnAndSortByTime) {
  TempDir dir;
  // Grouped by label, not in time order (as the Ferraris session).
  std::string csv = "part,samples,acc_x,acc_y,acc_z\n";
  for (int k = 10; k < 20; ++k) csv += "x_a," + std::to_string(k) + ",-2000,100,-100\n";
  for (int k = 0; k < 10; ++k) csv += "x_p," + std::to_string(k) + ",2000,100,-100\n";
  dir.Write("s.csv", csv);
  const std::string base =
      "data: s.csv\n"
      "columns: {t: {source: samples, scale: 0.0048828125}, lambda1: {value: 0}, "
      "lambda2: {value: 0}, wx: acc_x, wy: acc_y, wz: acc_z, label: part}\n"
      "triad: {scale_mV_per_g: [2048, 2048, 2048], bias_mV: [0, 0, 0]}\n";
  const RunDescription run = LoadRunDescription(dir.Write("run.yaml", base +
                                                          "data_format: {sort_by_time: true}\n"));
  EXPECT_TRUE(run.sort_by_time);
  EXPECT_EQ(LabelSource(run), "part");
  const RunData d = LoadRunData(run, nullptr);
  ASSERT_EQ(d.size(), 20u);
  ASSERT_TRUE(d.has_label());
  for (std::size_t k = 0; k < 20; ++k) {
    EXPECT_EQ(d.t_s[k], k * 0.0048828125);
    EXPECT_EQ(d.label[k], k < 10 ? "x_p" : "x_a");
    EXPECT_EQ(d.w_mV[0][k], k < 10 ? 2000.0 : -2000.0);
  }
  // Unsorted without the option: the time check names the line.
  const RunDescription unsorted = LoadRunDescription(dir.Write("u.yaml", base));
  EXPECT_EQ(ErrorOf([&] { LoadRunData(unsorted, nullptr); }),
            dir.Path("s.csv") +
                ":12: column 'samples' (t): time decreases from 0.09277 s to 0 s");
  // The label column must exist.
  const std::string missing = dir.Write(
      "m.yaml", "data: s.csv\ndata_format: {sort_by_time: true}\n"
                "columns: {t: {source: samples, scale: 0.0048828125}, lambda1: {value: 0}, "
                "lambda2: {value: 0}, wx: acc_x, wy: acc_y, wz: acc_z, label: position}\n"
                "triad: {scale_mV_per_g: [2048, 2048, 2048], bias_mV: [0, 0, 0]}\n");
  EXPECT_EQ(ErrorOf([&] { LoadRunData(LoadRunDescription(missing), nullptr); }),
            dir.Path("s.csv") + ":1: missing column 'position' (for label) (header: part, samples, "
                                "acc_x, acc_y, acc_z)");
}

TEST(StaticReader, PositionsAndDataFormatErrorsNameTheKey) {
  TempDir dir;
  const std::string f = dir.Path("run.yaml");
  auto error = [&](const std::string& yaml) {
    return ErrorOf([&] { LoadRunDescription(dir.Write("run.yaml", "data: x.csv\n" + yaml)); });
  };
  EXPECT_EQ(error("positions: {x_p: \"+w\"}\n"),
            f + ": positions.x_p: expected +x, -x, +y, -y, +z, -z, a list [x, y, z] or none, got "
                "'+w'");
  EXPECT_EQ(error("positions: {x_p: [0, 0, 0]}\n"),
            f + ": positions.x_p: the up direction must not be [0, 0, 0]");
  EXPECT_EQ(error("positions: []\n"),
            f + ": positions: expected a map {LABEL: \"+x\" or [x, y, z]} of the direction that "
                "points up");
  EXPECT_EQ(error("data_format: {header: [a, a]}\n"),
            f + ": data_format.header[1]: column name 'a' given twice");
  EXPECT_EQ(error("data_format: {sort_by_time: maybe}\n"),
            f + ": data_format.sort_by_time: expected true or false, got 'maybe'");
  EXPECT_EQ(error("data_format: {headers: [a]}\n"),
            f + ": data_format.headers: unknown key (allowed: header, sort_by_time)");
  EXPECT_EQ(error("columns: {label: {unit: deg}}\n"),
            f + ": columns.label.unit: unknown key (allowed: source)");
  // A diagonal up direction is normalised; the Ferraris default otherwise.
  const RunDescription run =
      LoadRunDescription(dir.Write("run.yaml", "data: x.csv\npositions: {tilt: [1, 0, 1]}\n"));
  EXPECT_NEAR(run.positions.at("tilt").x(), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(PositionsOf(run).size(), 1u);
  // The new keys survive RunDescriptionToYaml (simulate writes run.yaml with it).
  RunDescription full = LoadRunDescription(dir.Write(
      "run.yaml",
      "data: x.csv\npositions: {tilt: [1, 0, 1], x_p: \"+x\"}\n"
      "data_format: {header: [time, a, b, c, part], sort_by_time: true}\n"
      "columns: {t: time, wx: a, wy: b, wz: c, label: part}\n"));
  const RunDescription back =
      LoadRunDescription(dir.Write("back.yaml", RunDescriptionToYaml(full, "x.csv")));
  EXPECT_EQ(back.data_header, full.data_header);
  EXPECT_TRUE(back.sort_by_time);
  EXPECT_EQ(LabelSource(back), "part");
  ASSERT_EQ(back.positions.size(), 2u);
  EXPECT_TRUE(back.positions.at("tilt").isApprox(full.positions.at("tilt"), 1e-15));
  EXPECT_TRUE(back.positions.at("x_p") == Eigen::Vector3d::UnitX());
  EXPECT_TRUE(PositionsOf(RunDescription()).at("y_a") == Eigen::Vector3d(0, -1, 0));
}

// ---------------------------------------------------------------------------
// Still intervals.
// ---------------------------------------------------------------------------

TEST(StaticStill, ReadingVarianceFindsEachHold) {
  std::vector<Hold> holds;
  for (int p = 0; p < 8; ++p) holds.push_back({Eigen::Vector3d(100.0 * p, -50.0 * p, 7.0), ""});
  const double rate = 100.0, hold_s = 4.0, move_s = 1.5;
  const RunData d = MakeHolds(holds, hold_s, move_s, rate, 2.0, 400.0, 3);
  StillOptions opt;
  const StillResult r = FindStillIntervals(d, StillTest::kReadingVariance, 2.0, 0.0, {}, opt);
  ASSERT_EQ(r.intervals.size(), holds.size());
  EXPECT_EQ(r.window_samples, 50u);
  for (std::size_t p = 0; p < holds.size(); ++p) {
    const double t0 = p * (hold_s + move_s);  // the hold is [t0, t0 + hold_s)
    const StillInterval& iv = r.intervals[p];
    // Inside the hold, and losing at most half a window plus the edge at an end.
    EXPECT_GE(iv.t_begin_s, t0 - 1e-9) << p;
    EXPECT_LE(iv.t_end_s, t0 + hold_s - 1.0 / rate + 1e-9) << p;
    EXPECT_GT(iv.duration_s(), hold_s - 2 * (0.25 + opt.edge_s) - 0.05) << p;
  }
  // A stricter minimum drops them all and says so.
  opt.min_still_s = 10.0;
  const StillResult none = FindStillIntervals(d, StillTest::kReadingVariance, 2.0, 0.0, {}, opt);
  EXPECT_TRUE(none.intervals.empty());
  EXPECT_EQ(none.dropped_short, holds.size());
  opt.min_still_s = -1.0;
  EXPECT_EQ(ErrorOf([&] { FindStillIntervals(d, StillTest::kReadingVariance, 2, 0, {}, opt); }),
            "min_still_s: must be > 0");
}

TEST(StaticStill, LabelsSplitAndSelect) {
  // Two holds with no motion between them but different labels, and one
  // with a label that is not a position.
  std::vector<Hold> holds = {{Eigen::Vector3d(1, 2, 3), "a"},
                             {Eigen::Vector3d(1, 2, 3), "b"},
                             {Eigen::Vector3d(1, 2, 3), "rot"}};
  const RunData d = MakeHolds(holds, 3.0, 0.0, 100.0, 2.0, 0.0, 4);
  const StillResult r =
      FindStillIntervals(d, StillTest::kReadingVariance, 2.0, 0.0, {"a", "b"}, StillOptions{});
  ASSERT_EQ(r.intervals.size(), 2u);
  EXPECT_EQ(r.intervals[0].label, "a");
  EXPECT_EQ(r.intervals[1].label, "b");
  EXPECT_LT(r.intervals[0].t_end_s, 3.0);
  EXPECT_GE(r.intervals[1].t_begin_s, 3.0);
}

// ---------------------------------------------------------------------------
// The fits on simulated positions.
// ---------------------------------------------------------------------------

// 26 directions: 6 faces, 12 edges, 8 corners of a cube.
std::vector<std::pair<std::string, Eigen::Vector3d>> CubeDirections() {
  std::vector<std::pair<std::string, Eigen::Vector3d>> out;
  for (int a = -1; a <= 1; ++a) {
    for (int b = -1; b <= 1; ++b) {
      for (int c = -1; c <= 1; ++c) {
        if (a == 0 && b == 0 && c == 0) continue;
        out.push_back({"d" + std::to_string(a) + std::to_string(b) + std::to_string(c),
                       Eigen::Vector3d(a, b, c).normalized()});
      }
    }
  }
  return out;
}

TEST(StaticMethod, LabelsRecoverTheFullSensorModelFromACube) {
  const Eigen::VectorXd truth = SensorTruth(174.0, 1500.0);
  RunDescription run = NoBenchRun(174.0, 1500.0, 2.0);
  std::vector<Hold> holds;
  for (const auto& [name, up] : CubeDirections()) {
    run.positions[name] = up;
    holds.push_back({ReadingsAt(truth, up), name});
  }
  const RunData d = MakeHolds(holds, 3.0, 1.0, 100.0, 0.0, 300.0, 5);  // noise-free
  const StaticResult r = SolveStatic(run, d, StaticReference::kLabels, StaticOptions{});
  ASSERT_EQ(r.positions.size(), 26u);
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(r.not_separable.empty());  // all 21 sensor parameters from 26 directions
  for (int i = 0; i <= kKzz; ++i) {
    // Noise-free, so only the weak priors pull: by (sigma / sigma_prior) (truth -
    // nominal) / sigma_prior in units of sigma, < 0.01 here.
    EXPECT_LT(std::abs(Z(r, truth, i)), 0.01) << r.layout.info(i).name;
  }
  for (const char* held : {"dpsi", "dtheta_c", "dlambda2", "dx2", "dy2", "dz2"}) {
    EXPECT_TRUE(IsHeld(r, held)) << held;
  }
  EXPECT_LT(r.residual_rms_mg, 1e-3);  // the same prior pull, < 1 ug
  EXPECT_EQ(r.sigma_source, "declared noise");  // noise-free: chi2 << dof
}

TEST(StaticMethod, SixPositionsCannotSeparateTheCrossCoupling) {
  const Eigen::VectorXd truth = SensorTruth(174.0, 1500.0);
  RunDescription run = NoBenchRun(174.0, 1500.0, 2.0);  // Ferraris labels by default
  std::vector<Hold> holds;
  for (const auto& [label, up] : DefaultLabelPositions()) holds.push_back({ReadingsAt(truth, up), label});
  const RunData d = MakeHolds(holds, 4.0, 1.0, 100.0, 2.0, 300.0, 6);
  const StaticResult r = SolveStatic(run, d, StaticReference::kLabels, StaticOptions{});
  ASSERT_EQ(r.positions.size(), 6u);
  // W = +-e_j never multiplies two different components: the six K_ij (i != j)
  // are prior values; scale, bias, the six angles and the K_ii are estimated.
  const std::set<std::string> weak(r.not_separable.begin(), r.not_separable.end());
  EXPECT_EQ(weak, (std::set<std::string>{"Kxy", "Kxz", "Kyx", "Kyz", "Kzx", "Kzy"}));
  for (int i = 0; i <= kKzz; ++i) {
    if (weak.count(r.layout.info(i).name)) continue;
    EXPECT_LT(std::abs(Z(r, truth, i)), 4.5) << r.layout.info(i).name;
  }
  // 18 numbers, 15 parameters: 3 degrees of freedom.
  EXPECT_NEAR(r.dof, 3.0, 0.01);
}

// Random orientations of a triad whose frame follows the norm fit's
// convention (alpha_y = beta_z = gamma_z = 0, K_ij = 0).
std::vector<Hold> RandomPoses(const Eigen::VectorXd& truth, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Hold> holds;
  for (int p = 0; p < n; ++p) {
    const Eigen::Vector3d W = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    holds.push_back({ReadingsAt(truth, W), ""});
  }
  return holds;
}

TEST(StaticMethod, GravityNormFitOverSeeds) {
  Eigen::VectorXd truth = SensorTruth(4050.0, 32768.0);
  for (const char* n : {"alpha_y", "beta_z", "gamma_z"}) truth[ParameterLayout().IndexOf(n)] = 0;
  for (int i = kKxx; i <= kKzz; ++i) truth[i] = 0.0;
  const RunDescription run = NoBenchRun(4000.0, 32768.0, 3.3);
  double sum = 0.0;
  int count = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const RunData d = MakeHolds(RandomPoses(truth, 30, seed), 3.0, 1.0, 100.0, 3.3, 2000.0, seed);
    const StaticResult r = SolveStatic(run, d, StaticReference::kNone, StaticOptions{});
    ASSERT_EQ(r.positions.size(), 30u) << seed;
    EXPECT_TRUE(r.converged);
    EXPECT_TRUE(r.not_separable.empty());
    for (const char* n : {"alpha_y", "beta_z", "gamma_z", "Kxy", "dpsi", "dx2"}) {
      EXPECT_TRUE(IsHeld(r, n)) << n;
    }
    // chi2/dof on 21 dof: standard deviation sqrt(2/21) = 0.31.
    EXPECT_NEAR(r.chi2_per_dof, 1.0, 4 * 0.31) << seed;
    for (int i : {kKx, kKy, kKz, kW0x, kW0y, kW0z, kAlphaX, kBetaX, kGammaY}) {
      const double z = (r.theta[i] - truth[i]) / std::sqrt(r.cov_declared(i, i));
      EXPECT_LT(std::abs(z), 4.5) << r.layout.info(i).name << " seed " << seed;
      sum += z * z;
      ++count;
    }
  }
  const double rms = std::sqrt(sum / count);  // 54 draws: +-0.1 around 1
  EXPECT_GT(rms, 0.7);
  EXPECT_LT(rms, 1.3);
}

// ---------------------------------------------------------------------------
// A static multi-position run on the bench, simulated with the model of
// bench_model.h: hold each (lambda1, lambda2) for hold_s, move to the next in
// move_s along lambda(tau) = a + (b - a)(1 - cos(pi tau / T)) / 2 (with its
// exact rates, so the motion is physical), white noise on readings and angles.
// ---------------------------------------------------------------------------
RunData SimulateStaticBench(const Scenario& s, const std::vector<std::array<double, 2>>& pos_deg,
                            double hold_s, double move_s) {
  const ModelConfig cfg = TruthModelConfig(s);
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  RunData d;
  double t = 0.0;
  const double dt = 1.0 / s.profile.rate_hz;
  auto sample = [&](const BenchAngles<double>& b) {
    const SampleContext ctx{t, 0.0};
    const Eigen::Vector3d z = PredictReadings_mV(cfg, s.truth.data(), b, ctx);
    d.t_s.push_back(t);
    for (int i = 0; i < 2; ++i) {
      d.lambda_rad[i].push_back(b.axis[i].angle + s.angle_noise_rad * normal(rng));
    }
    for (int i = 0; i < 3; ++i) d.w_mV[i].push_back(z[i] + s.accel_noise_mV * normal(rng));
    t += dt;
  };
  for (std::size_t p = 0; p < pos_deg.size(); ++p) {
    if (p > 0) {
      const double T = move_s;
      for (double tau = 0.0; tau < T; tau += dt) {
        BenchAngles<double> b;
        for (int i = 0; i < 2; ++i) {
          const double a = pos_deg[p - 1][i] * kDegToRad, c = pos_deg[p][i] * kDegToRad;
          const double w = kPi / T;
          b.axis[i].angle = a + 0.5 * (c - a) * (1.0 - std::cos(w * tau));
          b.axis[i].rate = 0.5 * (c - a) * w * std::sin(w * tau);
          b.axis[i].accel = 0.5 * (c - a) * w * w * std::cos(w * tau);
        }
        sample(b);
      }
    }
    BenchAngles<double> b;
    for (int i = 0; i < 2; ++i) b.axis[i].angle = pos_deg[p][i] * kDegToRad;
    for (double tau = 0.0; tau < hold_s; tau += dt) sample(b);
  }
  return d;
}

// lambda1 every 45 deg at lambda2 = 0, 45, 90, 135 deg: W = (cos l1,
// sin l1 sin l2, sin l1 cos l2) covers -g, 0, +g on each axis and the
// diagonals that the K_ij need. 32 positions of 70 + 5 s: 40 min.
std::vector<std::array<double, 2>> BenchPositions() {
  std::vector<std::array<double, 2>> p;
  for (double l2 : {0.0, 45.0, 90.0, 135.0}) {
    for (int k = 0; k < 8; ++k) p.push_back({45.0 * k, l2});
  }
  return p;
}

TEST(StaticMethod, BenchAnglesRecoverTheSensorAndTheBench) {
  Scenario s = PaperScenario(100.0, 0.0, 2.0, 15.0, 21);
  const RunData d = SimulateStaticBench(s, BenchPositions(), 20.0, 3.0);
  const StaticResult r = SolveStatic(s.run, d, StaticReference::kAngles, StaticOptions{});
  ASSERT_EQ(r.positions.size(), 32u);
  EXPECT_EQ(r.still.test, StillTest::kAngleRates);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.constraints_used, std::vector<std::string>{"dpsi - dlambda2"});
  for (int i = 0; i <= kDlambda2; ++i) {
    EXPECT_LT(std::abs(Z(r, s.truth, i)), 4.5) << r.layout.info(i).name;
  }
  for (const char* held : {"dx2", "dy2", "dz2"}) EXPECT_TRUE(IsHeld(r, held));
  // Without the constraint a static test cannot tell dlambda2 from a common
  // rotation of the triad about the inner axis (gamma_y, gamma_z), as the
  // quasi-harmonic run cannot (docs/method.md); dpsi and dtheta_c it separates.
  s.run.constraints.clear();
  const StaticResult u = SolveStatic(s.run, d, StaticReference::kAngles, StaticOptions{});
  const std::set<std::string> weak(u.not_separable.begin(), u.not_separable.end());
  EXPECT_TRUE(weak.count("dlambda2"));
  EXPECT_TRUE(weak.count("gamma_y") || weak.count("gamma_z"));
  EXPECT_FALSE(weak.count("dpsi"));
  EXPECT_FALSE(weak.count("dtheta_c"));
  for (const WeakDirection& w : u.weak) std::printf("  without the constraint: %s\n", w.description.c_str());
}

// The paper's Table 2 columns for one simulated sensor: the standard static
// method (40 min of positions on the bench) next to the quasi-harmonic batch
// (90 s of the paper's profile), each with its sigma. The bench is tilted as
// in experiment 3 for both; the truth is the fixture's (Table 2, exp. 3).
TEST(StaticVsQuasiHarmonic, Table2) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scenario qs = PaperScenario(100.0, 90.0, 2.0, 15.0, 31);
  const RunData qd = Simulate(qs);
  const BatchResult q = SolveBatch(qs.run, qd, ParameterLayout(), BatchOptions{});
  const Scenario ss = PaperScenario(100.0, 0.0, 2.0, 15.0, 32);
  const RunData sd = SimulateStaticBench(ss, BenchPositions(), 70.0, 5.0);
  const StaticResult st = SolveStatic(ss.run, sd, StaticReference::kAngles, StaticOptions{});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const ParameterLayout layout;
  std::printf("Simulated ADXL325-like triad, 100 Hz, 2 mV, 15\" (solvers/static/static_method_test.cpp)\n");
  std::printf("static: %.1f min, %zu positions; quasi-harmonic: %.1f min\n",
              (sd.t_s.back() - sd.t_s.front()) / 60.0, st.positions.size(),
              (qd.t_s.back() - qd.t_s.front()) / 60.0);
  std::printf("| parameter | unit | truth | static method | sigma | quasi-harmonic | sigma |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  const char* rows[] = {"Kx",      "Ky",      "Kz",      "W0x",     "W0y",      "W0z",
                        "alpha_y", "beta_z",  "alpha_x", "gamma_z", "beta_x",   "gamma_y",
                        "Kxx",     "Kyz",     "Kzy",     "dpsi",    "dtheta_c", "dlambda2",
                        "dx2",     "dy2",     "dz2"};
  double worst = 0.0;
  for (const char* name : rows) {
    const int i = layout.IndexOf(name);
    const double f = layout.info(i).si_per_unit;
    const double sq = std::sqrt(q.estimate.cov(i, i));
    // K_ij in 1e-3/g, everything else in its file unit.
    const double show = i >= kKxx && i <= kKzz ? f * 1e-3 : f;
    const std::string unit = i >= kKxx && i <= kKzz ? "1e-3/g" : layout.info(i).unit;
    char static_value[32] = "-", static_sigma[32] = "-";
    if (!IsHeld(st, name)) {
      std::snprintf(static_value, sizeof(static_value), "%.3f", st.theta[i] / show);
      std::snprintf(static_sigma, sizeof(static_sigma), "%.3f", std::sqrt(st.cov(i, i)) / show);
      worst = std::max(worst, std::abs(Z(st, ss.truth, i)));
    }
    std::printf("| %s | %s | %.6g | %s | %s | %.3f | %.3f |\n", name, unit.c_str(),
                qs.truth[i] / show, static_value, static_sigma, q.estimate.theta[i] / show,
                sq / show);
    EXPECT_LT(std::abs(q.estimate.theta[i] - qs.truth[i]) / sq, 4.5) << name;
  }
  std::printf("static: chi2/dof %.2f (%s); lever arm held (no effect at rest); %.1f s\n",
              st.chi2_per_dof, st.sigma_source.c_str(), seconds);
  EXPECT_LT(worst, 4.5);
}

// ---------------------------------------------------------------------------
// The real sessions of the shared folder (docs/real-data.md), skipped without it.
// ---------------------------------------------------------------------------

std::string SharedFile(const std::string& example, const std::string& rest) {
  const std::string yaml = std::string(TRIADCAL_SOURCE_DIR) + "/examples/" + example + "/run.yaml";
  const std::string path = ResolveDataPath(yaml, "shared:data/real/" + rest);
  return !path.empty() && fs::exists(path) ? path : "";
}

// Ferraris's estimator (imucal eqs. 19-23) on our averages of the six positions.
void FerrarisOnMeans(const StaticResult& r, double g, Eigen::Matrix3d* KR, Eigen::Vector3d* b) {
  std::map<std::string, Eigen::Vector3d> m;
  for (const StaticPosition& p : r.positions) m[p.name] = p.mean_mV;
  for (int j = 0; j < 3; ++j) {
    const std::string ax(1, "xyz"[j]);
    KR->col(j) = (m[ax + "_p"] - m[ax + "_a"]) / (2.0 * g);
    (*b)[j] = 0.5 * (m[ax + "_p"][j] + m[ax + "_a"][j]);
  }
}

// Regression: the published Ferraris calibration of the session (imucal's
// expected_calibration.json). Their model raw = K_a R_a a + b_a (a in m/s^2,
// g = 9.81) against ours raw = diag(K) M W + W0 (+ K_i K_ii on axis i):
//   K_a R_a = diag(K) M / 9.81,    b_a = W0 + diag(K) (Kxx, Kyy, Kzz)
// Tolerances, from what separates the two estimators (both average the same
// six positions):
//   1. the samples: Ferraris averages every sample of a label, we the still
//      intervals inside it. For white noise sigma the two means of a position
//      differ by sigma sqrt(1/N_ours - 1/N_label): 3 of those, propagated, per
//      element and for b_a;
//   2. the weights: Ferraris takes (z_p - z_a)/2 for a pair, our least
//      squares weighs z_p and z_a by their 1/sigma^2. Off the diagonal this
//      moves K_i M_ij by exactly (w_p - w_a)/(w_p + w_a) (e_p + e_a)/2 (e the
//      pair's residuals on axis i), and the weak prior on the angle shrinks
//      it by 1 - sigma_post^2/sigma_prior^2; both computed here and added. On
//      the diagonal and for b_a the pair of axis i is fitted exactly (K_i and
//      W0_i + K_i K_ii have only it), so there is no such term.
// The test checks that these two terms account for ours - Ferraris-on-our-
// means, and that ours - published stays within them plus the sample term.
TEST(StaticRealData, FerrarisReproducesThePublishedCalibration) {
  const std::string csv = SharedFile("ferraris", "ferraris-six-position/annotated_session.csv");
  if (csv.empty()) GTEST_SKIP() << "shared data folder absent";
  const std::string yaml = std::string(TRIADCAL_SOURCE_DIR) + "/examples/ferraris/run.yaml";
  const RunDescription run = LoadRunDescription(yaml);
  const RunData data = LoadRunData(run, nullptr);
  const nlohmann::json pub = nlohmann::json::parse(
      ReadFile((fs::path(csv).parent_path() / "expected_calibration.json").string()));
  Eigen::Matrix3d KR_pub;
  Eigen::Vector3d b_pub;
  for (int i = 0; i < 3; ++i) {
    b_pub[i] = pub["b_a"][i].get<double>();
    for (int j = 0; j < 3; ++j) {
      KR_pub(i, j) = pub["K_a"][i][i].get<double>() * pub["R_a"][i][j].get<double>();
    }
  }
  std::map<std::string, double> label_count;
  for (const std::string& l : data.label) label_count[l] += 1.0;

  const double g_ferraris = 9.81;  // their value
  for (const double placement_deg : {0.0, 0.35}) {
    StaticOptions opt;
    opt.placement_sigma_rad = placement_deg * kDegToRad;
    const StaticResult r = SolveStatic(run, data, StaticReference::kLabels, opt);
    ASSERT_EQ(r.positions.size(), 6u);
    Eigen::Matrix3d M;
    M << 1, -r.theta[kAlphaY], r.theta[kBetaZ], r.theta[kAlphaX], 1, -r.theta[kGammaZ],
        -r.theta[kBetaX], r.theta[kGammaY], 1;
    const Eigen::Vector3d K = r.theta.segment<3>(kKx);
    const Eigen::Matrix3d KR = K.asDiagonal() * M / g_ferraris;
    const Eigen::Vector3d b =
        r.theta.segment<3>(kW0x) + K.cwiseProduct(Eigen::Vector3d(r.theta[kKxx], r.theta[kKyy],
                                                                  r.theta[kKzz]));
    Eigen::Matrix3d KR_F;
    Eigen::Vector3d b_F;
    FerrarisOnMeans(r, g_ferraris, &KR_F, &b_F);

    std::map<std::string, const StaticPosition*> pos;
    for (const StaticPosition& p : r.positions) pos[p.name] = &p;
    auto sample_sigma = [&](const std::string& name) {  // of (our mean - label mean)
      return run.noise_mV *
             std::sqrt(1.0 / pos[name]->samples - 1.0 / label_count[name]);
    };
    std::printf("placement sigma %.2f deg: chi2/dof %.3g on %.2f dof (%s)\n", placement_deg,
                r.chi2_per_dof, r.dof, r.sigma_source.c_str());
    std::printf("  K_a R_a  published    ours        diff    tolerance  sigma\n");
    double worst_rel = 0.0;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const std::string ax(1, "xyz"[j]);
        const std::string P = ax + "_p", A = ax + "_a";
        const double sample_tol =
            3.0 * std::hypot(sample_sigma(P), sample_sigma(A)) / (2.0 * g_ferraris);
        double weight_term = 0.0, prior_term = 0.0;
        // K_i M_ij off the diagonal is K_i times one angle (paper eq. 1 M).
        const int angle_of[3][3] = {{-1, kAlphaY, kBetaZ}, {kAlphaX, -1, kGammaZ},
                                    {kBetaX, kGammaY, -1}};
        const int a = angle_of[i][j];
        if (i != j) {
          // Weights of axis i's readings in the two positions (placement adds
          // K_i^2 sigma_o^2 to a horizontal axis).
          const double s2o = opt.placement_sigma_rad * opt.placement_sigma_rad;
          const double Ki2 = run.scale_mV_per_g[i] * run.scale_mV_per_g[i];
          const double wp = 1.0 / (run.noise_mV * run.noise_mV / pos[P]->samples + Ki2 * s2o);
          const double wa = 1.0 / (run.noise_mV * run.noise_mV / pos[A]->samples + Ki2 * s2o);
          const double e = pos[P]->residual_mV[i] + pos[A]->residual_mV[i];
          weight_term = (wp - wa) / (wp + wa) * e / 2.0 / g_ferraris;
          // The weak prior (3 deg around 0) on the angle shrinks it by the
          // factor 1 - rho, rho = sigma_posterior^2 / sigma_prior^2.
          const double rho = r.cov_declared(a, a) / (r.prior.sigma[a] * r.prior.sigma[a]);
          prior_term = rho * std::abs(KR_F(i, j) + weight_term);
          // Ours = (Ferraris on our means + the weighting term) (1 - rho).
          EXPECT_NEAR(KR(i, j), (KR_F(i, j) + weight_term) * (1.0 - rho),
                      1e-4 * std::abs(weight_term) + 1e-6 * prior_term + 1e-9)
              << i << j;
        } else {
          // The pair of axis i alone fixes K_i: equal up to the priors' pull.
          EXPECT_NEAR(KR(i, j), KR_F(i, j), 1e-7 * KR_F(i, j)) << i;
        }
        const double tol = sample_tol + std::abs(weight_term) + prior_term;
        const double diff = KR(i, j) - KR_pub(i, j);
        const double sigma =
            (i == j ? std::sqrt(r.cov(kKx + i, kKx + i)) : K[i] * std::sqrt(r.cov(a, a))) /
            g_ferraris;
        std::printf("  (%d,%d) %11.5f %11.5f %10.5f %10.5f %8.4f\n", i, j, KR_pub(i, j), KR(i, j),
                    diff, tol, sigma);
        EXPECT_LE(std::abs(diff), tol) << i << j;
        worst_rel = std::max(worst_rel, std::abs(diff) / KR_pub(i, i));
      }
    }
    std::printf("  largest |diff| / K_a,ii = %.2e\n", worst_rel);
    EXPECT_LT(worst_rel, 1e-3);
    std::printf("  b_a      published    ours        diff    tolerance\n");
    for (int i = 0; i < 3; ++i) {
      const std::string ax(1, "xyz"[i]);
      const double tol = 3.0 * std::hypot(sample_sigma(ax + "_p"), sample_sigma(ax + "_a")) / 2.0;
      std::printf("  %c      %11.5f %11.5f %10.5f %10.5f\n", "xyz"[i], b_pub[i], b[i],
                  b[i] - b_pub[i], tol);
      EXPECT_NEAR(b[i], b_F[i], 1e-3) << i;  // exact up to the priors' pull
      EXPECT_LE(std::abs(b[i] - b_pub[i]), tol) << i;
    }
  }
}

// The hand-held session: no reference orientation, the gravity-norm fit, the
// residual |W| - 1 reported per pose.
TEST(StaticRealData, HandheldGravityNormFitPerPose) {
  const std::string txt = SharedFile("handheld", "handheld-multipose/xsens_acc.txt");
  if (txt.empty()) GTEST_SKIP() << "shared data folder absent";
  const RunDescription run =
      LoadRunDescription(std::string(TRIADCAL_SOURCE_DIR) + "/examples/handheld/run.yaml");
  const RunData data = LoadRunData(run, nullptr);
  EXPECT_EQ(data.size(), 51175u);
  const StaticReference ref = ChooseReference(run, data, "auto");
  ASSERT_EQ(ref, StaticReference::kNone);
  const StaticResult r = SolveStatic(run, data, ref, StaticOptions{});
  std::printf("hand-held: %zu poses, chi2/dof %.3g on %.1f dof (%s), RMS %.3f mg\n",
              r.positions.size(), r.chi2_per_dof, r.dof, r.sigma_source.c_str(),
              r.residual_rms_mg);
  double worst = 0.0;
  for (const StaticPosition& p : r.positions) {
    std::printf("  %-4s %6.1f s  |W|-1 = %+7.3f mg\n", p.name.c_str(), p.duration_s,
                p.norm_residual_mg);
    worst = std::max(worst, std::abs(p.norm_residual_mg));
  }
  // About 40 poses after the initial 50 s at rest (data README).
  EXPECT_GE(r.positions.size(), 35u);
  EXPECT_LE(r.positions.size(), 50u);
  EXPECT_GT(r.positions.front().duration_s, 40.0);
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(r.not_separable.empty());
  // A 16-bit Xsens: about 4050 counts/g, zero near 32768 (data README).
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r.theta[kKx + i], 4050.0, 100.0);
    EXPECT_NEAR(r.theta[kW0x + i], 32768.0, 1000.0);
  }
  // The poses agree with |W| = 1 g to a fraction of a mg (hand-held, so more
  // than the 3.3-count noise alone: chi2/dof > 1 and the sigma are scaled).
  EXPECT_LT(r.residual_rms_mg, 0.5);
  EXPECT_LT(worst, 1.5);
  EXPECT_EQ(r.sigma_source, "residual scatter");
}

// ---------------------------------------------------------------------------
// The command.
// ---------------------------------------------------------------------------

int RunCli(const std::string& args, const std::string& out_txt, const std::string& err_txt) {
  return std::system((std::string(TRIADCAL_BIN) + " " + args + " > " + out_txt + " 2> " + err_txt)
                         .c_str());
}

TEST(StaticCommand, WritesOutAndRejectsBadInput) {
  TempDir dir;
  const Eigen::VectorXd truth = SensorTruth(2048.0, 0.0);
  RunData d;
  std::vector<Hold> holds;
  for (const auto& [label, up] : DefaultLabelPositions()) holds.push_back({ReadingsAt(truth, up), label});
  d = MakeHolds(holds, 3.0, 1.0, 100.0, 7.0, 3000.0, 9);
  std::string csv = "part,samples,acc_x,acc_y,acc_z\n";
  for (std::size_t k = d.size(); k-- > 0;) {  // written backwards: needs sort_by_time
    csv += d.label[k] + "," + std::to_string(k) + "," + FormatDouble(d.w_mV[0][k]) + "," +
           FormatDouble(d.w_mV[1][k]) + "," + FormatDouble(d.w_mV[2][k]) + "\n";
  }
  dir.Write("s.csv", csv);
  const std::string yaml = dir.Write(
      "run.yaml",
      "data: s.csv\ndata_format: {sort_by_time: true}\n"
      "columns: {t: {source: samples, scale: 0.01}, lambda1: {value: 0}, lambda2: {value: 0}, "
      "wx: acc_x, wy: acc_y, wz: acc_z, label: part}\n"
      "triad: {scale_mV_per_g: [2048, 2048, 2048], bias_mV: [0, 0, 0], noise_mV: 7}\n");
  const std::string out = dir.Path("out.json"), txt = dir.Path("out.txt"), err = dir.Path("err");
  ASSERT_EQ(RunCli("static " + yaml + " -o " + out, txt, err), 0) << ReadFile(err);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(out));
  EXPECT_EQ(j["reference"], "labels");
  EXPECT_EQ(j["positions"].size(), 6u);
  EXPECT_EQ(j["parameters"].size(), static_cast<std::size_t>(kNumBaseParams));
  EXPECT_EQ(j["parameters"]["Kx"]["unit"], "mV/g");
  EXPECT_FALSE(j["parameters"]["Kxy"]["estimable"].get<bool>());
  EXPECT_FALSE(j["parameters"]["dpsi"]["estimable"].get<bool>());
  EXPECT_TRUE(j["parameters"]["dpsi"].contains("held"));
  EXPECT_TRUE(j["parameters"]["Kxx"]["estimable"].get<bool>());
  for (const char* key : {"sigma", "still_intervals", "held", "unobservable", "not_estimable",
                          "residual_rms_mg"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_TRUE(j["positions"][0].contains("residual_mg"));
  EXPECT_NE(ReadFile(txt).find("x_p"), std::string::npos);

  // --fix K_ij holds all nine.
  ASSERT_EQ(RunCli("static " + yaml + " -o " + out + " --fix K_ij", txt, err), 0);
  EXPECT_TRUE(nlohmann::json::parse(ReadFile(out))["held"].contains("Kxx"));

  // Bad input: one line, exit 2, no output file.
  const std::string bad = dir.Path("bad.json");
  auto error_of = [&](const std::string& args) {
    EXPECT_EQ(RunCli(args + " -o " + bad, txt, err) >> 8, 2) << args;
    EXPECT_FALSE(fs::exists(bad)) << args;
    return ReadFile(err);
  };
  EXPECT_EQ(error_of("static " + yaml + " --reference angles"),
            "triadcal: error: --reference angles: " + yaml +
                ": columns.lambda1/lambda2 are constants: no bench angles in this run\n");
  EXPECT_EQ(error_of("static " + yaml + " --reference sideways"),
            "triadcal: error: --reference: expected auto, angles, labels or none, got "
            "'sideways'\n");
  EXPECT_EQ(error_of("static " + yaml + " --fix Kqq"),
            "triadcal: error: --fix: unknown parameter 'Kqq' (names of docs/file-formats.md, or K_ij "
            "for all nine)\n");
  EXPECT_EQ(error_of("static " + yaml + " --noise-factor 0"),
            "triadcal: error: --noise-factor: must be > 0\n");
  const std::string quiet = dir.Write(
      "quiet.yaml",
      "data: s.csv\ndata_format: {sort_by_time: true}\n"
      "columns: {t: {source: samples, scale: 0.01}, lambda1: {value: 0}, lambda2: {value: 0}, "
      "wx: acc_x, wy: acc_y, wz: acc_z, label: part}\n"
      "triad: {scale_mV_per_g: [2048, 2048, 2048], bias_mV: [0, 0, 0], noise_mV: 0.5}\n");
  EXPECT_EQ(error_of("static " + quiet),
            "triadcal: error: " + dir.Path("s.csv") +
                ": no still interval of at least 1 s found (reading std below 1 mV; "
                "check triad.noise_mV or the noise factor)\n");
  const std::string other = dir.Write(
      "other.yaml",
      "data: s.csv\ndata_format: {sort_by_time: true}\n"
      "columns: {t: {source: samples, scale: 0.01}, lambda1: {value: 0}, lambda2: {value: 0}, "
      "wx: acc_x, wy: acc_y, wz: acc_z, label: part}\n"
      "positions: {up: \"+x\"}\n"
      "triad: {scale_mV_per_g: [2048, 2048, 2048], bias_mV: [0, 0, 0], noise_mV: 7}\n");
  EXPECT_EQ(error_of("static " + other),
            "triadcal: error: " + other +
                ": positions: none of the position labels (up) occurs in column 'part' (it has: "
                "move, x_a, x_p, y_a, y_p, z_a, z_p)\n");
}

}  // namespace
}  // namespace triadcal
