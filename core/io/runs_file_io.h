// The runs file: several runs of one IMU fitted as one problem
// (docs/multi-run.md). `triadcal fit runs.yaml -o OUT.json`.
//
//   runs:
//     - {run: slow.yaml, name: slow, temperature_C: 21}   # name, temperature optional
//     - {run: ../pitch/pitch.yaml}
//   per_run: [W0x, W0y, W0z, mounting]   # triad parameters each run has its own of
//   shared: [dx2, dy2, dz2]              # set-up parameters all runs share
//   temperature: {reference_C: 20, degree: {W0x: 1, Kx: 1}}
//
// Run files are relative to the runs file. A run's name defaults to its
// file's stem, or its folder's name for a file named run.yaml.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace triadcal {

struct RunsFile {
  std::string path;  // the runs file, or "" for runs listed on the command line
  struct Entry {
    std::string run_yaml;  // resolved
    std::string name;
    std::optional<double> temperature_C;
    std::string where;     // "runs.yaml: runs[1]" or "command line: run 2", for messages
  };
  std::vector<Entry> runs;
  std::vector<std::string> per_run, shared;
  std::map<std::string, int> temperature_degree;
  double temperature_ref_C = 20.0;
};

// True when the YAML file is a map with a `runs` key (a runs file, not a
// run); false for a file that cannot be read (the run reader says why).
bool IsRunsFile(const std::string& yaml_path);

// Throws InputError "FILE: key: what is wrong" (a run listed twice, two runs of
// one name, unknown keys, a degree that is not 1-3, ...).
RunsFile LoadRunsFile(const std::string& path);

// The runs of the command line (`fit a.yaml b.yaml`), named as in a runs file.
RunsFile RunsFromCommandLine(const std::vector<std::string>& run_yamls);

}  // namespace triadcal
