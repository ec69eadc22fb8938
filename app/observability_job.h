// `triadcal observability`: the Cramer-Rao sigma per parameter and the
// directions a run cannot determine, with and without its constraints
// (solvers/estimation/observability.h), of one run, of a scenario's profile,
// or of several runs together; the settings, the analysis and the OUT.json.
// The command prints it (tools/report/observability_report.h).
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "app/joint_fit_job.h"
#include "app/session.h"
#include "core/model/angle_derivatives.h"
#include "core/model/parameters.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/diagnosis/effect_discovery.h"
#include "solvers/estimation/observability.h"
#include "solvers/multirun/joint_solver.h"

namespace triadcal {

// The settings of `observability`, each default declared here once.
struct ObservabilitySettings {
  std::string effects;  // catalogue effects to include, "a,b"
  // Evaluate at these parameters (a fit/filter OUT or a truth.json) instead
  // of the nominal values (run) or the truth (scenario); empty: those.
  std::string at;
  double epoch_s = kDefaultEpoch_s;                               // [s]
  double rate_window_s = AngleDerivativeOptions().half_window_s;  // [s]
  // Information along a direction, in prior units, below which it is
  // unobservable, and below which weakly observable.
  double unobservable_below = ObservabilityThresholds{}.unobservable;
  double weak_below = ObservabilityThresholds{}.weak;
  int threads = 0;  // 0: all cores
  // A scenario only: the catalogue effects that could go undetected on its
  // profile (as diagnose's could_hide), at this false-selection rate.
  bool could_hide = false;
  double alpha = DiagnoseOptions().alpha;

  // Throws InputError naming the option (as the command line's flag).
  void Validate() const;
};

// What is analysed: a recorded run at its noise (the readings' own with
// noise_mV: auto, as `fit` starts from), or a scenario's profile simulated
// without noise (its declared noise kept), with the point of evaluation.
struct ObservabilityInput {
  std::string path;
  bool scenario = false;
  RunDescription run;
  RunData data;
  ParameterLayout layout;   // units named for the readings; the gyro's with a gyro block
  Eigen::VectorXd theta;    // nominal (run) or truth (scenario)
  bool noise_auto = false;  // run.yaml said noise_mV: auto
};

// Whether `path` is a SCENARIO.yaml (it has a `profile` key).
bool IsScenarioFile(const std::string& path);

// Loads a RUN.yaml or SCENARIO.yaml, recorded in the session's provenance.
// threads: the job's (LoadRun).
ObservabilityInput LoadObservabilityInput(const std::string& path, const std::string& effects,
                                          Session* session, int threads = 0);

struct ObservabilityOutcome {
  ObservabilityResult result;
  std::string source;  // "run" or "scenario (simulated without noise)"
  std::string at;      // "nominal", "truth" or the --at file
  std::vector<HideCase> could_hide;
  nlohmann::json json;  // OUT.json (without the provenance)
};

// Validates the settings and analyses `in`; stages go to the session.
ObservabilityOutcome ObservabilityRun(const ObservabilitySettings& s, const ObservabilityInput& in,
                                      const Session& session);

struct JointObservabilityOutcome {
  JointInformation info;
  nlohmann::json json;  // OUT.json of the runs together (without the provenance)
};

// Several runs together (`in` loaded with s.effects) at the nominal values,
// as `fit` on several runs poses the problem (docs/multi-run.md); each run at
// its noise: with noise_mV: auto the readings' own, set in in->runs
// (WithReadingNoise). --at is not available for several runs (InputError).
JointObservabilityOutcome JointObservabilityRun(const ObservabilitySettings& s, JointInput* in,
                                                const Session& session);

// The parts of OUT (docs/file-formats.md): a direction, a set of
// constraints, the whole analysis (without the command's settings); and
// the parameters in a variant's unobservable directions.
nlohmann::json DirectionJson(const ParameterLayout& layout, const Direction& d);
nlohmann::json VariantJson(const ParameterLayout& layout, const ObservabilityVariant& v);
nlohmann::json ObservabilityJson(const ObservabilityResult& r);
std::set<std::string> UnobservableNames(const ObservabilityVariant& v);

}  // namespace triadcal
