// The subcommands of `triadcal`. Each Add* registers its options on the app and
// returns the action to run when the subcommand was chosen. Actions throw
// InputError for bad input; main() turns that into one line on stderr and a
// non-zero exit.
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace triadcal {

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Command AddSimulateCommand(CLI::App& app);
Command AddInfoCommand(CLI::App& app);
Command AddFilterCommand(CLI::App& app);
Command AddFitCommand(CLI::App& app);
Command AddCompareCommand(CLI::App& app);

}  // namespace triadcal
