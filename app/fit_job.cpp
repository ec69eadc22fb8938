#include "app/fit_job.h"

#include <cstdio>

#include "app/option_lists.h"
#include "core/io/column_mapping.h"
#include "core/model/errors.h"
#include "solvers/diagnosis/residual_analysis.h"
#include "app/residual_plot_json.h"

namespace triadcal {

const char* FitInitName(FitInit init) { return init == FitInit::kRts ? "rts" : "nominal"; }

const char* SigmaMethodName(SigmaMethod sigma) {
  switch (sigma) {
    case SigmaMethod::kWhite:
      return "white";
    case SigmaMethod::kHac:
      return "hac";
    case SigmaMethod::kAuto:
      break;
  }
  return "auto";
}

const char* FitCheckName(FitCheck check) {
  switch (check) {
    case FitCheck::kWhite:
      return "white";
    case FitCheck::kNoise:
      return "noise";
    case FitCheck::kPass:
      return "pass";
    case FitCheck::kConverged:
      break;
  }
  return "converged";
}

FitInit ParseFitInit(const std::string& text) {
  for (FitInit i : {FitInit::kRts, FitInit::kNominal}) {
    if (text == FitInitName(i)) return i;
  }
  throw InputError("--init: expected rts or nominal, got '" + text + "'");
}

SigmaMethod ParseSigmaMethod(const std::string& text) {
  for (SigmaMethod m : {SigmaMethod::kAuto, SigmaMethod::kWhite, SigmaMethod::kHac}) {
    if (text == SigmaMethodName(m)) return m;
  }
  throw InputError("--sigma: expected auto, white or hac, got '" + Excerpt(text, 40) + "'");
}

std::vector<FitCheck> ParseFitChecks(const std::string& list) {
  std::vector<FitCheck> out;
  for (const std::string& req : SplitList(list)) {
    bool known = false;
    for (FitCheck c : {FitCheck::kConverged, FitCheck::kWhite, FitCheck::kNoise, FitCheck::kPass}) {
      if (req == FitCheckName(c)) out.push_back(c), known = true;
    }
    if (!known) {
      throw InputError("--require: unknown check '" + req + "' (converged, white, noise, pass)");
    }
  }
  return out;
}

void FitSettings::Validate() const {
  CheckHoldFree(hold, free, ParameterLayout(ParseEffectList(effects)));
  // The library's own guard for a bad window (a batch or Python caller).
  AngleDerivativeOptions window;
  window.half_window_s = rate_window_s;
  WithFlags({{"half_window_s", "--rate-window-s"}}, [&] { window.Check(); });
  if (threads < 0 || threads > 1024) {
    throw InputError("--threads: Value " + std::to_string(threads) + " not in range 0 to 1024");
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
  // did not converge, and for a required check that failed.
  if (!r.converged) {
    *message =
        run_yaml + ": the fit did not converge (exit " + std::to_string(kExitNotConverged) + ")";
    return kExitNotConverged;
  }
  for (FitCheck req : s.require) {
    const bool ok = req == FitCheck::kConverged ? r.converged
                    : req == FitCheck::kWhite   ? rep.residual_white
                    : req == FitCheck::kNoise   ? rep.noise_consistent
                                                : rep.pass;
    if (!ok) {
      *message = run_yaml + ": --require " + FitCheckName(req) + " failed (exit " +
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
  opt.init = a.init == FitInit::kRts ? BatchInit::kRts : BatchInit::kNominal;
  opt.threads = a.threads;
  opt.sigma = SigmaMethodName(a.sigma);
  opt.holding.auto_hold = a.auto_hold;
  opt.holding.hold = a.hold;
  opt.holding.free = a.free;
  return opt;
}

FitOutcome FitRun(const FitSettings& a, const std::string& run_yaml, const LoadedRun& run,
                  const Session& session) {
  a.Validate();
  FitOutcome f;
  f.layout = ParameterLayout(ParseEffectList(a.effects, run.data),
                             run.description.gyro.has_value() && run.data.has_gyro(),
                             ReadingsUnit(run.description));
  BatchOptions opt = MakeBatchOptions(a);
  opt.progress = session.stage;
  opt.fraction = session.fraction;
  f.result = SolveBatch(run.description, run.data, f.layout, opt);
  if (!f.result.start_note.empty()) {
    f.warnings.push_back(run_yaml + ": " + f.result.start_note);
    if (session.warning) session.warning(f.warnings.back());
  }
  f.report = MakeFitReport(f.layout, f.result);
  f.json = FitJson(f.layout, f.result, f.report, a.correlations);
  f.json["command"] = "fit";
  f.json["run"] = run_yaml;
  f.json["samples"] = run.data.size();
  f.json["settings"]["init"] = FitInitName(a.init);
  f.json["settings"]["effects"] = a.effects;
  // What the residual holds (whiteness, peaks) and, thinned, the residual
  // itself and its spectrum: what the HTML report draws.
  const ResidualReport rr = AnalyzeResiduals(run.description, run.data, f.layout, f.result);
  f.json["residual_analysis"] = ResidualReportJson(rr);
  f.json["residual_plot"] = ResidualPlotJson(rr);
  if (f.result.gyro.present) {
    // The gyro's own: its verdict, and the same analysis and plot of its
    // increment residuals.
    AddGyroAnalysis(run.description, run.data, f.layout, f.result, f.report, &f.json["gyro"]);
  }
  return f;
}

}  // namespace triadcal
