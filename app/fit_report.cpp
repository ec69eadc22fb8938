#include "app/fit_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/io/file_util.h"
#include "solvers/estimation/observability.h"
#include "app/estimate_json.h"
#include "app/residual_plot_json.h"

namespace triadcal {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// The gyro's rate noise per channel in the readings' unit [deg/s]: |gyro.K_i|
// times the input-rate noise (r.gyro's are in rad/s of input rate).
Eigen::Vector3d GyroReadingNoise_dps(const ParameterLayout& layout, const BatchResult& r,
                                     const Eigen::Vector3d& noise_rad_s) {
  const int go = layout.gyro_offset();
  Eigen::Vector3d dps;
  for (int i = 0; i < 3; ++i) {
    dps[i] = noise_rad_s[i] * std::abs(r.estimate.theta[go + kGKx + i]) * kRadToDeg;
  }
  return dps;
}

bool IsGyroParameter(const ParameterLayout& layout, const std::string& name) {
  const int i = layout.IndexOf(name);
  return i >= 0 && layout.is_gyro(i);
}

}  // namespace

FitReport MakeFitReport(const ParameterLayout& layout, const BatchResult& r) {
  FitReport rep;
  rep.held.insert(r.held.begin(), r.held.end());
  rep.consider.insert(r.consider.begin(), r.consider.end());
  // The same analysis as `observability`, on the fit's own covariance given
  // the parameters it does not estimate (their prior uncertainty, carried
  // into the others' sigma, is not the data's weakness).
  const Eigen::MatrixXd& cov =
      r.cov_given_consider.rows() == layout.size() ? r.cov_given_consider : r.estimate.cov;
  rep.weak = UnsupportedDirections(layout, cov, r.prior.sigma);
  for (const std::string& s : ParametersIn(rep.weak)) rep.not_estimable.insert(s);
  rep.not_estimable.insert(rep.held.begin(), rep.held.end());
  rep.not_estimable.insert(rep.consider.begin(), rep.consider.end());
  for (const auto& [name, anchors] : r.relative_to) rep.not_estimable.insert(name);
  const int m = static_cast<int>(r.consider.size());
  if (m > 0 && r.consider_sensitivity.rows() == layout.size() &&
      r.consider_sensitivity.cols() == m && r.consider_cov.rows() == m &&
      r.cov_given_consider.rows() == layout.size()) {
    std::vector<int> estimated;
    for (int i = 0; i < layout.size(); ++i) {
      const std::string& name = layout.info(i).name;
      if (!rep.held.count(name) && !rep.consider.count(name)) estimated.push_back(i);
    }
    for (const auto& [i, with] : DeterminedOnlyWithConsidered(
             r.estimate.cov, r.cov_given_consider, r.consider_sensitivity,
             r.consider_cov.diagonal(), r.prior.sigma, r.min_information, estimated)) {
      std::vector<std::string>& names = rep.with_considered[layout.info(i).name];
      for (int q : with) names.push_back(r.consider[q]);
    }
  }
  rep.beyond_prior = BeyondPrior(layout, r.estimate.theta, r.prior.mean, r.prior.sigma);
  // Whiteness of the whitened process residuals (the solver's test).
  rep.whiteness_p_value = r.whiteness_p_value;
  rep.residual_white = r.residual_white;
  rep.noise_consistent = r.noise_check.consistent;
  rep.pass = r.converged && rep.residual_white;
  std::ostringstream v;
  if (r.converged) {
    v << "converged in " << r.iterations << " step(s), " << r.passes << " pass(es) over the samples";
  } else {
    v << "NOT CONVERGED: " << r.termination;
  }
  v << "; chi2/dof " << std::round(1000 * r.chi2_per_dof) / 1000 << " (1 expected)";
  const Eigen::Vector3d& nd = r.noise_declared_mV;
  const Eigen::Vector3d& nu = r.noise_used_mV;
  const std::string& unit = layout.readings_unit();
  char noise[320];
  if (r.noise_source == "estimated") {
    std::snprintf(noise, sizeof(noise),
                  "; reading noise estimated with the parameters %.3g %.3g %.3g %s", nu[0], nu[1],
                  nu[2], unit.c_str());
    v << noise;
    if (r.noise_auto) {
      std::snprintf(noise, sizeof(noise), " (noise_mV auto, from the readings' own %.3g %.3g %.3g)",
                    r.noise_start_mV[0], r.noise_start_mV[1], r.noise_start_mV[2]);
    } else {
      std::snprintf(noise, sizeof(noise), " (declared %.3g %.3g %.3g%s)", nd[0], nd[1], nd[2],
                    rep.noise_consistent ? ", consistent" : ": NOT what the residuals hold");
    }
    v << noise;
  } else {
    std::snprintf(noise, sizeof(noise), "; reading noise as declared %.3g %.3g %.3g %s", nu[0],
                  nu[1], nu[2], unit.c_str());
    v << noise;
  }
  if (rep.residual_white) {
    v << "; residuals white";
  } else if (r.sigma_method == "hac") {
    char hac[160];
    std::snprintf(hac, sizeof(hac),
                  "; RESIDUALS NOT WHITE: sigma from the HAC covariance (Bartlett, %.1f epochs), "
                  "which allows for their correlation in time",
                  r.hac_bandwidth_epochs);
    v << hac;
  } else {
    v << "; RESIDUALS NOT WHITE (sigma may be optimistic)";
  }
  if (rep.beyond_prior.empty()) {
    v << "; no parameter beyond 3 prior sigma";
  } else {
    v << "; BEYOND 3 PRIOR SIGMA (value - nominal in prior sigma): "
      << DescribeExcursions(rep.beyond_prior)
      << ": the nominal values or priors are wrong, or the model lacks an effect whose misfit "
         "they absorb (diagnose looks for one)";
  }
  if (!r.consider.empty()) {
    v << "; NOT DETERMINED by this run (kept at nominal, their prior uncertainty carried into "
         "the other parameters' sigma):";
    for (const std::string& s : r.consider) v << " " << s;
  }
  if (!r.held.empty()) {
    v << "; held at nominal:";
    for (const std::string& s : r.held) v << " " << s;
    if (!r.unsupported_at_start.empty()) {
      v << " (undetermined:";
      for (std::size_t k = 0; k < r.unsupported_at_start.size(); ++k) {
        v << (k ? "; " : " ") << r.unsupported_at_start[k].description;
      }
      v << "; the other parameters of these directions are estimated relative to the held ones)";
    }
  }
  if (!rep.with_considered.empty()) {
    v << "; DETERMINED ONLY WITH the considered parameters at nominal (their prior uncertainty "
         "is most of the sigma):";
    for (const auto& [name, with] : rep.with_considered) {
      v << " " << name << " (with";
      for (const std::string& c : with) v << " " << c;
      v << ")";
    }
  }
  if (rep.weak.empty()) {
    v << (rep.with_considered.empty() ? "; every estimated parameter determined"
                                      : "; every other estimated parameter determined");
  } else {
    v << "; NOT SEPARABLE in this run:";
    for (const std::string& s : ParametersIn(rep.weak)) v << " " << s;
  }
  rep.verdict = v.str();
  return rep;
}

void AddConsiderJson(const ParameterLayout& layout, const BatchResult& r, nlohmann::json* out) {
  nlohmann::json consider = nlohmann::json::array();
  const int m = static_cast<int>(r.consider.size());
  const bool model = r.consider_sensitivity.rows() == layout.size() &&
                     r.consider_sensitivity.cols() == m && r.consider_cov.rows() == m;
  for (int q = 0; q < m; ++q) {
    const std::string& name = r.consider[q];
    const int iq = layout.IndexOf(name);
    const double unit_q = layout.info(iq).si_per_unit;
    nlohmann::json e = {{"parameter", name},
                        {"prior_sigma", r.prior.sigma[iq] / unit_q}};
    if (r.conditional_information.size() == layout.size()) {
      e["data_information"] = r.conditional_information[iq];
    }
    if (model) {
      // How each estimate follows the considered value (file units per file unit).
      nlohmann::json sens = nlohmann::json::object();
      for (int i = 0; i < layout.size(); ++i) {
        if (r.consider_sensitivity(i, q) == 0.0) continue;
        sens[layout.info(i).name] =
            r.consider_sensitivity(i, q) * unit_q / layout.info(i).si_per_unit;
      }
      e["sensitivity"] = sens;
    }
    consider.push_back(e);
    nlohmann::json& pj = (*out)["parameters"][name];
    pj["sigma"] = r.prior.sigma[iq] / unit_q;
    pj["determined"] = false;
    pj["considered"] = true;
    pj.erase("held");  // not held: its uncertainty is carried
  }
  (*out)["consider"] = consider;
}

nlohmann::json GyroJson(const ParameterLayout& layout, const BatchResult& r) {
  // The gyro triad's part (SPEC section 10): its noise in the readings'
  // unit (deg/s: |gyro.K_i| times the rate noise), the increment residuals.
  constexpr double kDeg = kRadToDeg;
  auto vec = [](const Eigen::Vector3d& v) { return std::vector<double>{v[0], v[1], v[2]}; };
  const Eigen::Vector3d est_dps = GyroReadingNoise_dps(layout, r, r.gyro.noise_rad_s);
  const Eigen::Vector3d decl_dps = GyroReadingNoise_dps(layout, r, r.gyro.noise_declared_rad_s);
  return {{"noise", {{"estimated_dps", vec(est_dps)},
                     {"declared_dps", vec(decl_dps)},
                     {"unit", "deg/s"},
                     {"source", "estimated"}}},
          {"residual_rms_arcsec",
           {{"inner", r.gyro.residual_rms_rad[0] * kDeg * 3600.0},
            {"outer", r.gyro.residual_rms_rad[1] * kDeg * 3600.0},
            {"normal", r.gyro.residual_rms_rad[2] * kDeg * 3600.0}}},
          {"residual", "attitude increments between epochs: gyro integrated "
                       "against the angle sensors (outer-axis frame)"},
          {"whitened_rms", r.gyro.whitened_rms},
          {"intervals", r.gyro.intervals},
          {"interval_s", r.gyro.interval_s},
          {"intervals_left_out_clipped", r.gyro.intervals_clipped},
          {"degrees_of_freedom", r.gyro.degrees_of_freedom}};
}

void AddGyroAnalysis(const RunDescription& run, const RunData& data, const ParameterLayout& layout,
                     const BatchResult& r, const FitReport& rep, nlohmann::json* gyro) {
  const ResidualReport gr = AnalyzeGyroResiduals(run, data, layout, r);
  (*gyro)["verdict"] = GyroVerdictJson(MakeGyroVerdict(layout, r, rep, gr));
  (*gyro)["residual_analysis"] = ResidualReportJson(gr);
  (*gyro)["residual_plot"] = ResidualPlotJson(gr);
}

nlohmann::json FitJson(const ParameterLayout& layout, const BatchResult& r, const FitReport& rep,
                       bool correlations) {
  nlohmann::json out;
  out["parameters"] = ParametersJson(layout, r.estimate.theta, r.estimate.cov, rep.not_estimable);
  MarkRelative(r.relative_to, &out["parameters"]);
  // Both sigma next to the reported one: the model's (white) and the HAC's.
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& pi = layout.info(i);
    nlohmann::json& pj = out["parameters"][pi.name];
    pj["determined"] = !rep.held.count(pi.name) && !rep.consider.count(pi.name) &&
                       !rep.with_considered.count(pi.name);
    if (const auto w = rep.with_considered.find(pi.name); w != rep.with_considered.end()) {
      pj["determined_with_considered"] = w->second;
    }
    if (pj["sigma"].is_null()) continue;
    if (r.cov_white.rows() == layout.size()) {
      pj["sigma_white"] = std::sqrt(std::max(0.0, r.cov_white(i, i))) / pi.si_per_unit;
    }
    if (r.cov_hac.rows() == layout.size()) {
      pj["sigma_hac"] = std::sqrt(std::max(0.0, r.cov_hac(i, i))) / pi.si_per_unit;
    }
    if (r.cov_given_consider.rows() == layout.size()) {
      pj["sigma_given_consider"] =
          std::sqrt(std::max(0.0, r.cov_given_consider(i, i))) / pi.si_per_unit;
    }
  }
  AddConsiderJson(layout, r, &out);
  out["sigma_method"] = r.sigma_method;
  if (r.cov_hac.rows() > 0) {
    out["hac"] = {{"kernel", "Bartlett"},
                  {"bandwidth_epochs", r.hac_bandwidth_epochs},
                  {"bandwidth_rule", "Andrews (1991) AR(1) plug-in over the epoch scores"},
                  {"kernel_bias_correction",
                   r.hac_kernel_bias_corrected ? "AR(1) ratio per parameter" : "none"},
                  {"kernel_bias_sigma_factor_max", r.hac_kernel_bias_factor_max}};
  }
  out["initial"] = {{"parameters", ParametersJson(layout, r.initial.theta, r.initial.cov, {})}};
  if (!r.start_note.empty()) out["initial"]["note"] = r.start_note;
  if (correlations) {
    out["correlation"] = CorrelationJson(layout, r.estimate.cov);
    // Given the considered parameters at their nominal values: what two fits
    // that consider the same parameters share no part of.
    if (r.cov_given_consider.rows() == layout.size()) {
      out["correlation_given_consider"] = CorrelationJson(layout, r.cov_given_consider);
    }
  }
  // The directions the run cannot determine: those still weak in the fit's
  // covariance, and those removed by holding a parameter (structural nulls).
  std::vector<WeakDirection> unobservable = rep.weak;
  for (const WeakDirection& d : r.unsupported_at_start) {
    for (const auto& [name, weight] : d.weights) {
      if (rep.held.count(name)) {
        unobservable.push_back(d);
        break;
      }
    }
  }
  out["unobservable"] = WeakDirectionsJson(unobservable);
  out["not_estimable"] = std::vector<std::string>(rep.not_estimable.begin(), rep.not_estimable.end());
  out["held"] = r.held;
  out["unobservable_at_nominal"] = WeakDirectionsJson(r.unsupported_at_start);
  std::vector<std::string> beyond_prior;
  for (const PriorExcursion& e : rep.beyond_prior) beyond_prior.push_back(e.name);
  out["at_prior_bound"] = beyond_prior;
  out["verdict"] = {{"converged", r.converged},
                    {"termination", r.termination},
                    {"chi2_per_dof", r.chi2_per_dof},
                    {"noise_consistent", rep.noise_consistent},
                    {"residual_white", rep.residual_white},
                    {"whiteness_p_value", rep.whiteness_p_value},
                    {"held", r.held},
                    {"not_determined", r.consider},
                    {"beyond_prior", beyond_prior},
                    {"pass", rep.pass},
                    {"sentence", rep.verdict}};
  out["converged"] = r.converged;
  auto vec = [](const Eigen::Vector3d& v) { return std::vector<double>{v[0], v[1], v[2]}; };
  out["noise"] = {{"declared_mV", r.noise_auto ? nlohmann::json(nullptr)
                                                : nlohmann::json(vec(r.noise_declared_mV))},
                  {"auto", r.noise_auto},
                  {"unit", layout.readings_unit()},
                  {"start_mV", vec(r.noise_start_mV)},
                  {"estimated_mV", vec(r.noise_check.estimated_mV)},
                  {"estimated_sd_mV", vec(r.noise_check.sd_mV)},
                  {"estimated_dof", vec(r.noise_check.dof)},
                  {"used_mV", vec(r.noise_used_mV)},
                  {"source", r.noise_source},
                  {"residual_lag1", std::vector<double>(r.noise_check.lag1.data(),
                                                        r.noise_check.lag1.data() + 6)}};
  if (r.gyro.present) out["gyro"] = GyroJson(layout, r);
  out["final_cost"] = r.final_cost;
  out["residual_count"] = r.residual_count;
  out["iterations"] = {{"steps", r.iterations}, {"passes", r.passes}, {"reductions", r.reductions}};
  const auto& m = r.residuals.measurement_rms;
  const auto& p = r.residuals.process_rms;
  out["residual_rms"] = {
      {"measurement_v_mps", {m[0], m[1], m[2]}},
      {"measurement_s_m", {m[3], m[4], m[5]}},
      {"process_v_mps", {p[0], p[1], p[2]}},
      {"process_s_m", {p[3], p[4], p[5]}},
      {"measurement_whitened", r.residuals.measurement_whitened_rms},
      {"process_whitened", r.residuals.process_whitened_rms}};
  out["chi2_per_dof"] = r.chi2_per_dof;
  out["degrees_of_freedom"] = r.degrees_of_freedom;
  out["time_s"] = {{"init", r.init_seconds},
                   {"decide", r.decide_seconds},
                   {"solve", r.solve_seconds},
                   {"solve_passes", r.solve_pass_seconds},
                   {"solve_reductions", r.solve_reduction_seconds},
                   {"covariance", r.covariance_seconds}};
  out["settings"] = {{"epochs", r.epochs}};
  return out;
}

GyroVerdict MakeGyroVerdict(const ParameterLayout& layout, const BatchResult& r,
                            const FitReport& rep, const ResidualReport& gyro_residuals) {
  GyroVerdict g;
  double p_min = 1.0;
  int tested = 0;
  for (const ChannelReport& ch : gyro_residuals.channels) {
    if (!ch.tested) continue;
    p_min = std::min(p_min, ch.whiteness.p_value);
    ++tested;
  }
  g.whiteness_p_value = std::min(1.0, tested * p_min);
  g.residual_white = g.whiteness_p_value >= 0.01;
  g.pass = r.converged && g.residual_white;
  auto gyro_only = [&](const auto& names) {
    std::vector<std::string> out;
    for (const std::string& s : names) {
      if (IsGyroParameter(layout, s)) out.push_back(s);
    }
    return out;
  };
  g.held = gyro_only(r.held);
  g.not_determined = gyro_only(r.consider);
  g.not_separable = gyro_only(ParametersIn(rep.weak));
  std::vector<PriorExcursion> beyond;
  for (const PriorExcursion& e : rep.beyond_prior) {
    if (IsGyroParameter(layout, e.name)) {
      beyond.push_back(e);
      g.beyond_prior.push_back(e.name);
    }
  }

  std::ostringstream v;
  char buf[320];
  if (!r.converged) v << "the fit did NOT CONVERGE; ";
  const ChannelReport* worst = nullptr;
  for (const ChannelReport& ch : gyro_residuals.channels) {
    if (ch.tested && (!worst || ch.whiteness.p_value < worst->whiteness.p_value)) worst = &ch;
  }
  if (g.residual_white) {
    std::snprintf(buf, sizeof(buf), "gyro increment residuals white (Ljung-Box p %.2g)",
                  g.whiteness_p_value);
  } else {
    std::snprintf(buf, sizeof(buf),
                  "gyro increment residuals NOT WHITE (Ljung-Box p %.2g, worst %s, lag-1 "
                  "autocorrelation %.2f)",
                  g.whiteness_p_value, worst ? worst->name.c_str() : "-",
                  worst ? worst->whiteness.rho1 : 0.0);
  }
  v << buf;
  std::snprintf(buf, sizeof(buf), ", whitened RMS %.3f (1 expected)", r.gyro.whitened_rms);
  v << buf;
  const Eigen::Vector3d est = GyroReadingNoise_dps(layout, r, r.gyro.noise_rad_s);
  const Eigen::Vector3d decl = GyroReadingNoise_dps(layout, r, r.gyro.noise_declared_rad_s);
  std::snprintf(buf, sizeof(buf), "; rate noise estimated %.3g %.3g %.3g deg/s", est[0], est[1],
                est[2]);
  v << buf;
  if (r.gyro.noise_auto) {
    v << " (noise_dps auto)";
  } else {
    std::snprintf(buf, sizeof(buf), " (declared %.3g %.3g %.3g deg/s)", decl[0], decl[1], decl[2]);
    v << buf;
  }
  // The intervals' spacing as the samples make it (the analysis's).
  std::snprintf(buf, sizeof(buf), "; %d intervals of %.3g s", r.gyro.intervals,
                gyro_residuals.dt_s > 0.0 ? gyro_residuals.dt_s : r.gyro.interval_s);
  v << buf;
  if (r.gyro.intervals_clipped > 0) {
    v << ", " << r.gyro.intervals_clipped
      << " LEFT OUT (a gyro sample at the range's limit: saturated)";
  }
  if (!g.beyond_prior.empty()) {
    v << "; BEYOND 3 PRIOR SIGMA (value - nominal in prior sigma): " << DescribeExcursions(beyond);
  }
  auto list = [&](const char* what, const std::vector<std::string>& names) {
    if (names.empty()) return;
    v << "; " << what << ":";
    for (const std::string& s : names) v << " " << s;
  };
  list("gyro parameters NOT DETERMINED by this run (kept at nominal, prior uncertainty carried)",
       g.not_determined);
  list("held at nominal", g.held);
  if (g.not_separable.empty()) {
    v << "; every estimated gyro parameter determined";
  } else {
    list("NOT SEPARABLE in this run", g.not_separable);
  }
  g.sentence = v.str();
  return g;
}

nlohmann::json GyroVerdictJson(const GyroVerdict& v) {
  return {{"pass", v.pass},
          {"residual_white", v.residual_white},
          {"whiteness_p_value", v.whiteness_p_value},
          {"held", v.held},
          {"not_determined", v.not_determined},
          {"not_separable", v.not_separable},
          {"beyond_prior", v.beyond_prior},
          {"sentence", v.sentence}};
}

}  // namespace triadcal
