#include "tools/report/fit_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/io/file_util.h"
#include "solvers/estimation/observability.h"
#include "tools/report/estimate_json.h"
#include "tools/report/value_format.h"

namespace triadcal {

FitReport MakeFitReport(const ParameterLayout& layout, const BatchResult& r) {
  FitReport rep;
  rep.held.insert(r.held.begin(), r.held.end());
  // The same analysis as `observability`, on the fit's own covariance. Held
  // parameters are pinned far below their (original) prior sigma, so they
  // come out determined and are reported as held instead.
  // Judged on the reported (honest) covariance: a parameter whose HAC sigma
  // is as large as its prior's is not determined by this run, whatever the
  // white-noise information says (real slow roll run: dpsi 4555' with white
  // sigma 28' and HAC sigma 2237' against a prior of 180').
  rep.weak = UnsupportedDirections(layout, r.estimate.cov, r.prior.sigma);
  for (const std::string& s : ParametersIn(rep.weak)) rep.not_estimable.insert(s);
  rep.not_estimable.insert(rep.held.begin(), rep.held.end());
  for (const auto& [name, anchors] : r.relative_to) rep.not_estimable.insert(name);
  rep.beyond_prior = BeyondPrior(layout, r.estimate.theta, r.prior.mean, r.prior.sigma);
  // Whiteness of the whitened process residuals (the solver's test).
  rep.whiteness_p_value = r.whiteness_p_value;
  rep.residual_white = r.residual_white;
  rep.noise_consistent = r.noise_check.consistent;
  rep.pass = r.converged && rep.residual_white;
  std::ostringstream v;
  v << (r.converged ? "converged" : "NOT CONVERGED") << " in " << r.outer_iterations
    << " relinearisation(s), " << r.ceres_iterations << " Ceres iterations";
  v << "; chi2/dof " << std::round(1000 * r.chi2_per_dof) / 1000 << " (1 expected)";
  const Eigen::Vector3d& nd = r.noise_declared_mV;
  const Eigen::Vector3d& ne = r.noise_check.estimated_mV;
  char noise[320];
  std::snprintf(noise, sizeof(noise), "; reading noise from the residuals %.3g %.3g %.3g mV",
                ne[0], ne[1], ne[2]);
  v << noise;
  // What run.yaml said: the figures, or auto (with the start it took).
  char said[120];
  if (r.noise_auto) {
    std::snprintf(said, sizeof(said), "noise_mV auto, started at %.3g mV", r.noise_start_mV);
  } else {
    std::snprintf(said, sizeof(said), "declared %.3g %.3g %.3g", nd[0], nd[1], nd[2]);
  }
  if (r.noise_source == "estimated") {
    std::snprintf(noise, sizeof(noise), " (%s: sigma rest on the estimate)", said);
    v << noise;
  } else if (r.noise_source == "estimated_common") {
    if (r.noise_check.white) {
      std::snprintf(noise, sizeof(noise),
                    " (%s; its channels differ beyond 3x, more than one triad's noise does: "
                    "one weight for all three, variance factor chi2/dof %.3g)",
                    said, r.variance_factor);
    } else {
      std::snprintf(noise, sizeof(noise),
                    " (%s; the residual is not white, so its split between channels is misfit: "
                    "the model's sigma scaled by one variance factor, chi2/dof %.3g)",
                    said, r.variance_factor);
    }
    v << noise;
  }
  if (rep.residual_white) {
    v << "; residuals white";
    if (r.sigma_method == "hac" && r.hac_floor == "per_channel_bound") {
      v << "; sigma from the HAC covariance, which measures what each channel's residual holds "
           "(one weight served channels that differ beyond 3x)";
    }
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
    v << "; no parameter at a prior bound";
  } else {
    v << "; BEYOND 3 PRIOR SIGMA (value - nominal in prior sigma): "
      << DescribeExcursions(rep.beyond_prior)
      << ": the nominal values or priors are wrong, or the model lacks an effect whose misfit "
         "they absorb (diagnose looks for one, --hold pins them)";
  }
  if (!r.pinned.empty()) {
    v << "; PINNED at nominal after a first fit (value - nominal there in prior sigma, data "
         "information at the nominal values in prior units): "
      << DescribePins(r.pinned) << ": the run knows them at most twice as well as their priors, so only a nominal value "
         "wrong by 4.5 prior sigma or the model's nonlinearity following a misfit moves them "
         "that far; their uncertainty is kept in the other parameters' sigma (--free NAME "
         "estimates one)";
  }
  std::vector<std::string> held_by_motion;
  for (const std::string& s : r.held) {
    if (!IsPinned(r, s)) {
      held_by_motion.push_back(s);
    }
  }
  if (!held_by_motion.empty()) {
    v << "; held at nominal (this run's motion does not determine them):";
    for (const std::string& s : held_by_motion) v << " " << s;
    if (!r.unsupported_at_start.empty()) {
      v << " (undetermined:";
      for (std::size_t k = 0; k < r.unsupported_at_start.size(); ++k) {
        v << (k ? "; " : " ") << r.unsupported_at_start[k].description;
      }
      v << "; the other parameters of these directions are estimated relative to the held ones)";
    }
  }
  if (rep.weak.empty()) {
    v << "; every other parameter estimable";
  } else {
    // A parameter the data do not determine that still ended far from its
    // prior mean was moved there by the misfit through its correlations: its
    // value is neither the prior's nor an estimate.
    std::set<std::string> beyond;
    for (const PriorExcursion& e : rep.beyond_prior) beyond.insert(e.name);
    std::vector<std::string> at_prior, moved;
    for (const std::string& s : ParametersIn(rep.weak)) {
      (beyond.count(s) ? moved : at_prior).push_back(s);
    }
    if (!at_prior.empty()) {
      v << "; NOT SEPARABLE in this run (values are the prior's):";
      for (const std::string& s : at_prior) v << " " << s;
    }
    if (!moved.empty()) {
      v << "; NOT SEPARABLE in this run and MOVED beyond 3 prior sigma by the misfit (values "
           "neither the prior's nor estimates):";
      for (const std::string& s : moved) v << " " << s;
    }
  }
  rep.verdict = v.str();
  return rep;
}

void AddPinnedJson(const ParameterLayout& layout, const BatchResult& r, nlohmann::json* out) {
  nlohmann::json pinned = nlohmann::json::array();
  const int m = static_cast<int>(r.pinned.size());
  const bool consider = r.pinned_sensitivity.rows() == layout.size() &&
                        r.pinned_sensitivity.cols() == m && r.pinned_cov.rows() == m;
  for (int q = 0; q < m; ++q) {
    const PinnedExcursion& p = r.pinned[q];
    nlohmann::json e = {{"parameter", p.name},
                        {"prior_sigmas", p.z},
                        {"data_information", p.data_information}};
    if (consider) {
      // The consider model in file units: the pinned value's uncertainty,
      // its correlation with the other pins, and how each estimate follows it.
      const double unit_q = layout.info(layout.IndexOf(p.name)).si_per_unit;
      const double var_q = std::max(0.0, r.pinned_cov(q, q));
      e["sigma"] = std::sqrt(var_q) / unit_q;
      nlohmann::json corr = nlohmann::json::object();
      for (int c = 0; c < m; ++c) {
        if (c == q) continue;
        const double d = std::sqrt(var_q * std::max(0.0, r.pinned_cov(c, c)));
        corr[r.pinned[c].name] = d > 0.0 ? r.pinned_cov(q, c) / d : 0.0;
      }
      e["correlation"] = corr;
      nlohmann::json sens = nlohmann::json::object();
      for (int i = 0; i < layout.size(); ++i) {
        if (r.pinned_sensitivity(i, q) == 0.0) continue;
        sens[layout.info(i).name] = r.pinned_sensitivity(i, q) * unit_q / layout.info(i).si_per_unit;
      }
      e["sensitivity"] = sens;
    }
    pinned.push_back(e);
    (*out)["parameters"][p.name]["pinned"] = true;
  }
  (*out)["pinned"] = pinned;
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
    if (pj["sigma"].is_null()) continue;
    if (r.cov_white.rows() == layout.size()) {
      pj["sigma_white"] = std::sqrt(std::max(0.0, r.cov_white(i, i))) / pi.si_per_unit;
    }
    if (r.cov_hac.rows() == layout.size()) {
      pj["sigma_hac"] = std::sqrt(std::max(0.0, r.cov_hac(i, i))) / pi.si_per_unit;
    }
    if (r.cov_given_pinned.rows() == layout.size()) {
      pj["sigma_given_pinned"] =
          std::sqrt(std::max(0.0, r.cov_given_pinned(i, i))) / pi.si_per_unit;
    }
  }
  out["sigma_method"] = r.sigma_method;
  if (r.cov_hac.rows() > 0) {
    out["hac"] = {{"kernel", "Bartlett"},
                  {"bandwidth_epochs", r.hac_bandwidth_epochs},
                  {"bandwidth_rule", "Andrews (1991) AR(1) plug-in over the epoch scores"},
                  {"kernel_bias_correction",
                   r.hac_kernel_bias_corrected ? "AR(1) ratio per parameter" : "none"},
                  {"kernel_bias_sigma_factor_max", r.hac_kernel_bias_factor_max}};
    if (!r.hac_floor.empty()) out["hac"]["floor"] = r.hac_floor;
  }
  out["initial"] = {{"parameters", ParametersJson(layout, r.initial.theta, r.initial.cov, {})}};
  if (correlations) {
    out["correlation"] = CorrelationJson(layout, r.estimate.cov);
    // With pins: the correlation given the pinned values (of cov_given_pinned),
    // what two fits that pin alike share no part of.
    if (r.cov_given_pinned.rows() == layout.size()) {
      out["correlation_given_pinned"] = CorrelationJson(layout, r.cov_given_pinned);
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
  AddPinnedJson(layout, r, &out);
  std::vector<std::string> pinned_names;
  for (const PinnedExcursion& p : r.pinned) pinned_names.push_back(p.name);
  out["unobservable_at_nominal"] = WeakDirectionsJson(r.unsupported_at_start);
  std::vector<std::string> beyond_prior;
  for (const PriorExcursion& e : rep.beyond_prior) beyond_prior.push_back(e.name);
  out["at_prior_bound"] = beyond_prior;
  out["verdict"] = {{"converged", r.converged},
                    {"chi2_per_dof", r.chi2_per_dof},
                    {"noise_consistent", rep.noise_consistent},
                    {"residual_white", rep.residual_white},
                    {"whiteness_p_value", rep.whiteness_p_value},
                    {"held", r.held},
                    {"pinned", pinned_names},
                    {"beyond_prior", beyond_prior},
                    {"pass", rep.pass},
                    {"sentence", rep.verdict}};
  out["converged"] = r.converged;
  auto vec = [](const Eigen::Vector3d& v) { return std::vector<double>{v[0], v[1], v[2]}; };
  out["noise"] = {{"declared_mV", r.noise_auto ? nlohmann::json(nullptr)
                                                : nlohmann::json(vec(r.noise_declared_mV))},
                  {"auto", r.noise_auto},
                  {"estimated_mV", vec(r.noise_check.estimated_mV)},
                  {"estimated_sd_mV", vec(r.noise_check.sd_mV)},
                  {"estimated_dof", vec(r.noise_check.dof)},
                  {"used_mV", vec(r.noise_used_mV)},
                  {"source", r.noise_source},
                  {"variance_factor", r.variance_factor},
                  {"residual_lag1", std::vector<double>(r.noise_check.lag1.data(),
                                                        r.noise_check.lag1.data() + 6)},
                  {"residual_white_for_noise", r.noise_check.white},
                  {"channels_alike", r.noise_check.channels_alike}};
  if (r.noise_auto) out["noise"]["start_mV"] = r.noise_start_mV;
  out["final_cost"] = r.final_cost;
  out["residual_count"] = r.residual_count;
  out["iterations"] = {{"relinearisations", r.outer_iterations}, {"ceres", r.ceres_iterations}};
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
                   {"solve", r.solve_seconds},
                   {"covariance", r.covariance_seconds}};
  out["settings"] = {{"epochs", r.epochs}, {"linear_solver", r.linear_solver}};
  return out;
}

void PrintParameterTable(const ParameterLayout& layout, const BatchResult& r,
                         const FitReport& rep) {
  // Values to the digit of their sigma (value_format.h).
  std::printf("%-26s %16s %10s %10s  %s\n", "parameter", "value", "sigma", "start", "unit");
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& pi = layout.info(i);
    const double f = pi.si_per_unit;
    // A held parameter's sigma is its pinning prior's, not an estimate: "-".
    const double sigma =
        rep.held.count(pi.name) ? 0.0 : std::sqrt(std::max(0.0, r.estimate.cov(i, i))) / f;
    const ValueText v = FormatWithSigma(r.estimate.theta[i] / f, sigma);
    std::string label;
    if (rep.held.count(pi.name)) {
      label = "  (held at nominal)";
      for (const PinnedExcursion& p : r.pinned) {
        if (p.name != pi.name) continue;
        char pin[80];
        std::snprintf(pin, sizeof(pin), "  (pinned at nominal: a first fit moved it %+.1f prior sigma)",
                      p.z);
        label = pin;
      }
    } else if (rep.not_estimable.count(pi.name)) {
      label = "  (not estimable: prior value)";
      for (const PriorExcursion& e : rep.beyond_prior) {
        if (e.name != pi.name) continue;
        char moved[80];
        std::snprintf(moved, sizeof(moved), "  (not estimable, moved %+.1f prior sigma by misfit)",
                      e.z);
        label = moved;
      }
    }
    std::printf("%-26s %16s %10s %10.5g  %s%s\n", pi.name.c_str(), v.value.c_str(),
                v.sigma.c_str(), r.initial.theta[i] / f, pi.unit.c_str(), label.c_str());
  }
  for (const WeakDirection& d : rep.weak) {
    std::printf("NOT SEPARABLE: %s (sigma %.0f%% of the prior along it)\n", d.description.c_str(),
                100.0 * d.sigma_ratio);
  }
}

std::string ResidualsCsv(const BatchResult& r) {
  std::ostringstream s;
  s << "# triadcal fit residuals per epoch: measurement m_* = x - B2 reference, process p_* of\n"
    << "# the interval ending at the epoch (0 at the first); v in m/s, s in m\n";
  s << "t,m_vx,m_vy,m_vz,m_sx,m_sy,m_sz,p_vx,p_vy,p_vz,p_sx,p_sy,p_sz\n";
  for (std::size_t e = 0; e < r.epoch_t.size(); ++e) {
    s << FormatDouble(r.epoch_t[e]);
    for (int c = 0; c < 6; ++c) s << "," << FormatDouble(r.measurement_residual[e][c]);
    for (int c = 0; c < 6; ++c) s << "," << FormatDouble(r.process_residual[e][c]);
    s << "\n";
  }
  return s.str();
}

}  // namespace triadcal
