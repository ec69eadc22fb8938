// Tests of the simulator (core/simulation/simulator.h) and `triadcal simulate`: noise
// statistics over several seeds, reproducibility, noise-free data against the
// model and against gravity projections worked out by hand, the injected
// effects, the sensor chain, every bad scenario with its message, the command
// end to end, and the written files read back by the run loaders.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/model/errors.h"
#include "core/model/gyro_model.h"
#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/simulation/simulator.h"
#include "core/io/run_description_io.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

// A fresh empty folder for one test, removed by the destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(fs::temp_directory_path() /
              ("triadcal_test_sim_" + std::to_string(getpid()) + "_" + name)) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string operator/(const std::string& f) const { return (path_ / f).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Scenario LoadFromText(const TempDir& dir, const std::string& text) {
  return LoadScenario(WriteText(dir / "scenario.yaml", text));
}

// The message LoadScenario throws for this text, or "no error".
std::string LoadError(const TempDir& dir, const std::string& text) {
  try {
    LoadFromText(dir, text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// A truth with every base group non-zero, short enough to keep tests fast.
const char* kTruthYaml = R"(
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1498, W0z: 1502.5,
        alpha_x: 16, alpha_y: -32, beta_x: 11, beta_z: 26, gamma_y: 140, gamma_z: 64,
        Kxx: 0.002, Kyz: -0.001, Kzy: 0.0015, Kyy: -0.0005,
        dpsi: -30, dtheta_c: 40, dlambda2: -30, dx2: -7, dy2: 16, dz2: 4}
)";

// The paper's profile over duration_s at rate_hz, with kTruthYaml.
std::string NoisyScenario(double accel_mV, double angle_arcsec, double duration_s = 90,
                          double rate_hz = 100) {
  return std::string(kTruthYaml) +
         "profile: {amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0],\n"
         "          duration_s: " +
         FormatDouble(duration_s) + ", rate_hz: " + FormatDouble(rate_hz) +
         "}\n"
         "noise: {accel_mV: " +
         std::to_string(accel_mV) + ", angle_arcsec: " + std::to_string(angle_arcsec) + "}\n";
}

// The noise-free readings of sample k, through the model.
Eigen::Vector3d ModelReadings_mV(const Scenario& s, const ModelConfig& cfg, double t_s) {
  const SampleContext ctx{t_s, ScenarioTemperature_C(s, t_s)};
  return PredictReadings_mV(cfg, s.truth.data(), s.profile.At(t_s), ctx);
}

struct Moments {
  double mean = 0.0, std = 0.0;
};

Moments MomentsOf(const std::vector<double>& x) {
  Moments m;
  for (double v : x) m.mean += v;
  m.mean /= static_cast<double>(x.size());
  double ss = 0.0;
  for (double v : x) ss += (v - m.mean) * (v - m.mean);
  m.std = std::sqrt(ss / static_cast<double>(x.size() - 1));
  return m;
}

// Mean within 3 sigma/sqrt(N) of 0, sample std within 3 sigma/sqrt(2(N-1)) of sigma.
void ExpectWhiteNoise(const std::vector<double>& e, double sigma, const std::string& what) {
  const double n = static_cast<double>(e.size());
  const Moments m = MomentsOf(e);
  EXPECT_LT(std::abs(m.mean), 3.0 * sigma / std::sqrt(n)) << what;
  EXPECT_LT(std::abs(m.std - sigma), 3.0 * sigma / std::sqrt(2.0 * (n - 1.0))) << what;
}

// ---------------------------------------------------------------------------
// The profile.

TEST(SimulatorProfile, AtIsTheExactHarmonicAndItsDerivatives) {
  HarmonicProfile p;
  p.amplitude_rad[0] = 2.0;
  p.amplitude_rad[1] = -0.7;
  p.period_s[0] = 7.0;
  p.period_s[1] = 3.0;
  p.phase_rad[0] = 0.4;
  p.phase_rad[1] = -1.2;
  for (double t : {0.0, 0.37, 5.1, 88.8}) {
    const BenchAngles<double> b = p.At(t);
    for (int i = 0; i < 2; ++i) {
      const double w = 2.0 * kPi / p.period_s[i];
      const double a = w * t + p.phase_rad[i];
      EXPECT_DOUBLE_EQ(b.axis[i].angle, p.amplitude_rad[i] * std::sin(a));
      EXPECT_DOUBLE_EQ(b.axis[i].rate, p.amplitude_rad[i] * w * std::cos(a));
      EXPECT_DOUBLE_EQ(b.axis[i].accel, -p.amplitude_rad[i] * w * w * std::sin(a));
      // and they are derivatives of each other (central differences)
      const double h = 1e-5;
      EXPECT_NEAR(b.axis[i].rate, (p.At(t + h).axis[i].angle - p.At(t - h).axis[i].angle) / (2 * h),
                  1e-8);
      EXPECT_NEAR(b.axis[i].accel, (p.At(t + h).axis[i].rate - p.At(t - h).axis[i].rate) / (2 * h),
                  1e-8);
    }
  }
}

TEST(SimulatorProfile, SamplesAreKOverRateBelowDuration) {
  for (auto [duration, rate] :
       {std::pair{90.0, 100.0}, {0.3, 10.0}, {1.0, 3.0}, {0.05, 1000.0}, {2.5, 1.0}}) {
    HarmonicProfile p;
    p.duration_s = duration;
    p.rate_hz = rate;
    std::size_t n = 0;
    while (static_cast<double>(n) / rate < duration) ++n;
    EXPECT_EQ(p.NumSamples(), n) << duration << " s at " << rate << " Hz";
  }
  HarmonicProfile p;
  p.duration_s = 0.3;
  p.rate_hz = 10.0;
  EXPECT_EQ(p.NumSamples(), 3u);  // 3 / 10 == 0.3 is not < 0.3
}

// ---------------------------------------------------------------------------
// Noise.

TEST(SimulatorNoise, ResidualsAgainstTheModelHaveTheDeclaredSigma) {
  TempDir dir("noise");
  const double accel_mV = 2.0, angle_arcsec = 15.0;
  Scenario s = LoadFromText(dir, NoisyScenario(accel_mV, angle_arcsec));
  const ModelConfig cfg = TruthModelConfig(s);
  for (std::uint64_t seed : {1u, 2u, 3u, 77u}) {
    s.seed = seed;
    const RunData d = Simulate(s);
    ASSERT_EQ(d.size(), 9000u);
    std::vector<double> e_w[3], e_l[2];
    for (std::size_t k = 0; k < d.size(); ++k) {
      const Eigen::Vector3d w0 = ModelReadings_mV(s, cfg, d.t_s[k]);
      for (int i = 0; i < 3; ++i) e_w[i].push_back(d.w_mV[i][k] - w0[i]);
      for (int i = 0; i < 2; ++i) {
        e_l[i].push_back(d.lambda_rad[i][k] - s.profile.At(d.t_s[k]).axis[i].angle);
      }
    }
    const std::string tag = "seed " + std::to_string(seed);
    for (int i = 0; i < 3; ++i) ExpectWhiteNoise(e_w[i], accel_mV, tag + " w" + "xyz"[i]);
    for (int i = 0; i < 2; ++i) {
      ExpectWhiteNoise(e_l[i], angle_arcsec * kArcsecToRad, tag + " lambda" + "12"[i]);
    }
    // channels independent: correlation of wx and wy within 4/sqrt(N)
    const Moments mx = MomentsOf(e_w[0]), my = MomentsOf(e_w[1]);
    double c = 0.0;
    for (std::size_t k = 0; k < d.size(); ++k) c += (e_w[0][k] - mx.mean) * (e_w[1][k] - my.mean);
    c /= (d.size() - 1) * mx.std * my.std;
    EXPECT_LT(std::abs(c), 4.0 / std::sqrt(static_cast<double>(d.size()))) << tag;
  }
}

// noise.accel_mV: [x, y, z]: each channel has its own sigma.
TEST(SimulatorNoise, PerChannelNoiseGivesEachChannelItsSigma) {
  TempDir dir("noise_channels");
  std::string text = NoisyScenario(1.0, 0.0);
  text.replace(text.find("accel_mV: "), std::string("accel_mV: 1.000000").size(),
               "accel_mV: [1.5, 6, 0.5]");
  const Scenario s = LoadFromText(dir, text);
  const ModelConfig cfg = TruthModelConfig(s);
  const RunData d = Simulate(s);
  std::vector<double> e_w[3];
  for (std::size_t k = 0; k < d.size(); ++k) {
    const Eigen::Vector3d w0 = ModelReadings_mV(s, cfg, d.t_s[k]);
    for (int i = 0; i < 3; ++i) e_w[i].push_back(d.w_mV[i][k] - w0[i]);
  }
  const Eigen::Vector3d sigma(1.5, 6.0, 0.5);
  for (int i = 0; i < 3; ++i) ExpectWhiteNoise(e_w[i], sigma[i], std::string("w") + "xyz"[i]);
}

TEST(SimulatorNoise, SameSeedSameDataOtherSeedOtherData) {
  TempDir dir("seed");
  Scenario s = LoadFromText(dir, NoisyScenario(2.0, 15.0));
  s.profile.duration_s = 5.0;
  s.seed = 42;
  const RunData a = Simulate(s), b = Simulate(s);
  s.seed = 43;
  const RunData c = Simulate(s);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(a.w_mV[i], b.w_mV[i]);
    EXPECT_NE(a.w_mV[i], c.w_mV[i]);
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(a.lambda_rad[i], b.lambda_rad[i]);
    EXPECT_NE(a.lambda_rad[i], c.lambda_rad[i]);
  }
}

TEST(SimulatorNoise, AngleNoiseDoesNotChangeTheReadingNoiseSequence) {
  // All five draws are made every sample, so switching one noise off leaves
  // the others' samples unchanged (documented draw order).
  TempDir dir("draws");
  Scenario s = LoadFromText(dir, NoisyScenario(2.0, 15.0));
  s.profile.duration_s = 2.0;
  const RunData a = Simulate(s);
  s.angle_noise_rad = 0.0;
  const RunData b = Simulate(s);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.w_mV[i], b.w_mV[i]);
}

// ---------------------------------------------------------------------------
// Noise-free data.

TEST(SimulatorNoiseFree, ReadingsAreTheModelAtTheProfileAngles) {
  TempDir dir("model");
  const Scenario s = LoadFromText(dir, NoisyScenario(0.0, 0.0));
  const ModelConfig cfg = TruthModelConfig(s);
  const RunData d = Simulate(s);
  ASSERT_EQ(d.size(), 9000u);
  for (std::size_t k = 0; k < d.size(); k += 7) {
    EXPECT_EQ(d.t_s[k], static_cast<double>(k) / 100.0);
    const Eigen::Vector3d w = ModelReadings_mV(s, cfg, d.t_s[k]);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(d.w_mV[i][k], w[i]) << k;
    for (int i = 0; i < 2; ++i) EXPECT_EQ(d.lambda_rad[i][k], s.profile.At(d.t_s[k]).axis[i].angle);
  }
  EXPECT_FALSE(d.has_rates());
  EXPECT_FALSE(d.has_temp());
}

// Gravity projection by hand, docs/method.md: at rest W = C_L2^T (0 - g_L)/g
// = first row of C_L2 = Rz(psi) Ry(a) Rx(b), a = l1 + dtheta_c, b = l2 + dlambda2:
//   row0(Rz(psi))              = (cpsi, -spsi, 0)
//   row0(Rz(psi) Ry(a))        = (cpsi ca, -spsi, cpsi sa)
//   row0(Rz(psi) Ry(a) Rx(b))  = (cpsi ca, -spsi cb + cpsi sa sb, spsi sb + cpsi sa cb)
Eigen::Vector3d GravityAtRest_g(double l1, double l2, double psi, double theta_c, double dlambda2) {
  const double a = l1 + theta_c, b = l2 + dlambda2;
  return {std::cos(psi) * std::cos(a),
          -std::sin(psi) * std::cos(b) + std::cos(psi) * std::sin(a) * std::sin(b),
          std::sin(psi) * std::sin(b) + std::cos(psi) * std::sin(a) * std::cos(b)};
}

// Paper eq. 1 written out by hand for one W.
Eigen::Vector3d ReadingsByHand_mV(const Eigen::VectorXd& th, const Eigen::Vector3d& W) {
  const double ax = th[kAlphaX], ay = th[kAlphaY], bx = th[kBetaX], bz = th[kBetaZ],
               gy = th[kGammaY], gz = th[kGammaZ];
  const double u[3] = {W[0] - ay * W[1] + bz * W[2], ax * W[0] + W[1] - gz * W[2],
                       -bx * W[0] + gy * W[1] + W[2]};
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) {
    double kw = 0.0;
    for (int j = 0; j < 3; ++j) kw += th[kKxx + 3 * i + j] * W[j];
    out[i] = th[kKx + i] * (u[i] + W[i] * kw) + th[kW0x + i];
  }
  return out;
}

// A bench standing still at (l1, l2) [deg]: amplitude A, phase 90 deg and a
// period of 1e12 s give lambda = A cos(tiny) = A with negligible motion.
RunData StaticRun(Scenario s, double l1_deg, double l2_deg) {
  s.profile.amplitude_rad[0] = l1_deg * kDegToRad;
  s.profile.amplitude_rad[1] = l2_deg * kDegToRad;
  s.profile.period_s[0] = s.profile.period_s[1] = 1e12;
  s.profile.phase_rad[0] = s.profile.phase_rad[1] = 90.0 * kDegToRad;
  s.profile.rate_hz = 1.0;
  s.profile.duration_s = 3.0;
  return Simulate(s);
}

TEST(SimulatorNoiseFree, StaticPositionsReadTheGravityProjectionByHand) {
  TempDir dir("static");
  Scenario s = LoadFromText(dir, NoisyScenario(0.0, 0.0));
  // First without bench errors: the textbook positions.
  s.truth[kDpsi] = s.truth[kDthetaC] = s.truth[kDlambda2] = 0.0;
  struct Case {
    double l1, l2;
    Eigen::Vector3d W;
  };
  const double c30 = std::cos(30 * kDegToRad), s30 = std::sin(30 * kDegToRad);
  const double c60 = std::cos(60 * kDegToRad), s60 = std::sin(60 * kDegToRad);
  const std::vector<Case> cases = {
      {0, 0, {1, 0, 0}},     // x up reads +1 g
      {90, 0, {0, 0, 1}},    // Ry(90): z up
      {-90, 0, {0, 0, -1}},  // z down
      {180, 0, {-1, 0, 0}},  // x down
      {0, 90, {1, 0, 0}},    // turning about the (vertical) inner axis: x still up
      {90, 90, {0, 1, 0}},   // Ry(90) Rx(90): row0 = (0, 1, 0), y up
      {90, -90, {0, -1, 0}}, {30, 60, {c30, s30 * s60, s30 * c60}},  // (c1, s1 s2, s1 c2)
  };
  for (const Case& c : cases) {
    const RunData d = StaticRun(s, c.l1, c.l2);
    ASSERT_EQ(d.size(), 3u);
    const Eigen::Vector3d expected = ReadingsByHand_mV(s.truth, c.W);
    for (std::size_t k = 0; k < d.size(); ++k) {
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(d.w_mV[i][k], expected[i], 1e-9) << c.l1 << "/" << c.l2 << " axis " << i;
      }
    }
  }
  // The plain scale-and-bias reading at x up: Kx + W0x, W0y + Ky * alpha_x, ...
  const RunData up = StaticRun(s, 0, 0);
  EXPECT_NEAR(up.w_mV[0][0], s.truth[kKx] * (1 + s.truth[kKxx]) + s.truth[kW0x], 1e-9);
  EXPECT_NEAR(up.w_mV[1][0], s.truth[kKy] * s.truth[kAlphaX] + s.truth[kW0y], 1e-9);
  EXPECT_NEAR(up.w_mV[2][0], -s.truth[kKz] * s.truth[kBetaX] + s.truth[kW0z], 1e-9);

  // Then with the bench errors of the scenario put back.
  s.truth[kDpsi] = -30 * kArcminToRad;
  s.truth[kDthetaC] = 40 * kArcminToRad;
  s.truth[kDlambda2] = -25 * kArcminToRad;
  for (auto [l1, l2] : {std::pair{0.0, 0.0}, {90.0, 0.0}, {37.0, -71.0}, {-120.0, 45.0}}) {
    const RunData d = StaticRun(s, l1, l2);
    const Eigen::Vector3d W = GravityAtRest_g(l1 * kDegToRad, l2 * kDegToRad, s.truth[kDpsi],
                                              s.truth[kDthetaC], s.truth[kDlambda2]);
    const Eigen::Vector3d expected = ReadingsByHand_mV(s.truth, W);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(d.w_mV[i][1], expected[i], 1e-9) << l1 << "/" << l2;
  }
}

// ---------------------------------------------------------------------------
// Injected effects.

TEST(SimulatorEffects, LatencyRecordsTheProfileTauLate) {
  TempDir dir("latency");
  const Scenario s =
      LoadFromText(dir, NoisyScenario(0.0, 0.0) +
                            "effects: {angle_latency: {tau_ms: 20}}\noutput: {rates: true}\n");
  ASSERT_TRUE(s.truth_layout.has(Effect::kAngleLatency));
  EXPECT_DOUBLE_EQ(s.truth[s.truth_layout.offset(Effect::kAngleLatency)], 0.020);
  const ModelConfig cfg = TruthModelConfig(s);
  const RunData d = Simulate(s);
  ASSERT_TRUE(d.has_rates());
  double max_lag_rad = 0.0;
  for (std::size_t k = 0; k < d.size(); k += 13) {
    const double t = d.t_s[k];
    const BenchAngles<double> late = s.profile.At(t - 0.020);
    for (int i = 0; i < 2; ++i) {
      EXPECT_EQ(d.lambda_rad[i][k], late.axis[i].angle);
      EXPECT_EQ(d.rate_rad_s[i][k], late.axis[i].rate);
      max_lag_rad =
          std::max(max_lag_rad, std::abs(d.lambda_rad[i][k] - s.profile.At(t).axis[i].angle));
    }
    // the bench itself is not late: readings are the model at the profile at t
    const Eigen::Vector3d w = ModelReadings_mV(s, cfg, t);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(d.w_mV[i][k], w[i]);
  }
  EXPECT_GT(max_lag_rad, 0.02 * 70 * kDegToRad);  // tau times a peak rate near 75 deg/s
}

TEST(SimulatorEffects, EncoderHarmonicRecordsAnglePlusSinCos) {
  TempDir dir("encoder");
  const Scenario s = LoadFromText(
      dir, NoisyScenario(0.0, 0.0) +
               "effects: {encoder_harmonic: {l1_sin_arcmin: 3, l1_cos: -2, l2_sin: 1.5}}\n"
               "output: {rates: true}\n");
  const double sc[2][2] = {{3 * kArcminToRad, -2 * kArcminToRad}, {1.5 * kArcminToRad, 0.0}};
  const RunData d = Simulate(s);
  for (std::size_t k = 0; k < d.size(); k += 11) {
    const BenchAngles<double> b = s.profile.At(d.t_s[k]);
    for (int i = 0; i < 2; ++i) {
      const double l = b.axis[i].angle;
      EXPECT_NEAR(d.lambda_rad[i][k], l + sc[i][0] * std::sin(l) + sc[i][1] * std::cos(l), 1e-15);
      const double dl = b.axis[i].rate;
      EXPECT_NEAR(d.rate_rad_s[i][k], dl * (1 + sc[i][0] * std::cos(l) - sc[i][1] * std::sin(l)),
                  1e-14);
    }
  }
}

TEST(SimulatorEffects, ThermalDriftsAddToTheZeroOffsets) {
  TempDir dir("thermal");
  const std::string base = NoisyScenario(0.0, 0.0);
  const Scenario plain = LoadFromText(dir, base);
  const Scenario drift =
      LoadFromText(dir, base +
                            "effects: {thermal_drift: {rate_x_mV_per_min: 0.5, rate_z: -0.25},\n"
                            "          thermal_drift_temp: {coef_y_mV_per_degC: 0.3}}\n"
                            "temperature: {start_C: 20, rate_C_per_h: 10}\n");
  const RunData a = Simulate(plain), b = Simulate(drift);
  ASSERT_TRUE(b.has_temp());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); k += 17) {
    const double t = a.t_s[k];
    EXPECT_DOUBLE_EQ(b.temp_C[k], 20.0 + 10.0 * t / 3600.0);
    EXPECT_NEAR(b.w_mV[0][k] - a.w_mV[0][k], 0.5 * t / 60.0, 1e-9);
    EXPECT_NEAR(b.w_mV[1][k] - a.w_mV[1][k], 0.3 * (b.temp_C[k] - 20.0), 1e-9);
    EXPECT_NEAR(b.w_mV[2][k] - a.w_mV[2][k], -0.25 * t / 60.0, 1e-9);
  }
}

// ---------------------------------------------------------------------------
// Sensor chain.

TEST(SimulatorSensor, QuantizationRoundsAndSaturationClips) {
  TempDir dir("sensor");
  Scenario s = LoadFromText(dir, NoisyScenario(2.0, 0.0));
  s.profile.duration_s = 30.0;
  const RunData raw = Simulate(s);
  s.quantization_mV = 0.8;
  const RunData quantized = Simulate(s);
  s.saturation_low_mV = 1400.0;
  s.saturation_high_mV = 1600.0;
  const RunData clipped = Simulate(s);
  int low = 0, high = 0;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    for (int i = 0; i < 3; ++i) {
      const double q = quantized.w_mV[i][k];
      EXPECT_EQ(q, std::round(raw.w_mV[i][k] / 0.8) * 0.8);
      EXPECT_LE(std::abs(q - raw.w_mV[i][k]), 0.4 + 1e-9);
      EXPECT_NEAR(q / 0.8, std::round(q / 0.8), 1e-9);
      const double c = clipped.w_mV[i][k];
      EXPECT_EQ(c, std::min(std::max(q, 1400.0), 1600.0));
      low += c == 1400.0;
      high += c == 1600.0;
    }
  }
  EXPECT_GT(low, 0);  // +-1 g at ~174 mV/g spans 1330..1680 mV: both limits hit
  EXPECT_GT(high, 0);
}

// ---------------------------------------------------------------------------
// Scenario loading.

TEST(ScenarioLoad, DefaultsNominalTruthAndDeclaredNoise) {
  TempDir dir("defaults");
  const Scenario s = LoadFromText(dir,
                                  "truth: {Kx: 171.5, dpsi: -33, dx2: -7}\n"
                                  "noise: {accel_mV: 1.5, angle_arcsec: 0}\n"
                                  "run: {triad: {scale_mV_per_g: [170, 171, 172],\n"
                                  "              bias_mV: [1490, 1500, 1510]}}\n");
  EXPECT_EQ(s.profile.NumSamples(), 9000u);  // the paper profile, 90 s at 100 Hz
  EXPECT_EQ(s.truth_layout.size(), kNumBaseParams);
  EXPECT_EQ(s.truth[kKx], 171.5);
  EXPECT_EQ(s.truth[kKy], 171.0);  // nominal from run.triad
  EXPECT_EQ(s.truth[kKz], 172.0);
  EXPECT_EQ(s.truth[kW0x], 1490.0);
  EXPECT_EQ(s.truth[kW0z], 1510.0);
  EXPECT_DOUBLE_EQ(s.truth[kDpsi], -33 * kArcminToRad);
  EXPECT_DOUBLE_EQ(s.truth[kDx2], -0.007);
  EXPECT_EQ(s.truth[kAlphaX], 0.0);
  EXPECT_EQ(s.run.noise_mV, 1.5);  // the run declares the true noise
  EXPECT_EQ(s.run.angle_noise_rad, 0.0);
  EXPECT_EQ(s.seed, 1u);
  ASSERT_EQ(s.run.constraints.size(), 1u);  // the run parser's default constraint

  // A declared noise different from the true one is kept; noise 0 declares the floor.
  const Scenario t = LoadFromText(dir,
                                  "noise: {accel_mV: 0, angle_arcsec: 4}\nseed: 99\n"
                                  "run: {bench: {angle_noise_arcsec: 15}}\n");
  EXPECT_EQ(t.run.noise_mV, kMinDeclaredNoise_mV);
  EXPECT_DOUBLE_EQ(t.run.angle_noise_rad, 15 * kArcsecToRad);
  EXPECT_DOUBLE_EQ(t.angle_noise_rad, 4 * kArcsecToRad);
  EXPECT_EQ(t.seed, 99u);
  // Quantization adds q^2/12 to the declared variance.
  const Scenario q = LoadFromText(dir, "noise: {accel_mV: 0.6}\nsensor: {quantization_mV: 2.4}\n");
  EXPECT_NEAR(q.run.noise_mV, std::sqrt(0.36 + 2.4 * 2.4 / 12), 1e-12);
  EXPECT_FALSE(q.run.noise_channel_mV.has_value());
  // One figure per channel: the run declares each channel's.
  const Scenario c =
      LoadFromText(dir, "noise: {accel_mV: [1, 4, 0.6]}\nsensor: {quantization_mV: 2.4}\n");
  ASSERT_TRUE(c.accel_noise_channel_mV.has_value());
  EXPECT_EQ(c.AccelNoise_mV(), Eigen::Vector3d(1, 4, 0.6));
  ASSERT_TRUE(c.run.noise_channel_mV.has_value());
  for (int i = 0; i < 3; ++i) {
    const double a = c.AccelNoise_mV()[i];
    EXPECT_NEAR((*c.run.noise_channel_mV)[i], std::sqrt(a * a + 2.4 * 2.4 / 12), 1e-12) << i;
  }
  EXPECT_NEAR(c.run.noise_mV, std::sqrt(c.run.noise_channel_mV->squaredNorm() / 3), 1e-12);
}

TEST(ScenarioLoad, EffectParametersByNameOrNameUnitInCatalogueOrder) {
  TempDir dir("effects");
  const Scenario s = LoadFromText(dir,
                                  "effects:\n"
                                  "  scale_asymmetry: {dKy_mV_per_g: 0.4}\n"
                                  "  angle_latency: {tau: 2}\n"
                                  "  axis_nonintersection:\n");
  ASSERT_EQ(s.truth_layout.effects().size(), 3u);
  EXPECT_EQ(s.truth_layout.effects()[0], Effect::kAngleLatency);
  EXPECT_EQ(s.truth_layout.effects()[1], Effect::kAxisNonintersection);
  EXPECT_EQ(s.truth_layout.effects()[2], Effect::kScaleAsymmetry);
  EXPECT_DOUBLE_EQ(s.truth[s.truth_layout.IndexOf("angle_latency.tau")], 0.002);
  EXPECT_EQ(s.truth[s.truth_layout.IndexOf("axis_nonintersection.d")], 0.0);
  EXPECT_EQ(s.truth[s.truth_layout.IndexOf("scale_asymmetry.dKy")], 0.4);
  EXPECT_EQ(s.truth[s.truth_layout.IndexOf("scale_asymmetry.dKx")], 0.0);
  EXPECT_EQ(TruthFileKey(s.truth_layout, s.truth_layout.IndexOf("angle_latency.tau")),
            "angle_latency.tau_ms");
  EXPECT_EQ(TruthFileValue(s.truth_layout, s.truth, s.truth_layout.IndexOf("angle_latency.tau")),
            2.0);
}

TEST(ScenarioErrors, EveryBadInputNamesFileKeyAndProblem) {
  TempDir dir("errors");
  const std::string f = dir / "scenario.yaml";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"foo: 1\n",
       f + ": foo: unknown key (allowed: profile, truth, truth_spread, noise, effects, run, seed, sensor, "
           "output, temperature, truth_temperature)"},
      {"truth_temperature: {per_C: {W0x: 0.1}}\n",
       f + ": truth_temperature: needs a section temperature: {start_C} (the run's temperature)"},
      {"temperature: {start_C: 30}\ntruth_temperature: {per_C: {W0q: 0.1}}\n",
       f + ": truth_temperature.per_C.W0q: unknown parameter (docs/file-formats.md names)"},
      {"profile: {durations: 3}\n",
       f + ": profile.durations: unknown key (allowed: amplitude_deg, period_s, phase_deg, "
           "duration_s, rate_hz)"},
      {"effects: {angle_lag: {tau_ms: 2}}\n",
       f + ": effects: unknown effect 'angle_lag' (known: angle_latency, encoder_harmonic, "
           "axis_nonintersection, axis_nonperpendicularity, size_effect, thermal_drift, "
           "thermal_drift_temp, scale_asymmetry, angle_scale, cross_quadratic, "
           "thermal_drift_quadratic, gyro_scale_asymmetry, gyro_nonlinearity)"},
      {"effects: {gyro_nonlinearity: {k2_x: 0.1}}\n",
       f + ": effects: gyro_nonlinearity acts on the gyro, but the scenario has no run.gyro "
           "block"},
      {"effects: {angle_latency: {tau_s: 2}}\n",
       f + ": effects.angle_latency.tau_s: unknown key (allowed: tau, tau_ms)"},
      {"effects: {angle_latency: {tau: 2, tau_ms: 2}}\n",
       f + ": effects.angle_latency: both 'tau' and 'tau_ms' given"},
      {"effects: {angle_latency: {tau_ms: fast}}\n",
       f + ": effects.angle_latency.tau_ms: expected a number, got 'fast'"},
      {"effects: [angle_latency]\n",
       f + ": effects: expected a map {effect: {param: value}}, got a list"},
      {"profile: {amplitude_deg: [360, 90, 5]}\n",
       f + ": profile.amplitude_deg: expected a list of 2 numbers, got 3"},
      {"profile: {phase_deg: 0}\n",
       f + ": profile.phase_deg: expected a list of 2 numbers, got '0'"},
      {"profile: {period_s: [30, 0]}\n", f + ": profile.period_s[1]: must be > 0, got 0"},
      {"profile: {duration_s: 0}\n", f + ": profile.duration_s: must be > 0, got 0"},
      {"profile: {duration_s: -2}\n", f + ": profile.duration_s: must be > 0, got -2"},
      {"profile: {rate_hz: -5}\n", f + ": profile.rate_hz: must be > 0, got -5"},
      {"profile: {rate_hz: 0}\n", f + ": profile.rate_hz: must be > 0, got 0"},
      {"profile: {duration_s: 1e6, rate_hz: 1000}\n",
       f + ": profile: duration_s * rate_hz = 1000000000 samples, more than the limit 20000000"},
      {"noise: {accel_mV: -1}\n", f + ": noise.accel_mV: must be >= 0, got -1"},
      {"noise: {angle_arcsec: -0.5}\n", f + ": noise.angle_arcsec: must be >= 0, got -0.5"},
      {"noise: {accel_mV: abc}\n", f + ": noise.accel_mV: expected a number, got 'abc'"},
      {"noise: {accel_mV: [2, -1, 2]}\n", f + ": noise.accel_mV[1]: must be >= 0, got -1"},
      {"noise: {accel_mV: [2, 10]}\n",
       f + ": noise.accel_mV: expected a list of 3 numbers, got 2"},
      {"noise: {accel_mV: .nan}\n", f + ": noise.accel_mV: expected a finite number, got '.nan'"},
      {"noise: 2\n", f + ": noise: expected a map, got '2'"},
      {"truth: {Kq: 1}\n",
       f + ": truth.Kq: unknown key (allowed: Kx, Ky, Kz, W0x, W0y, W0z, alpha_x, alpha_y, "
           "beta_x, beta_z, gamma_y, gamma_z, Kxx, Kxy, Kxz, Kyx, Kyy, Kyz, Kzx, Kzy, Kzz, "
           "dpsi, dtheta_c, dlambda2, dx2, dy2, dz2)"},
      {"truth: {Kx: [1, 2]}\n", f + ": truth.Kx: expected a number, got a list"},
      {"sensor: {quantization_mV: -1}\n", f + ": sensor.quantization_mV: must be >= 0, got -1"},
      {"sensor: {saturation_mV: [10, 10]}\n",
       f + ": sensor.saturation_mV: expected [low, high] with low < high, got [10, 10]"},
      {"output: {rates: maybe}\n", f + ": output.rates: expected true or false, got 'maybe'"},
      {"seed: -3\n", f + ": seed: expected a non-negative integer, got '-3'"},
      {"seed: 1.5\n", f + ": seed: expected a non-negative integer, got '1.5'"},
      {"effects: {thermal_drift_temp: {coef_x: 1}}\n",
       f + ": effects.thermal_drift_temp: needs a section temperature: {start_C, rate_C_per_h} "
           "(the drift follows temp_C)"},
      {"run: {data: x.csv}\n",
       f + ": run.data: not allowed in a scenario (simulate writes run.csv itself)"},
      {"run: {bench: {lever_arm_mm: [138, 20]}}\n",
       f + ": run: bench.lever_arm_mm: expected a list of 3 numbers, got 2"},
      {"noise: {accel_mV: 1}\nnoise: {accel_mV: 2}\n", f + ": noise: given twice"},
      {"profile: {rate_hz: 1, rate_hz: 2}\n", f + ": profile.rate_hz: given twice"},
      {"effects: {angle_latency: {tau: 1}, angle_latency: {tau: 2}}\n",
       f + ": effects.angle_latency: given twice"},
      {"- 1\n- 2\n", f + ": expected a map with the sections profile, truth, noise, effects, run"},
      // The gyro (SPEC section 10): its truth and noise need a run.gyro block.
      {"truth: {gyro.Kx: 1.002}\n",
       f + ": truth.gyro.Kx: a gyro parameter, but the scenario has no run.gyro block (add run: "
           "{gyro: {scale: [1, 1, 1]}} to simulate gx gy gz)"},
      {"noise: {gyro_dps: 0.1}\n",
       f + ": noise.gyro_dps: a gyro noise, but the scenario has no run.gyro block (add run: "
           "{gyro: {scale: [1, 1, 1]}} to simulate gx gy gz)"},
      {"truth: {gyro.Kq: 1}\nrun: {gyro: {}}\n",
       f + ": truth.gyro.Kq: unknown key (allowed: gyro.Kx, gyro.Ky, gyro.Kz, gyro.W0x, "
           "gyro.W0y, gyro.W0z, gyro.alpha_x, gyro.alpha_y, gyro.beta_x, gyro.beta_z, "
           "gyro.gamma_y, gyro.gamma_z, gyro.Gxx, gyro.Gxy, gyro.Gxz, gyro.Gyx, gyro.Gyy, "
           "gyro.Gyz, gyro.Gzx, gyro.Gzy, gyro.Gzz)"},
      {"noise: {gyro_dps: -1}\nrun: {gyro: {}}\n", f + ": noise.gyro_dps: must be >= 0, got -1"},
      {"noise: {gyro_dps: [0.1, 0.1]}\nrun: {gyro: {}}\n",
       f + ": noise.gyro_dps: expected a list of 3 numbers, got 2"},
      {"run: {gyro: {scale: [1, 0, 1]}}\n",
       f + ": run: gyro.scale[1]: must not be 0 (readings per deg/s; nominal 1)"},
      {"run: {bench: {latitude_deg: 48}}\n",
       f + ": run: bench.latitude_deg: given without bench.heading_deg (Earth's rate needs "
           "both; give both, or neither)"},
  };
  for (const auto& [text, message] : cases) {
    EXPECT_EQ(LoadError(dir, text), message) << text;
  }
  // Syntax errors name the line.
  const std::string syntax = LoadError(dir, "profile:\n  rate_hz: [1, 2\n");
  EXPECT_EQ(syntax.rfind(f + ":", 0), 0u) << syntax;
  EXPECT_NE(syntax.find("YAML syntax error"), std::string::npos) << syntax;
  // A missing file.
  try {
    LoadScenario(dir / "none.yaml");
    ADD_FAILURE() << "no error for a missing file";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              dir / "none.yaml" + ": cannot read (no such file or not readable)");
  }
}

// ---------------------------------------------------------------------------
// The written files and the command.

TEST(SimulatorOutput, WrittenRunLoadsBackAsTheSimulatedData) {
  TempDir dir("roundtrip");
  Scenario s = LoadFromText(dir, NoisyScenario(2.0, 15.0) +
                                     "effects: {angle_latency: {tau_ms: 2}}\n"
                                     "output: {rates: true}\n"
                                     "temperature: {start_C: 22, rate_C_per_h: 5}\n");
  s.profile.duration_s = 20.0;
  const RunData data = Simulate(s);
  WriteSimulation(s, data, dir / "out");

  const RunDescription run = LoadRunDescription(dir / "out/run.yaml");
  EXPECT_EQ(fs::path(run.data_path), fs::path(dir / "out/run.csv"));
  EXPECT_NEAR((run.lever_arm0_m - s.run.lever_arm0_m).norm(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(run.noise_mV, 2.0);
  EXPECT_DOUBLE_EQ(run.angle_noise_rad, 15 * kArcsecToRad);
  ASSERT_EQ(run.constraints.size(), 1u);
  EXPECT_EQ(run.constraints[0].expr, "dpsi - dlambda2");

  RunWarnings warnings;
  const RunData back = LoadRunData(run, &warnings);
  ASSERT_EQ(back.size(), data.size());
  ASSERT_TRUE(back.has_rates());
  ASSERT_TRUE(back.has_temp());
  for (std::size_t k = 0; k < data.size(); ++k) {
    EXPECT_EQ(back.t_s[k], data.t_s[k]);
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(back.lambda_rad[i][k], data.lambda_rad[i][k], 1e-14);
      EXPECT_NEAR(back.rate_rad_s[i][k], data.rate_rad_s[i][k], 1e-14);
    }
    for (int i = 0; i < 3; ++i) EXPECT_EQ(back.w_mV[i][k], data.w_mV[i][k]);
    EXPECT_EQ(back.temp_C[k], data.temp_C[k]);
  }
  // No temporary files left behind.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir / "out")) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 3);
}

TEST(SimulatorOutput, TruthJsonHasEveryParameterInFileUnits) {
  TempDir dir("truthjson");
  Scenario s = LoadFromText(dir, NoisyScenario(1.0, 0.0) +
                                     "effects: {angle_latency: {tau_ms: 2},\n"
                                     "          thermal_drift: {rate_y_mV_per_min: 0.125}}\n");
  s.profile.duration_s = 1.0;
  WriteSimulation(s, Simulate(s), dir / "out");
  const nlohmann::json j = nlohmann::json::parse(ReadText(dir / "out/truth.json"));
  const nlohmann::json& p = j.at("parameters");
  EXPECT_EQ(p.size(), static_cast<std::size_t>(kNumBaseParams + 4));
  for (const ParameterInfo& info : BaseParameterInfo())
    EXPECT_TRUE(p.contains(info.name)) << info.name;
  EXPECT_EQ(p.at("Kx").get<double>(), 171.5);
  EXPECT_EQ(p.at("dpsi").get<double>(), -30.0);  // exactly, not -30.000000000000004
  EXPECT_EQ(p.at("gamma_y").get<double>(), 140.0);
  EXPECT_EQ(p.at("dx2").get<double>(), -7.0);
  EXPECT_EQ(p.at("Kxy").get<double>(), 0.0);
  EXPECT_EQ(p.at("angle_latency.tau_ms").get<double>(), 2.0);
  EXPECT_EQ(p.at("thermal_drift.rate_y_mV_per_min").get<double>(), 0.125);
  EXPECT_EQ(p.at("thermal_drift.rate_x_mV_per_min").get<double>(), 0.0);
  EXPECT_EQ(j.at("units").at("dpsi"), "arcmin");
  EXPECT_EQ(j.at("seed").get<std::uint64_t>(), 1u);
}

int RunCommand(const std::string& args, const TempDir& dir, std::string* out, std::string* err) {
  const std::string cmd = std::string(TRIADCAL_BIN) + " " + args + " >" + (dir / "stdout.txt") +
                          " 2>" + (dir / "stderr.txt");
  const int status = std::system(cmd.c_str());
  *out = ReadText(dir / "stdout.txt");
  *err = ReadText(dir / "stderr.txt");
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(SimulateCommand, WritesThreeFilesAndASummary) {
  TempDir dir("cmd");
  const std::string scenario =
      WriteText(dir / "scen.yaml", NoisyScenario(2.0, 15.0, 10, 50) +
                                       "effects: {angle_latency: {tau_ms: 2}}\nseed: 5\n");
  std::string out, err;
  ASSERT_EQ(RunCommand("simulate " + scenario + " -o " + (dir / "run1"), dir, &out, &err), 0)
      << err;
  EXPECT_EQ(err, "");
  for (const char* f : {"run.csv", "run.yaml", "truth.json"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / (std::string("run1/") + f))) << f;
  }
  EXPECT_NE(out.find("500 samples"), std::string::npos) << out;
  EXPECT_NE(out.find("angle_latency.tau_ms = 2\n"), std::string::npos) << out;
  const std::string csv = ReadText(dir / "run1/run.csv");
  EXPECT_EQ(csv.rfind("# simulated by triadcal simulate\n# scenario: scen.yaml\n# seed: 5\n", 0),
            0u)
      << csv.substr(0, 200);
  // run.yaml does not declare the injected effect
  EXPECT_EQ(ReadText(dir / "run1/run.yaml").find("latency"), std::string::npos);

  // --seed overrides the scenario's seed; the same seed gives the same file.
  ASSERT_EQ(
      RunCommand("simulate " + scenario + " -o " + (dir / "run2") + " --seed 5", dir, &out, &err),
      0);
  EXPECT_EQ(ReadText(dir / "run2/run.csv"), csv);
  ASSERT_EQ(
      RunCommand("simulate " + scenario + " -o " + (dir / "run3") + " --seed 6", dir, &out, &err),
      0);
  EXPECT_NE(ReadText(dir / "run3/run.csv"), csv);
  EXPECT_NE(ReadText(dir / "run3/run.csv").find("# seed: 6\n"), std::string::npos);
}

TEST(SimulateCommand, BadScenarioGivesOneLineAndNoOutput) {
  TempDir dir("cmdbad");
  const std::string scenario = WriteText(dir / "bad.yaml", "noise: {accel_mV: -1}\n");
  std::string out, err;
  const int code = RunCommand("simulate " + scenario + " -o " + (dir / "out"), dir, &out, &err);
  EXPECT_NE(code, 0);
  EXPECT_EQ(err, "triadcal: error: " + scenario + ": noise.accel_mV: must be >= 0, got -1\n");
  EXPECT_FALSE(fs::exists(dir / "out"));
  // A folder that cannot be created: also one line, and nothing written.
  WriteText(dir / "blocker", "a file, not a folder");
  const std::string good = WriteText(dir / "good.yaml", "profile: {duration_s: 1}\n");
  EXPECT_NE(RunCommand("simulate " + good + " -o " + (dir / "blocker/out"), dir, &out, &err), 0);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_FALSE(fs::exists(dir / "blocker/out"));
}

TEST(SimulateCommand, PaperExampleRuns) {
  TempDir dir("paper");
  std::string out, err;
  const std::string scenario =
      std::string(TRIADCAL_SOURCE_DIR) + "/examples/noise-free/scenario.yaml";
  ASSERT_EQ(RunCommand("simulate " + scenario + " -o " + (dir / "nf"), dir, &out, &err), 0) << err;
  const Scenario s =
      LoadScenario(std::string(TRIADCAL_SOURCE_DIR) + "/examples/paper-experiment3/scenario.yaml");
  EXPECT_EQ(s.profile.NumSamples(), 90000u);
  EXPECT_EQ(s.truth[kKy], 175.8);
  EXPECT_DOUBLE_EQ(s.truth[kGammaZ], 64 * kArcminToRad);
  EXPECT_DOUBLE_EQ(s.truth[kGammaY], 140 * kArcminToRad);
  EXPECT_DOUBLE_EQ(s.truth[kDlambda2], s.truth[kDpsi]);
  EXPECT_DOUBLE_EQ(s.run.angle_noise_rad, 15 * kArcsecToRad);
  EXPECT_DOUBLE_EQ(s.run.noise_mV, 0.97);
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// truth_spread draws a per-seed truth from its own stream: different seeds give
// different truths, the same seed the same, and the data noise is unchanged.
TEST(Scenario, TruthSpreadIsPerSeedAndLeavesNoiseAlone) {
  Scenario s;
  s.truth_layout = ParameterLayout();
  s.truth = NominalTheta(s.run, s.truth_layout);
  s.truth_spread = {{kDlambda2, 0.5 * kArcminToRad}};
  std::vector<double> draws;
  for (std::uint64_t seed : {1, 2, 1}) {
    Scenario c = s;
    c.seed = seed;
    SampleTruth(&c);
    draws.push_back(c.truth[kDlambda2]);
    for (int i = 0; i < s.truth_layout.size(); ++i) {
      if (i != kDlambda2) {
        EXPECT_EQ(c.truth[i], s.truth[i]);
      }
    }
  }
  EXPECT_NE(draws[0], draws[1]);
  EXPECT_EQ(draws[0], draws[2]);
  EXPECT_LT(std::abs(draws[0]), 5 * 0.5 * kArcminToRad);
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// ---------------------------------------------------------------------------
// The gyro triad (SPEC section 10).

// kTruthYaml's accelerometer and bench, with a gyro of every group non-zero,
// at a bench with Earth's rate, and a latency so that the recorded angles are
// not the true ones: 10 s at 50 Hz.
std::string GyroScenario(const std::string& gyro_noise = "0") {
  return std::string(kTruthYaml) +
         "profile: {amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0],\n"
         "          duration_s: 10, rate_hz: 50}\n"
         "noise: {accel_mV: 0, angle_arcsec: 0, gyro_dps: " +
         gyro_noise +
         "}\n"
         "effects: {angle_latency: {tau_ms: 2}}\n"
         "run:\n"
         "  bench: {latitude_deg: 48.15, heading_deg: 30}\n"
         "  gyro: {scale: [1, 1, 1], bias_dps: [0.2, -0.1, 0.3]}\n";
}

// GyroScenario with its gyro truth (the truth section of kTruthYaml, widened).
std::string GyroScenarioWithTruth(const std::string& gyro_noise = "0") {
  std::string text = GyroScenario(gyro_noise);
  text.replace(text.find("dx2: -7, dy2: 16, dz2: 4}"),
               std::string("dx2: -7, dy2: 16, dz2: 4}").size(),
               "dx2: -7, dy2: 16, dz2: 4,\n        gyro.Kx: 1.002, gyro.Kz: -0.998, gyro.W0z: "
               "0.3, gyro.alpha_x: -20, gyro.beta_z: 10, gyro.gamma_y: 5, gyro.Gxy: 0.05, "
               "gyro.Gzz: -0.02}");
  return text;
}

TEST(SimulatorGyro, ScenarioGyroTruthNoiseAndDeclaredRun) {
  TempDir dir("gyro_load");
  const Scenario s = LoadFromText(dir, GyroScenarioWithTruth("[0.1, 0.2, 0.05]"));
  ASSERT_TRUE(s.run.gyro.has_value());
  ASSERT_TRUE(s.truth_layout.has_gyro());
  const int o = s.truth_layout.gyro_offset();
  EXPECT_EQ(o, kNumBaseParams + 1);  // after angle_latency.tau
  EXPECT_EQ(s.truth[o + kGKx], 1.002);
  EXPECT_EQ(s.truth[o + kGKy], 1.0);  // nominal from run.gyro
  EXPECT_EQ(s.truth[o + kGKz], -0.998);
  EXPECT_DOUBLE_EQ(s.truth[o + kGW0x], 0.2 * kDegToRad);  // nominal from run.gyro
  EXPECT_DOUBLE_EQ(s.truth[o + kGW0z], 0.3 * kDegToRad);
  EXPECT_DOUBLE_EQ(s.truth[o + kGBetaZ], 10 * kArcminToRad);
  EXPECT_DOUBLE_EQ(s.truth[o + kGGxy], 0.05 * kDegToRad);
  EXPECT_EQ(s.truth[o + kGGxx], 0.0);
  EXPECT_TRUE(s.gyro_noise_per_channel);
  EXPECT_NEAR((s.gyro_noise_rad_s - Eigen::Vector3d(0.1, 0.2, 0.05) * kDegToRad).norm(), 0, 1e-18);
  // The run declares the true gyro noise, floored above 0.
  EXPECT_NEAR((s.run.gyro->noise_rad_s - s.gyro_noise_rad_s).norm(), 0.0, 1e-18);
  const Scenario quiet = LoadFromText(dir, GyroScenario("0"));
  EXPECT_EQ(quiet.run.gyro->noise_rad_s,
            Eigen::Vector3d::Constant(kMinDeclaredNoise_dps * kDegToRad));
  EXPECT_EQ(quiet.gyro_noise_rad_s, Eigen::Vector3d::Zero());
  ASSERT_TRUE(quiet.run.latitude_rad && quiet.run.heading_rad);
  EXPECT_DOUBLE_EQ(*quiet.run.latitude_rad, 48.15 * kDegToRad);
  EXPECT_FALSE(TruthModelConfig(quiet).earth_rate_L.isZero());
  // A declared gyro noise is kept; without a gyro block nothing changes.
  std::string declared = GyroScenario("0.1");
  declared.replace(declared.find("bias_dps: [0.2, -0.1, 0.3]}"),
                   std::string("bias_dps: [0.2, -0.1, 0.3]}").size(),
                   "bias_dps: [0.2, -0.1, 0.3], noise_dps: 0.07}");
  EXPECT_NEAR(LoadFromText(dir, declared).run.gyro->noise_rad_s[1], 0.07 * kDegToRad, 1e-18);
  const Scenario plain = LoadFromText(dir, NoisyScenario(1.0, 0.0));
  EXPECT_FALSE(plain.run.gyro.has_value());
  EXPECT_FALSE(plain.truth_layout.has_gyro());
}

// Noise-free gx gy gz, written to run.csv [deg/s] and read back through the
// written run.yaml, are PredictGyroReadings at the true (not the recorded)
// angles and the true theta, Earth's rate included.
TEST(SimulatorGyro, NoiseFreeGyroReadsBackAsTheModelAtTheTrueAngles) {
  TempDir dir("gyro_model");
  const Scenario s = LoadFromText(dir, GyroScenarioWithTruth());
  const RunData d = Simulate(s);
  ASSERT_TRUE(d.has_gyro());
  WriteSimulation(s, d, dir / "out");

  const RunDescription run = LoadRunDescription(dir / "out/run.yaml");
  ASSERT_TRUE(run.gyro.has_value());
  ASSERT_TRUE(run.latitude_rad.has_value());
  RunWarnings warnings;
  const RunData back = LoadRunData(run, &warnings);
  ASSERT_TRUE(back.has_gyro());
  ASSERT_EQ(back.size(), 500u);
  const ModelConfig cfg = TruthModelConfig(s);
  double worst_dps = 0.0, latency_dps = 0.0;
  for (std::size_t k = 0; k < back.size(); ++k) {
    const double t = back.t_s[k];
    const Eigen::Vector3d g = PredictGyroReadings(cfg, s.truth.data(), s.profile.At(t));
    worst_dps = std::max(worst_dps, (back.gyro(k) - g).cwiseAbs().maxCoeff() / kDegToRad);
    // The recorded angles are 2 ms late: the gyro at them differs.
    const Eigen::Vector3d late = PredictGyroReadings(cfg, s.truth.data(), s.profile.At(t - 0.002));
    latency_dps = std::max(latency_dps, (late - g).cwiseAbs().maxCoeff() / kDegToRad);
  }
  EXPECT_LT(worst_dps, 1e-9);
  EXPECT_GT(latency_dps, 1e-3);
  // The same without Earth's rate differs by about Omega_E (0.0042 deg/s).
  ModelConfig no_earth = cfg;
  no_earth.earth_rate_L.setZero();
  const Eigen::Vector3d g0 = PredictGyroReadings(no_earth, s.truth.data(), s.profile.At(0.0));
  EXPECT_NEAR((back.gyro(0) - g0).norm(), kEarthRate_rad_s, 0.01 * kEarthRate_rad_s);
}

TEST(SimulatorGyro, TruthJsonRunYamlAndCsvCarryTheGyro) {
  TempDir dir("gyro_files");
  Scenario s = LoadFromText(dir, GyroScenarioWithTruth("0.05"));
  WriteSimulation(s, Simulate(s), dir / "out");
  const nlohmann::json j = nlohmann::json::parse(ReadText(dir / "out/truth.json"));
  const nlohmann::json& p = j.at("parameters");
  EXPECT_EQ(p.size(), static_cast<std::size_t>(kNumBaseParams + 1 + kNumGyroParams));
  for (const ParameterInfo& info : GyroParameterInfo()) {
    EXPECT_TRUE(p.contains(info.name)) << info.name;
    EXPECT_EQ(j.at("units").at(info.name), info.unit) << info.name;
  }
  EXPECT_EQ(p.at("gyro.Kx").get<double>(), 1.002);
  EXPECT_EQ(p.at("gyro.Ky").get<double>(), 1.0);
  EXPECT_EQ(p.at("gyro.W0x").get<double>(), 0.2);  // nominal, in deg/s
  EXPECT_EQ(p.at("gyro.W0z").get<double>(), 0.3);
  EXPECT_EQ(p.at("gyro.beta_z").get<double>(), 10.0);
  EXPECT_EQ(p.at("gyro.Gxy").get<double>(), 0.05);
  EXPECT_EQ(p.at("gyro.Gzz").get<double>(), -0.02);
  EXPECT_EQ(p.at("gyro.Gyx").get<double>(), 0.0);
  EXPECT_EQ(j.at("units").at("gyro.W0x"), "deg/s");
  EXPECT_EQ(j.at("noise").at("gyro_dps").get<double>(), 0.05);
  EXPECT_EQ(p.at("Kx").get<double>(), 171.5);

  const std::string yaml = ReadText(dir / "out/run.yaml");
  EXPECT_NE(yaml.find("latitude_deg: 48.15"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("gyro:\n  scale: [1, 1, 1]\n  bias_dps: [0.2, -0.1, 0.3]\n"
                      "  noise_dps: 0.05\n"),
            std::string::npos)
      << yaml;
  const std::string csv = ReadText(dir / "out/run.csv");
  EXPECT_NE(csv.find("\nt,lambda1,lambda2,wx,wy,wz,gx,gy,gz\n"), std::string::npos)
      << csv.substr(0, 200);
  // Without a gyro, no gyro anywhere.
  Scenario plain = LoadFromText(dir, NoisyScenario(1.0, 0.0));
  plain.profile.duration_s = 1.0;
  WriteSimulation(plain, Simulate(plain), dir / "plain");
  EXPECT_EQ(ReadText(dir / "plain/run.csv").find("gx"), std::string::npos);
  EXPECT_EQ(ReadText(dir / "plain/run.yaml").find("gyro"), std::string::npos);
  EXPECT_EQ(ReadText(dir / "plain/truth.json").find("gyro"), std::string::npos);
}

// The gyro's noise is white with its sigma per channel, and comes from a
// stream of its own: the accelerometer's data and the angles are those of the
// same scenario without a gyro.
TEST(SimulatorGyro, NoiseIsWhiteAndLeavesTheAccelerometerAlone) {
  TempDir dir("gyro_noise");
  std::string text = GyroScenarioWithTruth("[0.1, 0.2, 0.05]");
  text.replace(text.find("accel_mV: 0, angle_arcsec: 0"),
               std::string("accel_mV: 0, angle_arcsec: 0").size(), "accel_mV: 2, angle_arcsec: 15");
  text.replace(text.find("duration_s: 10"), std::string("duration_s: 10").size(), "duration_s: 60");
  const Scenario s = LoadFromText(dir, text);
  const ModelConfig cfg = TruthModelConfig(s);
  const RunData d = Simulate(s);
  std::vector<double> e[3];
  for (std::size_t k = 0; k < d.size(); ++k) {
    const Eigen::Vector3d g = PredictGyroReadings(cfg, s.truth.data(), s.profile.At(d.t_s[k]));
    for (int i = 0; i < 3; ++i) e[i].push_back((d.gyro_rad_s[i][k] - g[i]) / kDegToRad);
  }
  const Eigen::Vector3d sigma(0.1, 0.2, 0.05);
  for (int i = 0; i < 3; ++i) ExpectWhiteNoise(e[i], sigma[i], std::string("g") + "xyz"[i]);

  Scenario without = s;
  without.run.gyro.reset();
  without.truth_layout = without.truth_layout.WithGyro(false);
  without.truth.conservativeResize(without.truth_layout.size());
  const RunData a = Simulate(without);
  EXPECT_FALSE(a.has_gyro());
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a.w_mV[i], d.w_mV[i]);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(a.lambda_rad[i], d.lambda_rad[i]);
}

// A simulated run whose gyro columns are rewritten in rad/s (still declared
// deg/s) is refused by the reader, and so is the reverse.
TEST(SimulatorGyro, RadiansPerSecondDeclaredAsDegreesIsRefused) {
  TempDir dir("gyro_units");
  const Scenario s = LoadFromText(dir, GyroScenarioWithTruth("0.01"));
  RunData d = Simulate(s);
  for (auto& g : d.gyro_rad_s) {
    for (double& v : g) v *= kDegToRad;  // written as deg/s: the rad/s numbers
  }
  WriteSimulation(s, d, dir / "out");
  const std::string csv = dir / "out/run.csv";
  try {
    RunWarnings w;
    LoadRunData(LoadRunDescription(dir / "out/run.yaml"), &w);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(csv + ": column 'gx', column 'gy', column 'gz': the RMS of |g| over the "
                            "run is ",
                      0),
              0u)
        << m;
    EXPECT_NE(m.find(": the gyro readings look like rad/s, not deg/s; declare `unit: rad/s` "
                     "(columns.gx, gy, gz)"),
              std::string::npos)
        << m;
  }
  // The original run, declared rad/s: the reverse.
  WriteSimulation(s, Simulate(s), dir / "ok");
  const std::string yaml =
      ReadText(dir / "ok/run.yaml") +
      "columns: {gx: {source: gx, unit: rad/s}, gy: {source: gy, unit: rad/s}, gz: {source: gz, "
      "unit: rad/s}}\n";
  try {
    RunWarnings w;
    LoadRunData(LoadRunDescription(WriteText(dir / "ok/rad.yaml", yaml)), &w);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the gyro readings look like deg/s declared as rad/s"),
              std::string::npos)
        << e.what();
  }
  RunWarnings w;
  EXPECT_TRUE(LoadRunData(LoadRunDescription(dir / "ok/run.yaml"), &w).has_gyro());
}

TEST(SimulateCommand, GyroRunSaysSoAndListsNoGyroParameterAsAnEffect) {
  TempDir dir("cmd_gyro");
  const std::string scenario = WriteText(dir / "scen.yaml", GyroScenarioWithTruth("0.05"));
  std::string out, err;
  ASSERT_EQ(RunCommand("simulate " + scenario + " -o " + (dir / "run"), dir, &out, &err), 0) << err;
  EXPECT_EQ(err, "");
  EXPECT_NE(out.find("gyro: gx gy gz written, noise 0.05 0.05 0.05 deg/s, with Earth's rate\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("effects injected (not declared in run.yaml): angle_latency.tau_ms = 2\n"),
            std::string::npos)
      << out;
}

}  // namespace
}  // namespace triadcal
