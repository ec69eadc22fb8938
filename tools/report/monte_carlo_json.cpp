#include "tools/report/monte_carlo_json.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/model/errors.h"

namespace triadcal {

nlohmann::json MonteCarloSettingsJson(const MonteCarloSettings& s) {
  return {{"scenario", s.scenario},   {"effects", s.effects},       {"estimators", s.estimators},
          {"runs", s.runs},           {"first_seed", s.first_seed}, {"epoch_s", s.epoch_s},
          {"tolerance", s.tolerance}, {"rate_hz", s.rate_hz},       {"duration_s", s.duration_s},
          {"per_seed", s.per_seed},   {"gyro", s.gyro}};
}

MonteCarloSettings MonteCarloSettingsFromJson(const nlohmann::json& j, const std::string& where) {
  MonteCarloSettings s;
  try {
    s.scenario = j.at("scenario").get<std::string>();
    s.effects = j.at("effects").get<std::string>();
    s.estimators = j.at("estimators").get<std::vector<std::string>>();
    s.runs = j.at("runs").get<int>();
    s.first_seed = j.at("first_seed").get<std::uint64_t>();
    s.epoch_s = j.at("epoch_s").get<double>();
    s.tolerance = j.at("tolerance").get<double>();
    s.rate_hz = j.at("rate_hz").get<double>();
    s.duration_s = j.at("duration_s").get<double>();
    s.per_seed = j.at("per_seed").get<bool>();
    s.gyro = j.value("gyro", false);  // absent in shards written before the gyro
  } catch (const nlohmann::json::exception& e) {
    throw InputError(where + ": settings: " + e.what());
  }
  return s;
}

nlohmann::json MonteCarloJson(const MonteCarloSettings& a, const MonteCarloResult& r) {
  const ParameterLayout& L = r.layout;
  const int n = L.size();
  nlohmann::json out;
  out["command"] = "montecarlo";
  out["scenario"] = a.scenario;
  out["runs"] = a.runs;
  out["seeds"] = {a.first_seed, a.first_seed + a.runs - 1};
  out["threads"] = r.threads;
  out["estimators"] = a.estimators;
  out["settings"] = {{"epoch_s", a.epoch_s},
                     {"effects", a.effects},
                     {"rate_hz", a.rate_hz},
                     {"duration_s", a.duration_s}};
  out["sampling_error_relative"] = 1.0 / std::sqrt(2.0 * a.runs);
  nlohmann::json params = nlohmann::json::object();
  for (int i = 0; i < n; ++i) {
    const ParameterInfo& p = L.info(i);
    const double f = p.si_per_unit;
    nlohmann::json j = {{"unit", p.unit}, {"truth", r.truth[i] / f}, {"crb", r.crb[i] / f}};
    for (const EstimatorStats& st : r.estimators) {
      if (st.runs > 0 && st.held_runs[i] >= st.runs) {
        // Never estimated (held; the filter and the gyro): no figure to give.
        j[st.name] = {{"estimated", false}, {"held_runs", st.held_runs[i]}};
        continue;
      }
      const double spread = std::sqrt(
          std::max(0.0, st.scatter[i] * st.scatter[i] - st.mean_error[i] * st.mean_error[i]));
      j[st.name] = {
          {"mean_error", st.mean_error[i] / f},  {"bias_over_crb", st.mean_error[i] / r.crb[i]},
          {"scatter", st.scatter[i] / f},        {"spread_about_mean_over_crb", spread / r.crb[i]},
          {"mean_sigma", st.mean_sigma[i] / f},  {"scatter_over_crb", st.scatter[i] / r.crb[i]},
          {"rms_normalised_error", st.rms_z[i]}, {"max_abs_normalised_error", st.max_abs_z[i]},
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
    pooled[st.name] = {
        {"rms_normalised_error", st.pooled_rms_z}, {"runs", st.runs}, {"failures", st.failures}};
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
      if (std::abs(ratio - 1.0) >= std::abs(worst - 1.0))
        worst = ratio, worst_name = L.info(i).name;
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
  return out;
}

void PrintMonteCarlo(const MonteCarloSettings& a, const MonteCarloResult& r,
                     const nlohmann::json& out) {
  const ParameterLayout& L = r.layout;
  const int n = L.size();
  const nlohmann::json& check = out["scatter_over_crb"];
  std::printf("montecarlo: %s, %d runs (seeds %llu..%llu), %d threads, %.1f s (CRB %.2f s)\n",
              a.scenario.c_str(), a.runs, static_cast<unsigned long long>(a.first_seed),
              static_cast<unsigned long long>(a.first_seed + a.runs - 1), r.threads, r.seconds,
              r.crb_seconds);
  // The columns as wide as the longest name and unit (the gyro's: gyro.alpha_x,
  // (deg/s)/g).
  int wn = 9, wu = 7;
  for (int i = 0; i < n; ++i) {
    wn = std::max(wn, static_cast<int>(L.info(i).name.size()));
    wu = std::max(wu, static_cast<int>(L.info(i).unit.size()));
  }
  std::printf("%-*s %-*s %9s", wn, "", wu, "", "");
  for (const EstimatorStats& st : r.estimators) std::printf(" | %-33s", st.name.c_str());
  std::printf("\n%-*s %-*s %9s", wn, "parameter", wu, "unit", "CRB");
  for (std::size_t j = 0; j < r.estimators.size(); ++j) {
    std::printf(" | %9s %9s %6s %6s", "scatter", "sigma", "/CRB", "rms z");
  }
  std::printf("\n");
  for (int i = 0; i < n; ++i) {
    const ParameterInfo& p = L.info(i);
    const double f = p.si_per_unit;
    std::printf("%-*s %-*s %9.3g", wn, p.name.c_str(), wu, p.unit.c_str(), r.crb[i] / f);
    std::string held;  // the estimators that left it out, and in how many runs
    for (const EstimatorStats& st : r.estimators) {
      if (st.runs > 0 && st.held_runs[i] >= st.runs) {
        std::printf(" | %9s %9s %6s %6s", "-", "-", "-", "-");
      } else {
        std::printf(" | %9.3g %9.3g %6.3f %6.3f", st.scatter[i] / f, st.mean_sigma[i] / f,
                    st.scatter[i] / r.crb[i], st.rms_z[i]);
      }
      if (st.held_runs[i] > 0) {
        held += (held.empty() ? "" : ", ") + st.name + " in " + std::to_string(st.held_runs[i]);
      }
    }
    if (!held.empty()) std::printf("  not estimated by %s runs", held.c_str());
    std::printf("\n");
  }
  std::printf("sampling error of a scatter from %d runs: about %.1f %% (1/sqrt(2N))\n", a.runs,
              100.0 / std::sqrt(2.0 * a.runs));
  for (const EstimatorStats& st : r.estimators) {
    const nlohmann::json& c = check[st.name];
    std::printf(
        "%-5s: pooled rms z %.3f over %d runs%s; scatter/CRB %.3f .. %.3f, worst %s %.3f: %s\n",
        st.name.c_str(), st.pooled_rms_z, st.runs,
        st.failures ? (" (" + std::to_string(st.failures) + " FAILED)").c_str() : "",
        c["min_ratio"].get<double>(), c["max_ratio"].get<double>(),
        c["worst_parameter"].get<std::string>().c_str(), c["worst_ratio"].get<double>(),
        c["within_tolerance"].get<bool>() ? "within tolerance" : "OUTSIDE tolerance");
    std::printf(
        "       spread about the mean / CRB %.3f .. %.3f; largest bias %s %+.3f CRB (%.1f standard "
        "errors)\n",
        c["spread_about_mean_min_ratio"].get<double>(),
        c["spread_about_mean_max_ratio"].get<double>(),
        c["largest_bias_parameter"].get<std::string>().c_str(),
        c["largest_bias_over_crb"].get<double>(), c["bias_standard_errors"].get<double>());
  }
}

}  // namespace triadcal
