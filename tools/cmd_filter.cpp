// `triadcal filter RUN.yaml -o OUT.json [--series FILE.csv]`: the paper's EKF
// with the RTS smoother (solvers/estimation/kalman_smoother.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <sstream>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/units.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/kalman_smoother.h"
#include "solvers/estimation/observability.h"
#include "solvers/estimation/separability.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "app/estimate_json.h"
#include "app/fit_report.h"
#include "app/output_guard.h"
#include "core/io/column_mapping.h"
#include "tools/report/result_plausibility.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

// At most this many smoother passes (--iterations): each is a whole EKF + RTS
// pass over the run, and the relinearised estimate settles in two or three
// (1e9 ran on without end).
constexpr int kMaxIterations = 20;

struct FilterArgs {
  std::string run_yaml, out_json, report_html, series_csv, effects;
  double epoch_s = kDefaultEpoch_s;
  double rate_window_s = AngleDerivativeOptions().half_window_s;
  int iterations = 2;
  bool correlations = false, no_auto_hold = false;
  std::string hold, free;
};

std::string SeriesCsv(const ParameterLayout& layout, const FilterResult& r) {
  std::ostringstream s;
  s << "# triadcal filter: forward-pass estimates with 1-sigma, and innovations\n";
  s << "# units: t s; parameters in the units of docs/file-formats.md (";
  for (int i = 0; i < layout.size(); ++i) {
    s << (i ? ", " : "") << layout.info(i).name << " " << layout.info(i).unit;
  }
  s << "); innov_v* m/s, innov_s* m\n";
  s << "t";
  for (int i = 0; i < layout.size(); ++i) {
    s << "," << layout.info(i).name << "," << layout.info(i).name << "_sigma";
  }
  const char* ch[6] = {"v_x", "v_y", "v_z", "s_x", "s_y", "s_z"};
  for (const char* c : ch) s << ",innov_" << c;
  for (const char* c : ch) s << ",innov_" << c << "_sigma";
  s << "\n";
  for (const FilterSeriesRow& row : r.series) {
    s << FormatDouble(row.t_s);
    for (int i = 0; i < layout.size(); ++i) {
      const double f = layout.info(i).si_per_unit;
      s << "," << FormatDouble(row.theta[i] / f) << "," << FormatDouble(row.sigma[i] / f);
    }
    for (int c = 0; c < 6; ++c) s << "," << FormatDouble(row.innovation[c]);
    for (int c = 0; c < 6; ++c) s << "," << FormatDouble(row.innovation_sigma[c]);
    s << "\n";
  }
  return s.str();
}

int RunFilter(const FilterArgs& a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, "--report");
  const auto t0 = std::chrono::steady_clock::now();
  CheckOutputPath(a.out_json);
  if (!a.series_csv.empty()) CheckOutputPath(a.series_csv, "--series");
  if (a.iterations < 1 || a.iterations > kMaxIterations) {
    throw InputError("--iterations: Value " + std::to_string(a.iterations) + " not in range 1 to " +
                     std::to_string(kMaxIterations));
  }
  CheckHoldFree(SplitList(a.hold), SplitList(a.free), ParameterLayout(ParseEffectList(a.effects)));
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  CheckOverwrite(a.out_json, session);  // before the long work
  const ParameterLayout layout(ParseEffectList(a.effects, run.data), /*gyro=*/false,
                               ReadingsUnit(run.description));
  FilterOptions opt;
  opt.epoch_s = a.epoch_s;
  opt.derivatives.half_window_s = a.rate_window_s;
  opt.smoother_iterations = a.iterations;
  opt.keep_series = !a.series_csv.empty();
  const int passes = std::max(1, a.iterations);
  opt.progress = [passes](int pass, double f) {
    ShowProgress("filter: pass " + std::to_string(pass) + "/" + std::to_string(passes),
                 (pass - 1 + f) / passes);
  };
  // The same decision as fit: what the run does not determine (held as a
  // structural null, or kept at nominal and considered in fit) is held at its
  // nominal value (removed from the filter's state), so that the filter does
  // not wander along flat directions. The filter carries no consider
  // covariance: its sigma of the others are conditional on the held values.
  HoldDecision hd;
  const Prior prior = MakePrior(run.description, layout);
  if (!a.no_auto_hold || !a.hold.empty()) {
    HoldPolicy hp;
    hp.auto_hold = !a.no_auto_hold;
    hp.hold = SplitList(a.hold);
    hp.free = SplitList(a.free);
    hd = ChooseHeldParameters(run.description, run.data, layout, hp, a.epoch_s, opt.derivatives);
    opt.held = hd.held;
    opt.held.insert(opt.held.end(), hd.consider.begin(), hd.consider.end());
  }
  const FilterResult r = RunFilterSmoother(run.description, run.data, layout, opt);
  EndProgress();
  if (!r.ekf.theta.allFinite() || !r.rts.theta.allFinite()) {
    // No number to write: a diverged filter's estimate is not a result.
    std::fprintf(stderr,
                 "triadcal: error: %s: the filter diverged (its estimate is not finite): the "
                 "readings are far from the nominal model (check triad.bias_mV, "
                 "triad.scale_mV_per_g and the readings' unit)\n",
                 a.run_yaml.c_str());
    return kExitNotConverged;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // Against the run's own prior: held parameters come out determined there.
  const std::vector<WeakDirection> weak = UnsupportedDirections(layout, r.rts.cov, prior.sigma);
  std::vector<std::string> held = ParametersIn(weak);
  held.insert(held.end(), opt.held.begin(), opt.held.end());
  for (const auto& [name, anchors] : hd.relative_to) held.push_back(name);
  const std::set<std::string> held_set(held.begin(), held.end());
  const std::set<std::string> pinned(opt.held.begin(), opt.held.end());

  nlohmann::json out;
  out["command"] = "filter";
  out["run"] = a.run_yaml;
  out["ekf"] = {{"parameters", ParametersJson(layout, r.ekf.theta, r.ekf.cov, held_set)}};
  out["rts"] = {{"parameters", ParametersJson(layout, r.rts.theta, r.rts.cov, held_set)}};
  MarkRelative(hd.relative_to, &out["ekf"]["parameters"]);
  MarkRelative(hd.relative_to, &out["rts"]["parameters"]);
  if (a.correlations) out["rts"]["correlation"] = CorrelationJson(layout, r.rts.cov);
  std::vector<WeakDirection> unobservable = weak;
  for (const WeakDirection& d : hd.unsupported) {
    for (const auto& [name, w] : d.weights) {
      if (pinned.count(name)) {
        unobservable.push_back(d);
        break;
      }
    }
  }
  out["unobservable"] = WeakDirectionsJson(unobservable);
  out["not_estimable"] = held;
  out["held"] = hd.held;
  out["not_determined"] = hd.consider;
  out["unobservable_at_nominal"] = WeakDirectionsJson(hd.unsupported);
  out["settings"] = {{"epoch_s", a.epoch_s},
                     {"epochs", r.epochs},
                     {"passes", r.passes},
                     {"rate_source", run.data.has_rates() ? "rate columns" : "local cubic fit"},
                     {"rate_window_half_s", a.rate_window_s},
                     {"rate_noise_deg_s", r.rate_noise_rad_s / kDegToRad},
                     {"effects", a.effects}};
  out["innovations"] = {
      {"rms_v_mps", {r.innovation_rms[0], r.innovation_rms[1], r.innovation_rms[2]}},
      {"rms_s_m", {r.innovation_rms[3], r.innovation_rms[4], r.innovation_rms[5]}},
      {"mean_nis", r.mean_nis},
      {"mean_nis_expected", 6}};
  out["samples"] = run.data.size();
  out["time_s"] = seconds;
  for (const std::string& w : ImplausibleResultWarnings(out["rts"]["parameters"], a.out_json)) {
    std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(w).c_str());
  }
  WriteJson(out, a.out_json, session);
  WriteReportIfAsked(a.report_html, out, a.out_json, session);
  if (!a.series_csv.empty()) WriteFileAtomically(a.series_csv, SeriesCsv(layout, r));

  std::printf("filter: %zu samples, %d epochs of %.3g s, %d pass(es), %.2f s\n",
              run.data.size(), r.epochs, a.epoch_s, r.passes, seconds);
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
    return held_set.count(name) ? "  (not estimable: prior value)" : "";
  };
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& p = layout.info(i);
    const double f = p.si_per_unit;
    if (pinned.count(p.name)) {
      // Not a calibration result: its nominal, without a sigma.
      const ValueText v = FormatWithSigma(r.rts.theta[i] / f, 0.0);
      std::printf("%-26s %16s %10s %16s %10s  %s  (not determined: nominal)\n", p.name.c_str(),
                  v.value.c_str(), "-", v.value.c_str(), "-", p.unit.c_str());
      continue;
    }
    const ValueText e = FormatWithSigma(r.ekf.theta[i] / f, std::sqrt(r.ekf.cov(i, i)) / f);
    const ValueText s = FormatWithSigma(r.rts.theta[i] / f, std::sqrt(r.rts.cov(i, i)) / f);
    std::printf("%-26s %16s %10s %16s %10s  %s%s\n", p.name.c_str(), e.value.c_str(),
                e.sigma.c_str(), s.value.c_str(), s.sigma.c_str(), p.unit.c_str(),
                Label(p.name).c_str());
  }
  std::printf("innovations: mean NIS %.2f (6 expected for a consistent filter)\n", r.mean_nis);
  auto advice = [](const WeakDirection& d) {
    for (const auto& w : d.weights) {
      if (w.first == "dlambda2") return " A constraint such as dpsi - dlambda2 in run.yaml fixes it.";
    }
    return "";
  };
  if (!opt.held.empty()) {
    std::string names;
    for (const std::string& h : opt.held) names += (names.empty() ? "" : ", ") + h;
    std::printf("NOT DETERMINED, held at nominal (this run's motion does not determine them): "
                "%s\n", names.c_str());
    for (const WeakDirection& d : hd.unsupported) {
      std::printf("  undetermined: %s; its other parameters are estimated relative to the held "
                  "ones.%s\n",
                  d.description.c_str(), advice(d));
    }
  }
  for (const WeakDirection& d : weak) {
    std::string names;
    for (const auto& w : d.weights) names += (names.empty() ? "" : ", ") + w.first;
    std::printf(
        "NOT SEPARABLE in this run: %s -- %s. Their values above are the prior's, not "
        "estimates (sigma %.0f%% of the prior).%s\n",
        names.c_str(), d.description.c_str(), 100.0 * d.sigma_ratio, advice(d));
  }
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
  c.app->add_option("--epoch-s", args->epoch_s, "interval between measurement epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app
      ->add_option("--rate-window-s", args->rate_window_s,
                   "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  c.app
      ->add_option("--iterations", args->iterations,
                   "smoother passes; >1 relinearises about the previous smoothed estimate "
                   "(each a whole EKF + RTS pass; the estimate settles in 2 or 3)")
      ->capture_default_str()
      ->check(BoundedInt(1, kMaxIterations));
  c.app->add_option("--effects", args->effects, "catalogue effects to estimate too, e.g. a,b");
  c.app->add_flag("--correlations", args->correlations, "add the correlation matrix to OUT");
  c.app->add_option("--hold", args->hold, "parameters to hold at their nominal values, e.g. dpsi,Kxy");
  c.app->add_option("--free", args->free, "parameters to estimate even if the run barely supports them");
  c.app->add_flag("--no-auto-hold", args->no_auto_hold,
                  "estimate every parameter (by default those the run's motion does not support "
                  "are held at nominal, as in fit)");
  c.run = [args](Session& session) { return RunFilter(*args, session); };
  return c;
}

}  // namespace triadcal
