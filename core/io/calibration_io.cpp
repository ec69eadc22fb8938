#include "core/io/calibration_io.h"

#include "core/io/parameters_json.h"
#include "core/model/errors.h"
#include "core/io/file_util.h"

#include <cmath>

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

const char kExpected[] =
    "an OUT of fit, static, filter (\"rts\"), compare (\"batch\") or a truth.json";
Calibration CalibrationFrom(const ParametersFile& file, const std::string& path);
}  // namespace

Calibration LoadCalibration(const std::string& path) {
  ReadParametersJson(path, {"", "rts", "batch"}, kExpected);  // its messages for a bad file
  // Valid JSON by now: read again for the joint fit's keys.
  return CalibrationFromJson(nlohmann::json::parse(ReadFile(path)), path);
}

Calibration CalibrationFromJson(const nlohmann::json& root, const std::string& path) {
  Calibration cal =
      CalibrationFrom(ParametersFromJson(root, path, {"", "rts", "batch"}, kExpected), path);
  ReadJointKeys(root, path, &cal);
  return cal;
}

namespace {
Calibration CalibrationFrom(const ParametersFile& file, const std::string& path) {
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
  cal.layout = ParameterLayout(effects);
  cal.theta = Eigen::VectorXd::Zero(cal.layout.size());
  for (int i = 0; i < cal.layout.size(); ++i) {
    const ParameterInfo& info = cal.layout.info(i);
    const auto it = file.entries.find(info.name);
    if (it == file.entries.end()) {
      if (i <= kKzz || info.effect) {
        throw InputError(file.At() + info.name +
                         ": missing (a calibration needs the 21 sensor parameters Kx..Kzz of "
                         "docs/file-formats.md, and every parameter of an effect it names)");
      }
      continue;  // bench and lever arm: not used by the inverse
    }
    cal.theta[i] = it->second.value_file * info.si_per_unit;
  }
  for (int i = 0; i < 3; ++i) {
    if (cal.theta[kKx + i] == 0.0) {
      throw InputError(file.At() + cal.layout.info(kKx + i).name + ": scale factor 0");
    }
  }
  return cal;
}
}  // namespace

}  // namespace triadcal
