// `triadcal fit RUN1.yaml RUN2.yaml ... -o OUT.json` and `triadcal fit
// runs.yaml -o OUT.json`: several runs of one IMU as one problem
// (solvers/multirun/, docs/multi-run.md). Loads the runs, solves, writes the
// joint OUT.json and prints the parameters, each run's part and whether the
// runs agree.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/runs_file_io.h"
#include "solvers/multirun/joint_solver.h"
#include "tools/fit_job.h"

namespace triadcal {

// The runs of the command line: one runs file, or several run.yaml.
RunsFile RunsOfCommandLine(const std::vector<std::string>& inputs);

// The runs, loaded (warnings printed), with their temperatures.
std::vector<JointRun> LoadJointRuns(const RunsFile& runs);

JointSpec JointSpecOf(const RunsFile& runs);

// What `fit` and `observability` on several runs start from: the runs (one
// runs file, or several run.yaml), loaded, and their joint unknowns with
// the effects of `effects` (checked against every run's data). Checks that
// out_json can be written before the loading and that it is not another
// input's result after it.
struct JointInput {
  RunsFile file;
  std::vector<JointRun> runs;
  std::unique_ptr<JointLayout> layout;
};
JointInput LoadJointInput(const std::vector<std::string>& inputs, const std::string& effects,
                          const std::string& out_json);

// OUT.json of a joint fit (docs/multi-run.md).
nlohmann::json JointJson(const JointLayout& layout, const std::vector<JointRun>& runs,
                         const JointResult& r, const RunsFile& file);

// The verdict line: converged or not, and which runs disagree.
std::string JointVerdict(const JointLayout& jl, const JointResult& r);

// Runs `fit` on several runs; returns the exit status.
int RunJointFit(const FitSettings& settings, const std::vector<std::string>& inputs,
                const std::string& out_json, const std::string& report_html);

}  // namespace triadcal
