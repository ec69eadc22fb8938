#include "app/compare_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

#include "app/estimate_json.h"
#include "app/fit_job.h"
#include "app/option_lists.h"

namespace triadcal {
namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

nlohmann::json CompareJson(const std::string& run_yaml, const LoadedRun& run,
                           const CompareOutcome& c) {
  const ParameterLayout& layout = c.filter.layout;
  const FilterResult& fr = c.filter.result;
  const BatchResult& br = c.batch;
  const FitReport& rep = c.report;
  nlohmann::json out;
  out["command"] = "compare";
  out["run"] = run_yaml;
  out["ekf"] = {
      {"parameters", ParametersJson(layout, fr.ekf.theta, fr.ekf.cov, rep.not_estimable)}};
  out["rts"] = {
      {"parameters", ParametersJson(layout, fr.rts.theta, fr.rts.cov, rep.not_estimable)}};
  out["batch"] = {
      {"parameters", ParametersJson(layout, br.estimate.theta, br.estimate.cov, rep.not_estimable)},
      {"verdict", rep.verdict},
      {"chi2_per_dof", br.chi2_per_dof}};
  out["not_estimable"] = std::vector<std::string>(ParametersIn(rep.weak));
  if (c.filter.gyro && br.gyro.present) {
    // Each estimator's gyro block, with fit's keys: the smoother's (at the
    // noise the filter ran at) and the batch's (at its estimated noise).
    nlohmann::json batch = GyroJson(layout, br);
    AddGyroAnalysis(run.description, run.data, layout, br, rep, &batch);
    out["gyro"] = {{"rts", c.filter.json["gyro"]}, {"batch", batch}};
  }
  out["time_s"] = {{"filter", c.filter_s}, {"fit_from_rts", c.fit_s}};
  nlohmann::json diff = nlohmann::json::object();
  double max_abs = 0.0;
  std::string max_name;
  const std::set<std::string> nominal(c.filter.pinned.begin(), c.filter.pinned.end());
  for (int i = 0; i < layout.size(); ++i) {
    const std::string& name = layout.info(i).name;
    if (nominal.count(name)) {
      // Held at nominal by all three: no estimate, no difference.
      diff[name] = {{"rts_minus_ekf", nullptr},
                    {"batch_minus_rts", nullptr},
                    {"batch_minus_ekf", nullptr},
                    {"unit", "batch sigma"}};
      continue;
    }
    const double s = std::sqrt(std::max(br.estimate.cov(i, i), 1e-300));
    const double d_br = (br.estimate.theta[i] - fr.rts.theta[i]) / s;
    diff[name] = {{"rts_minus_ekf", (fr.rts.theta[i] - fr.ekf.theta[i]) / s},
                  {"batch_minus_rts", d_br},
                  {"batch_minus_ekf", (br.estimate.theta[i] - fr.ekf.theta[i]) / s},
                  {"unit", "batch sigma"}};
    if (!rep.not_estimable.count(name) && std::abs(d_br) > max_abs) {
      max_abs = std::abs(d_br);
      max_name = name;
    }
  }
  out["differences_in_sigma"] = diff;
  out["largest_batch_minus_rts"] = {{"parameter", max_name}, {"sigma", max_abs}};
  return out;
}

}  // namespace

void CompareSettings::Validate() const { ParseEffectList(effects); }

CompareOutcome CompareRun(const CompareSettings& s, const std::string& run_yaml,
                          const LoadedRun& run, const Session& session) {
  s.Validate();
  CompareOutcome c;
  // The filter job with its defaults: the fit job's decision of what the run
  // determines, held at nominal by both estimators.
  FilterSettings filter;
  filter.effects = s.effects;
  filter.epoch_s = s.epoch_s;
  Session filtering = session;
  if (session.stage) filtering.stage = [&](const std::string& x) { session.stage("filter " + x); };
  if (session.fraction) filtering.fraction = [&](double x) { session.fraction(0.5 * x); };
  auto t0 = std::chrono::steady_clock::now();
  c.filter = FilterRun(filter, run_yaml, run, filtering);
  c.filter_s = Seconds(t0);
  if (!c.filter.error.empty()) {
    c.error = c.filter.error;
    return c;
  }
  // The fit job's batch, started at the smoother's answer.
  FitSettings fit;
  fit.effects = s.effects;
  fit.epoch_s = s.epoch_s;
  BatchOptions bo = MakeBatchOptions(fit);
  bo.decision = &c.filter.decision;
  bo.init = BatchInit::kGiven;
  bo.init_theta = c.filter.result.rts.theta;
  if (session.stage) bo.progress = [&](const std::string& x) { session.stage("fit " + x); };
  if (session.fraction) bo.fraction = [&](double x) { session.fraction(0.5 + 0.5 * x); };
  t0 = std::chrono::steady_clock::now();
  c.batch = SolveBatch(run.description, run.data, c.filter.layout, bo);
  c.batch.initial = c.filter.result.rts;
  c.fit_s = Seconds(t0);
  c.report = MakeFitReport(c.filter.layout, c.batch);
  c.json = CompareJson(run_yaml, run, c);
  return c;
}

}  // namespace triadcal
