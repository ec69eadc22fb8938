#include "tools/fit_job.h"

#include <cstdio>

#include "core/model/errors.h"
#include "solvers/diagnosis/residual_analysis.h"
#include "tools/report/residual_plot_json.h"

namespace triadcal {

void CheckFitSettings(const FitSettings& s) {
  if (s.init != "rts" && s.init != "nominal") {
    throw InputError("--init: expected rts or nominal, got '" + s.init + "'");
  }
  ParseEffectList(s.effects);
  for (const std::string& req : SplitList(s.require)) {
    if (req != "converged" && req != "white" && req != "noise" && req != "pass") {
      throw InputError("--require: unknown check '" + req + "' (converged, white, noise, pass)");
    }
  }
}

std::string NoiseWarning(const std::string& run_yaml, const LoadedRun& run, const BatchResult& r) {
  if (r.noise_check.consistent || run.description.noise_auto) return "";
  const Eigen::Vector3d& d = r.noise_declared_mV;
  const Eigen::Vector3d& e = r.noise_check.estimated_mV;
  const Eigen::Vector3d& sd = r.noise_check.sd_mV;
  char w[600];
  if (!r.noise_check.PerChannel()) {
    std::snprintf(w, sizeof(w),
                  "%s: triad.noise_mV: declared %.3g %.3g %.3g mV, chi2/dof %.3g; per channel the "
                  "residuals hold %.3g %.3g %.3g mV with worst lag-1 %.2f, too unequal or not "
                  "white to be noise alone: %s (run diagnose to find what the model lacks)",
                  run_yaml.c_str(), d[0], d[1], d[2], r.chi2_per_dof, e[0], e[1], e[2],
                  r.noise_check.lag1.cwiseAbs().maxCoeff(),
                  r.sigma_method != "hac"          ? "sigma scaled by chi2/dof"
                  : r.hac_floor == "per_channel_bound"
                      ? "sigma from the HAC covariance, at least the bound of each channel's noise"
                      : "sigma from the HAC covariance, at least the model's scaled by chi2/dof");
    return w;
  }
  std::snprintf(w, sizeof(w),
                "%s: triad.noise_mV: declared %.3g %.3g %.3g mV, the residuals hold %.3g %.3g "
                "%.3g mV (+- %.2g %.2g %.2g); sigma use the estimate (say noise_mV: auto to "
                "silence this)",
                run_yaml.c_str(), d[0], d[1], d[2], e[0], e[1], e[2], sd[0], sd[1], sd[2]);
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
  opt.linear_solver = a.linear_solver;
  opt.robust_loss = a.robust;
  opt.robust_scale = a.robust_scale;
  opt.threads = a.threads;
  opt.covariance_method = a.covariance;
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
  f.layout = ParameterLayout(ParseEffectList(a.effects, run.data));
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
  f.json["settings"]["robust_loss"] = a.robust.empty() ? "none" : a.robust;
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
  app->add_option("--robust", a->robust, "robust loss on whitened residuals: huber or cauchy");
  app->add_option("--robust-scale", a->robust_scale, "robust loss scale [whitened units]")
      ->capture_default_str();
  app->add_option("--linear-solver", a->linear_solver,
                  "sparse_normal_cholesky (SuiteSparse), sparse_schur or dense_qr")
      ->capture_default_str();
  app->add_option("--covariance", a->covariance,
                  "schur (Schur complement on theta) or ceres (SuiteSparse QR)")
      ->capture_default_str();
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
      ->capture_default_str();
  app->add_flag("--correlations", a->correlations, "add the correlation matrix to OUT");
  app->add_option("--hold", a->hold, "parameters to hold at their nominal values, e.g. dpsi,Kxy");
  app->add_option("--free", a->free,
                  "parameters to estimate even if the run barely supports them, and never pin");
  app->add_flag("--no-auto-hold", a->no_auto_hold,
                "estimate every parameter (by default those the run's motion does not support "
                "are held at nominal, and weakly determined ones that a first fit moves beyond 3 "
                "prior sigma are pinned there and the run refitted)");
}

}  // namespace triadcal
