// `triadcal compare RUN.yaml`: the filter job (EKF and RTS smoother) and the
// batch solution of the same run side by side, the batch started at the
// smoother's answer under the same hold decision, with their differences in
// units of the batch sigma. The command prints it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "app/filter_job.h"
#include "app/fit_report.h"
#include "app/run_loading.h"
#include "app/session.h"

namespace triadcal {

// The settings of `compare`, each default declared here once.
struct CompareSettings {
  std::string effects;               // catalogue effects to estimate too, "a,b"
  double epoch_s = kDefaultEpoch_s;  // [s]

  // Throws InputError naming the option (as the command line's flag).
  void Validate() const;
};

struct CompareOutcome {
  FilterOutcome filter;  // its layout and decision are the batch's
  BatchResult batch;     // started at filter.result.rts
  FitReport report;      // of the batch
  double filter_s = 0.0, fit_s = 0.0;
  // Not empty when the filter diverged (no batch, json null).
  std::string error;
  nlohmann::json json;  // OUT.json of `compare` (without the provenance)
};

// Validates the settings and runs both on `run` (read from run_yaml);
// progress: "filter pass 1/2" for the first half, "fit STAGE" the second.
CompareOutcome CompareRun(const CompareSettings& s, const std::string& run_yaml,
                          const LoadedRun& run, const Session& session);

}  // namespace triadcal
