// The manifest of `triadcal batch`: which runs to fit, the serial of the unit
// each one calibrates, and its acceptance limits.
//
// CSV (a header line, then one run a line; `#` lines are comments; an empty
// cell is "no limit"):
//
//   serial,run,diagnose,Kx_min,Kx_max,W0x_sigma_max
//   A001,A001/run.yaml,false,165,185,0.5
//
// YAML (`limits` and `diagnose` at the top are every run's defaults; a run's
// own limit on a parameter replaces the default one for that parameter):
//
//   limits: {Kx: {min: 165, max: 185}, W0x: {sigma_max: 0.5}}
//   diagnose: false
//   runs:
//     - {serial: A001, run: A001/run.yaml}
//     - {serial: A002, run: A002/run.yaml, diagnose: true, limits: {Kx: {max: 180}}}
//
// Limits are in the units the fit gives each parameter (SPEC section 3: mV/g,
// mV, arcmin, 1/g, mm for readings in mV; counts/g, counts for readings in
// counts: the readings' unit; effect parameters by their `effect.param` name). `run` paths are relative to
// the manifest (or `shared:`, core/io/file_util.h). A serial becomes a folder
// name: letters, digits, '.', '_' and '-' only.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace triadcal {

struct ParameterLimit {
  std::string parameter;
  std::optional<double> min, max, sigma_max;  // in the unit the fit gives the parameter
};

struct ManifestEntry {
  std::string serial;
  std::string run;       // as written in the manifest
  std::string run_path;  // resolved
  bool diagnose = false;
  std::vector<ParameterLimit> limits;
};

// Reads a .csv or .yaml/.yml manifest; throws InputError
// ("MANIFEST[:LINE]: key: what is wrong") on a malformed one. Missing or bad
// run files are not the manifest's errors: each run fails on its own.
std::vector<ManifestEntry> LoadManifest(const std::string& path);

}  // namespace triadcal
