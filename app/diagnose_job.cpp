#include "app/diagnose_job.h"

#include <cmath>

#include "app/option_lists.h"
#include "core/model/errors.h"
#include "app/estimate_json.h"
#include "app/fit_report.h"
#include "app/residual_plot_json.h"

namespace triadcal {
namespace {

nlohmann::json StateJson(const LoadedRun& run, const ParameterLayout& layout, const BatchResult& r,
                         const ResidualReport& rr, const std::map<std::string, double>* truth) {
  const FitReport rep = MakeFitReport(layout, r);
  nlohmann::json j;
  j["effects"] = nlohmann::json::array();
  for (Effect e : layout.effects()) j["effects"].push_back(GetEffectSpec(e).name);
  j["parameters"] = ParametersJson(layout, r.estimate.theta, r.estimate.cov, rep.not_estimable);
  MarkRelative(r.relative_to, &j["parameters"]);
  j["held"] = r.held;
  if (!r.start_note.empty()) j["initial"] = {{"note", r.start_note}};
  AddConsiderJson(layout, r, &j);
  j["chi2_per_dof"] = r.chi2_per_dof;
  j["residual"] = ResidualReportJson(rr);
  j["residual_plot"] = ResidualPlotJson(rr);  // thinned series and spectrum for the report
  nlohmann::json rms = nlohmann::json::object();
  nlohmann::json white = nlohmann::json::object();
  for (const ChannelReport& c : rr.channels) {
    rms[c.name] = c.rms;
    white[c.name] = c.whiteness.p_value;
  }
  j["residual_rms"] = rms;
  j["whiteness_p"] = white;
  if (r.gyro.present) {
    j["gyro"] = GyroJson(layout, r);
    AddGyroAnalysis(run.description, run.data, layout, r, rep, &j["gyro"]);
  }
  if (truth) {
    nlohmann::json err = nlohmann::json::object();
    double sum2 = 0.0;
    int count = 0;
    for (int i = 0; i < layout.size(); ++i) {
      const ParameterInfo& p = layout.info(i);
      auto it = truth->find(p.name);
      if (it == truth->end() || rep.not_estimable.count(p.name)) continue;
      const double v = r.estimate.theta[i] / p.si_per_unit;
      const double s = std::sqrt(r.estimate.cov(i, i)) / p.si_per_unit;
      err[p.name] = {
          {"error", v - it->second}, {"error_in_sigma", (v - it->second) / s}, {"unit", p.unit}};
      sum2 += std::pow((v - it->second) / s, 2);
      ++count;
    }
    j["error_vs_truth"] = err;
    j["error_vs_truth_rms_sigma"] = count ? std::sqrt(sum2 / count) : 0.0;
  }
  return j;
}

// What a refit has: its chi2/dof and the Wald test of the effect; a
// candidate not refitted for its one-step Wald test has that test's keys
// (docs/file-formats.md).
void AddRefitKeys(const CandidateTest& t, nlohmann::json* j) {
  if (!t.refit && !t.one_step_wald) return;
  if (t.refit) (*j)["chi2_per_dof_after"] = t.chi2_per_dof_after;
  (*j)["wald"] = t.wald;
  (*j)["wald_p_value"] = t.wald_p_value;
  (*j)["wald_dof"] =
      std::isfinite(t.wald_dof) && t.wald_dof > 0.0 ? nlohmann::json(t.wald_dof) : nlohmann::json();
  if (!t.not_separable_from.empty()) {
    (*j)["not_separable_from"] = t.not_separable_from;
    (*j)["not_separable_share"] = t.not_separable_share;
    (*j)["wald_p_given_consider"] = t.wald_p_given_consider;
  }
}

}  // namespace

nlohmann::json CouldHideJson(const std::vector<HideCase>& could_hide) {
  nlohmann::json hide = nlohmann::json::array();
  for (const HideCase& h : could_hide) {
    nlohmann::json j = {{"effect", GetEffectSpec(h.effect).name},
                        {"unit", h.unit},
                        {"alpha", h.alpha},
                        {"power", h.power},
                        {"undetectable", h.undetectable}};
    if (h.direction.empty()) {
      j["minimal_detectable"] = nullptr;
      j["max_shift_sigma"] = nullptr;
      j["parameter"] = nullptr;
      j["note"] = "this run's motion cannot detect it";
    } else {
      nlohmann::json comp = nlohmann::json::object();
      for (const auto& [name, value] : h.direction) comp[name] = value;
      j["minimal_detectable"] = h.minimal_detectable;
      j["components"] = comp;
      j["noncentrality"] = h.lambda0;
      j["max_shift_sigma"] = h.max_shift_sigma;
      j["parameter"] = h.parameter;
    }
    hide.push_back(j);
  }
  return hide;
}

nlohmann::json DiagnoseJson(const std::string& run_yaml, const LoadedRun& run, double alpha,
                            const DiagnosisResult& d,
                            const std::map<std::string, double>* tp) {
  nlohmann::json out;
  out["command"] = "diagnose";
  out["run"] = run_yaml;
  nlohmann::json ranking = nlohmann::json::array();
  for (const CandidateTest& t : d.ranking) {
    ranking.push_back({{"effect", GetEffectSpec(t.effect).name},
                       {"statistic", t.statistic},
                       {"likelihood_ratio", t.lr},
                       {"dof", t.dof},
                       {"p_value", t.p_value},
                       {"threshold", t.threshold},
                       {"selected", t.selected},
                       {"note", t.note},
                       {"score", t.score},
                       {"score_p_value", t.score_p_value},
                       {"refit", t.refit},
                       {"one_step_wald", t.one_step_wald}});
    AddRefitKeys(t, &ranking.back());
    if (!t.absorbs.empty()) ranking.back()["absorbs"] = t.absorbs;
  }
  out["ranking"] = ranking;
  nlohmann::json tests = nlohmann::json::array();
  for (const CandidateTest& t : d.tests) {
    tests.push_back({{"round", t.round},
                     {"effect", GetEffectSpec(t.effect).name},
                     {"statistic", t.statistic},
                     {"likelihood_ratio", t.lr},
                     {"note", t.note},
                     {"dof", t.dof},
                     {"p_value", t.p_value},
                     {"threshold", t.threshold},
                     {"selected", t.selected},
                     {"score", t.score},
                     {"score_p_value", t.score_p_value},
                     {"refit", t.refit},
                     {"one_step_wald", t.one_step_wald}});
    AddRefitKeys(t, &tests.back());
    if (!t.absorbs.empty()) tests.back()["absorbs"] = t.absorbs;
  }
  out["tests"] = tests;
  // chi2_per_dof_after is the refit's: null for a candidate judged on its
  // one-step estimate (not refitted).
  auto brief = [](const CandidateTest& t) {
    return nlohmann::json{{"round", t.round},
                          {"effect", GetEffectSpec(t.effect).name},
                          {"statistic", t.statistic},
                          {"dof", t.dof},
                          {"p_value", t.p_value},
                          {"refit", t.refit},
                          {"chi2_per_dof_after", t.refit ? nlohmann::json(t.chi2_per_dof_after)
                                                         : nlohmann::json(nullptr)}};
  };
  out["absorbing"] = nlohmann::json::array();
  for (const CandidateTest& t : d.absorbing) {
    out["absorbing"].push_back(brief(t));
    out["absorbing"].back()["absorbs"] = t.absorbs;
  }
  out["alternatives"] = nlohmann::json::array();
  for (const CandidateTest& t : d.alternatives) out["alternatives"].push_back(brief(t));
  out["correlations"] = nlohmann::json::array();
  for (const EffectCorrelation& c : d.correlations) {
    out["correlations"].push_back({{"parameter", c.parameter}, {"with", c.with}, {"rho", c.rho}});
  }
  out["selected"] = nlohmann::json::array();
  for (Effect e : d.selected) out["selected"].push_back(GetEffectSpec(e).name);
  out["selection_rule"] =
      "forward, one effect per round; selected when its p-value and, refitted, its Wald "
      "p-value (against the refit's reported covariance) are both < alpha / (candidates in "
      "the round), alpha = " +
      std::to_string(alpha);
  out["before"] = StateJson(run, d.before_layout, d.before, d.before_residuals, tp);
  out["after"] = StateJson(run, d.after_layout, d.after, d.after_residuals, tp);
  out["parameters"] = out["after"]["parameters"];
  out["score_rule"] =
      "every candidate is scored from the current fit (score test); refitted for the "
      "likelihood ratio only when its score p-value < refit_factor x threshold";
  out["could_hide"] = CouldHideJson(d.could_hide);
  out["unexplained_structure"] = d.unexplained;
  out["beyond_prior"] = nlohmann::json::array();
  for (const PriorExcursion& e : d.beyond_prior) {
    out["beyond_prior"].push_back({{"parameter", e.name}, {"prior_sigmas", e.z}});
  }
  out["notes"] = d.notes;
  out["verdict"] = d.verdict;
  return out;
}

void DiagnoseSettings::Validate() const {
  ParseEffectList(candidates, "--candidates");
  if (!(alpha > 0.0 && alpha < 1.0)) throw InputError("--alpha: must be in (0, 1)");
  if (max_effects < 0 || max_effects > 20) {
    throw InputError("--max-effects: Value " + std::to_string(max_effects) +
                     " not in range 0 to 20");
  }
  AngleDerivativeOptions window;
  window.half_window_s = rate_window_s;
  WithFlags({{"half_window_s", "--rate-window-s"}}, [&] { window.Check(); });
}

DiagnoseOutcome DiagnoseRun(const DiagnoseSettings& s, const std::string& run_yaml,
                            const LoadedRun& run, const std::map<std::string, double>* truth,
                            const Session& session) {
  s.Validate();
  DiagnoseOptions opt;
  opt.alpha = s.alpha;
  opt.max_effects = s.max_effects;
  opt.fit.epoch_s = s.epoch_s;
  opt.fit.derivatives.half_window_s = s.rate_window_s;
  opt.fit.threads = s.threads;
  opt.candidates = ParseEffectList(s.candidates, "--candidates");
  opt.progress = session.stage;
  opt.fraction = session.fraction;
  DiagnoseOutcome out;
  out.result = Diagnose(run.description, run.data, opt);
  if (!out.result.before.start_note.empty()) {
    out.warnings.push_back(run_yaml + ": " + out.result.before.start_note);
    if (session.warning) session.warning(out.warnings.back());
  }
  out.json = DiagnoseJson(run_yaml, run, s.alpha, out.result, truth);
  return out;
}

}  // namespace triadcal
