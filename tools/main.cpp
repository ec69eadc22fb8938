// triadcal: calibration of a MEMS accelerometer triad from a two-axis bench run.
#include <algorithm>
#include <exception>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glog/logging.h>
#include <malloc.h>

#include "core/io/data_table.h"
#include "core/io/file_util.h"
#include "core/io/temporary_files.h"
#include "core/model/errors.h"
#include "core/version/version.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "app/provenance.h"
#include "app/session.h"
#include "tools/distribution/mpi_context.h"

namespace {

// The process's temporaries being written (core/io/temporary_files.h): every
// command's writes register theirs here (Session::temporaries), and the
// handler removes them on SIGINT, SIGTERM or SIGHUP before the signal takes
// its default course. Static storage: the handler may run at any time.
triadcal::TemporaryFiles g_temporaries;

extern "C" void RemoveTemporariesAndReraise(int sig) {
  g_temporaries.UnlinkAll();
  triadcal::ReraiseWithDefaultAction(sig);
}

// The last guard on what an error echoes: the readers quote at most short
// excerpts of their input (errors.h Excerpt), and no error line is longer than
// this; a longer one keeps its start (the file and key) and its end (what is
// wrong).
std::string Bounded(const std::string& line) {
  constexpr std::size_t kMax = 2000;
  if (line.size() <= kMax) return line;
  return line.substr(0, 1200) + " ... " + line.substr(line.size() - 600);
}

// Levenshtein distance (insertions, deletions, substitutions).
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

int main(int argc, char** argv) {
  // Two malloc arenas, not glibc's eight per core: a pass's blocks are made
  // on the worker threads and freed on the main one, and each arena kept its
  // share, so the peak grew with the threads (`bench/solver_speed.py
  // --threads 8`: the 40-min 1-kHz fit's peak 203 MB, 191 MB with two
  // arenas, in the same time).
  mallopt(M_ARENA_MAX, 2);
  // MPI only under an MPI launcher (tools/distribution/mpi_context.h).
  triadcal::MpiSession mpi(&argc, &argv);
  CLI::App app{
      "triadcal: calibrate a MEMS accelerometer triad from a quasi-harmonic two-axis bench run"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("triadcal ") + triadcal::ToolVersion());

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
      triadcal::AddExportCommand(app),
      triadcal::AddBatchCommand(app),
      triadcal::AddMergeCommand(app),
      triadcal::AddReportCommand(app),
  };

  // Library logs (Ceres through glog) never reach the user: below FATAL they
  // are dropped; what matters comes back as an error or a warning line.
  FLAGS_minloglevel = google::GLOG_FATAL;
  FLAGS_logtostderr = false;
  // Nor do matio's and HDF5's (a damaged v7.3 file): the reader's error says
  // what is wrong, on one line.
  triadcal::SilenceMatioDiagnostics();

  // What every command runs in: the provenance of its outputs (this binary,
  // this command line), --force, the process's temporaries, and its warnings
  // on stderr.
  triadcal::Session session;
  session.temporaries = &g_temporaries;
  triadcal::InstallTerminationHandler(&RemoveTemporariesAndReraise);
  session.provenance = triadcal::Provenance(triadcal::ToolVersion(), triadcal::ToolGitCommit(),
                                            triadcal::CommandLineOf(argc, argv));
  session.warning = [](const std::string& w) {
    std::cerr << "triadcal: warning: " << triadcal::OneLine(w) << "\n";
  };
  bool quiet = false;
  for (const triadcal::Command& c : commands) {
    c.app->add_flag("--force", session.force, "replace outputs that hold results of other inputs");
    c.app->add_flag("-q,--quiet", quiet, "no progress lines on stderr");
  }
  // An unknown command is named, with the nearest one (CLI11 says only
  // "A subcommand is required" for `triadcal fitt`).
  if (argc >= 2 && argv[1][0] != '-') {
    const std::string word = argv[1];
    std::string nearest;
    std::size_t best = std::string::npos;
    bool known = false;
    for (const triadcal::Command& c : commands) {
      const std::string& name = c.app->get_name();
      known = known || name == word;
      const std::size_t d = EditDistance(word, name);
      if (d < best) best = d, nearest = name;
    }
    if (!known) {
      std::cerr << "triadcal: error: unknown command '" << Bounded(triadcal::OneLine(word)) << "'"
                << (best <= 2 ? " (did you mean '" + nearest + "'?)" : std::string())
                << " (see `triadcal --help`)\n";
      return 2;
    }
  }
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
    std::cerr << "triadcal: error: " << Bounded(triadcal::OneLine(e.what())) << " (see `triadcal "
              << (command.empty() ? "" : command + " ") << "--help`)\n";
    return 2;
  }
  // An output never replaces an input: the jobs note the files they load
  // into the session's guard, and every write checks it.
  session.output_guard = std::make_shared<triadcal::OutputGuard>();
  try {
    for (const triadcal::Command& c : commands) {
      if (!c.app->parsed()) continue;
      // Under mpirun only montecarlo and batch share out their work; any
      // other command runs once, on rank 0.
      const std::string name = c.app->get_name();
      if (!triadcal::MpiRoot() && name != "montecarlo" && name != "batch") return 0;
      triadcal::SetQuiet(quiet);
      return c.run(session);
    }
  } catch (const triadcal::OptionError& e) {
    // A setting the estimators rejected, named by its flag here.
    static const std::map<std::string, std::string> kFlags = {{"epoch_s", "--epoch-s"},
                                                              {"hold_free", "--hold/--free"},
                                                              {"effects", "--effects"},
                                                              {"sigma", "--sigma"},
                                                              {"hold", "--hold"},
                                                              {"free", "--free"},
                                                              {"half_window_s", "--rate-window-s"}};
    const auto it = kFlags.find(e.option());
    if (triadcal::MpiRoot()) {
      std::cerr << "triadcal: error: "
                << Bounded(triadcal::OneLine(it == kFlags.end() ? std::string(e.what())
                                                                : it->second + ": " + e.problem()))
                << "\n";
    }
    return 2;
  } catch (const triadcal::InputError& e) {
    // Every rank reads the same input and fails the same way: rank 0 says so.
    if (triadcal::MpiRoot()) {
      std::cerr << "triadcal: error: " << Bounded(triadcal::OneLine(e.what())) << "\n";
    }
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "triadcal: internal error: " << Bounded(triadcal::OneLine(e.what())) << "\n";
    triadcal::MpiAbortIfShared(3);  // other ranks may wait for this one
    return 3;
  }
  return 1;
}
