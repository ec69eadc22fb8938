// `triadcal fit RUN1.yaml RUN2.yaml ... -o OUT.json` and `triadcal fit
// runs.yaml -o OUT.json`: several runs of one IMU as one problem
// (solvers/multirun/, docs/multi-run.md). Loads the runs, solves, and gives
// the joint OUT.json (the command prints it: tools/cmd_fit_joint.cpp).
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/fit_job.h"
#include "app/session.h"
#include "core/io/runs_file_io.h"
#include "solvers/multirun/joint_solver.h"

namespace triadcal {

// The runs of the command line: one runs file, or several run.yaml.
RunsFile RunsOfCommandLine(const std::vector<std::string>& inputs);

// The runs, loaded (their warnings said through session->warning), with
// their temperatures; each recorded in the provenance as "run NAME".
// threads: the job's (LoadRun).
std::vector<JointRun> LoadJointRuns(const RunsFile& runs, Session* session, int threads = 0);

JointSpec JointSpecOf(const RunsFile& runs);

// What `fit` and `observability` on several runs start from: the runs (one
// runs file, or several run.yaml), loaded, and their joint unknowns with
// the effects of `effects` (checked against every run's data). The units
// follow the first run's readings.
// The runs that carry a gyro (a gyro block and its columns) are named in
// gyro_not_calibrated: the joint problem holds the accelerometer triad only,
// and loading says so (a warning); each such run calibrates its gyro alone.
struct JointInput {
  RunsFile file;
  std::vector<JointRun> runs;
  std::unique_ptr<JointLayout> layout;
  std::vector<std::string> gyro_not_calibrated;
};
JointInput LoadJointInput(const std::vector<std::string>& inputs, const std::string& effects,
                          Session* session, int threads = 0);

// The OUT key of a joint fit or observability: the runs whose gyro the joint
// problem leaves out, and why (an empty array: none carries one).
nlohmann::json GyroNotCalibratedJson(const std::vector<std::string>& runs);

// OUT.json of a joint fit (docs/multi-run.md).
nlohmann::json JointJson(const JointLayout& layout, const JointInput& in, const JointResult& r);

// The verdict line: converged or not, and which runs disagree.
std::string JointVerdict(const JointLayout& jl, const JointResult& r);

// What the joint fit did with an unknown.
enum class Treatment { kEstimated, kConsidered, kHeld };
std::vector<Treatment> TreatmentOf(const JointResult& r, int unknowns);

struct JointFitOutcome {
  JointResult result;
  nlohmann::json json;  // OUT.json of the joint fit (without the provenance)
};

// Fits the runs of `in` as one problem with the settings of `fit` (its
// effects are those `in` was loaded with); progress goes to the session.
JointFitOutcome JointFitRun(const FitSettings& s, const JointInput& in, const Session& session);

}  // namespace triadcal
