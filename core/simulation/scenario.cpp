// LoadScenario: reads and checks a scenario file (docs/file-formats.md, the input of
// `triadcal simulate`; the schema is in simulator.h). Every message is one line
// "FILE: key.path: what is wrong", through the shared helpers of yaml_fields.h.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/io/file_util.h"
#include "core/io/plausibility.h"
#include "core/io/run_description_io.h"
#include "core/io/yaml_fields.h"
#include "core/model/errors.h"
#include "core/simulation/simulator.h"

namespace triadcal {
namespace {

// A map section: null (absent or empty) counts as an empty map. Besides the
// allowed keys, rejects a key given twice (yaml-cpp would keep the first).
void CheckSection(const YAML::Node& n, const YamlPlace& at,
                  const std::vector<std::string>& allowed) {
  if (n.IsNull()) return;
  CheckKeys(n, at, allowed);
  std::set<std::string> seen;
  for (const auto& kv : n) {
    if (!seen.insert(KeyOf(kv.first, at)).second) at.Child(kv.first.Scalar()).Fail("given twice");
  }
}

void ReadPair(const YAML::Node& n, const YamlPlace& at, double out[2]) {
  if (!n.IsSequence()) at.Fail("expected a list of 2 numbers, got " + DescribeNode(n));
  if (n.size() != 2) at.Fail("expected a list of 2 numbers, got " + std::to_string(n.size()));
  for (std::size_t i = 0; i < 2; ++i) out[i] = ReadNumber(n[i], at.Index(i));
}

bool ReadBool(const YAML::Node& n, const YamlPlace& at) {
  bool b = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, b)) {
    at.Fail("expected true or false, got " + DescribeNode(n));
  }
  return b;
}

std::uint64_t ReadSeed(const YAML::Node& n, const YamlPlace& at) {
  const std::string text = n.IsScalar() ? n.Scalar() : "";
  const bool digits =
      !text.empty() && text.size() <= 20 &&
      std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits) at.Fail("expected a non-negative integer, got " + DescribeNode(n));
  try {
    return std::stoull(text);
  } catch (const std::exception&) {
    at.Fail("expected a non-negative integer below 2^64, got " + DescribeNode(n));
  }
}

void ParseProfile(const YAML::Node& n, const YamlPlace& at, HarmonicProfile* p) {
  CheckSection(n, at, {"amplitude_deg", "period_s", "phase_deg", "duration_s", "rate_hz"});
  if (n.IsNull()) return;
  double pair[2];
  if (n["amplitude_deg"]) {
    ReadPair(n["amplitude_deg"], at.Child("amplitude_deg"), pair);
    for (int i = 0; i < 2; ++i) p->amplitude_rad[i] = pair[i] * kDegToRad;
  }
  if (n["period_s"]) {
    ReadPair(n["period_s"], at.Child("period_s"), pair);
    for (std::size_t i = 0; i < 2; ++i) {
      p->period_s[i] = ReadPositive(n["period_s"][i], at.Child("period_s").Index(i));
    }
  }
  if (n["phase_deg"]) {
    ReadPair(n["phase_deg"], at.Child("phase_deg"), pair);
    for (int i = 0; i < 2; ++i) p->phase_rad[i] = pair[i] * kDegToRad;
  }
  // The peak rate A 2 pi / T of each axis within the bound of run data: a
  // run beyond it would be refused by every command (and 1e300 deg gave NaN
  // readings).
  for (int i = 0; i < 2; ++i) {
    const double amplitude_deg = std::abs(p->amplitude_rad[i]) / kDegToRad;
    const double peak_deg_s = amplitude_deg * 2.0 * kPi / p->period_s[i];
    if (!(peak_deg_s <= PlausibilityBounds::kMaxRate_deg_s)) {
      char text[200];
      std::snprintf(text, sizeof(text),
                    "%g deg over a period of %g s swings at up to %g deg/s, beyond the bound %g "
                    "deg/s of run data",
                    amplitude_deg, p->period_s[i], peak_deg_s, PlausibilityBounds::kMaxRate_deg_s);
      at.Child("amplitude_deg").Index(i).Fail(text);
    }
  }
  if (n["duration_s"]) p->duration_s = ReadPositive(n["duration_s"], at.Child("duration_s"));
  if (n["rate_hz"]) p->rate_hz = ReadPositive(n["rate_hz"], at.Child("rate_hz"));
  const double samples = p->duration_s * p->rate_hz;
  if (samples < 10.0) {  // every command needs 10 samples (core/io/run_validation.h)
    at.Fail("duration_s * rate_hz = " + FormatDouble(samples) +
            " samples; a run needs at least 10");
  }
  if (samples > static_cast<double>(kMaxSimulatedSamples)) {
    char text[40];
    std::snprintf(text, sizeof(text), "%.15g", samples);
    at.Fail("duration_s * rate_hz = " + std::string(text) + " samples, more than the limit " +
            std::to_string(kMaxSimulatedSamples));
  }
}

// An injected effect and its parameter values in file units.
struct InjectedEffect {
  Effect id;
  std::vector<double> values_file;
};

// The `effects` section, in catalogue order.
std::vector<InjectedEffect> ParseEffects(const YAML::Node& n, const YamlPlace& at) {
  std::vector<InjectedEffect> out;
  if (n.IsNull()) return out;
  if (!n.IsMap()) at.Fail("expected a map {effect: {param: value}}, got " + DescribeNode(n));
  std::set<std::string> seen;
  for (const auto& kv : n) {
    const std::string name = KeyOf(kv.first, at);
    if (!seen.insert(name).second) at.Child(name).Fail("given twice");
    InjectedEffect inj;
    try {
      inj.id = EffectFromName(name);
    } catch (const std::invalid_argument& e) {
      at.Fail(e.what());
    }
    const YamlPlace eat = at.Child(name);
    const EffectSpec& spec = GetEffectSpec(inj.id);
    std::vector<std::string> allowed;
    for (const ParamSpec& p : spec.params) {
      allowed.push_back(p.name);
      allowed.push_back(UnitSuffixedKey(p));
    }
    const YAML::Node params = kv.second;
    CheckSection(params, eat, allowed);
    for (const ParamSpec& p : spec.params) {
      const std::string suffixed = UnitSuffixedKey(p);
      const bool plain = !params.IsNull() && params[p.name];
      const bool with_unit = !params.IsNull() && params[suffixed];
      if (plain && with_unit) eat.Fail("both '" + p.name + "' and '" + suffixed + "' given");
      double v = 0.0;
      if (plain) v = ReadNumber(params[p.name], eat.Child(p.name));
      if (with_unit) v = ReadNumber(params[suffixed], eat.Child(suffixed));
      inj.values_file.push_back(v);
    }
    out.push_back(inj);
  }
  std::sort(out.begin(), out.end(), [](const InjectedEffect& a, const InjectedEffect& b) {
    return static_cast<int>(a.id) < static_cast<int>(b.id);
  });
  return out;
}

// The truth's keys: the base parameters, and the gyro's (gyro.Kx ...) only
// with a run.gyro block. An unknown name lists the keys of its own group.
void CheckTruthKeys(const YAML::Node& n, const YamlPlace& at, bool gyro) {
  if (n.IsNull()) return;
  std::vector<std::string> base, gyro_names;
  for (const ParameterInfo& p : BaseParameterInfo()) base.push_back(p.name);
  for (const ParameterInfo& p : GyroParameterInfo()) gyro_names.push_back(p.name);
  if (n.IsMap()) {
    for (const auto& kv : n) {
      const std::string name = KeyOf(kv.first, at);
      if (name.rfind("gyro.", 0) != 0) continue;
      const YamlPlace p = at.Child(name);
      if (std::find(gyro_names.begin(), gyro_names.end(), name) == gyro_names.end()) {
        std::string list;
        for (const std::string& g : gyro_names) list += (list.empty() ? "" : ", ") + g;
        p.Fail("unknown key (allowed: " + list + ")");
      }
      if (!gyro) {
        p.Fail(
            "a gyro parameter, but the scenario has no run.gyro block (add run: {gyro: "
            "{scale: [1, 1, 1]}} to simulate gx gy gz)");
      }
    }
  }
  if (gyro) base.insert(base.end(), gyro_names.begin(), gyro_names.end());
  CheckSection(n, at, base);
}

// The truth: the nominal of the run, then the base (and gyro) parameters the
// file gives, then the injected effects' parameters.
Eigen::VectorXd ParseTruth(const YAML::Node& n, const YamlPlace& at, const RunDescription& run,
                           const ParameterLayout& layout,
                           const std::vector<InjectedEffect>& effects) {
  CheckTruthKeys(n, at, layout.has_gyro());
  Eigen::VectorXd theta = NominalTheta(run, layout);
  if (!n.IsNull()) {
    for (const auto& kv : n) {
      const std::string name = KeyOf(kv.first, at);
      const int i = layout.IndexOf(name);
      theta[i] = ReadNumber(kv.second, at.Child(name)) * layout.info(i).si_per_unit;
    }
  }
  for (const InjectedEffect& e : effects) {
    const int o = layout.offset(e.id);
    for (std::size_t j = 0; j < e.values_file.size(); ++j) {
      const int i = o + static_cast<int>(j);
      theta[i] = e.values_file[j] * layout.info(i).si_per_unit;
    }
  }
  return theta;
}

// The `run` section: what run.yaml will declare. Its noise defaults to the
// true noise of the scenario: angles as given (0 included), readings
// sqrt(accel^2 + q^2 / 12) with the quantization step q, floored at
// kMinDeclaredNoise_mV because run.yaml requires noise_mV > 0; the gyro's
// (with a gyro block) noise.gyro_dps, floored at kMinDeclaredNoise_dps.
RunDescription ParseRunSection(const YAML::Node& n, const YamlPlace& at,
                               const std::string& yaml_path, const Eigen::Vector3d& accel_noise_mV,
                               bool per_channel, double quantization_mV, double angle_noise_rad,
                               const Eigen::Vector3d& gyro_noise_rad_s) {
  if (!n.IsNull() && !n.IsMap()) at.Fail("expected a map, got " + DescribeNode(n));
  const YAML::Node node = n.IsNull() ? YAML::Node(YAML::NodeType::Map) : n;
  for (const char* key : {"data", "columns", "mounting"}) {
    if (node[key]) {
      at.Child(key).Fail("not allowed in a scenario (simulate writes run.csv itself)");
    }
  }
  // Messages from the run parser read "FILE: run: bench.lever_arm_mm: ...".
  RunDescription run = ParseRunDescription(node, yaml_path, at.where + ": " + at.path);
  const YAML::Node triad = node["triad"], bench = node["bench"];
  if (!(triad && triad.IsMap() && triad["noise_mV"])) {
    Eigen::Vector3d declared;
    for (int i = 0; i < 3; ++i) {
      const double variance_mV2 =
          accel_noise_mV[i] * accel_noise_mV[i] + quantization_mV * quantization_mV / 12.0;
      declared[i] = std::max(std::sqrt(variance_mV2), kMinDeclaredNoise_mV);
    }
    run.noise_mV = std::sqrt(declared.squaredNorm() / 3.0);
    if (per_channel) run.noise_channel_mV = declared;
  }
  if (!(bench && bench.IsMap() && bench["angle_noise_arcsec"])) {
    run.angle_noise_rad = angle_noise_rad;
  }
  const YAML::Node gyro = node["gyro"];
  if (run.gyro && !(gyro && gyro.IsMap() && gyro["noise_dps"])) {
    run.gyro->noise_rad_s =
        gyro_noise_rad_s.cwiseMax(Eigen::Vector3d::Constant(kMinDeclaredNoise_dps * kDegToRad));
  }
  return run;
}

}  // namespace

Scenario LoadScenario(const std::string& yaml_path) {
  const YAML::Node root = LoadYamlFile(yaml_path);
  const YamlPlace top{yaml_path, ""};
  if (!root.IsMap())
    top.Fail("expected a map with the sections profile, truth, noise, effects, run");
  CheckSection(
      root, top,
      {"profile", "truth", "truth_spread", "noise", "effects", "run", "seed", "sensor", "output",
       "temperature", "truth_temperature"});
  auto section = [&root](const char* key) {
    return root[key] ? root[key] : YAML::Node(YAML::NodeType::Null);
  };

  Scenario s;
  s.yaml_path = yaml_path;
  ParseProfile(section("profile"), top.Child("profile"), &s.profile);

  const YAML::Node noise = section("noise");
  const YamlPlace noise_at = top.Child("noise");
  CheckSection(noise, noise_at, {"accel_mV", "angle_arcsec", "accel_correlation_s", "gyro_dps"});
  if (!noise.IsNull() && noise["accel_mV"]) {
    const YamlPlace accel_at = noise_at.Child("accel_mV");
    if (noise["accel_mV"].IsSequence()) {
      // One figure per channel [x, y, z].
      const Eigen::Vector3d v = ReadVector3(noise["accel_mV"], accel_at);
      for (int i = 0; i < 3; ++i) {
        if (!(v[i] >= 0.0)) accel_at.Index(i).Fail("must be >= 0, got " + FormatDouble(v[i]));
      }
      s.accel_noise_channel_mV = v;
      s.accel_noise_mV = std::sqrt(v.squaredNorm() / 3.0);
    } else {
      s.accel_noise_mV = ReadNonNegative(noise["accel_mV"], accel_at);
    }
  }
  if (!noise.IsNull() && noise["accel_correlation_s"]) {
    s.accel_correlation_s =
        ReadNonNegative(noise["accel_correlation_s"], noise_at.Child("accel_correlation_s"));
  }
  if (!noise.IsNull() && noise["angle_arcsec"]) {
    s.angle_noise_rad =
        ReadNonNegative(noise["angle_arcsec"], noise_at.Child("angle_arcsec")) * kArcsecToRad;
  }
  // noise.gyro_dps: one figure or [x, y, z]; only a scenario whose run has a
  // gyro block simulates a gyro (checked with the run section below).
  const bool gyro_noise_given = !noise.IsNull() && noise["gyro_dps"];
  if (gyro_noise_given) {
    const YamlPlace gyro_at = noise_at.Child("gyro_dps");
    if (noise["gyro_dps"].IsSequence()) {
      const Eigen::Vector3d v = ReadVector3(noise["gyro_dps"], gyro_at);
      for (int i = 0; i < 3; ++i) {
        if (!(v[i] >= 0.0)) gyro_at.Index(i).Fail("must be >= 0, got " + FormatDouble(v[i]));
      }
      s.gyro_noise_rad_s = v * kDegToRad;
      s.gyro_noise_per_channel = true;
    } else {
      s.gyro_noise_rad_s =
          Eigen::Vector3d::Constant(ReadNonNegative(noise["gyro_dps"], gyro_at) * kDegToRad);
    }
  }

  const YAML::Node sensor = section("sensor");
  const YamlPlace sensor_at = top.Child("sensor");
  CheckSection(sensor, sensor_at, {"quantization_mV", "saturation_mV"});
  if (!sensor.IsNull() && sensor["quantization_mV"]) {
    s.quantization_mV =
        ReadNonNegative(sensor["quantization_mV"], sensor_at.Child("quantization_mV"));
  }
  if (!sensor.IsNull() && sensor["saturation_mV"]) {
    const YamlPlace sat_at = sensor_at.Child("saturation_mV");
    double lim[2];
    ReadPair(sensor["saturation_mV"], sat_at, lim);
    if (!(lim[0] < lim[1])) {
      sat_at.Fail("expected [low, high] with low < high, got [" + FormatDouble(lim[0]) + ", " +
                  FormatDouble(lim[1]) + "]");
    }
    s.saturation_low_mV = lim[0];
    s.saturation_high_mV = lim[1];
  }

  s.run = ParseRunSection(section("run"), top.Child("run"), yaml_path, s.AccelNoise_mV(),
                          s.accel_noise_channel_mV.has_value(), s.quantization_mV,
                          s.angle_noise_rad, s.gyro_noise_rad_s);
  if (gyro_noise_given && !s.run.gyro) {
    noise_at.Child("gyro_dps")
        .Fail(
            "a gyro noise, but the scenario has no run.gyro block (add run: {gyro: {scale: [1, 1, "
            "1]}} to simulate gx gy gz)");
  }

  const std::vector<InjectedEffect> effects =
      ParseEffects(section("effects"), top.Child("effects"));
  std::vector<Effect> ids;
  for (const InjectedEffect& e : effects) {
    if (GetEffectSpec(e.id).stage == EffectStage::kGyro && !s.run.gyro) {
      top.Child("effects").Fail(GetEffectSpec(e.id).name +
                                " acts on the gyro, but the scenario has no run.gyro block");
    }
    ids.push_back(e.id);
  }
  s.truth_layout = ParameterLayout(ids, /*gyro=*/s.run.gyro.has_value());
  s.truth = ParseTruth(section("truth"), top.Child("truth"), s.run, s.truth_layout, effects);

  const YAML::Node temp = section("temperature");
  const YamlPlace temp_at = top.Child("temperature");
  CheckSection(temp, temp_at, {"start_C", "rate_C_per_h"});
  const bool has_temperature = bool(root["temperature"]);
  if (!temp.IsNull() && temp["start_C"]) {
    s.temp_start_C = ReadNumber(temp["start_C"], temp_at.Child("start_C"));
  }
  if (!temp.IsNull() && temp["rate_C_per_h"]) {
    s.temp_rate_C_per_h = ReadNumber(temp["rate_C_per_h"], temp_at.Child("rate_C_per_h"));
  }
  for (Effect e : s.truth_layout.effects()) {
    if (GetEffectSpec(e).needs.temp_C && !has_temperature) {
      top.Child("effects")
          .Child(GetEffectSpec(e).name)
          .Fail("needs a section temperature: {start_C, rate_C_per_h} (the drift follows temp_C)");
    }
  }

  // truth_temperature: {reference_C: 20, per_C: {W0x: 0.05}}: the truth is
  // that of reference_C; the run, at temperature.start_C, gets
  // truth + per_C * (start_C - reference_C) (runs of one IMU at several
  // temperatures, docs/multi-run.md).
  const YAML::Node tt = section("truth_temperature");
  if (!tt.IsNull()) {
    const YamlPlace tt_at = top.Child("truth_temperature");
    CheckSection(tt, tt_at, {"reference_C", "per_C"});
    if (!has_temperature) tt_at.Fail("needs a section temperature: {start_C} (the run's temperature)");
    const double ref = tt["reference_C"] ? ReadNumber(tt["reference_C"], tt_at.Child("reference_C"))
                                         : 20.0;
    const YAML::Node per = tt["per_C"];
    const YamlPlace per_at = tt_at.Child("per_C");
    if (!per || !per.IsMap()) per_at.Fail("expected a map {parameter: change per degC, file units}");
    for (const auto& kv : per) {
      const std::string name = KeyOf(kv.first, per_at);
      const int i = s.truth_layout.IndexOf(name);
      if (i < 0) per_at.Child(name).Fail("unknown parameter (docs/file-formats.md names)");
      s.truth[i] += ReadNumber(kv.second, per_at.Child(name)) * (s.temp_start_C - ref) *
                    s.truth_layout.info(i).si_per_unit;
    }
  }

  const YAML::Node output = section("output");
  const YamlPlace output_at = top.Child("output");
  CheckSection(output, output_at, {"rates", "temperature"});
  s.write_temp = has_temperature;
  if (!output.IsNull() && output["rates"]) {
    s.write_rates = ReadBool(output["rates"], output_at.Child("rates"));
  }
  if (!output.IsNull() && output["temperature"]) {
    s.write_temp = ReadBool(output["temperature"], output_at.Child("temperature"));
  }

  const YAML::Node spread = section("truth_spread");
  const YamlPlace spread_at = top.Child("truth_spread");
  if (!spread.IsNull()) {
    if (!spread.IsMap()) spread_at.Fail("expected a map {parameter: sigma in file units}");
    for (const auto& kv : spread) {
      const std::string name = KeyOf(kv.first, spread_at);
      const int i = s.truth_layout.IndexOf(name);
      if (i < 0) spread_at.Child(name).Fail("unknown parameter (docs/file-formats.md names)");
      s.truth_spread.push_back(
          {i, ReadNonNegative(kv.second, spread_at.Child(name)) * s.truth_layout.info(i).si_per_unit});
    }
  }

  if (root["seed"]) s.seed = ReadSeed(root["seed"], top.Child("seed"));
  return s;
}

}  // namespace triadcal
