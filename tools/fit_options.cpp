#include "tools/fit_options.h"

#include "app/option_lists.h"
#include "tools/command_util.h"

namespace triadcal {

FitSettings FitOptions::Settings() const {
  FitSettings s = settings;
  s.init = ParseFitInit(init);
  s.sigma = ParseSigmaMethod(sigma);
  s.hold = SplitList(hold);
  s.free = SplitList(free);
  s.auto_hold = !no_auto_hold;
  s.Validate();
  s.require = ParseFitChecks(require);
  return s;
}

void AddFitOptions(CLI::App* app, FitOptions* a) {
  FitSettings& s = a->settings;
  app->add_option("--init", a->init, "starting point: rts (EKF+RTS smoother) or nominal")
      ->capture_default_str();
  app->add_option("--effects", s.effects, "catalogue effects to estimate too, e.g. a,b");
  app->add_option("--require", a->require,
                  "checks that must hold, else exit 5: converged, white (residuals), noise "
                  "(declared = estimated), pass (converged and white); e.g. converged,white");
  app->add_option("--sigma", a->sigma,
                  "which covariance gives sigma: auto (HAC when the residuals are not white), "
                  "white (the model's) or hac (sandwich robust to residuals correlated in time)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "white", "hac"}));
  app->add_option("--epoch-s", s.epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  app->add_option("--rate-window-s", s.rate_window_s,
                  "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  app->add_flag("--correlations", s.correlations, "add the correlation matrix to OUT");
  app->add_option("--hold", a->hold, "parameters to hold at their nominal values, e.g. dpsi,Kxy");
  app->add_option("--free", a->free,
                  "parameters to estimate even if the run does not determine them");
  app->add_flag("--no-auto-hold", a->no_auto_hold,
                "estimate every parameter (by default those this run does not determine are "
                "kept at nominal: structural nulls held, the others' prior uncertainty carried "
                "into the estimated parameters' sigma)");
}

}  // namespace triadcal
