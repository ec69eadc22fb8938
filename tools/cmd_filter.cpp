// `triadcal filter RUN.yaml -o OUT.json [--series FILE.csv]`: the paper's EKF
// with the RTS smoother (solvers/estimation/kalman_smoother.h).
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "app/filter_job.h"
#include "app/fit_report.h"
#include "app/output_guard.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/result_plausibility.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

struct FilterArgs {
  std::string run_yaml, out_json, report_html, series_csv, hold, free;
  bool no_auto_hold = false;
  FilterSettings settings;  // the numbers and flags, filled by CLI11 directly
};

void PrintFilter(const FilterSettings& s, const LoadedRun& run, const FilterOutcome& f) {
  const ParameterLayout& layout = f.layout;
  const FilterResult& r = f.result;
  const HoldDecision& hd = f.decision;
  std::printf("filter: %zu samples, %d epochs of %.3g s, %d pass(es), %.2f s\n", run.data.size(),
              r.epochs, s.epoch_s, r.passes, f.seconds);
  std::printf("%-26s %16s %10s %16s %10s  %s\n", "parameter", "EKF", "sigma", "RTS", "sigma",
              "unit");
  // A parameter estimated relative to held ones is named with them; one in a
  // direction the run leaves to the prior is the prior's value.
  auto Label = [&](const std::string& name) -> std::string {
    const auto rel = hd.relative_to.find(name);
    if (rel != hd.relative_to.end()) {
      std::string anchors;
      for (const std::string& h : rel->second) anchors += (anchors.empty() ? "" : ", ") + h;
      return "  (relative to held " + anchors + ")";
    }
    return f.not_estimable.count(name) ? "  (not estimable: prior value)" : "";
  };
  const std::set<std::string> pinned(f.pinned.begin(), f.pinned.end());
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& p = layout.info(i);
    const double u = p.si_per_unit;
    if (pinned.count(p.name)) {
      // Not a calibration result: its nominal, without a sigma.
      const ValueText v = FormatWithSigma(r.rts.theta[i] / u, 0.0);
      std::printf("%-26s %16s %10s %16s %10s  %s  (not determined: nominal)\n", p.name.c_str(),
                  v.value.c_str(), "-", v.value.c_str(), "-", p.unit.c_str());
      continue;
    }
    const ValueText e = FormatWithSigma(r.ekf.theta[i] / u, std::sqrt(r.ekf.cov(i, i)) / u);
    const ValueText m = FormatWithSigma(r.rts.theta[i] / u, std::sqrt(r.rts.cov(i, i)) / u);
    std::printf("%-26s %16s %10s %16s %10s  %s%s\n", p.name.c_str(), e.value.c_str(),
                e.sigma.c_str(), m.value.c_str(), m.sigma.c_str(), p.unit.c_str(),
                Label(p.name).c_str());
  }
  std::printf("innovations: mean NIS %.2f (6 expected for a consistent filter)\n", r.mean_nis);
  auto advice = [](const WeakDirection& d) {
    for (const auto& w : d.weights) {
      if (w.first == "dlambda2") return " A constraint such as dpsi - dlambda2 in run.yaml fixes it.";
    }
    return "";
  };
  if (!f.pinned.empty()) {
    std::string names;
    for (const std::string& h : f.pinned) names += (names.empty() ? "" : ", ") + h;
    std::printf("NOT DETERMINED, held at nominal (this run's motion does not determine them): "
                "%s\n", names.c_str());
    for (const WeakDirection& d : hd.unsupported) {
      std::printf("  undetermined: %s; its other parameters are estimated relative to the held "
                  "ones.%s\n",
                  d.description.c_str(), advice(d));
    }
  }
  for (const WeakDirection& d : f.weak) {
    std::string names;
    for (const auto& w : d.weights) names += (names.empty() ? "" : ", ") + w.first;
    std::printf(
        "NOT SEPARABLE in this run: %s -- %s. Their values above are the prior's, not "
        "estimates (sigma %.0f%% of the prior).%s\n",
        names.c_str(), d.description.c_str(), 100.0 * d.sigma_ratio, advice(d));
  }
}

int RunFilter(FilterArgs a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session, "--report");
  CheckOutputPath(a.out_json, session);
  if (!a.series_csv.empty()) CheckOutputPath(a.series_csv, session, "--series");
  FilterSettings& s = a.settings;
  s.hold = SplitList(a.hold);
  s.free = SplitList(a.free);
  s.auto_hold = !a.no_auto_hold;
  s.keep_series = !a.series_csv.empty();
  s.Validate();
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  CheckOverwrite(a.out_json, session);  // before the long work
  StageProgress progress("filter: ");
  const Session filtering = WithProgress(session, &progress);
  const FilterOutcome f = FilterRun(s, a.run_yaml, run, filtering);
  EndProgress();
  if (!f.error.empty()) {
    std::fprintf(stderr, "triadcal: error: %s\n", f.error.c_str());
    return kExitNotConverged;
  }
  for (const std::string& w : ImplausibleResultWarnings(f.json["rts"]["parameters"], a.out_json)) {
    std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(w).c_str());
  }
  WriteJson(f.json, a.out_json, session);
  WriteReportIfAsked(a.report_html, f.json, a.out_json, session);
  if (!a.series_csv.empty()) {
    WriteFileAtomically(a.series_csv, FilterSeriesCsv(f.layout, f.result), session.write_options());
  }
  PrintFilter(s, run, f);
  std::printf("wrote %s%s%s\n", a.out_json.c_str(), a.series_csv.empty() ? "" : " and ",
              a.series_csv.c_str());
  return 0;
}

}  // namespace

Command AddFilterCommand(CLI::App& app) {
  auto args = std::make_shared<FilterArgs>();
  Command c;
  c.app = app.add_subcommand("filter", "EKF + Rauch-Tung-Striebel smoother (the paper's filter)");
  c.app->add_option("run", args->run_yaml, "run description (run.yaml)")->required();
  c.app->add_option("-o,--output", args->out_json, "output JSON")->required();
  c.app->add_option("--report", args->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  c.app->add_option("--series", args->series_csv,
                    "write forward-pass estimates, sigma and innovations against time (CSV)");
  c.app->add_option("--epoch-s", args->settings.epoch_s, "interval between measurement epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app
      ->add_option("--rate-window-s", args->settings.rate_window_s,
                   "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  c.app
      ->add_option("--iterations", args->settings.iterations,
                   "smoother passes; >1 relinearises about the previous smoothed estimate "
                   "(each a whole EKF + RTS pass; the estimate settles in 2 or 3)")
      ->capture_default_str()
      ->check(BoundedInt(1, kMaxFilterIterations));
  c.app->add_option("--effects", args->settings.effects,
                    "catalogue effects to estimate too, e.g. a,b");
  c.app->add_flag("--correlations", args->settings.correlations,
                  "add the correlation matrix to OUT");
  c.app->add_option("--hold", args->hold, "parameters to hold at their nominal values, e.g. dpsi,Kxy");
  c.app->add_option("--free", args->free, "parameters to estimate even if the run barely supports them");
  c.app->add_flag("--no-auto-hold", args->no_auto_hold,
                  "estimate every parameter (by default those the run's motion does not support "
                  "are held at nominal, as in fit)");
  c.run = [args](Session& session) { return RunFilter(*args, session); };
  return c;
}

}  // namespace triadcal
