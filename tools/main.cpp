// triadcal: calibration of a MEMS accelerometer triad from a two-axis bench run.
#include <exception>
#include <iostream>
#include <vector>

#include <CLI/CLI.hpp>
#include <glog/logging.h>

#include "core/io/file_util.h"
#include "core/model/errors.h"
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
      triadcal::AddMountingCommand(app),
      triadcal::AddInfoCommand(app),
  };

  // Library logs (Ceres through glog) never reach the user: below FATAL they
  // are dropped; what matters comes back as an error or a warning line.
  FLAGS_minloglevel = google::GLOG_FATAL;
  FLAGS_logtostderr = false;

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string command;
    for (const CLI::App* sub : app.get_subcommands()) command = sub->get_name();
    std::cerr << "triadcal: error: " << triadcal::OneLine(e.what()) << " (see `triadcal "
              << (command.empty() ? "" : command + " ") << "--help`)\n";
    return 2;
  }
  triadcal::EnableOutputGuard();  // an output never replaces an input
  try {
    for (const triadcal::Command& c : commands) {
      if (c.app->parsed()) return c.run();
    }
  } catch (const triadcal::InputError& e) {
    std::cerr << "triadcal: error: " << triadcal::OneLine(e.what()) << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "triadcal: internal error: " << triadcal::OneLine(e.what()) << "\n";
    return 3;
  }
  return 1;
}
