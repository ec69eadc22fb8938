// `triadcal fit RUN.yaml -o OUT.json`: the batch solution (solvers/estimation/batch_solver.h).
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <sstream>

#include "core/model/errors.h"
#include "core/io/file_util.h"
#include "solvers/estimation/batch_solver.h"
#include "tools/report/estimate_json.h"
#include "solvers/estimation/separability.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/fit_report.h"

namespace triadcal {
namespace {

struct FitArgs {
  std::string run_yaml, out_json, residuals_csv, effects, init = "rts", robust;
  std::string linear_solver = "sparse_normal_cholesky";
  std::string covariance = "schur";
  double epoch_s = 0.5, rate_window_s = 0.1, robust_scale = 3.0;
  int threads = 0;
  bool correlations = false, no_auto_hold = false;
  std::string hold, free;
};

int RunFit(const FitArgs& a) {
  if (a.init != "rts" && a.init != "nominal") {
    throw InputError("--init: expected rts or nominal, got '" + a.init + "'");
  }
  CheckOutputPath(a.out_json);
  if (!a.residuals_csv.empty()) CheckOutputPath(a.residuals_csv);
  const LoadedRun run = LoadRunOrThrow(a.run_yaml);
  const ParameterLayout layout(ParseEffectList(a.effects));
  BatchOptions opt;
  opt.epoch_s = a.epoch_s;
  opt.derivatives.half_window_s = a.rate_window_s;
  opt.init = a.init == "rts" ? BatchInit::kRts : BatchInit::kNominal;
  opt.linear_solver = a.linear_solver;
  opt.robust_loss = a.robust;
  opt.robust_scale = a.robust_scale;
  opt.threads = a.threads;
  opt.covariance_method = a.covariance;
  opt.holding.auto_hold = !a.no_auto_hold;
  opt.holding.hold = SplitList(a.hold);
  opt.holding.free = SplitList(a.free);
  opt.progress = [](const std::string& s) { ShowProgress("fit: " + s, 0.0); };
  const BatchResult r = SolveBatch(run.description, run.data, layout, opt);
  EndProgress();

  const FitReport rep = MakeFitReport(layout, r);
  nlohmann::json out = FitJson(layout, r, rep, a.correlations);
  out["command"] = "fit";
  out["run"] = a.run_yaml;
  out["samples"] = run.data.size();
  out["settings"]["init"] = a.init;
  out["settings"]["effects"] = a.effects;
  out["settings"]["robust_loss"] = a.robust.empty() ? "none" : a.robust;
  WriteJson(out, a.out_json);
  if (!a.residuals_csv.empty()) WriteFileAtomically(a.residuals_csv, ResidualsCsv(r));

  std::printf("fit: %zu samples, %d epochs, %s\n", run.data.size(), r.epochs,
              rep.verdict.c_str());
  PrintParameterTable(layout, r, rep);
  std::printf("residual RMS: measurement V %.3g %.3g %.3g m/s, S %.3g %.3g %.3g m; whitened %.3f\n",
              r.residuals.measurement_rms[0], r.residuals.measurement_rms[1],
              r.residuals.measurement_rms[2], r.residuals.measurement_rms[3],
              r.residuals.measurement_rms[4], r.residuals.measurement_rms[5],
              r.residuals.measurement_whitened_rms);
  std::printf("              process V %.3g %.3g %.3g m/s, S %.3g %.3g %.3g m; whitened %.3f\n",
              r.residuals.process_rms[0], r.residuals.process_rms[1], r.residuals.process_rms[2],
              r.residuals.process_rms[3], r.residuals.process_rms[4], r.residuals.process_rms[5],
              r.residuals.process_whitened_rms);
  std::printf("time: init %.2f s, solve %.2f s, covariance %.2f s\n", r.init_seconds,
              r.solve_seconds, r.covariance_seconds);
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddFitCommand(CLI::App& app) {
  auto a = std::make_shared<FitArgs>();
  Command c;
  c.app = app.add_subcommand("fit", "Batch least-squares solution of the whole run (Ceres)");
  c.app->add_option("run", a->run_yaml, "run description (run.yaml)")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--init", a->init, "starting point: rts (EKF+RTS smoother) or nominal")
      ->capture_default_str();
  c.app->add_option("--effects", a->effects, "catalogue effects to estimate too, e.g. a,b");
  c.app->add_option("--robust", a->robust, "robust loss on whitened residuals: huber or cauchy");
  c.app->add_option("--robust-scale", a->robust_scale, "robust loss scale [whitened units]")
      ->capture_default_str();
  c.app->add_option("--linear-solver", a->linear_solver,
                    "sparse_normal_cholesky (SuiteSparse), sparse_schur or dense_qr")
      ->capture_default_str();
  c.app->add_option("--covariance", a->covariance,
                    "schur (Schur complement on theta) or ceres (SuiteSparse QR)")
      ->capture_default_str();
  c.app->add_option("--epoch-s", a->epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app->add_option("--rate-window-s", a->rate_window_s,
                    "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str();
  c.app->add_option("--threads", a->threads, "threads (0: all cores)")->capture_default_str();
  c.app->add_option("--residuals", a->residuals_csv, "write the residuals per epoch (CSV)");
  c.app->add_flag("--correlations", a->correlations, "add the correlation matrix to OUT");
  c.app->add_option("--hold", a->hold, "parameters to hold at their nominal values, e.g. dpsi,Kxy");
  c.app->add_option("--free", a->free, "parameters to estimate even if the run barely supports them");
  c.app->add_flag("--no-auto-hold", a->no_auto_hold,
                  "estimate every parameter (by default those the run's motion does not support "
                  "are held at nominal)");
  c.run = [a] { return RunFit(*a); };
  return c;
}

}  // namespace triadcal
