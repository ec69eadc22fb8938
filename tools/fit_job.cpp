#include "tools/fit_job.h"

#include <cstdio>

#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/model/angle_derivatives.h"
#include "core/model/errors.h"
#include "solvers/diagnosis/residual_analysis.h"
#include "tools/report/residual_plot_json.h"

namespace triadcal {

void CheckFitSettings(const FitSettings& s) {
  if (s.init != "rts" && s.init != "nominal") {
    throw InputError("--init: expected rts or nominal, got '" + s.init + "'");
  }
  CheckHoldFree(s.hold, s.free, ParameterLayout(ParseEffectList(s.effects)));
  // The library's own guard for a bad window (a batch or Python caller).
  AngleDerivativeOptions window;
  window.half_window_s = s.rate_window_s;
  WithFlags({{"half_window_s", "--rate-window-s"}}, [&] { window.Check(); });
  if (s.threads < 0 || s.threads > 1024) {
    throw InputError("--threads: Value " + std::to_string(s.threads) + " not in range 0 to 1024");
  }
  for (const std::string& req : SplitList(s.require)) {
    if (req != "converged" && req != "white" && req != "noise" && req != "pass") {
      throw InputError("--require: unknown check '" + req + "' (converged, white, noise, pass)");
    }
  }
}

std::string NoiseWarning(const std::string& run_yaml, const LoadedRun& run, const BatchResult& r) {
  if (r.noise_check.consistent || run.description.noise_auto || r.noise_source != "estimated") {
    return "";
  }
  const Eigen::Vector3d& d = r.noise_declared_mV;
  const Eigen::Vector3d& e = r.noise_check.estimated_mV;
  const Eigen::Vector3d& sd = r.noise_check.sd_mV;
  const std::string unit = ReadingsUnit(run.description);
  char w[600];
  std::snprintf(w, sizeof(w),
                "%s: triad.noise_mV: declared %.3g %.3g %.3g %s, the residuals hold %.3g %.3g "
                "%.3g %s (+- %.2g %.2g %.2g); sigma rest on the estimate (noise_mV: auto says "
                "so)",
                run_yaml.c_str(), d[0], d[1], d[2], unit.c_str(), e[0], e[1], e[2], unit.c_str(),
                sd[0], sd[1], sd[2]);
  return w;
}

int FitExitStatus(const FitSettings& s, const std::string& run_yaml, const BatchResult& r,
                  const FitReport& rep, std::string* message) {
  // Failure must not look like success: a documented status for a fit that
  // did not converge, and for a --require check that failed.
  if (!r.converged) {
    *message = run_yaml + ": the fit did not converge (exit " +
               std::to_string(kExitNotConverged) + ")";
    return kExitNotConverged;
  }
  for (const std::string& req : SplitList(s.require)) {
    const bool ok = req == "converged" ? r.converged
                    : req == "white"   ? rep.residual_white
                    : req == "noise"   ? rep.noise_consistent
                                       : rep.pass;
    if (!ok) {
      *message = run_yaml + ": --require " + req + " failed (exit " +
                 std::to_string(kExitRequirementFailed) + ")";
      return kExitRequirementFailed;
    }
  }
  return 0;
}

BatchOptions MakeBatchOptions(const FitSettings& a) {
  BatchOptions opt;
  opt.epoch_s = a.epoch_s;
  opt.derivatives.half_window_s = a.rate_window_s;
  opt.init = a.init == "rts" ? BatchInit::kRts : BatchInit::kNominal;
  opt.threads = a.threads;
  opt.sigma = a.sigma;
  opt.holding.auto_hold = !a.no_auto_hold;
  opt.holding.hold = SplitList(a.hold);
  opt.holding.free = SplitList(a.free);
  return opt;
}

FitOutcome FitRun(const FitSettings& a, const std::string& run_yaml, const LoadedRun& run,
                  const std::function<void(const std::string&)>& progress,
                  const std::function<void(double)>& fraction) {
  CheckFitSettings(a);
  FitOutcome f;
  f.layout = ParameterLayout(ParseEffectList(a.effects, run.data),
                             run.description.gyro.has_value() && run.data.has_gyro(),
                             ReadingsUnit(run.description));
  BatchOptions opt = MakeBatchOptions(a);
  opt.progress = progress;
  opt.fraction = fraction;
  f.result = SolveBatch(run.description, run.data, f.layout, opt);
  f.report = MakeFitReport(f.layout, f.result);
  f.json = FitJson(f.layout, f.result, f.report, a.correlations);
  f.json["command"] = "fit";
  f.json["run"] = run_yaml;
  f.json["samples"] = run.data.size();
  f.json["settings"]["init"] = a.init;
  f.json["settings"]["effects"] = a.effects;
  // What the residual holds (whiteness, peaks) and, thinned, the residual
  // itself and its spectrum: what the HTML report draws.
  const ResidualReport rr = AnalyzeResiduals(run.description, run.data, f.layout, f.result);
  f.json["residual_analysis"] = ResidualReportJson(rr);
  f.json["residual_plot"] = ResidualPlotJson(rr);
  return f;
}

void AddFitOptions(CLI::App* app, FitSettings* a) {
  app->add_option("--init", a->init, "starting point: rts (EKF+RTS smoother) or nominal")
      ->capture_default_str();
  app->add_option("--effects", a->effects, "catalogue effects to estimate too, e.g. a,b");
  app->add_option("--require", a->require,
                  "checks that must hold, else exit 5: converged, white (residuals), noise "
                  "(declared = estimated), pass (converged and white); e.g. converged,white");
  app->add_option("--sigma", a->sigma,
                  "which covariance gives sigma: auto (HAC when the residuals are not white), "
                  "white (the model's) or hac (sandwich robust to residuals correlated in time)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "white", "hac"}));
  app->add_option("--epoch-s", a->epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  app->add_option("--rate-window-s", a->rate_window_s,
                  "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  app->add_flag("--correlations", a->correlations, "add the correlation matrix to OUT");
  app->add_option("--hold", a->hold, "parameters to hold at their nominal values, e.g. dpsi,Kxy");
  app->add_option("--free", a->free,
                  "parameters to estimate even if the run does not determine them");
  app->add_flag("--no-auto-hold", a->no_auto_hold,
                "estimate every parameter (by default those this run does not determine are "
                "kept at nominal: structural nulls held, the others' prior uncertainty carried "
                "into the estimated parameters' sigma)");
}

}  // namespace triadcal
