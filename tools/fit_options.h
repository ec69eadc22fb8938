// The options of a fit on the command line (`fit`, `batch`): registered on a
// subcommand as text, turned into the typed settings of the fit job
// (app/fit_job.h) once parsed.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "app/fit_job.h"

namespace triadcal {

struct FitOptions {
  FitSettings settings;  // the numbers and flags, filled by CLI11 directly
  // The options given as text, with the settings' defaults.
  std::string init = FitInitName(FitSettings().init);
  std::string sigma = SigmaMethodName(FitSettings().sigma);
  std::string hold, free, require;
  bool no_auto_hold = false;

  // The typed settings, validated: InputError naming the option for a bad
  // one (--init, --effects, --hold/--free, --rate-window-s, --threads,
  // --require, in this order).
  FitSettings Settings() const;
};

// Registers the fit options shared by `fit` and `batch` on a subcommand
// (not --threads: each command says what its threads are).
void AddFitOptions(CLI::App* app, FitOptions* options);

}  // namespace triadcal
