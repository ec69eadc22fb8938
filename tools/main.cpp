// triadcal: calibration of a MEMS accelerometer triad from a two-axis bench run.
#include <exception>
#include <iostream>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/model/errors.h"
#include "tools/command_util.h"
#include "tools/commands.h"

int main(int argc, char** argv) {
  CLI::App app{
      "triadcal: calibrate a MEMS accelerometer triad from a quasi-harmonic two-axis bench run"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "triadcal 0.1.0");

  std::vector<triadcal::Command> commands = {
      triadcal::AddSimulateCommand(app),
      triadcal::AddFilterCommand(app),
      triadcal::AddFitCommand(app),
      triadcal::AddCompareCommand(app),
      triadcal::AddDiagnoseCommand(app),
      triadcal::AddStaticCommand(app),
      triadcal::AddApplyCommand(app),
      triadcal::AddObservabilityCommand(app),
      triadcal::AddDesignCommand(app),
      triadcal::AddMonteCarloCommand(app),
      triadcal::AddInfoCommand(app),
      triadcal::AddReportCommand(app),
  };

  bool quiet = false;
  for (const triadcal::Command& c : commands) {
    c.app->add_flag("-q,--quiet", quiet, "no progress lines on stderr");
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    for (const triadcal::Command& c : commands) {
      if (c.app->parsed()) {
        triadcal::SetQuiet(quiet);
        return c.run();
      }
    }
  } catch (const triadcal::InputError& e) {
    std::cerr << "triadcal: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "triadcal: internal error: " << e.what() << "\n";
    return 3;
  }
  return 1;
}
