// The subcommands of `triadcal`. Each Add* registers its options on the app and
// returns the action to run when the subcommand was chosen, in the session
// main() makes (app/session.h: provenance, --force, warnings). Actions throw
// InputError for bad input; main() turns that into one line on stderr and a
// non-zero exit.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

#include "app/session.h"

namespace triadcal {

struct Command {
  CLI::App* app = nullptr;
  std::function<int(Session&)> run;
};

Command AddSimulateCommand(CLI::App& app);
Command AddInfoCommand(CLI::App& app);
Command AddFilterCommand(CLI::App& app);
Command AddFitCommand(CLI::App& app);
Command AddCompareCommand(CLI::App& app);
Command AddDiagnoseCommand(CLI::App& app);
Command AddStaticCommand(CLI::App& app);  // standard static method (cmd_static.cpp)
Command AddApplyCommand(CLI::App& app);   // calibration -> specific force (cmd_apply.cpp)
Command AddObservabilityCommand(CLI::App& app);  // CRB, unobservable directions (cmd_observability.cpp)
Command AddDesignCommand(CLI::App& app);  // experiment design from the CRB (cmd_design.cpp)
Command AddMonteCarloCommand(CLI::App& app);  // Monte Carlo against the CRB (cmd_montecarlo.cpp)
Command AddExportCommand(CLI::App& app);  // calibration -> C99 code or matrices (cmd_export.cpp)
Command AddBatchCommand(CLI::App& app);  // a manifest of runs, filed by serial (cmd_batch.cpp)
Command AddMergeCommand(CLI::App& app);  // shards of montecarlo/batch -> one output (cmd_merge.cpp)
Command AddReportCommand(CLI::App& app);  // HTML report from OUT files (cmd_report.cpp)
Command AddMountingCommand(CLI::App& app);  // mounting and zeros from the data (cmd_mounting.cpp)

}  // namespace triadcal
