// Provenance of every output: which tool (version, git commit), when (UTC),
// how (the command line) and from what (SHA-256 of every input file, and the
// sensor named in run.yaml). Every OUT file carries it under "provenance":
//
//   "provenance": {
//     "tool": "triadcal", "version": "0.1.0", "git_commit": "3f2c...",
//     "date_utc": "2026-11-23T08:01:02Z",
//     "command_line": "triadcal fit run.yaml -o fit.json",
//     "inputs": [{"role": "run", "path": "/abs/run.yaml", "sha256": "..."}, ...],
//     "sensor": {"serial": "0042", "model": "ADXL325"}       (when run.yaml has it)
//   }
//
// A value: each job's Session (app/session.h) holds one; the loaders record
// their inputs into it as they read them (app/run_loading.h), the writers
// stamp it and the output guard (app/output_guard.h) compares it with what an
// existing output holds.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace triadcal {

class Provenance {
 public:
  Provenance() = default;
  // The tool's version and git commit, and the command line (may be empty).
  Provenance(std::string version, std::string git_commit, std::string command_line);

  // Records an input file: its role ("run", "data", "calibration", "scenario"),
  // its absolute path and its SHA-256 (read now: what the command used). An
  // input recorded twice (same role and path) is kept once.
  void RecordInput(const std::string& role, const std::string& path);
  // The same with the file's SHA-256 taken by the caller (while it read it).
  void RecordInput(const std::string& role, const std::string& path, const std::string& sha256);
  // The sensor of run.yaml's `sensor:` key (empty strings: not given).
  void RecordSensor(const std::string& serial, const std::string& model);

  // The inputs recorded so far: [{"role", "path", "sha256"}, ...].
  const nlohmann::json& inputs() const { return inputs_; }

  // The provenance of what has been read so far, dated now. Text outputs
  // carry it on one comment line "# provenance: {...}" (CSV, YAML) or
  // " * provenance: {...}" (C), within their first 40 lines.
  nlohmann::json Json() const;

 private:
  std::string version_ = "unknown", git_commit_ = "unknown", command_line_;
  nlohmann::json inputs_ = nlohmann::json::array();
  std::string sensor_serial_, sensor_model_;
};

// argv as one shell line (argv[0] by its file name; words quoted when they
// hold anything but safe characters), for the provenance's command line.
std::string CommandLineOf(int argc, char** argv);

}  // namespace triadcal
