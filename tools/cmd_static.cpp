// `triadcal static RUN.yaml -o OUT.json`: the standard static method
// (solvers/static/static_method.h): still intervals, averaged positions, and the
// readings model fitted to them with the angles, the position labels, or the
// gravity norm as the reference.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

#include "app/output_guard.h"
#include "app/static_job.h"
#include "core/io/column_mapping.h"
#include "core/model/errors.h"
#include "core/model/units.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/result_plausibility.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

struct StaticArgs {
  std::string run_yaml, out_json, report_html, fix;
  std::string reference = StaticReferenceName(StaticSettings().reference);
  StaticSettings settings;  // the numbers, filled by CLI11 directly
};

void PrintGyroReport(const StaticGyroResult& g) {
  std::printf("gyro: %zu positions, %zu turns; W0, G sigma: %s (chi2/dof = %.3g on %.0f dof)\n",
              g.positions.size(), g.turns.size(), g.sigma_source.c_str(),
              g.dof >= 1.0 ? g.chi2 / g.dof : 0.0, g.dof);
  std::printf("%-13s %14s %11s %11s  %s\n", "parameter", "value", "sigma", "sigma_noise", "unit");
  const std::vector<ParameterInfo>& info = GyroParameterInfo();
  for (int i = 0; i < kNumGyroParams; ++i) {
    const double f = info[i].si_per_unit;
    const std::string unit = info[i].unit;
    if (std::isfinite(g.sigma[i])) {
      const ValueText v = FormatWithSigma(g.theta[i] / f, g.sigma[i] / f);
      std::printf("%-13s %14s %11s %11s  %s\n", info[i].name.c_str(), v.value.c_str(),
                  v.sigma.c_str(), "-", unit.c_str());
    } else {
      std::printf("%-13s %14.6g %11s %11.3g  %s (three turns: no residual)\n", info[i].name.c_str(),
                  g.theta[i] / f, "-", g.sigma_noise[i] / f, unit.c_str());
    }
  }
  for (const StaticGyroTurnResult& t : g.turns) {
    std::printf("turn %-6s %5zu samples %6.2f s, sense %+d, integral %9.1f %9.1f %9.1f deg\n",
                t.label.c_str(), t.samples, t.duration_s, t.sense, t.integral_rad[0] / kDegToRad,
                t.integral_rad[1] / kDegToRad, t.integral_rad[2] / kDegToRad);
  }
}

void PrintReport(const LoadedRun& run, const StaticResult& r) {
  const bool rates = r.still.test == StillTest::kAngleRates;
  std::printf("static: %zu samples, reference: %s", run.data.size(), ReferenceName(r.reference));
  if (r.reference == StaticReference::kLabels) {
    std::printf(" (column '%s')", LabelSource(run.description).c_str());
  }
  std::printf("\n");
  double lo = 1e300, hi = 0.0, total = 0.0;
  for (const StillInterval& iv : r.still.intervals) {
    lo = std::min(lo, iv.duration_s());
    hi = std::max(hi, iv.duration_s());
    total += iv.duration_s();
  }
  std::printf(
      "still intervals: %zu (%s %.3g %s), durations %.3g-%.3g s, %.4g s in all; %zu shorter runs "
      "dropped\n",
      r.still.intervals.size(), rates ? "angle rates below" : "moving std below",
      r.still.threshold, rates ? "deg/s" : "mV", lo, hi, total, r.still.dropped_short);
  std::printf("positions: %zu; fit %s after %d iterations\n", r.positions.size(),
              r.converged ? "converged" : "NOT converged", r.iterations);
  std::printf("%-10s %14s %11s %11s %11s  %s\n", "parameter", "value", "sigma", "sigma_decl",
              "sigma_scat", "unit");
  const double scatter = r.dof >= 0.5 ? std::sqrt(r.chi2_per_dof) : 0.0;
  std::set<std::string> weak(r.not_separable.begin(), r.not_separable.end());
  for (int i = 0; i < r.layout.size(); ++i) {
    const ParameterInfo& p = r.layout.info(i);
    const double f = p.si_per_unit;
    bool held = false;
    for (const HeldParameter& h : r.held) held = held || h.name == p.name;
    if (held) {
      std::printf("%-10s %14.6g %11s %11s %11s  %-6s (held)\n", p.name.c_str(), r.theta[i] / f,
                  "-", "-", "-", p.unit.c_str());
      continue;
    }
    const double decl = std::sqrt(r.cov_declared(i, i)) / f;
    const ValueText v = FormatWithSigma(r.theta[i] / f, std::sqrt(r.cov(i, i)) / f);
    std::printf("%-10s %14s %11s %11.3g %11.3g  %-6s%s\n", p.name.c_str(), v.value.c_str(),
                v.sigma.c_str(), decl, decl * scatter, p.unit.c_str(),
                weak.count(p.name) ? " NOT SEPARABLE (prior value)" : "");
  }
  std::printf("sigma: %s (chi2/dof = %.3g on %.3g dof; reported = declared x %.3g)\n",
              r.sigma_source.c_str(), r.chi2_per_dof, r.dof, r.sigma_scale);
  for (const WeakDirection& d : r.weak) {
    std::string names;
    for (const auto& w : d.weights) names += (names.empty() ? "" : ", ") + w.first;
    std::printf("NOT SEPARABLE by these positions: %s -- %s\n", names.c_str(),
                d.description.c_str());
  }
  if (r.reference == StaticReference::kNone) {
    std::printf("%-6s %7s %7s %12s\n", "pose", "samples", "s", "|W|-1 [mg]");
    for (const StaticPosition& p : r.positions) {
      std::printf("%-6s %7zu %7.2f %12.3f\n", p.name.c_str(), p.samples, p.duration_s,
                  p.norm_residual_mg);
    }
  } else {
    std::printf("%-8s %7s %7s %27s %10s\n", "position", "samples", "s", "residual x y z [mg]",
                "|W|-1 [mg]");
    for (const StaticPosition& p : r.positions) {
      std::printf("%-8s %7zu %7.2f %9.3f %8.3f %8.3f %10.3f\n", p.name.c_str(), p.samples,
                  p.duration_s, p.residual_mg[0], p.residual_mg[1], p.residual_mg[2],
                  p.norm_residual_mg);
    }
  }
  std::printf("residual RMS over positions: %.3g mg\n", r.residual_rms_mg);
}

int RunStatic(StaticArgs a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session, "--report");
  CheckOutputPath(a.out_json, session);
  StaticSettings& s = a.settings;
  s.reference = ParseStaticReference(a.reference);
  s.fix = SplitList(a.fix);
  s.Validate();
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  CheckOverwrite(a.out_json, session);  // before the long work
  const StaticOutcome o = StaticRun(s, a.run_yaml, run, session);
  for (const std::string& w : ImplausibleResultWarnings(o.json["parameters"], a.out_json)) {
    std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(w).c_str());
  }
  WriteJson(o.json, a.out_json, session);
  WriteReportIfAsked(a.report_html, o.json, a.out_json, session);
  PrintReport(run, o.result);
  if (o.gyro) PrintGyroReport(*o.gyro);
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddStaticCommand(CLI::App& app) {
  auto a = std::make_shared<StaticArgs>();
  Command c;
  c.app = app.add_subcommand(
      "static", "Standard static method: still positions averaged, readings model fitted");
  c.app->add_option("run", a->run_yaml, "run description (run.yaml)")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--report", a->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  c.app->add_option("--reference", a->reference,
                    "orientation of the positions: auto (angles, else labels, else none), "
                    "angles, labels, or none (gravity-norm fit)")
      ->capture_default_str();
  c.app->add_option("--fix", a->fix,
                    "parameters held at their nominal value, e.g. Kxy,Kyx or K_ij (all nine)");
  c.app
      ->add_option("--placement-sigma-deg", a->settings.placement_sigma_deg,
                   "1 sigma orientation error of each position that does not average out "
                   "(hand placement, table tilt, bench positioning) [deg], 0 to 45; angles, labels")
      ->capture_default_str();
  StillOptions& s = a->settings.still;
  c.app
      ->add_option("--min-still-s", s.min_still_s,
                   "shortest still interval kept [s], > 0 and at most 3600")
      ->capture_default_str();
  c.app->add_option("--edge-s", s.edge_s, "dropped at each end of a still interval [s], 0 to 600")
      ->capture_default_str();
  c.app
      ->add_option("--merge-gap-s", s.merge_gap_s,
                   "still runs closer than this are merged [s], 0 to 600")
      ->capture_default_str();
  c.app
      ->add_option(
          "--window-s", s.window_s,
          "without angles: window of the moving standard deviation [s], > 0 and at most 600")
      ->capture_default_str();
  c.app
      ->add_option(
          "--noise-factor", s.noise_factor,
          "without angles: still when the moving std < factor x triad.noise_mV; > 0 and at most "
          "10000")
      ->capture_default_str();
  c.app
      ->add_option("--still-rate-deg-s", s.rate_threshold_deg_s,
                   "with angles: still when |lambda'| is below this [deg/s]; 0: max(0.05, "
                   "5 sigma of the estimated rate)")
      ->capture_default_str();
  c.app
      ->add_option("--rate-window-s", s.rate_half_window_s,
                   "with angles: half window of the local cubic fit giving lambda' [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  c.run = [a](Session& session) { return RunStatic(*a, session); };
  return c;
}

}  // namespace triadcal
