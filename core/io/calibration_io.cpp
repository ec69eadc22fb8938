#include "core/io/calibration_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/io/parameters_json.h"
#include "core/io/plausibility.h"
#include "core/model/errors.h"

namespace triadcal {

namespace {
// The joint fit's keys (docs/multi-run.md): "axes": "imu", and
// "temperature_model": {"reference_C": T, "degree": {"Kx": 1, ...}} with the
// coefficients as parameters "Kx.t1", ... in the unit of Kx per degC^k.
void ReadJointKeys(const nlohmann::json& root, const std::string& path, Calibration* cal) {
  if (!root.is_object()) return;
  if (root.contains("axes")) {
    if (!root["axes"].is_string() || (root["axes"] != "imu" && root["axes"] != "platform")) {
      throw InputError(path + ": axes: expected \"imu\" or \"platform\"");
    }
    cal->imu_axes = root["axes"] == "imu";
  }
  if (!root.contains("temperature_model") || root["temperature_model"].is_null()) return;
  const nlohmann::json& tm = root["temperature_model"];
  const std::string at = path + ": temperature_model.";
  if (!tm.is_object() || !tm.contains("reference_C") || !tm["reference_C"].is_number() ||
      !tm.contains("degree") || !tm["degree"].is_object()) {
    throw InputError(path + ": temperature_model: expected {\"reference_C\": number, "
                            "\"degree\": {parameter: degree}}");
  }
  cal->temperature_ref_C = tm["reference_C"].get<double>();
  const nlohmann::json& params = root["parameters"];
  for (const auto& [name, degree] : tm["degree"].items()) {
    const int index = cal->layout.IndexOf(name);
    if (index < 0) throw InputError(at + "degree." + name + ": not a parameter of the calibration");
    if (!degree.is_number_integer() || degree.get<int>() < 1 || degree.get<int>() > 3) {
      throw InputError(at + "degree." + name + ": expected a degree of 1 to 3");
    }
    Calibration::TemperatureTerm term{index, {}};
    for (int k = 1; k <= degree.get<int>(); ++k) {
      const std::string key = name + ".t" + std::to_string(k);
      if (!params.contains(key)) throw InputError(path + ": parameters." + key + ": missing");
      const nlohmann::json& e = params[key];
      const nlohmann::json& v = e.is_object() && e.contains("value") ? e["value"] : e;
      if (!v.is_number() || !std::isfinite(v.get<double>())) {
        throw InputError(path + ": parameters." + key + ": expected a finite number");
      }
      term.coefficients.push_back(v.get<double>() * cal->layout.info(index).si_per_unit);
    }
    cal->temperature_terms.push_back(term);
  }
}

// The commands whose OUT is a calibration (a truth.json has no "command"):
// fit (one run, several runs, batch), static, diagnose (its final fit),
// filter ("rts") and compare ("batch").
const char* const kCalibrationCommands[] = {"fit", "static", "diagnose", "filter", "compare"};
const char kExpected[] =
    "an OUT of fit, static, diagnose, filter (\"rts\"), compare (\"batch\") or a truth.json";
Calibration CalibrationFrom(const ParametersFile& file, const std::string& path);
}  // namespace

Calibration LoadCalibration(const std::string& path) {
  return CalibrationFromJson(ParseJsonStrict(ReadFile(path), path), path);
}

Calibration CalibrationFromJson(const nlohmann::json& root, const std::string& path) {
  // An OUT of another command (observability, design, montecarlo, ...) may
  // hold a "parameters" object of nominal values: not a calibration.
  if (root.is_object() && root.contains("command")) {
    const nlohmann::json& c = root["command"];
    const std::string command = c.is_string() ? c.get<std::string>() : c.dump();
    bool calibration = false;
    for (const char* k : kCalibrationCommands) calibration = calibration || command == k;
    if (!calibration) {
      throw InputError(path + ": command '" + Excerpt(command, 40) +
                       "': not a calibration (expected " + kExpected + ")");
    }
  }
  Calibration cal =
      CalibrationFrom(ParametersFromJson(root, path, {"", "rts", "batch"}, kExpected), path);
  ReadJointKeys(root, path, &cal);
  return cal;
}

namespace {

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", x);
  return buf;
}

// Unknown keys of the parameters: an effect (or an effect's parameter) this
// build does not know is refused, since applying the calibration without it
// would be silently wrong; so is any unknown name in an OUT file (it has a
// "command"). A truth.json may hold other plain keys: its readers ignore what
// they do not know (SPEC section 7).
void RefuseUnknownKeys(const ParametersFile& file) {
  std::string key;
  for (const std::string& k : file.unknown_keys) {
    if (k.find('.') != std::string::npos || !file.command.empty()) {
      key = k;
      break;
    }
  }
  if (key.empty()) return;
  if (key.rfind("gyro.", 0) == 0) {
    throw InputError(file.At() + Excerpt(key) +
                     ": unknown gyro parameter (the gyro's are gyro.Kx ... gyro.Gzz, SPEC "
                     "section 10 and docs/file-formats.md)");
  }
  std::string effects;
  for (const EffectSpec& e : EffectCatalogue()) effects += (effects.empty() ? "" : ", ") + e.name;
  const std::size_t dot = key.find('.');
  if (dot == std::string::npos) {
    throw InputError(file.At() + Excerpt(key) +
                     ": unknown parameter (the names of docs/file-formats.md; a calibration "
                     "is applied whole or not at all)");
  }
  const std::string effect = key.substr(0, dot);
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.name != effect) continue;
    std::string params;
    for (const ParamSpec& p : e.params) params += (params.empty() ? "" : ", ") + p.name;
    throw InputError(file.At() + Excerpt(key) + ": unknown parameter of effect " + effect +
                     " (its parameters: " + params + ")");
  }
  throw InputError(file.At() + Excerpt(key) + ": unknown effect '" + Excerpt(effect, 40) +
                   "' (this build knows " + effects +
                   "); applied without it the correction would be silently wrong: a "
                   "calibration of another build?");
}

// The readings unit an entry's unit names ("mV", "mg", "counts"), "" when the
// parameter's unit does not depend on the readings (or none was given).
std::string ReadingsUnitOfEntry(const std::string& given, const std::string& canonical) {
  if (given.empty()) return "";
  for (const char* token : {"mV", "mg", "counts"}) {
    const std::size_t at = canonical.find(token);
    if (at == std::string::npos) continue;
    const std::size_t len = std::string(token).size();
    for (const char* r : {"mV", "mg", "counts"}) {
      if (given == canonical.substr(0, at) + r + canonical.substr(at + len)) return r;
    }
  }
  return "";
}

// The bounds of run.yaml and CalibrationBounds, in file units.
void CheckCalibrationPlausible(const ParametersFile& file, const Calibration& cal) {
  using B = PlausibilityBounds;
  using C = CalibrationBounds;
  const ParameterLayout& layout = cal.layout;
  auto value = [&](int i) { return cal.theta[i] / layout.info(i).si_per_unit; };
  auto fail = [&](int i, const std::string& what) {
    const auto it = file.entries.find(layout.info(i).name);
    const std::string key = it == file.entries.end() ? layout.info(i).name : it->second.key;
    throw InputError(file.At() + key + ": " + what);
  };
  for (int i = 0; i < 3; ++i) {
    const double k = value(kKx + i);
    const std::string unit =
        " " + (cal.readings_unit.empty() ? layout.info(kKx + i).unit : cal.readings_unit + "/g");
    if (!(k > 0.0)) {
      fail(kKx + i, Num(k) + unit +
                        ": a scale factor must be > 0 (an axis that reads -1 g when it points "
                        "up belongs in the run's mounting.axes)");
    }
    if (k < B::kMinScale || k > B::kMaxScale) {
      fail(kKx + i, Num(k) + unit + " is outside [" + Num(B::kMinScale) + ", " +
                        Num(B::kMaxScale) +
                        "] per g (no accelerometer output is outside this range)");
    }
    const double b = value(kW0x + i);
    if (std::abs(b) > B::kMaxBiasInG * k) {
      fail(kW0x + i, Num(b) + " is " + Num(std::abs(b) / k) + " g worth of " +
                         layout.info(kKx + i).name + " = " + Num(k) + " (bound " +
                         Num(B::kMaxBiasInG) +
                         " g): scale and bias in different units (V/g for mV/g?)");
    }
  }
  for (int i = kAlphaX; i <= kGammaZ; ++i) {
    const double a = value(i);
    if (std::abs(a) > C::kMaxAngle_arcmin) {
      fail(i, Num(a) + " " + layout.info(i).unit + " is beyond the bound " +
                  Num(C::kMaxAngle_arcmin) +
                  " arcmin (30 deg: no triad's axes are that far off; arcsec given as arcmin?)");
    }
  }
  for (int i = kKxx; i <= kKzz; ++i) {
    const double k = value(i);
    if (std::abs(k) > C::kMaxNonlinearity_per_g) {
      fail(i, Num(k) + " " + layout.info(i).unit + " is beyond the bound " +
                  Num(C::kMaxNonlinearity_per_g) + " /g (a nonlinearity of 1000 % at 1 g)");
    }
  }
  if (!layout.has_gyro()) return;
  // The gyro (SPEC section 10): a scale factor may be negative (an axis
  // reversed against the accelerometer's, as run.yaml's gyro.scale) but not 0;
  // the angles within the accelerometer's bound.
  const int g = layout.gyro_offset();
  for (int i = 0; i < 3; ++i) {
    if (value(g + kGKx + i) == 0.0) {
      fail(g + kGKx + i, "0: a gyro scale factor must not be 0 (readings per deg/s; nominal 1)");
    }
  }
  for (int i = g + kGAlphaX; i <= g + kGGammaZ; ++i) {
    const double a = value(i);
    if (std::abs(a) > C::kMaxAngle_arcmin) {
      fail(i, Num(a) + " " + layout.info(i).unit + " is beyond the bound " +
                  Num(C::kMaxAngle_arcmin) +
                  " arcmin (30 deg: no triad's axes are that far off; arcsec given as arcmin?)");
    }
  }
}

Calibration CalibrationFrom(const ParametersFile& file, const std::string& path) {
  RefuseUnknownKeys(file);
  Calibration cal;
  cal.path = path;
  cal.section = file.section;
  cal.command = file.command;

  // Effects named by the parameters.
  std::vector<Effect> effects;
  for (const EffectSpec& e : EffectCatalogue()) {
    for (const ParamSpec& p : e.params) {
      if (file.entries.count(e.name + "." + p.name)) {
        effects.push_back(e.id);
        break;
      }
    }
  }
  // The gyro block when any gyro parameter is given (then all 21 are needed).
  const std::string gyro_given = [&] {
    for (const ParameterInfo& info : GyroParameterInfo()) {
      const auto it = file.entries.find(info.name);
      if (it != file.entries.end()) return it->second.key;
    }
    return std::string();
  }();
  for (Effect e : effects) {
    if (GetEffectSpec(e).stage == EffectStage::kGyro && gyro_given.empty()) {
      throw InputError(file.At() + GetEffectSpec(e).name +
                       ": a gyro effect without the gyro's parameters (gyro.Kx..gyro.Gzz, SPEC "
                       "section 10)");
    }
  }
  cal.layout = ParameterLayout(effects, /*gyro=*/!gyro_given.empty());
  cal.theta = Eigen::VectorXd::Zero(cal.layout.size());
  std::string unit_from;  // the entry that set cal.readings_unit
  for (int i = 0; i < cal.layout.size(); ++i) {
    const ParameterInfo& info = cal.layout.info(i);
    const auto it = file.entries.find(info.name);
    if (it == file.entries.end()) {
      if (cal.layout.is_gyro(i)) {
        throw InputError(file.At() + info.name + ": missing (" + gyro_given +
                         " is given: a calibration with the gyro needs its 21 parameters "
                         "gyro.Kx..gyro.Gzz, SPEC section 10)");
      }
      if (i <= kKzz || info.effect) {
        throw InputError(file.At() + info.name +
                         ": missing (a calibration needs the 21 sensor parameters Kx..Kzz of "
                         "docs/file-formats.md, and every parameter of an effect it names)");
      }
      continue;  // bench and lever arm: not used by the inverse
    }
    cal.theta[i] = it->second.value_file * info.si_per_unit;
    const std::string r = ReadingsUnitOfEntry(it->second.unit, info.unit);
    if (r.empty()) continue;
    if (cal.readings_unit.empty()) {
      cal.readings_unit = r;
      unit_from = it->second.key;
    } else if (r != cal.readings_unit) {
      throw InputError(file.At() + it->second.key + ": unit " + it->second.unit + " is in " + r +
                       ", but " + unit_from + " is in " + cal.readings_unit +
                       ": one calibration has one readings unit");
    }
  }
  CheckCalibrationPlausible(file, cal);
  return cal;
}

}  // namespace

void CheckCalibrationForRun(const Calibration& cal, const RunDescription& run) {
  const std::string at = cal.path + ": " + cal.section + ".";
  const std::string run_unit = ReadingsUnit(run);
  if (!cal.readings_unit.empty() && cal.readings_unit != run_unit) {
    throw InputError(at + "Kx: the calibration is in " + cal.readings_unit + "/g, but the run " +
                     run.yaml_path + " reads " + run_unit +
                     " (columns.wx.unit): a calibration applies to readings in its own unit");
  }
  const double lo = run.scale_mV_per_g.minCoeff(), hi = run.scale_mV_per_g.maxCoeff();
  for (int i = 0; i < 3; ++i) {
    const ParameterInfo& info = cal.layout.info(kKx + i);
    const double k = cal.theta[kKx + i] / info.si_per_unit;
    const double ratio = k < lo ? lo / k : k > hi ? k / hi : 1.0;
    if (ratio > CalibrationBounds::kMaxScaleRatio) {
      throw InputError(at + info.name + ": " + Num(k) + " " + run_unit + "/g is " + Num(ratio) +
                       " times " + (k < lo ? "below" : "above") + " the run's nominal scale " +
                       Num(k < lo ? lo : hi) + " " + run_unit + "/g (" + run.yaml_path +
                       ": triad.scale_mV_per_g; bound: a factor " +
                       Num(CalibrationBounds::kMaxScaleRatio) +
                       "): V/g given as mV/g, or the calibration of another sensor?");
    }
  }
  if (!cal.layout.has_gyro() || !run.gyro) return;
  // The gyro's scale against the run's nominal gyro.scale (both in readings
  // per deg/s once the run's columns are converted): a factor 57.3 is a
  // calibration in rad/s applied to deg/s or the reverse.
  for (int i = 0; i < 3; ++i) {
    const int index = cal.layout.gyro_offset() + kGKx + i;
    const double k = std::abs(cal.theta[index]), nominal = std::abs(run.gyro->scale[i]);
    const double ratio = std::max(k / nominal, nominal / k);
    if (ratio > CalibrationBounds::kMaxScaleRatio) {
      throw InputError(at + cal.layout.info(index).name + ": " + Num(cal.theta[index]) + " is " +
                       Num(ratio) + " times " + (k < nominal ? "below" : "above") +
                       " the run's nominal gyro scale " + Num(run.gyro->scale[i]) + " (" +
                       run.yaml_path + ": gyro.scale; bound: a factor " +
                       Num(CalibrationBounds::kMaxScaleRatio) +
                       "): a gyro calibrated in rad/s applied to deg/s, or the calibration of "
                       "another sensor?");
    }
  }
}

}  // namespace triadcal
