#include "app/filter_job.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sstream>

#include "app/estimate_json.h"
#include "app/fit_report.h"
#include "app/option_lists.h"
#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/priors.h"
#include "core/model/sample_noise.h"
#include "core/model/units.h"
#include "solvers/estimation/observability.h"

namespace triadcal {

void FilterSettings::Validate() const {
  if (iterations < 1 || iterations > kMaxFilterIterations) {
    throw InputError("--iterations: Value " + std::to_string(iterations) + " not in range 1 to " +
                     std::to_string(kMaxFilterIterations));
  }
  CheckHoldFree(hold, free, ParameterLayout(ParseEffectList(effects)));
  AngleDerivativeOptions window;
  window.half_window_s = rate_window_s;
  WithFlags({{"half_window_s", "--rate-window-s"}}, [&] { window.Check(); });
}

std::string FilterSeriesCsv(const ParameterLayout& layout, const FilterResult& r) {
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

nlohmann::json FilterGyroJson(const RunDescription& run, const RunData& data,
                              const FilterOutcome& f) {
  // The smoother's estimate as fit's report reads one (a batch result with
  // the RTS theta and the filter's gyro summary), its noise the estimate at
  // that theta; then what the filter ran at.
  const FilterResult& r = f.result;
  BatchResult view;
  view.estimate = r.rts;
  view.prior = r.prior;
  view.converged = true;
  view.held = f.decision.held;
  view.consider = f.decision.consider;
  view.relative_to = f.decision.relative_to;
  view.gyro = r.gyro;
  view.gyro.noise_rad_s = r.gyro_noise_ml_rad_s;
  view.gyro.noise_declared_rad_s = run.gyro ? run.gyro->noise_rad_s : r.gyro.noise_declared_rad_s;
  view.gyro.noise_auto = run.gyro && run.gyro->noise_auto;
  FitReport rep;
  rep.weak = f.weak;
  rep.not_estimable = f.not_estimable;
  rep.held.insert(f.decision.held.begin(), f.decision.held.end());
  rep.consider.insert(f.decision.consider.begin(), f.decision.consider.end());
  rep.beyond_prior = BeyondPrior(f.layout, r.rts.theta, r.prior.mean, r.prior.sigma);
  nlohmann::json g = GyroJson(f.layout, view);
  // The readings' unit: |gyro.K_i| times the rate noise (GyroJson's).
  const int go = f.layout.gyro_offset();
  std::vector<double> used(3);
  for (int i = 0; i < 3; ++i) {
    used[i] = r.gyro.noise_rad_s[i] * std::abs(r.rts.theta[go + kGKx + i]) / kDegToRad;
  }
  g["noise"]["used_dps"] = used;
  g["noise"]["source"] = view.gyro.noise_auto ? "readings' own white noise (noise_dps: auto)"
                                              : "declared";
  g["whitened_at"] = "the noise used";
  g["mean_nis"] = r.gyro_mean_nis;
  g["mean_nis_expected"] = 3;
  g["measurements"] = r.gyro_measurements;
  AddGyroAnalysis(run, data, f.layout, view, rep, &g);
  return g;
}

namespace {

nlohmann::json FilterJson(const FilterSettings& s, const std::string& run_yaml,
                          const LoadedRun& run, const FilterOutcome& f) {
  const ParameterLayout& layout = f.layout;
  const FilterResult& r = f.result;
  const HoldDecision& hd = f.decision;
  nlohmann::json out;
  out["command"] = "filter";
  out["run"] = run_yaml;
  out["ekf"] = {{"parameters", ParametersJson(layout, r.ekf.theta, r.ekf.cov, f.not_estimable)}};
  out["rts"] = {{"parameters", ParametersJson(layout, r.rts.theta, r.rts.cov, f.not_estimable)}};
  MarkRelative(hd.relative_to, &out["ekf"]["parameters"]);
  MarkRelative(hd.relative_to, &out["rts"]["parameters"]);
  if (s.correlations) out["rts"]["correlation"] = CorrelationJson(layout, r.rts.cov);
  // The weak directions, and the structural nulls a held parameter stands in.
  const std::set<std::string> pinned(f.pinned.begin(), f.pinned.end());
  std::vector<WeakDirection> unobservable = f.weak;
  for (const WeakDirection& d : hd.unsupported) {
    for (const auto& [name, w] : d.weights) {
      if (pinned.count(name)) {
        unobservable.push_back(d);
        break;
      }
    }
  }
  // Not estimable: the weak directions' parameters, the held ones, the
  // relative ones (in this order, as OUT has always listed them).
  std::vector<std::string> not_estimable = ParametersIn(f.weak);
  not_estimable.insert(not_estimable.end(), f.pinned.begin(), f.pinned.end());
  for (const auto& [name, anchors] : hd.relative_to) not_estimable.push_back(name);
  out["unobservable"] = WeakDirectionsJson(unobservable);
  out["not_estimable"] = not_estimable;
  out["held"] = hd.held;
  out["not_determined"] = hd.consider;
  out["unobservable_at_nominal"] = WeakDirectionsJson(hd.unsupported);
  out["settings"] = {{"epoch_s", s.epoch_s},
                     {"epochs", r.epochs},
                     {"passes", r.passes},
                     {"rate_source", run.data.has_rates() ? "rate columns" : "local cubic fit"},
                     {"rate_window_half_s", s.rate_window_s},
                     {"rate_noise_deg_s", r.rate_noise_rad_s / kDegToRad},
                     {"noise", {{"used", {f.noise[0], f.noise[1], f.noise[2]}},
                                {"unit", layout.readings_unit()},
                                {"auto", run.description.noise_auto}}},
                     {"effects", s.effects}};
  out["innovations"] = {
      {"rms_v_mps", {r.innovation_rms[0], r.innovation_rms[1], r.innovation_rms[2]}},
      {"rms_s_m", {r.innovation_rms[3], r.innovation_rms[4], r.innovation_rms[5]}},
      {"mean_nis", r.mean_nis},
      {"mean_nis_expected", 6}};
  if (f.gyro) out["gyro"] = FilterGyroJson(run.description, run.data, f);
  out["samples"] = run.data.size();
  out["time_s"] = f.seconds;
  return out;
}

}  // namespace

FilterOutcome FilterRun(const FilterSettings& s, const std::string& run_yaml, const LoadedRun& run,
                        const Session& session) {
  s.Validate();
  const auto t0 = std::chrono::steady_clock::now();
  FilterOutcome f;
  // The gyro's parameters beside the accelerometer's when the run has one,
  // as fit estimates them.
  f.gyro = run.description.gyro.has_value() && run.data.has_gyro();
  f.layout = ParameterLayout(ParseEffectList(s.effects, run.data), f.gyro,
                             ReadingsUnit(run.description));
  FilterOptions opt;
  opt.epoch_s = s.epoch_s;
  opt.derivatives.half_window_s = s.rate_window_s;
  opt.smoother_iterations = s.iterations;
  opt.keep_series = s.keep_series;
  opt.progress = [&session, passes = s.iterations, shown = 0](int pass, double x) mutable {
    if (session.stage && pass != shown) {
      session.stage("pass " + std::to_string(pass) + "/" + std::to_string(passes));
    }
    if (session.fraction) session.fraction((pass - 1 + x) / passes);
    shown = pass;
  };
  // The fit job's decision of what the run determines (held as a structural
  // null, or kept at nominal and considered in fit), all held here at their
  // nominal values (removed from the filter's state), so that the filter does
  // not wander along flat directions; its sigma of the others are conditional
  // on the held values. The filter estimates no noise: it runs at the
  // declared reading noise, with noise_mV: auto at the readings' own white
  // noise per channel (what fit starts from and decides at), and decides at it.
  const RunDescription declared = WithReadingNoise(run.description, run.data);
  f.noise = RunReadingNoise_mV(declared, run.data);
  BatchOptions holding;
  holding.epoch_s = s.epoch_s;
  holding.derivatives = opt.derivatives;
  holding.holding.auto_hold = s.auto_hold;
  holding.holding.hold = s.hold;
  holding.holding.free = s.free;
  f.decision = DecideHeldParameters(declared, run.data, f.layout, holding);
  f.pinned = f.decision.held;
  f.pinned.insert(f.pinned.end(), f.decision.consider.begin(), f.decision.consider.end());
  opt.held = f.pinned;
  f.result = RunFilterSmoother(declared, run.data, f.layout, opt);
  if (f.result.diverged_at_s >= 0.0 || !f.result.ekf.theta.allFinite() ||
      !f.result.rts.theta.allFinite()) {
    // No number to write: a diverged filter's estimate is not a result.
    char why[120] = "its estimate is not finite";
    if (f.result.diverged_at_s >= 0.0) {
      std::snprintf(why, sizeof(why), "its covariance lost its positive definiteness at t = %.3g s",
                    f.result.diverged_at_s);
    }
    f.error = run_yaml + ": the filter diverged (" + why +
              "): the readings are far from the nominal model (check triad.bias_mV, "
              "triad.scale_mV_per_g and the readings' unit)";
    return f;
  }
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Against the run's own prior: held parameters come out determined there.
  f.weak =
      UnsupportedDirections(f.layout, f.result.rts.cov, MakePrior(run.description, f.layout).sigma);
  f.not_estimable.insert(f.pinned.begin(), f.pinned.end());
  for (const std::string& name : ParametersIn(f.weak)) f.not_estimable.insert(name);
  for (const auto& [name, anchors] : f.decision.relative_to) f.not_estimable.insert(name);
  f.json = FilterJson(s, run_yaml, run, f);
  return f;
}

}  // namespace triadcal
