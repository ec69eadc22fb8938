// `triadcal montecarlo SCENARIO.yaml -n N -o OUT.json`: N simulated runs of a
// scenario through the EKF, the RTS smoother and the batch solver, their error
// scatter against their own sigma and against the Cramer-Rao bound
// (solvers/analysis/monte_carlo.h), in parallel over the cores.
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/model/errors.h"
#include "core/simulation/simulator.h"
#include "solvers/analysis/monte_carlo.h"
#include "tools/command_util.h"
#include "tools/commands.h"

namespace triadcal {
namespace {

struct MonteCarloArgs {
  std::string scenario, out_json, effects;
  std::string estimators = "ekf,rts,batch";
  int runs = 100;
  std::uint64_t first_seed = 1;
  int threads = 0;
  double epoch_s = 0.2;
  double tolerance = 0.1;
  bool per_seed = false;
};

std::vector<std::string> SplitComma(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

int RunMonteCarloCommand(const MonteCarloArgs& a) {
  if (a.runs < 1) throw InputError("-n: at least 1 run, got " + std::to_string(a.runs));
  if (!(a.tolerance > 0)) throw InputError("--tolerance: must be > 0");
  const Scenario s = LoadScenario(a.scenario);
  MonteCarloOptions opt;
  opt.runs = a.runs;
  opt.first_seed = a.first_seed;
  opt.threads = a.threads;
  opt.estimators = SplitComma(a.estimators);
  opt.layout = ParameterLayout(ParseEffectList(a.effects));
  opt.filter.epoch_s = a.epoch_s;
  opt.batch.epoch_s = a.epoch_s;
  opt.keep_runs = a.per_seed;
  opt.progress = [](int done, int total) {
    ShowProgress("montecarlo: " + std::to_string(done) + "/" + std::to_string(total) + " runs",
                 static_cast<double>(done) / total);
  };
  const MonteCarloResult r = RunMonteCarlo(s, opt);
  EndProgress();
  const ParameterLayout& L = r.layout;
  const int n = L.size();

  // ---- OUT.json
  nlohmann::json out;
  out["command"] = "montecarlo";
  out["scenario"] = a.scenario;
  out["runs"] = a.runs;
  out["seeds"] = {a.first_seed, a.first_seed + a.runs - 1};
  out["threads"] = r.threads;
  out["estimators"] = opt.estimators;
  out["settings"] = {{"epoch_s", a.epoch_s},
                     {"effects", a.effects},
                     {"rate_hz", s.profile.rate_hz},
                     {"duration_s", s.profile.duration_s}};
  out["sampling_error_relative"] = 1.0 / std::sqrt(2.0 * a.runs);
  nlohmann::json params = nlohmann::json::object();
  for (int i = 0; i < n; ++i) {
    const ParameterInfo& p = L.info(i);
    const double f = p.si_per_unit;
    nlohmann::json j = {{"unit", p.unit}, {"truth", r.truth[i] / f}, {"crb", r.crb[i] / f}};
    for (const EstimatorStats& st : r.estimators) {
      const double spread =
          std::sqrt(std::max(0.0, st.scatter[i] * st.scatter[i] - st.mean_error[i] * st.mean_error[i]));
      j[st.name] = {{"mean_error", st.mean_error[i] / f},
                    {"bias_over_crb", st.mean_error[i] / r.crb[i]},
                    {"scatter", st.scatter[i] / f},
                    {"spread_about_mean_over_crb", spread / r.crb[i]},
                    {"mean_sigma", st.mean_sigma[i] / f},
                    {"scatter_over_crb", st.scatter[i] / r.crb[i]},
                    {"rms_normalised_error", st.rms_z[i]},
                    {"max_abs_normalised_error", st.max_abs_z[i]},
                    {"held_runs", st.held_runs[i]}};
    }
    params[p.name] = j;
  }
  out["parameters"] = params;
  nlohmann::json crb = nlohmann::json::object();
  for (int i = 0; i < n; ++i) crb[L.info(i).name] = r.crb[i] / L.info(i).si_per_unit;
  out["crb"] = crb;
  nlohmann::json pooled = nlohmann::json::object();
  for (const EstimatorStats& st : r.estimators) {
    pooled[st.name] = {{"rms_normalised_error", st.pooled_rms_z},
                       {"runs", st.runs},
                       {"failures", st.failures}};
    if (!st.first_failure.empty()) pooled[st.name]["first_failure"] = st.first_failure;
  }
  out["pooled"] = pooled;
  // The check: scatter of each estimator within `tolerance` of the CRB.
  nlohmann::json check = nlohmann::json::object();
  for (const EstimatorStats& st : r.estimators) {
    double worst = 1.0, lo = 1e300, hi = 0.0, spread_lo = 1e300, spread_hi = 0.0, bias = 0.0;
    std::string worst_name, bias_name;
    for (int i = 0; i < n; ++i) {
      if (st.held_runs[i] >= st.runs) continue;  // never estimated
      const double ratio = st.scatter[i] / r.crb[i];
      const double b = st.mean_error[i] / r.crb[i];
      const double spread = std::sqrt(std::max(0.0, ratio * ratio - b * b));
      lo = std::min(lo, ratio);
      hi = std::max(hi, ratio);
      spread_lo = std::min(spread_lo, spread);
      spread_hi = std::max(spread_hi, spread);
      if (std::abs(ratio - 1.0) >= std::abs(worst - 1.0)) worst = ratio, worst_name = L.info(i).name;
      if (std::abs(b) >= std::abs(bias)) bias = b, bias_name = L.info(i).name;
    }
    check[st.name] = {{"min_ratio", lo},
                      {"max_ratio", hi},
                      {"worst_parameter", worst_name},
                      {"worst_ratio", worst},
                      {"spread_about_mean_min_ratio", spread_lo},
                      {"spread_about_mean_max_ratio", spread_hi},
                      {"largest_bias_parameter", bias_name},
                      {"largest_bias_over_crb", bias},
                      {"bias_standard_errors", bias * std::sqrt(static_cast<double>(st.runs))},
                      {"tolerance", a.tolerance},
                      {"within_tolerance", std::abs(worst - 1.0) <= a.tolerance}};
  }
  out["scatter_over_crb"] = check;
  if (a.per_seed) {
    nlohmann::json runs = nlohmann::json::array();
    for (const MonteCarloRun& run : r.runs) {
      nlohmann::json jr = {{"seed", run.seed}};
      for (std::size_t j = 0; j < r.estimators.size(); ++j) {
        if (run.error[j].size() == 0) {
          jr[r.estimators[j].name] = nullptr;
          continue;
        }
        std::vector<double> e(n), sg(n);
        for (int i = 0; i < n; ++i) {
          e[i] = run.error[j][i] / L.info(i).si_per_unit;
          sg[i] = run.sigma[j][i] / L.info(i).si_per_unit;
        }
        jr[r.estimators[j].name] = {{"error", e}, {"sigma", sg}};
      }
      runs.push_back(jr);
    }
    nlohmann::json names = nlohmann::json::array();
    for (int i = 0; i < n; ++i) names.push_back(L.info(i).name);
    out["per_seed"] = {{"parameters", names}, {"runs", runs}};
  }
  out["time_s"] = {{"total", r.seconds}, {"crb", r.crb_seconds}};
  WriteJson(out, a.out_json);

  // ---- stdout
  std::printf("montecarlo: %s, %d runs (seeds %llu..%llu), %d threads, %.1f s (CRB %.2f s)\n",
              a.scenario.c_str(), a.runs, static_cast<unsigned long long>(a.first_seed),
              static_cast<unsigned long long>(a.first_seed + a.runs - 1), r.threads, r.seconds,
              r.crb_seconds);
  std::printf("%-9s %-7s %9s", "", "", "");
  for (const EstimatorStats& st : r.estimators) std::printf(" | %-33s", st.name.c_str());
  std::printf("\n%-9s %-7s %9s", "parameter", "unit", "CRB");
  for (std::size_t j = 0; j < r.estimators.size(); ++j) {
    std::printf(" | %9s %9s %6s %6s", "scatter", "sigma", "/CRB", "rms z");
  }
  std::printf("\n");
  for (int i = 0; i < n; ++i) {
    const ParameterInfo& p = L.info(i);
    const double f = p.si_per_unit;
    std::printf("%-9s %-7s %9.3g", p.name.c_str(), p.unit.c_str(), r.crb[i] / f);
    for (const EstimatorStats& st : r.estimators) {
      std::printf(" | %9.3g %9.3g %6.3f %6.3f", st.scatter[i] / f, st.mean_sigma[i] / f,
                  st.scatter[i] / r.crb[i], st.rms_z[i]);
    }
    int held = 0;
    for (const EstimatorStats& st : r.estimators) held = std::max(held, st.held_runs[i]);
    if (held > 0) std::printf("  held in %d runs", held);
    std::printf("\n");
  }
  std::printf("sampling error of a scatter from %d runs: about %.1f %% (1/sqrt(2N))\n", a.runs,
              100.0 / std::sqrt(2.0 * a.runs));
  for (const EstimatorStats& st : r.estimators) {
    const nlohmann::json& c = check[st.name];
    std::printf("%-5s: pooled rms z %.3f over %d runs%s; scatter/CRB %.3f .. %.3f, worst %s %.3f: %s\n",
                st.name.c_str(), st.pooled_rms_z, st.runs,
                st.failures ? (" (" + std::to_string(st.failures) + " FAILED)").c_str() : "",
                c["min_ratio"].get<double>(), c["max_ratio"].get<double>(),
                c["worst_parameter"].get<std::string>().c_str(), c["worst_ratio"].get<double>(),
                c["within_tolerance"].get<bool>() ? "within tolerance" : "OUTSIDE tolerance");
    std::printf("       spread about the mean / CRB %.3f .. %.3f; largest bias %s %+.3f CRB (%.1f standard errors)\n",
                c["spread_about_mean_min_ratio"].get<double>(),
                c["spread_about_mean_max_ratio"].get<double>(),
                c["largest_bias_parameter"].get<std::string>().c_str(),
                c["largest_bias_over_crb"].get<double>(), c["bias_standard_errors"].get<double>());
  }
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddMonteCarloCommand(CLI::App& app) {
  auto a = std::make_shared<MonteCarloArgs>();
  Command c;
  c.app = app.add_subcommand(
      "montecarlo", "N simulated runs through EKF, RTS and batch: error scatter against sigma and CRB");
  c.app->add_option("scenario", a->scenario, "SCENARIO.yaml")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("-n,--runs", a->runs, "number of runs (seeds first-seed .. first-seed + n - 1)")
      ->capture_default_str();
  c.app->add_option("--first-seed", a->first_seed, "first seed")->capture_default_str();
  c.app->add_option("--estimators", a->estimators, "comma-separated: ekf, rts, batch")
      ->capture_default_str();
  c.app->add_option("--threads", a->threads, "parallel runs (0: all cores)")->capture_default_str();
  c.app->add_option("--effects", a->effects, "catalogue effects to estimate too, e.g. a,b");
  c.app->add_option("--epoch-s", a->epoch_s, "interval between epochs [s]")->capture_default_str()
      ->check(kEpochRange);
  c.app->add_option("--tolerance", a->tolerance,
                    "relative tolerance of scatter / CRB reported as within or outside")
      ->capture_default_str();
  c.app->add_flag("--per-seed", a->per_seed, "add every run's errors and sigmas to OUT");
  c.run = [a] { return RunMonteCarloCommand(*a); };
  return c;
}

}  // namespace triadcal
