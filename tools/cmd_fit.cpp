// `triadcal fit RUN.yaml -o OUT.json`: the batch solution of the fit job
// (app/fit_job.h), written and printed.
#include <cstdio>
#include <memory>

#include "app/fit_job.h"
#include "app/fit_report.h"
#include "app/output_guard.h"
#include "app/run_loading.h"
#include "core/io/file_util.h"
#include "core/io/runs_file_io.h"
#include "core/model/errors.h"
#include "tools/cmd_fit_joint.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/fit_options.h"
#include "tools/report/fit_table.h"
#include "tools/report/result_plausibility.h"

namespace triadcal {
namespace {

struct FitArgs {
  std::vector<std::string> runs;
  std::string run_yaml, out_json, report_html, residuals_csv;
  FitOptions fit;
};

int RunFit(FitArgs a, Session& session) {
  // Several runs, or one runs file: one problem over all (docs/multi-run.md).
  if (a.runs.size() > 1 || IsRunsFile(a.runs[0])) {
    if (!a.residuals_csv.empty()) {
      throw InputError("--residuals: not available for a joint fit of several runs");
    }
    return RunJointFit(a.fit.Settings(), a.runs, a.out_json, a.report_html, session);
  }
  a.run_yaml = a.runs[0];
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session, "--report");
  const FitSettings settings = a.fit.Settings();
  CheckOutputPath(a.out_json, session);
  if (!a.residuals_csv.empty()) CheckOutputPath(a.residuals_csv, session, "--residuals");
  const LoadedRun run = LoadRun(a.run_yaml, &session, settings.threads);
  CheckOverwrite(a.out_json, session);  // before the long work
  StageProgress progress("fit: ");
  const Session fitting = WithProgress(session, &progress);
  const FitOutcome f = FitRun(settings, a.run_yaml, run, fitting);
  EndProgress();
  const ParameterLayout& layout = f.layout;
  const BatchResult& r = f.result;
  const FitReport& rep = f.report;
  const std::string warning = NoiseWarning(a.run_yaml, run, r);
  if (!warning.empty()) std::fprintf(stderr, "triadcal: warning: %s\n", warning.c_str());
  for (const std::string& w : ImplausibleResultWarnings(f.json["parameters"], a.out_json)) {
    std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(w).c_str());
  }
  WriteJson(f.json, a.out_json, session);
  WriteReportIfAsked(a.report_html, f.json, a.out_json, session);
  if (!a.residuals_csv.empty()) {
    WriteFileAtomically(a.residuals_csv, ResidualsCsv(r), session.write_options());
  }

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
  if (f.json.contains("gyro")) {
    // The gyro triad's part, from the OUT (its units there).
    const nlohmann::json& g = f.json["gyro"];
    const auto& n = g["noise"]["estimated_dps"];
    const auto& res = g["residual_rms_arcsec"];
    std::printf("gyro: reading noise %.3g %.3g %.3g deg/s (estimated); increment residual RMS "
                "inner %.3g, outer %.3g, normal %.3g arcsec per %.2g s; whitened %.3f; %d "
                "intervals left out (clipped)\n",
                n[0].get<double>(), n[1].get<double>(), n[2].get<double>(),
                res["inner"].get<double>(), res["outer"].get<double>(),
                res["normal"].get<double>(), g["interval_s"].get<double>(),
                g["whitened_rms"].get<double>(),
                g["intervals_left_out_clipped"].get<int>());
  }
  std::printf("time: init %.2f s (the decision %.2f s), solve %.2f s (%d passes over the samples "
              "%.2f s, %d reductions %.2f s), covariance %.2f s\n",
              r.init_seconds, r.decide_seconds, r.solve_seconds, r.passes, r.solve_pass_seconds,
              r.reductions, r.solve_reduction_seconds, r.covariance_seconds);
  std::printf("wrote %s\n", a.out_json.c_str());
  std::string why;
  const int status = FitExitStatus(settings, a.run_yaml, r, rep, &why);
  if (status != 0) std::fprintf(stderr, "triadcal: error: %s\n", why.c_str());
  return status;
}

}  // namespace

Command AddFitCommand(CLI::App& app) {
  auto a = std::make_shared<FitArgs>();
  Command c;
  c.app = app.add_subcommand("fit",
                             "Batch least-squares solution of the whole run (Levenberg-Marquardt, "
                             "the trajectory solved for exactly)");
  c.app->add_option("run", a->runs,
                    "run description (run.yaml); several, or a runs file, fit one IMU "
                    "from several runs (docs/multi-run.md)")
      ->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--report", a->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  AddFitOptions(c.app, &a->fit);
  c.app->add_option("--threads", a->fit.settings.threads, "threads (0: all cores)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.app->add_option("--residuals", a->residuals_csv, "write the residuals per epoch (CSV)");
  c.run = [a](Session& session) { return RunFit(*a, session); };
  return c;
}

}  // namespace triadcal
