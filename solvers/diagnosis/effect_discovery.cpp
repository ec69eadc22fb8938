#include "solvers/diagnosis/effect_discovery.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <sstream>

#include "core/io/column_mapping.h"
#include "solvers/estimation/observability.h"
#include "solvers/statistics/statistics.h"

namespace triadcal {
namespace {

// The fit of a layout under a decision (what is held, what is considered),
// started from `start` (SI, in that layout). With `noise` the reading noise is
// fixed there (the candidates of a round are compared at one noise, as the
// likelihood ratio needs); without, it is estimated with the parameters.
BatchResult FitLayout(const RunDescription& run, const RunData& data, const ParameterLayout& layout,
                      const Eigen::VectorXd& start, const HoldDecision& decision,
                      const BatchOptions& base, bool covariance,
                      const Eigen::Vector3d* noise = nullptr) {
  BatchOptions o = base;
  o.init = BatchInit::kGiven;
  o.init_theta = start;
  o.decision = &decision;
  o.compute_covariance = covariance;
  o.estimate_noise = noise == nullptr;
  if (noise) o.noise_override = *noise;
  return SolveBatch(run, data, layout, o);
}

// theta of `from` (layout a) placed into layout b, zeros for the new entries.
Eigen::VectorXd Embed(const ParameterLayout& a, const Eigen::VectorXd& theta,
                      const ParameterLayout& b) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(b.size());
  for (int i = 0; i < a.size(); ++i) {
    const int j = b.IndexOf(a.info(i).name);
    if (j >= 0) out[j] = theta[i];
  }
  return out;
}

// The name of the catalogue effect with this zero-offset signal, or "".
std::string SameZeroOffsetSignal(ZeroOffsetSignal signal) {
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.zero_offset_signal == signal) return e.name;
  }
  return "";
}

// Three significant digits.
std::string FormatNumber(double x) {
  std::ostringstream o;
  o.precision(3);
  o << x;
  return o.str();
}

// Why effect e's fitted size in r cannot be a finding: the first parameter
// beyond its plausible range, or "" when all are within.
std::string Implausible(const RunDescription& run, const ParameterLayout& layout,
                        const BatchResult& r, Effect e) {
  const EffectSpec& spec = GetEffectSpec(e);
  const double k_nom = run.scale_mV_per_g.cwiseAbs().maxCoeff();
  for (std::size_t q = 0; q < spec.params.size(); ++q) {
    const ParamSpec& ps = spec.params[q];
    const double v = r.estimate.theta[layout.offset(e) + static_cast<int>(q)] / ps.si_per_unit;
    const double lo = PlausibleMin(spec, ps, k_nom), hi = PlausibleMax(spec, ps, k_nom);
    if (v < lo || v > hi) {
      return spec.name + "." + ps.name + " = " + FormatNumber(v) + " " + ps.unit +
             " is beyond its plausible range " + FormatNumber(lo) + " to " + FormatNumber(hi) +
             " " + ps.unit + " (" + spec.plausible_reason + ")";
    }
  }
  return "";
}

// For every parameter of the effects in `effects`, the free base parameter
// (not of an effect) it correlates with most in r's covariance.
std::vector<EffectCorrelation> Correlations(const ParameterLayout& layout, const BatchResult& r,
                                            const std::vector<Effect>& effects) {
  std::vector<EffectCorrelation> out;
  const Eigen::MatrixXd& C = r.estimate.cov;
  if (C.rows() != layout.size()) return out;
  for (Effect e : effects) {
    const EffectSpec& spec = GetEffectSpec(e);
    for (std::size_t q = 0; q < spec.params.size(); ++q) {
      const int i = layout.offset(e) + static_cast<int>(q);
      if (!(C(i, i) > 0.0)) continue;
      EffectCorrelation c;
      c.parameter = spec.name + "." + spec.params[q].name;
      for (int j = 0; j < layout.size(); ++j) {
        if (layout.info(j).effect || !(C(j, j) > 0.0)) continue;
        const double rho = C(i, j) / std::sqrt(C(i, i) * C(j, j));
        if (c.with.empty() || std::abs(rho) > std::abs(c.rho)) {
          c.rho = rho;
          c.with = layout.info(j).name;
        }
      }
      if (!c.with.empty()) out.push_back(c);
    }
  }
  return out;
}

// A refitted candidate is significant when both its likelihood ratio and its
// Wald test pass: the first assumes white residuals at the noise used, the
// second measures the fitted size against the refit's reported sigma, which
// hold for residuals correlated in time (the HAC sandwich, hac_covariance.h).
// With reading noise correlated over 0.5 s (bench/scenarios/paper-coloured
// .yaml, no effect) the likelihood ratio alone selected an effect on 41 of 50
// clean runs. (A score test with the long-run covariance of the epochs'
// scores at the base fit, which needs no refit, was tried: its variance comes
// from the residual that still holds the effect, and it found a 5' encoder
// harmonic in 35 % of the runs where the likelihood ratio finds it in 100 %.)
double DecisionP(const CandidateTest& t) {
  return t.refit ? std::max(t.p_value, t.wald_p_value) : t.p_value;
}
bool Significant(const CandidateTest& t, double threshold) { return DecisionP(t) < threshold; }

std::vector<Effect> WithEffect(std::vector<Effect> v, Effect e) {
  v.push_back(e);
  return v;
}

}  // namespace

std::vector<Effect> CatalogueCandidates(const RunData& data, const std::vector<Effect>& current,
                                        std::vector<std::string>* notes) {
  // Effects need the data their catalogue entry names (temp_C). With temp_C
  // recorded and (nearly) linear in time, a zero-offset drift in time and
  // one in temperature are the same function of the samples: test the
  // temperature form only (docs/method.md lists them as one effect).
  std::vector<Effect> out;
  const bool temp_linear_in_time =
      data.has_temp() && std::abs(Correlation(data.t_s, data.temp_C)) > 0.99;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (std::find(current.begin(), current.end(), e.id) != current.end()) continue;
    if (e.needs.temp_C && !data.has_temp()) continue;
    if (e.zero_offset_signal == ZeroOffsetSignal::kTime_s && temp_linear_in_time) {
      const std::string same = SameZeroOffsetSignal(ZeroOffsetSignal::kTempRise_C);
      if (!same.empty()) {
        if (notes) {
          notes->push_back(e.name + " not tested apart from " + same +
                           ": temp_C is linear in time in this run, so the two are the same");
        }
        continue;
      }
    }
    out.push_back(e.id);
  }
  return out;
}

std::vector<HideCase> CouldHideOnProfile(const RunDescription& run, const RunData& noise_free,
                                         const ParameterLayout& layout,
                                         const Eigen::VectorXd& theta,
                                         const DiagnoseOptions& options) {
  const std::vector<Effect> candidates =
      options.candidates.empty() ? CatalogueCandidates(noise_free, layout.effects(), nullptr)
                                 : options.candidates;
  if (candidates.empty()) return {};
  BatchOptions o = options.fit;
  o.estimate_noise = false;
  o.init = BatchInit::kGiven;
  o.init_theta = theta;
  RunDescription declared = run;
  declared.noise_auto = false;  // the scenario's declared noise
  const BatchResult fit = SolveBatch(declared, noise_free, layout, o);
  const EffectInformation info =
      AnalyseCandidates(declared, noise_free, layout.effects(), fit, candidates, o);
  const double threshold = options.alpha / static_cast<double>(candidates.size());
  std::vector<HideCase> out;
  for (const CandidateInformation& c : info.candidates) {
    out.push_back(MinimalDetectable(info, c, threshold, options.power));
  }
  std::stable_sort(out.begin(), out.end(), [](const HideCase& a, const HideCase& b) {
    return a.max_shift_sigma > b.max_shift_sigma;
  });
  return out;
}

DiagnosisResult Diagnose(const RunDescription& declared_run, const RunData& data,
                         const DiagnoseOptions& options) {
  // The noise is estimated as fit estimates it, in every round's fit of the
  // current model (run_evaluation.h); the candidates of a round are refitted
  // at that fit's noise, so that their likelihood ratios compare costs at one
  // noise (re-estimating it per candidate would let the noise absorb the
  // very structure under test).
  const DiagnoseOptions& opt = options;
  RunDescription run = declared_run;
  auto say = [&](const std::string& s) {
    if (opt.progress) opt.progress(s);
  };
  DiagnosisResult res;
  std::vector<Effect> candidates =
      opt.candidates.empty() ? CatalogueCandidates(data, {}, &res.notes) : opt.candidates;

  // Progress: every fit reports into [span_begin, span_end].
  double span_begin = 0.0, span_end = 0.15;
  BatchOptions fit_opt = opt.fit;
  if (opt.fraction) {
    fit_opt.fraction = [&](double f) { opt.fraction(span_begin + (span_end - span_begin) * f); };
  }
  // Each round takes 60 % of what is left before 0.95 (the closing analysis).
  double round_begin = 0.15, round_end = 0.15 + 0.6 * 0.8;
  say("fitting the declared model");
  BatchOptions first = fit_opt;
  // Units named for the readings (mV/g, counts/g, mg/g): every layout below
  // is made from this one.
  res.before_layout = ParameterLayout({}, /*gyro=*/false, ReadingsUnit(run));
  res.before = SolveBatch(run, data, res.before_layout, first);
  res.before_residuals = AnalyzeResiduals(run, data, res.before_layout, res.before);
  // Every refit keeps what the declared model's fit decided (held and
  // considered parameters); a candidate adds its own unsupported components.
  const HoldDecision base_decision = DecisionOf(res.before);

  std::vector<Effect> current;
  ParameterLayout layout = res.before_layout;
  BatchResult fit = res.before;
  std::vector<std::string> held = fit.held;
  EffectInformation info;     // the score analysis at the current fit
  bool info_current = false;  // computed at `fit` for the remaining candidates
  double last_threshold = opt.alpha / std::max<std::size_t>(1, candidates.size());
  for (int round = 1; round <= opt.max_effects && !candidates.empty(); ++round) {
    say("round " + std::to_string(round) + ": score tests of " + std::to_string(candidates.size()) +
        " candidates");
    info = AnalyseCandidates(run, data, current, fit, candidates, fit_opt);
    info_current = true;
    if (round == 1) res.base_gradient_sigma = info.base_gradient_sigma;
    const double threshold = opt.alpha / static_cast<double>(candidates.size());
    last_threshold = threshold;
    std::vector<CandidateTest> tests;
    std::vector<BatchResult> refits;  // parallel to tests (empty when not refit)
    // Refitted: score p-value within refit_factor of the threshold, and close
    // to the best candidate: its statistic minus its dof (the excess over
    // what noise gives) within 2 ln(refit_factor) of the best one's (for equal
    // dof: p-values within refit_factor; differences, not p-values, because
    // p underflows for a strong effect). One far behind the best cannot be
    // selected this round; it is scored again at the next round's fit.
    // A candidate whose every tested component the run determines only
    // weakly (CandidateInformation::weak) could not be told from its prior:
    // fitted, it would be "found" along directions the run does not
    // determine (real fast roll run: angle_scale.l1_scale, information 0.025
    // of its prior's, came out 2931 +- 1984 ppm and was selected). It is not
    // tested; could_hide still reports it.
    auto only_weak = [](const CandidateInformation& c) {
      return !c.supported.empty() && c.weak.size() == c.supported.size();
    };
    double best_excess = -std::numeric_limits<double>::infinity();
    for (const CandidateInformation& c : info.candidates) {
      if (!c.supported.empty() && !only_weak(c)) {
        best_excess = std::max(best_excess, c.statistic - static_cast<double>(c.supported.size()));
      }
    }
    auto refit_it = [&](const CandidateInformation& c) {
      return !c.supported.empty() && !only_weak(c) && c.p_value < opt.refit_factor * threshold &&
             c.statistic - static_cast<double>(c.supported.size()) >=
                 best_excess - 2.0 * std::log(opt.refit_factor);
    };
    int to_refit = 0;
    for (const CandidateInformation& c : info.candidates) to_refit += refit_it(c) ? 1 : 0;
    const double fit_share = (round_end - round_begin) / (to_refit + 1.0);
    const int planned_refits = to_refit;
    // Refits candidate c with its effect added, fills t (its LR test) and
    // returns the refit.
    auto refit_candidate = [&](const CandidateInformation& c, CandidateTest* tp,
                               int* count) -> BatchResult {
      CandidateTest& t = *tp;
      const Effect e = c.effect;
      int& refit_count = *count;
      say("round " + std::to_string(round) + ": refitting with " + GetEffectSpec(e).name + " (" +
          std::to_string(refit_count + 1) + "/" + std::to_string(to_refit) + ")");
      if (refit_count < planned_refits) {
        span_begin = round_begin + fit_share * refit_count;
        span_end = span_begin + fit_share;
      } else {  // the fallback's refits: half of what is left of the round each
        span_begin = span_end;
        span_end = span_begin + 0.5 * (round_end - span_begin);
      }
      ++refit_count;
      const ParameterLayout aug = res.before_layout.WithEffects(WithEffect(current, e));
      // Started at the Gauss-Newton step from the current fit (effect_information.h).
      Eigen::VectorXd start = Embed(layout, fit.estimate.theta, aug);
      for (std::size_t j = 0; j < info.base_names.size(); ++j) {
        start[aug.IndexOf(info.base_names[j])] += c.step_base[j];
      }
      for (std::size_t q = 0; q < c.supported.size(); ++q) {
        start[aug.offset(e) + c.supported[q]] += c.step_effect[q];
      }
      HoldDecision decision = DecisionOf(fit);
      const EffectSpec& spec = GetEffectSpec(e);
      for (int q : c.unsupported) decision.held.push_back(spec.name + "." + spec.params[q].name);
      for (const NotSeparable& ns : c.not_separable) {
        decision.consider.push_back(spec.name + "." + spec.params[ns.component].name);
      }
      // Refitted as fit does, the noise estimated with the parameters (the
      // round's noise still holds the misfit of the effect being tested:
      // real medium roll run, chi2/dof 0.05 after the 8.6-ms latency and the
      // drift at the first fit's noise); its likelihood ratio is taken at
      // the round's noise, the same for every candidate (cost_at_noise).
      BatchOptions refit_opt = fit_opt;
      refit_opt.cost_at_noise = fit.noise_used_mV;
      BatchResult r = FitLayout(run, data, aug, start, decision, refit_opt, true,
                                fit_opt.estimate_noise ? nullptr : &fit.noise_used_mV);
      const int k = static_cast<int>(GetEffectSpec(e).params.size());
      int held_new = 0;
      for (const std::vector<std::string>* names : {&r.held, &r.consider}) {
        for (const std::string& h : *names) {
          if (aug.IndexOf(h) >= aug.offset(e) && aug.IndexOf(h) < aug.offset(e) + k) ++held_new;
        }
      }
      t.refit = true;
      t.dof = k - held_new;
      t.lr = 2.0 * (fit.final_cost - r.cost_at_noise);
      t.chi2_per_dof_after = 2.0 * r.cost_at_noise / std::max(1, r.degrees_of_freedom);
      t.statistic = std::max(0.0, t.lr) / std::max(1.0, t.chi2_per_dof_after);
      if (t.dof == 0) {
        t.p_value = 1.0;
        t.note = "not supported by this run's motion";
      } else {
        t.p_value = ChiSquareSurvival(t.statistic, t.dof);
        // The Wald test of the effect's free components against the refit's
        // covariance (its reported sigma: the HAC sandwich when the residual
        // is not white).
        std::vector<int> free_e;
        for (int q = 0; q < k; ++q) {
          const int i = aug.offset(e) + q;
          if (IsEstimated(r, aug.info(i).name)) {
            free_e.push_back(i);
          }
        }
        if (r.estimate.cov.rows() == aug.size() && !free_e.empty()) {
          const int m = static_cast<int>(free_e.size());
          Eigen::MatrixXd C(m, m);
          Eigen::VectorXd v(m);
          for (int a = 0; a < m; ++a) {
            v[a] = r.estimate.theta[free_e[a]];
            for (int b = 0; b < m; ++b) C(a, b) = r.estimate.cov(free_e[a], free_e[b]);
          }
          t.wald = std::max(0.0, v.dot(C.ldlt().solve(v)));
          // The HAC covariance is an estimate: a Bartlett bandwidth of S
          // epochs over E gives it about nu = 1.5 E / S degrees of freedom
          // (its variance, 4/3 S/E of its square, Andrews 1991, as a scaled
          // chi-square's), and the Wald statistic is then Hotelling's. The
          // model's covariance is not estimated from this residual: chi2.
          t.wald_dof = std::numeric_limits<double>::infinity();
          if (r.sigma_method == "hac" && r.hac_bandwidth_epochs > 0.0) {
            t.wald_dof = 1.5 * r.epochs / std::max(1.0, r.hac_bandwidth_epochs);
          }
          t.wald_p_value = HotellingSurvival(t.wald, m, t.wald_dof);
        }
        if (t.p_value < threshold && !(t.wald_p_value < threshold)) {
          t.note = "likelihood ratio significant, but its size is not against its sigma (Wald p " +
                   FormatNumber(t.wald_p_value) +
                   "): what it fits is the residual's correlation in time";
        }
        t.absorbs = Implausible(run, aug, r, e);
        // Significant, but every component it frees is in a direction its own
        // refit cannot determine (the fit's "not estimable": real fast roll,
        // scale_asymmetry.dKx -5.8 +- 22.7 mg/g selected at LR 1486).
        if (t.absorbs.empty() && t.p_value < threshold && r.estimate.cov.rows() == aug.size()) {
          std::set<std::string> undetermined;
          for (const WeakDirection& w : UnsupportedDirections(aug, r.estimate.cov, r.prior.sigma)) {
            for (const auto& [name, weight] : w.weights) {
              if (std::abs(weight) >= 0.2) undetermined.insert(name);
            }
          }
          std::string names;
          bool any_determined = false;
          for (int q : c.supported) {
            const std::string name = spec.name + "." + spec.params[q].name;
            if (std::find(r.held.begin(), r.held.end(), name) != r.held.end()) continue;
            if (undetermined.count(name)) {
              names += (names.empty() ? "" : ", ") + name;
            } else {
              any_determined = true;
            }
          }
          if (!any_determined && !names.empty()) {
            t.absorbs = names + ", which its refit does not determine (not estimable)";
          }
        }
        // Significant, but not through the components the run determines
        // well: what it finds rides on directions the run does not determine.
        if (t.absorbs.empty() && !c.weak.empty() && t.p_value < threshold &&
            !(c.p_value_strong < threshold)) {
          std::string names;
          for (const auto& w : c.weak) {
            names += (names.empty() ? "" : ", ") + spec.name + "." + spec.params[w.first].name;
          }
          t.absorbs = names +
                      ", which this run determines only weakly (the components it "
                      "determines well score " +
                      FormatNumber(c.statistic_strong) + ", p " + FormatNumber(c.p_value_strong) +
                      ")";
        }
      }
      return r;
    };
    int refit_count = 0;
    for (const CandidateInformation& c : info.candidates) {
      const Effect e = c.effect;
      CandidateTest t;
      t.effect = e;
      t.round = round;
      t.dof = static_cast<int>(c.supported.size());
      t.score = c.statistic;
      t.score_p_value = c.p_value;
      t.statistic = c.statistic;
      t.p_value = c.p_value;
      t.lr = std::numeric_limits<double>::quiet_NaN();
      if (t.dof == 0) {
        t.p_value = 1.0;
        t.note = "not supported by this run's motion";
        if (!c.not_separable.empty()) {
          // Every component the data reach, the base parameters explain.
          const EffectSpec& spec = GetEffectSpec(e);
          t.note = "not tested: not separable from the base parameters:";
          for (const NotSeparable& ns : c.not_separable) {
            t.note += " " + spec.name + "." + spec.params[ns.component].name + " from " +
                      ns.with + " (rho " + FormatNumber(ns.rho) + ")";
          }
        }
        tests.push_back(t);
        refits.emplace_back();
        continue;
      }
      if (only_weak(c)) {
        double most = 0.0;
        for (const auto& w : c.weak) most = std::max(most, w.second);
        t.dof = 0;
        t.p_value = 1.0;
        t.note =
            "not tested: this run determines each of its components only weakly (data "
            "information at most " +
            FormatNumber(most) + " times its prior's, " + FormatNumber(kMinInformationFound) +
            " needed), so a fit could not tell it from its prior";
        tests.push_back(t);
        refits.emplace_back();
        continue;
      }
      if (!refit_it(c)) {
        t.note = "score test only: p above " + FormatNumber(opt.refit_factor) +
                 " x the threshold or far behind the best candidate, not refitted";
        tests.push_back(t);
        refits.emplace_back();
        continue;
      }
      BatchResult r = refit_candidate(c, &t, &refit_count);
      tests.push_back(t);
      refits.push_back(std::move(r));
    }
    // A refit that passes only beyond its plausible size absorbs something
    // else; the score ranking (a linearisation) can put such a candidate far
    // ahead of the real one (real fast roll run: size_effect's score 28608,
    // its refit's statistic 1806 at an implausible 57 mm, while
    // angle_latency's 3703 was never refitted). Then the significant ones not
    // yet refitted are refitted, best score first, until one is plausible.
    {
      auto selectable = [&](const CandidateTest& t) {
        return t.refit && Significant(t, threshold) && t.absorbs.empty();
      };
      bool found = std::any_of(tests.begin(), tests.end(), selectable);
      while (!found) {
        int next = -1;
        for (std::size_t i = 0; i < tests.size(); ++i) {
          const CandidateTest& t = tests[i];
          if (t.refit || t.dof == 0 || !Significant(t, threshold)) continue;
          if (next < 0 || t.statistic > tests[next].statistic) next = static_cast<int>(i);
        }
        if (next < 0) break;
        CandidateTest& t = tests[next];
        t.note.clear();
        ++to_refit;
        refits[next] = refit_candidate(info.candidates[next], &t, &refit_count);
        found = selectable(t);
      }
    }
    std::vector<int> order(tests.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      const CandidateTest& x = tests[a];
      const CandidateTest& y = tests[b];
      const double px = DecisionP(x), py = DecisionP(y);
      return px < py || (px == py && x.statistic > y.statistic);
    });
    std::vector<CandidateTest> sorted;
    for (int i : order) sorted.push_back(tests[i]);
    for (CandidateTest& t : sorted) t.threshold = threshold;
    if (round == 1) {
      for (const CandidateInformation& c : info.candidates) {
        const EffectSpec& spec = GetEffectSpec(c.effect);
        for (const auto& [q, why] : c.held_because) {
          res.notes.push_back(spec.name + "." + spec.params[q].name + " held, not tested: " + why);
        }
        for (const NotSeparable& ns : c.not_separable) {
          res.notes.push_back(spec.name + "." + spec.params[ns.component].name +
                              " not tested: not separable from " + ns.with +
                              " (multiple correlation " + FormatNumber(ns.rho) +
                              " with the base parameters); at zero in a refit, its prior "
                              "uncertainty carried into the others' sigma");
        }
      }
    }
    // The weak components of every refitted candidate, once each.
    for (std::size_t i = 0; i < info.candidates.size(); ++i) {
      if (!tests[i].refit) continue;
      const EffectSpec& spec = GetEffectSpec(info.candidates[i].effect);
      for (const auto& [q, information] : info.candidates[i].weak) {
        const std::string name = spec.name + "." + spec.params[q].name;
        const std::string note =
            name +
            " leans on its prior in the refit: this run determines it only weakly (data "
            "information " +
            FormatNumber(information) + " times its prior's; below " +
            FormatNumber(kMinInformationFound) + " the run knows it less than its prior does)";
        bool seen = false;
        for (const std::string& n : res.notes) seen = seen || n.rfind(name + " leans on", 0) == 0;
        if (!seen) res.notes.push_back(note);
      }
    }
    // The first significant candidate of plausible size is selected; the
    // significant ones before it absorb something else.
    int pick = -1;
    for (std::size_t i = 0; i < sorted.size() && pick < 0; ++i) {
      CandidateTest& t = sorted[i];
      // A score-only candidate cannot be selected, but a refitted one behind
      // it in this order can (p underflows to 0 for strong effects, and the
      // tie is broken by statistics of two kinds, score and LR).
      if (!t.refit) continue;
      if (!Significant(t, threshold)) break;
      if (t.absorbs.empty()) {
        pick = static_cast<int>(i);
      } else {
        res.absorbing.push_back(t);
        candidates.erase(std::find(candidates.begin(), candidates.end(), t.effect));
      }
    }
    const bool pass = pick >= 0;
    if (pass) {
      sorted[pick].selected = true;
      const CandidateTest& s = sorted[pick];
      for (std::size_t i = pick + 1; i < sorted.size(); ++i) {
        const CandidateTest& t = sorted[i];
        if (!t.refit || !Significant(t, threshold) || !t.absorbs.empty()) continue;
        if ((s.statistic - s.dof) - (t.statistic - t.dof) < 2.0 * std::log(10.0)) {
          res.alternatives.push_back(t);
          res.notes.push_back(
              "round " + std::to_string(round) + ": " + GetEffectSpec(t.effect).name +
              " explains the residual about as well as " + GetEffectSpec(s.effect).name +
              " (chi2/dof " + FormatNumber(fit.chi2_per_dof) + " -> " +
              FormatNumber(t.chi2_per_dof_after) + " against -> " +
              FormatNumber(s.chi2_per_dof_after) + "; statistic " + FormatNumber(t.statistic) +
              " against " + FormatNumber(s.statistic) + "): the data do not tell them apart; " +
              GetEffectSpec(s.effect).name + " was selected for its smaller p-value");
        }
      }
    }
    if (round == 1) res.ranking = sorted;
    res.tests.insert(res.tests.end(), sorted.begin(), sorted.end());
    if (!pass) break;
    const Effect chosen = sorted[pick].effect;
    res.selected.push_back(chosen);
    current.push_back(chosen);
    const ParameterLayout next = res.before_layout.WithEffects(current);
    // The selected candidate's refit (with its covariance) is the new fit.
    const Eigen::Vector3d round_noise = fit.noise_used_mV;
    fit = std::move(refits[order[pick]]);
    if (fit_opt.estimate_noise) {
      char figures[200];
      std::snprintf(figures, sizeof(figures),
                    "round %d: reading noise re-estimated with %s added: %.3g %.3g %.3g (was "
                    "%.3g %.3g %.3g)",
                    round, GetEffectSpec(chosen).name.c_str(), fit.noise_used_mV[0],
                    fit.noise_used_mV[1], fit.noise_used_mV[2], round_noise[0], round_noise[1],
                    round_noise[2]);
      res.notes.push_back(figures);
    }
    info_current = false;
    round_begin = round_end;
    round_end += 0.6 * (0.95 - round_end);
    layout = next;
    held = fit.held;
    candidates.erase(std::find(candidates.begin(), candidates.end(), chosen));
  }
  // Could hide: every candidate not selected, at the final fit.
  if (!candidates.empty()) {
    if (!info_current) {
      say("score analysis at the final fit");
      info = AnalyseCandidates(run, data, current, fit, candidates, fit_opt);
      last_threshold = opt.alpha / static_cast<double>(candidates.size());
    }
    for (const CandidateInformation& c : info.candidates) {
      if (std::find(candidates.begin(), candidates.end(), c.effect) == candidates.end()) continue;
      res.could_hide.push_back(MinimalDetectable(info, c, last_threshold, opt.power));
    }
    std::stable_sort(
        res.could_hide.begin(), res.could_hide.end(),
        [](const HideCase& a, const HideCase& b) { return a.max_shift_sigma > b.max_shift_sigma; });
  }
  say("analysing the residual");
  if (opt.fraction) opt.fraction(0.95);
  res.after_layout = layout;
  res.after = fit;
  res.after_residuals = res.selected.empty()
                            ? res.before_residuals
                            : AnalyzeResiduals(run, data, res.after_layout, res.after);
  res.unexplained = res.after_residuals.structure || !res.absorbing.empty();
  res.correlations = Correlations(res.after_layout, res.after, res.selected);
  res.beyond_prior =
      BeyondPrior(res.after_layout, res.after.estimate.theta, res.after.prior.mean,
                  res.after.prior.sigma);

  std::ostringstream v;
  if (res.selected.empty()) {
    v << "no catalogue effect is supported by the data";
  } else {
    v << "added";
    for (Effect e : res.selected) v << " " << GetEffectSpec(e).name;
  }
  for (const CandidateTest& t : res.absorbing) {
    v << "; " << GetEffectSpec(t.effect).name << " fits the residual (p " << FormatNumber(t.p_value)
      << ") only with " << t.absorbs << ": it ABSORBS SOMETHING ELSE, not reported as found";
  }
  if (res.after_residuals.structure) {
    v << "; STRUCTURE REMAINS that no candidate explains: "
      << res.after_residuals.structure_summary;
  } else if (res.unexplained) {
    v << "; the residual looks white (chi2/dof " << std::round(1000 * res.after.chi2_per_dof) / 1000
      << ") but something outside the catalogue remains (above)";
  } else {
    v << "; the residual is consistent with the declared noise (white, chi2/dof "
      << std::round(1000 * res.after.chi2_per_dof) / 1000 << ")";
  }
  // Far from the nominal values after the loop: not calibration results (real
  // slow roll run: the shaft tilted by dpsi = 49 deg after the loop, Kx 20 %
  // high), whatever the residual says.
  if (!res.beyond_prior.empty()) {
    v << "; AFTER THE LOOP BEYOND 3 PRIOR SIGMA (value - nominal in prior sigma): "
      << DescribeExcursions(res.beyond_prior)
      << ": they absorb what the model still lacks, or the nominal values or priors are "
         "wrong; their values are not calibration results";
  }
  // What could hide: never a clean verdict without it.
  std::vector<std::string> hiding, unseen;
  for (const HideCase& h : res.could_hide) {
    if (h.direction.empty()) {
      unseen.push_back(GetEffectSpec(h.effect).name);
    } else if (h.max_shift_sigma > 1.0) {
      hiding.push_back(GetEffectSpec(h.effect).name + " up to " +
                       FormatNumber(h.minimal_detectable) + " " + h.unit +
                       " would go undetected "
                       "and move " +
                       h.parameter + " by up to " + FormatNumber(h.max_shift_sigma) + " sigma");
    }
  }
  if (!hiding.empty()) {
    v << "; BUT effects could hide: ";
    for (std::size_t i = 0; i < hiding.size(); ++i) v << (i ? "; " : "") << hiding[i];
  } else if (!res.could_hide.empty()) {
    v << "; no catalogue effect small enough to escape detection would move a parameter by "
         "more than 1 sigma";
  }
  if (!unseen.empty()) {
    v << "; this run's motion cannot detect";
    for (const std::string& u : unseen) v << " " << u;
  }
  res.verdict = v.str();
  return res;
}

}  // namespace triadcal
