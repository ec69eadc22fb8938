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
// The loaders of the commands record their inputs here as they read them
// (RecordInput); the writers stamp the provenance and refuse to replace an
// output of other inputs (CheckOverwrite) unless the command got --force.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace triadcal {

// The command line of this process, for the provenance (main() calls it once).
void SetCommandLine(int argc, char** argv);

// The --force flag of every command: replace outputs of other inputs.
bool& ForceOverwrite();

// Records an input file: its role ("run", "data", "calibration", "scenario"),
// its absolute path and its SHA-256 (read now: what the command used).
void RecordInput(const std::string& role, const std::string& path);
// The sensor of run.yaml's `sensor:` key (empty strings: not given).
void RecordSensor(const std::string& serial, const std::string& model);

// The provenance of what this process has read so far. Text outputs carry it
// on one comment line "# provenance: {...}" (CSV, YAML) or " * provenance:
// {...}" (C), within their first 40 lines.
nlohmann::json CurrentProvenance();

// Before writing OUT: when OUT exists and its provenance names other inputs
// (other roles or paths), or it has none (it is not a triadcal output), throws
// InputError("OUT: holds results of other inputs (...); --force overwrites
// it") unless --force. Outputs of the same inputs are replaced silently.
// OUT must be missing or a regular file (or a link to one), with --force too
// (file_util.h CheckOutputFile); the stored provenance is looked for in the
// first and last megabyte of OUT only (WriteJson puts it first).
void CheckOverwrite(const std::string& out_path);

// The same for simulate's folder: a non-empty DIR holding results (run.csv,
// run.yaml, truth.json, or any JSON with a provenance) that do not come from
// the same scenario file is refused unless --force.
void CheckSimulationFolder(const std::string& dir);

// The tool version and the git commit the binary was built from ("unknown"
// outside a git checkout; "-dirty" appended when it had local changes).
const char* ToolVersion();
const char* ToolGitCommit();

}  // namespace triadcal
