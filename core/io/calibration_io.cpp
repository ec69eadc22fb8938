#include "core/io/calibration_io.h"

#include "core/io/parameters_json.h"
#include "core/model/errors.h"

namespace triadcal {

namespace {
const char kExpected[] =
    "an OUT of fit, static, filter (\"rts\"), compare (\"batch\") or a truth.json";
Calibration CalibrationFrom(const ParametersFile& file, const std::string& path);
}  // namespace

Calibration LoadCalibration(const std::string& path) {
  return CalibrationFrom(ReadParametersJson(path, {"", "rts", "batch"}, kExpected), path);
}

Calibration CalibrationFromJson(const nlohmann::json& root, const std::string& path) {
  return CalibrationFrom(ParametersFromJson(root, path, {"", "rts", "batch"}, kExpected), path);
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
