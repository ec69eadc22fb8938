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

#include "core/io/column_mapping.h"
#include "core/model/errors.h"
#include "core/model/units.h"
#include "solvers/static/static_gyro.h"
#include "solvers/static/static_method.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "app/output_guard.h"
#include "app/estimate_json.h"
#include "tools/report/result_plausibility.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

struct StaticArgs {
  std::string run_yaml, out_json, report_html, reference = "auto", fix;
  double placement_sigma_deg = 0.0;
  StaticOptions options;
};

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

nlohmann::json StillJson(const StaticResult& r, const StillOptions& o) {
  nlohmann::json j;
  const bool rates = r.still.test == StillTest::kAngleRates;
  j["test"] = rates ? "angle rates" : "reading variance";
  j["threshold"] = r.still.threshold;
  j["threshold_unit"] = rates ? "deg/s" : "mV (moving standard deviation)";
  if (!rates) j["window_samples"] = r.still.window_samples;
  j["count"] = r.still.intervals.size();
  nlohmann::json d = nlohmann::json::array();
  double total = 0.0;
  for (const StillInterval& iv : r.still.intervals) {
    d.push_back(iv.duration_s());
    total += iv.duration_s();
  }
  j["durations_s"] = d;
  j["total_s"] = total;
  j["dropped_short"] = r.still.dropped_short;
  j["options"] = {{"min_still_s", o.min_still_s},   {"edge_s", o.edge_s},
                  {"merge_gap_s", o.merge_gap_s},   {"window_s", o.window_s},
                  {"noise_factor", o.noise_factor}, {"still_rate_deg_s", o.rate_threshold_deg_s}};
  return j;
}

nlohmann::json PositionsJson(const StaticResult& r) {
  nlohmann::json out = nlohmann::json::array();
  for (const StaticPosition& p : r.positions) {
    nlohmann::json j;
    j["name"] = p.name;
    j["samples"] = p.samples;
    j["duration_s"] = p.duration_s;
    j["t_begin_s"] = p.intervals.front().t_begin_s;
    j["t_end_s"] = p.intervals.back().t_end_s;
    j["intervals"] = p.intervals.size();
    j["mean_mV"] = Vec(p.mean_mV);
    j["std_mV"] = Vec(p.std_mV);
    j["W_g"] = Vec(p.W_g);
    j["norm_residual_mg"] = p.norm_residual_mg;
    if (r.reference == StaticReference::kAngles) {
      j["lambda_deg"] = {p.lambda_rad[0] / kDegToRad, p.lambda_rad[1] / kDegToRad};
    }
    if (r.reference == StaticReference::kLabels) j["up"] = Vec(p.up);
    if (r.reference != StaticReference::kNone) {
      j["predicted_mV"] = Vec(p.predicted_mV);
      j["residual_mV"] = Vec(p.residual_mV);
      j["residual_mg"] = Vec(p.residual_mg);
    }
    out.push_back(j);
  }
  return out;
}

nlohmann::json StaticJson(const StaticArgs& a, const StaticResult& r, std::size_t samples) {
  const ParameterLayout& layout = r.layout;
  std::set<std::string> not_estimable(r.not_separable.begin(), r.not_separable.end());
  for (const HeldParameter& h : r.held) not_estimable.insert(h.name);
  nlohmann::json params = ParametersJson(layout, r.theta, r.cov, not_estimable);
  const double scatter = r.dof >= 0.5 ? std::sqrt(r.chi2_per_dof) : 0.0;
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& info = layout.info(i);
    nlohmann::json& p = params[info.name];
    const double declared = std::sqrt(std::max(0.0, r.cov_declared(i, i))) / info.si_per_unit;
    p["sigma_declared"] = declared;
    if (r.dof >= 0.5) p["sigma_scatter"] = declared * scatter;
    for (const HeldParameter& h : r.held) {
      if (h.name == info.name) p["held"] = h.reason;
    }
  }
  nlohmann::json out;
  out["command"] = "static";
  out["run"] = a.run_yaml;
  out["samples"] = samples;
  out["reference"] = ReferenceName(r.reference);
  out["model"] =
      "readings_i = K_i (sum_j M_ij W_j + W_i sum_j K_ij W_j) + W0_i (paper eq. 1), W in g in the "
      "triad frame; at rest W is gravity: from the bench angles (C_L2^T e_up), from the "
      "position label, or only |W| = 1 (gravity-norm fit)";
  out["parameters"] = params;
  nlohmann::json held = nlohmann::json::object();
  for (const HeldParameter& h : r.held) held[h.name] = h.reason;
  out["held"] = held;
  out["unobservable"] = WeakDirectionsJson(r.weak);
  out["not_estimable"] = std::vector<std::string>(not_estimable.begin(), not_estimable.end());
  out["constraints_used"] = r.constraints_used;
  out["constraints_ignored"] = r.constraints_ignored;
  out["sigma"] = {{"source", r.sigma_source},
                  {"scale", r.sigma_scale},
                  {"chi2", r.chi2},
                  {"dof", r.dof},
                  {"chi2_per_dof", r.chi2_per_dof},
                  {"data_residuals", r.data_residuals},
                  {"effective_parameters", r.effective_parameters},
                  {"rule",
                   "sigma = sigma_declared x max(1, sqrt(chi2/dof)): the larger of the declared "
                   "noise and the residual scatter"}};
  out["still_intervals"] = StillJson(r, a.options.still);
  out["positions"] = PositionsJson(r);
  out["residual_rms_mg"] = r.residual_rms_mg;
  out["converged"] = r.converged;
  out["iterations"] = r.iterations;
  out["settings"] = {{"reference_requested", a.reference},
                     {"fix", a.fix},
                     {"placement_sigma_deg", a.placement_sigma_deg}};
  return out;
}

// The gyro part (static_gyro.h): its 21 parameters beside the accelerometer's,
// and what they come from.
void AddGyroJson(const StaticGyroResult& g, nlohmann::json* out) {
  const std::vector<ParameterInfo>& info = GyroParameterInfo();
  nlohmann::json& params = (*out)["parameters"];
  for (int i = 0; i < kNumGyroParams; ++i) {
    const double f = info[i].si_per_unit;
    nlohmann::json p;
    p["value"] = g.theta[i] / f;
    if (std::isfinite(g.sigma[i])) {
      p["sigma"] = g.sigma[i] / f;
    } else {
      p["sigma"] = nullptr;
      p["sigma_noise"] = g.sigma_noise[i] / f;
    }
    p["unit"] = info[i].unit;
    p["estimable"] = true;
    params[info[i].name] = p;
  }
  nlohmann::json j;
  j["method"] =
      "Ferraris et al. 1995: W0 and G from the still positions (least squares on the "
      "accelerometer's specific force), diag(K) Mg from the corrected readings integrated over "
      "the three turns";
  j["sigma"] = {{"source", g.sigma_source},
                {"scale", g.sigma_scale},
                {"chi2", g.chi2},
                {"dof", g.dof},
                {"rule",
                 "W0, G: declared noise x max(1, sqrt(chi2/dof)) of the positions; K and the "
                 "angles: exactly determined by the three turns, no sigma from the data "
                 "(sigma_noise: white noise and the W0, G uncertainty only, not the turn's "
                 "angle error)"}};
  nlohmann::json pos = nlohmann::json::array();
  for (const StaticGyroPosition& p : g.positions) {
    pos.push_back({{"name", p.name},
                   {"samples", p.samples},
                   {"mean_dps", Vec(p.mean_rad_s / kDegToRad)},
                   {"W_g", Vec(p.W_g)},
                   {"residual_dps", Vec(p.residual_rad_s / kDegToRad)}});
  }
  j["positions"] = pos;
  nlohmann::json turns = nlohmann::json::array();
  for (const StaticGyroTurnResult& t : g.turns) {
    turns.push_back({{"label", t.label},
                     {"samples", t.samples},
                     {"duration_s", t.duration_s},
                     {"sense", t.sense},
                     {"integral_deg", Vec(t.integral_rad / kDegToRad)},
                     {"mean_W_g", Vec(t.mean_W_g)}});
  }
  j["turns"] = turns;
  (*out)["gyro_static"] = j;
}

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

// The flags of the StaticOptions / StillOptions settings, for errors found below.
const std::map<std::string, std::string>& StaticFlags() {
  static const std::map<std::string, std::string> flags = {
      {"reference", "--reference"},
      {"fixed", "--fix"},
      {"min_still_s", "--min-still-s"},
      {"edge_s", "--edge-s"},
      {"merge_gap_s", "--merge-gap-s"},
      {"window_s", "--window-s"},
      {"noise_factor", "--noise-factor"},
      {"rate_threshold_deg_s", "--still-rate-deg-s"},
      {"rate_half_window_s", "--rate-window-s"}};
  return flags;
}

// --reference: a run that lacks what the reference needs is an error of the
// run file, said after the flag that asked for it.
StaticReference Reference(const StaticArgs& a, const LoadedRun& run) {
  try {
    return ChooseReference(run.description, run.data, a.reference);
  } catch (const OptionError&) {
    throw;
  } catch (const InputError& e) {
    throw InputError("--reference " + a.reference + ": " + e.what());
  }
}

int RunStatic(const StaticArgs& a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, "--report");
  CheckOutputPath(a.out_json);
  StaticOptions opt = a.options;
  opt.fixed = SplitList(a.fix);
  if (!(a.placement_sigma_deg >= 0.0)) throw InputError("--placement-sigma-deg: must be >= 0");
  if (!(a.placement_sigma_deg <= 45.0)) {
    throw InputError("--placement-sigma-deg: must be at most 45");
  }
  opt.placement_sigma_rad = a.placement_sigma_deg * kDegToRad;
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  CheckOverwrite(a.out_json, session);  // before the long work
  const StaticResult r = WithFlags(StaticFlags(), [&] {
    return SolveStatic(run.description, run.data, Reference(a, run), opt);
  });
  nlohmann::json out = StaticJson(a, r, run.data.size());
  std::optional<StaticGyroResult> gyro;
  if (run.description.gyro && run.data.has_gyro()) {
    try {
      gyro = SolveStaticGyro(run.description, run.data, r, StaticGyroOptions());
      AddGyroJson(*gyro, &out);
    } catch (const InputError& e) {
      std::fprintf(stderr, "triadcal: warning: the gyro is not calibrated: %s\n", e.what());
    }
  }
  for (const std::string& w : ImplausibleResultWarnings(out["parameters"], a.out_json)) {
    std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(w).c_str());
  }
  WriteJson(out, a.out_json, session);
  WriteReportIfAsked(a.report_html, out, a.out_json, session);
  PrintReport(run, r);
  if (gyro) PrintGyroReport(*gyro);
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
      ->add_option("--placement-sigma-deg", a->placement_sigma_deg,
                   "1 sigma orientation error of each position that does not average out "
                   "(hand placement, table tilt, bench positioning) [deg], 0 to 45; angles, labels")
      ->capture_default_str();
  StillOptions& s = a->options.still;
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
