// WriteSimulation: the three files of `triadcal simulate` (docs/file-formats.md),
// DIR/run.csv, DIR/run.yaml and DIR/truth.json, all or none.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <system_error>
#include <vector>

#include "core/model/errors.h"
#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/simulation/simulator.h"
#include "core/io/run_description_io.h"

namespace triadcal {

namespace fs = std::filesystem;

std::string TruthFileKey(const ParameterLayout& layout, int i) {
  const ParameterInfo& info = layout.info(i);
  if (!info.effect) return info.name;
  const EffectSpec& spec = GetEffectSpec(*info.effect);
  const int j = i - layout.offset(*info.effect);
  return spec.name + "." + UnitSuffixedKey(spec.params[j]);
}

double TruthFileValue(const ParameterLayout& layout, const Eigen::VectorXd& theta, int i) {
  const double f = layout.info(i).si_per_unit;
  const double v = theta[i] / f;
  // Fewest significant digits whose value, converted back as readers do
  // (value * si_per_unit), gives exactly theta[i]: -33 arcmin stays -33.
  for (int digits = 1; digits <= 17; ++digits) {
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
    const double d = std::strtod(buf, nullptr);
    if (d * f == theta[i]) return d;
  }
  return v;
}

namespace {

std::string TruthJson(const Scenario& s, const RunData& data, const std::string& provenance) {
  nlohmann::ordered_json params = nlohmann::ordered_json::object();
  nlohmann::ordered_json units = nlohmann::ordered_json::object();
  for (int i = 0; i < s.truth_layout.size(); ++i) {
    const std::string key = TruthFileKey(s.truth_layout, i);
    params[key] = TruthFileValue(s.truth_layout, s.truth, i);
    units[key] = s.truth_layout.info(i).unit;
  }
  nlohmann::ordered_json effects = nlohmann::ordered_json::array();
  for (Effect e : s.truth_layout.effects()) effects.push_back(GetEffectSpec(e).name);

  nlohmann::ordered_json j;
  j["parameters"] = params;
  j["units"] = units;
  j["injected_effects"] = effects;  // in the data, not declared in run.yaml
  j["scenario"] = fs::path(s.yaml_path).filename().string();
  j["seed"] = s.seed;
  j["noise"] = {{"accel_mV", s.accel_noise_mV}, {"angle_arcsec", s.angle_noise_rad / kArcsecToRad}};
  if (s.accel_noise_channel_mV) {
    const Eigen::Vector3d& c = *s.accel_noise_channel_mV;
    j["noise"]["accel_mV"] = {c[0], c[1], c[2]};
  }
  if (s.run.gyro) {
    const Eigen::Vector3d c = s.gyro_noise_rad_s / kDegToRad;
    if (s.gyro_noise_per_channel) {
      j["noise"]["gyro_dps"] = {c[0], c[1], c[2]};
    } else {
      j["noise"]["gyro_dps"] = c[0];
    }
  }
  j["samples"] = data.size();
  if (!provenance.empty()) j["provenance"] = nlohmann::ordered_json::parse(provenance);
  return j.dump(2) + "\n";
}

std::string CsvComment(const Scenario& s) {
  return "simulated by triadcal simulate\nscenario: " + fs::path(s.yaml_path).filename().string() +
         "\nseed: " + std::to_string(s.seed);
}

// The staging folders ".simulate.tmp.HOST.PID" (and ".simulate.tmp.PID" of
// earlier versions) of processes of this host that are gone (kill -9).
void RemoveStaleStaging(const fs::path& dir) {
  RemoveStaleEntries(dir.string(), ".simulate.tmp.", true);
}

}  // namespace

void WriteSimulation(const Scenario& s, const RunData& data, const std::string& dir,
                     const std::string& provenance_json, const WriteOptions& options) {
  // Everything that can fail without touching the disk, first.
  const std::string yaml_text = RunDescriptionToYaml(s.run, "run.csv");
  const std::string json_text = TruthJson(s, data, provenance_json);
  const std::vector<std::string> names = {"run.csv", "run.yaml", "truth.json"};

  const fs::path out(dir);
  std::error_code ec;
  const bool existed = fs::exists(out, ec);
  if (existed && !fs::is_directory(out, ec)) throw InputError(dir + ": exists and is not a folder");
  // The files are moved in by rename, which would replace whatever has their
  // names: each must be missing or a regular file, and no input.
  for (const std::string& name : names) {
    const fs::path p = out / name;
    if (fs::is_symlink(fs::symlink_status(p, ec))) {
      throw InputError(p.string() +
                       ": cannot write: is a symbolic link (simulate moves its "
                       "files into the folder; remove the link or choose another "
                       "folder)");
    }
    CheckOutputFile(p.string());
    if (options.guard) options.guard->CheckOutputsAreNotInputs(p.string());
  }
  if (existed) RemoveStaleStaging(out);
  if (!existed) {
    fs::create_directories(out, ec);
    if (ec) throw InputError(dir + ": cannot create the folder: " + ec.message());
  }
  const fs::path staging = out / (".simulate.tmp." + HostTag() + "." + std::to_string(getpid()));
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) {
    if (!existed) fs::remove(out, ec);
    throw InputError(dir + ": cannot write into the folder: " + ec.message());
  }
  std::vector<fs::path> moved;
  try {
    WriteRunCsv(data, (staging / "run.csv").string(), CsvComment(s), options);
    WriteFileAtomically((staging / "run.yaml").string(), yaml_text, options);
    WriteFileAtomically((staging / "truth.json").string(), json_text, options);
    for (const std::string& name : names) {
      fs::rename(staging / name, out / name, ec);
      if (ec) throw InputError((out / name).string() + ": cannot write: " + ec.message());
      moved.push_back(out / name);
    }
  } catch (...) {
    for (const fs::path& p : moved) fs::remove(p, ec);
    fs::remove_all(staging, ec);
    if (!existed) fs::remove(out, ec);  // only removes it when empty
    throw;
  }
  fs::remove_all(staging, ec);
}

}  // namespace triadcal
