// `triadcal simulate SCENARIO.yaml -o DIR [--seed N]`: generates a run with known
// truth (DIR/run.csv, DIR/run.yaml, DIR/truth.json) and prints a short summary.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "app/output_guard.h"

namespace triadcal {
namespace {

struct SimulateOptions {
  std::string scenario_path;
  std::string out_dir;
  std::string seed;  // --seed as given (ParseSeed)
};

void PrintSummary(const Scenario& s, const RunData& data, const std::string& dir) {
  const HarmonicProfile& p = s.profile;
  std::printf("simulated %zu samples: %g s at %g Hz, profile %g/%g deg, %g/%g s\n", data.size(),
              p.duration_s, p.rate_hz, p.amplitude_rad[0] / kDegToRad,
              p.amplitude_rad[1] / kDegToRad, p.period_s[0], p.period_s[1]);
  char accel[96];
  if (s.accel_noise_channel_mV) {
    const Eigen::Vector3d& c = *s.accel_noise_channel_mV;
    std::snprintf(accel, sizeof(accel), "%g %g %g", c[0], c[1], c[2]);
  } else {
    std::snprintf(accel, sizeof(accel), "%g", s.accel_noise_mV);
  }
  std::printf("noise (1 sigma per sample): accelerometers %s mV, angles %g arcsec; seed %llu\n",
              accel, s.angle_noise_rad / kArcsecToRad, static_cast<unsigned long long>(s.seed));
  if (s.run.gyro) {
    const Eigen::Vector3d c = s.gyro_noise_rad_s / kDegToRad;
    std::printf("gyro: gx gy gz written, noise %g %g %g deg/s%s\n", c[0], c[1], c[2],
                s.run.latitude_rad ? ", with Earth's rate" : "");
  }
  std::string effects;
  // The effects' parameters: after the base ones, before the gyro block.
  const int effects_end =
      s.truth_layout.has_gyro() ? s.truth_layout.gyro_offset() : s.truth_layout.size();
  for (int i = kNumBaseParams; i < effects_end; ++i) {
    char value[32];
    std::snprintf(value, sizeof(value), "%g", TruthFileValue(s.truth_layout, s.truth, i));
    effects += (effects.empty() ? "" : ", ") + TruthFileKey(s.truth_layout, i) + " = " + value;
  }
  std::printf("effects injected (not declared in run.yaml): %s\n",
              effects.empty() ? "none" : effects.c_str());
  if (s.quantization_mV > 0.0 || s.saturation_low_mV > -1e300 || s.saturation_high_mV < 1e300) {
    std::printf("sensor: quantization %g mV, saturation [%g, %g] mV\n", s.quantization_mV,
                s.saturation_low_mV, s.saturation_high_mV);
  }
  std::printf("wrote %s/run.csv, %s/run.yaml, %s/truth.json\n", dir.c_str(), dir.c_str(),
              dir.c_str());
}

const char* const kSimulationFiles[] = {"run.csv", "run.yaml", "truth.json"};

// Before any work: DIR is a folder (or missing), and each of its three files
// is missing or a regular file; a FIFO, device node, directory or symbolic
// link in their place is never replaced (the files are moved in by rename).
// Notes the three in the session's guard.
void CheckSimulationOutputs(const std::string& dir, const Session& session) {
  namespace fs = std::filesystem;
  if (dir.empty()) throw InputError("-o: empty folder name (give a folder)");
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (fs::exists(st) && !fs::is_directory(st)) {
    throw InputError(dir + ": exists and is not a folder");
  }
  for (const char* name : kSimulationFiles) {
    const fs::path p = fs::path(dir) / name;
    const fs::file_status link = fs::symlink_status(p, ec);
    if (fs::is_symlink(link)) {
      throw InputError(p.string() +
                       ": cannot write: is a symbolic link (simulate moves its files into the "
                       "folder; remove the link or choose another folder)");
    }
    CheckOutputFile(p.string());
    session.NoteOutput(p.string());
  }
}

}  // namespace

Command AddSimulateCommand(CLI::App& app) {
  auto opt = std::make_shared<SimulateOptions>();
  Command c;
  c.app = app.add_subcommand(
      "simulate", "Generate a run with known truth: DIR/run.csv, DIR/run.yaml, DIR/truth.json");
  c.app->add_option("scenario", opt->scenario_path, "SCENARIO.yaml (docs/file-formats.md)")->required();
  c.app->add_option("-o,--out", opt->out_dir, "output folder (created when missing)")->required();
  CLI::Option* seed =
      c.app->add_option("--seed", opt->seed, "noise seed, 0 to 2^64 - 1 (overrides `seed:`)");
  c.run = [opt, seed](Session& session) {
    const std::uint64_t seed_value = seed->count() > 0 ? ParseSeed(opt->seed, "--seed") : 0;
    CheckSimulationOutputs(opt->out_dir, session);
    Scenario s = LoadScenario(opt->scenario_path);
    session.RecordInput("scenario", opt->scenario_path);
    // No output may be an input, --force or not: DIR/run.yaml of `simulate
    // run.yaml -o .` is the scenario itself.
    for (const char* name : kSimulationFiles) {
      const std::string out = (std::filesystem::path(opt->out_dir) / name).string();
      if (session.output_guard) session.output_guard->CheckOutputsAreNotInputs(out);
    }
    CheckSimulationFolder(opt->out_dir, session);
    if (seed->count() > 0) s.seed = seed_value;
    SampleTruth(&s);
    const RunData data = Simulate(s);
    WriteSimulation(s, data, opt->out_dir, session.provenance.Json().dump(),
                    session.write_options());
    PrintSummary(s, data, opt->out_dir);
    return 0;
  };
  return c;
}

}  // namespace triadcal
