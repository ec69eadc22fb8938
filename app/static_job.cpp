#include "app/static_job.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "app/estimate_json.h"
#include "app/option_lists.h"
#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {

std::optional<StaticReference> ParseStaticReference(const std::string& text) {
  if (text == "auto") return std::nullopt;
  for (StaticReference r :
       {StaticReference::kAngles, StaticReference::kLabels, StaticReference::kNone}) {
    if (text == ReferenceName(r)) return r;
  }
  throw InputError("--reference: expected auto, angles, labels or none, got '" + Excerpt(text, 40) +
                   "'");
}

const char* StaticReferenceName(const std::optional<StaticReference>& reference) {
  return reference ? ReferenceName(*reference) : "auto";
}

namespace {

// The flags of the StaticOptions / StillOptions settings, for errors found below.
const std::map<std::string, std::string>& StaticFlags() {
  static const std::map<std::string, std::string> flags = {
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

nlohmann::json StaticJson(const StaticSettings& s, const std::string& run_yaml,
                          const StaticResult& r, std::size_t samples) {
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
  out["run"] = run_yaml;
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
  out["still_intervals"] = StillJson(r, s.still);
  out["positions"] = PositionsJson(r);
  out["residual_rms_mg"] = r.residual_rms_mg;
  out["converged"] = r.converged;
  out["iterations"] = r.iterations;
  std::string fix;
  for (const std::string& f : s.fix) fix += (fix.empty() ? "" : ",") + f;
  out["settings"] = {{"reference_requested", StaticReferenceName(s.reference)},
                     {"fix", fix},
                     {"placement_sigma_deg", s.placement_sigma_deg}};
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

}  // namespace

void StaticSettings::Validate() const {
  if (!(placement_sigma_deg >= 0.0)) throw InputError("--placement-sigma-deg: must be >= 0");
  if (!(placement_sigma_deg <= 45.0)) {
    throw InputError("--placement-sigma-deg: must be at most 45");
  }
  WithFlags(StaticFlags(), [&] { CheckStillOptions(still); });
}

StaticOutcome StaticRun(const StaticSettings& s, const std::string& run_yaml, const LoadedRun& run,
                        const Session& session) {
  s.Validate();
  // A run that lacks what the reference needs is an error of the run file,
  // said after the option that asked for it.
  const std::string requested = StaticReferenceName(s.reference);
  StaticReference reference;
  try {
    reference = ChooseReference(run.description, run.data, requested);
  } catch (const InputError& e) {
    throw InputError("--reference " + requested + ": " + e.what());
  }
  StaticOptions opt;
  opt.still = s.still;
  opt.fixed = s.fix;
  opt.placement_sigma_rad = s.placement_sigma_deg * kDegToRad;
  StaticOutcome o;
  o.result = WithFlags(StaticFlags(),
                       [&] { return SolveStatic(run.description, run.data, reference, opt); });
  o.json = StaticJson(s, run_yaml, o.result, run.data.size());
  if (run.description.gyro && run.data.has_gyro()) {
    try {
      o.gyro = SolveStaticGyro(run.description, run.data, o.result, StaticGyroOptions());
      AddGyroJson(*o.gyro, &o.json);
    } catch (const InputError& e) {
      o.warnings.push_back(std::string("the gyro is not calibrated: ") + e.what());
      if (session.warning) session.warning(o.warnings.back());
    }
  }
  return o;
}

}  // namespace triadcal
