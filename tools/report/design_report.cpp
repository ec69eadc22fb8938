#include "tools/report/design_report.h"

#include <cmath>
#include <cstdio>

#include "core/io/file_util.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

std::string PairText(double a, double b) {
  char t[48];
  std::snprintf(t, sizeof(t), "%g:%g", a, b);
  return t;
}

nlohmann::json SettingsJson(const Scenario& s, const DesignStudy& r,
                            const DesignReportSettings& settings) {
  nlohmann::json j = {{"rate_hz", s.profile.rate_hz},
                      {"declared_noise_mV", s.run.noise_mV},
                      {"declared_angle_noise_arcsec", s.run.angle_noise_rad / kArcsecToRad},
                      {"epoch_s", settings.epoch_s},
                      {"design_duration_s", r.design_duration_s},
                      {"static_duration_s", r.static_duration_s},
                      {"static_positions", settings.static_positions},
                      {"effects", settings.effects}};
  nlohmann::json pos = nlohmann::json::array();
  for (const auto& p : r.positions) pos.push_back({p[0] / kDegToRad, p[1] / kDegToRad});
  j["static_positions_deg"] = pos;
  return j;
}

nlohmann::json SigmaSeriesJson(const ParameterLayout& layout, const DesignStudy& r,
                               const std::vector<DesignPoint>& pts) {
  nlohmann::json sig = nlohmann::json::object(), slope = nlohmann::json::object();
  for (int i = 0; i < layout.size(); ++i) {
    std::vector<double> v;
    for (const DesignPoint& d : pts) {
      v.push_back(Undetermined(d, layout.info(i).name) ? std::nan("")
                                                       : d.sigma[i] / layout.info(i).si_per_unit);
    }
    sig[layout.info(i).name] = v;
    const double sl = LogSlope(r.durations_s, v, 60.0);
    slope[layout.info(i).name] = std::isfinite(sl) ? nlohmann::json(sl) : nlohmann::json();
  }
  nlohmann::json unobs = nlohmann::json::array();
  for (const DesignPoint& d : pts) unobs.push_back(d.unobservable);
  return nlohmann::json{{"sigma", sig}, {"slope_log_log_from_60s", slope}, {"unobservable", unobs}};
}

nlohmann::json GridJson(const ParameterLayout& layout, const DesignStudy& r) {
  nlohmann::json jgrid = nlohmann::json::array();
  for (const DesignGridPoint& g : r.grid) {
    nlohmann::json sig = nlohmann::json::object(), worst = nlohmann::json::object();
    for (int i = 0; i < layout.size(); ++i) {
      sig[layout.info(i).name] = g.d.sigma[i] / layout.info(i).si_per_unit;
    }
    for (const ParameterGroup& grp : ParameterGroups()) {
      worst[grp.name] = WorstSigma(g.d, grp.members) / layout.info(grp.members[0]).si_per_unit;
    }
    jgrid.push_back({{"period_s", g.period_s},
                     {"amplitude_deg", g.amplitude_deg},
                     {"duration_s", r.design_duration_s},
                     {"sigma", sig},
                     {"worst_in_group", worst},
                     {"unobservable", g.d.unobservable}});
  }
  return jgrid;
}

nlohmann::json TargetsJson(const ParameterLayout& layout, const DesignStudyOptions& o,
                           const DesignStudy& r) {
  nlohmann::json jt = nlohmann::json::array();
  for (std::size_t k = 0; k < o.targets.size(); ++k) {
    const DesignTarget& t = o.targets[k];
    const TargetResult& tr = r.targets[k];
    const double f = layout.info(t.indices[0]).si_per_unit;
    jt.push_back({{"target", t.key},
                  {"sigma", t.sigma_file},
                  {"unit", layout.info(t.indices[0]).unit},
                  {"reached", tr.reached},
                  {"duration_s", tr.duration_s},
                  {"sigma_at_duration", tr.sigma_at_duration / f},
                  {"searched_s", {r.target_min_s, r.target_max_s}},
                  {"evaluations", tr.evaluations}});
  }
  return jt;
}

nlohmann::json ComparisonJson(const ParameterLayout& layout, const DesignStudy& r,
                              const DesignReportSettings& settings) {
  nlohmann::json rows = nlohmann::json::object();
  for (int i = 0; i < layout.size(); ++i) {
    const double f = layout.info(i).si_per_unit;
    const std::string& name = layout.info(i).name;
    rows[name] = {{"unit", layout.info(i).unit},
                  {"quasi_harmonic", r.qh_design.sigma[i] / f},
                  {"static", r.static_long.sigma[i] / f},
                  {"static_same_duration", r.static_design.sigma[i] / f},
                  {"ratio_static_over_quasi_harmonic",
                   Undetermined(r.static_long, name) || Undetermined(r.qh_design, name)
                       ? nlohmann::json()
                       : nlohmann::json(r.static_long.sigma[i] / r.qh_design.sigma[i])}};
  }
  return {{"quasi_harmonic_duration_s", r.design_duration_s},
          {"static_duration_s", r.static_duration_s},
          {"static_positions", settings.static_positions},
          {"rows", rows},
          {"quasi_harmonic_not_determined", r.qh_design.unobservable},
          {"static_not_determined", r.static_long.unobservable}};
}

void PrintDurationTable(const ParameterLayout& layout, const DesignStudy& r, const char* what,
                        const std::vector<DesignPoint>& pts) {
  std::printf("\n%s: sigma against run duration [s] (* not determined: the prior's)\n", what);
  std::printf("%-9s %-7s", "parameter", "unit");
  for (double T : r.durations_s) std::printf(" %9g", T);
  std::printf(" %7s\n", "slope");
  for (int i = 0; i < layout.size(); ++i) {
    const double f = layout.info(i).si_per_unit;
    std::printf("%-9s %-7s", layout.info(i).name.c_str(), layout.info(i).unit.c_str());
    std::vector<double> v;
    for (const DesignPoint& d : pts) {
      const bool held = Undetermined(d, layout.info(i).name);
      std::printf(" %8.3g%s", d.sigma[i] / f, held ? "*" : " ");
      v.push_back(held ? std::nan("") : d.sigma[i] / f);
    }
    const double slope = LogSlope(r.durations_s, v, 60.0);
    if (std::isfinite(slope)) {
      std::printf(" %7.3f\n", slope);
    } else {
      std::printf(" %7s\n", "-");
    }
  }
}

void PrintGrid(const ParameterLayout& layout, const DesignStudy& r) {
  std::printf("\nprofiles at %g s: worst sigma per group (* not determined)\n",
              r.design_duration_s);
  std::printf("%-12s %-12s", "periods s", "ampl. deg");
  for (const ParameterGroup& g : ParameterGroups()) std::printf(" %10s", g.name.c_str());
  std::printf("  unobservable\n");
  for (const DesignGridPoint& g : r.grid) {
    std::printf("%-12s %-12s", PairText(g.period_s[0], g.period_s[1]).c_str(),
                PairText(g.amplitude_deg[0], g.amplitude_deg[1]).c_str());
    for (const ParameterGroup& grp : ParameterGroups()) {
      std::printf(" %9.3g%s",
                  WorstSigma(g.d, grp.members) / layout.info(grp.members[0]).si_per_unit,
                  AnyUndetermined(g.d, layout, grp.members) ? "*" : " ");
    }
    std::string held;
    for (const std::string& h : g.d.unobservable) held += (held.empty() ? "" : " ") + h;
    std::printf("  %s\n", held.empty() ? "-" : held.c_str());
  }
}

void PrintTargets(const ParameterLayout& layout, const DesignStudyOptions& o,
                  const DesignStudy& r) {
  std::printf("\n");
  for (std::size_t k = 0; k < o.targets.size(); ++k) {
    const DesignTarget& t = o.targets[k];
    const TargetResult& tr = r.targets[k];
    const std::string unit = layout.info(t.indices[0]).unit;
    if (tr.reached) {
      std::printf(
          "target sigma(%s) <= %g %s: reached after %.3g s of the profile (sigma %.3g; %d CRB "
          "evaluations)\n",
          t.key.c_str(), t.sigma_file, unit.c_str(), tr.duration_s,
          tr.sigma_at_duration / layout.info(t.indices[0]).si_per_unit, tr.evaluations);
    } else {
      std::printf("target sigma(%s) <= %g %s: NOT reached within %g s (sigma %.3g there)\n",
                  t.key.c_str(), t.sigma_file, unit.c_str(), tr.duration_s,
                  tr.sigma_at_duration / layout.info(t.indices[0]).si_per_unit);
    }
  }
}

void PrintComparison(const ParameterLayout& layout, const DesignStudy& r,
                     const DesignReportSettings& settings) {
  const double Td = r.design_duration_s, Ts = r.static_duration_s;
  std::printf(
      "\nquasi-harmonic %g s against the static %d-position method, %g s (* not determined)\n", Td,
      settings.static_positions, Ts);
  std::printf("%-9s %-7s %14s %14s %14s %10s\n", "parameter", "unit", "quasi-harm.", "static",
              "static same T", "ratio");
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& p = layout.info(i);
    const double f = p.si_per_unit;
    auto held = [&](const DesignPoint& d) { return Undetermined(d, p.name) ? "*" : " "; };
    char ratio[32];
    if (Undetermined(r.static_long, p.name) || Undetermined(r.qh_design, p.name)) {
      std::snprintf(ratio, sizeof(ratio), "%10s", "-");
    } else {
      std::snprintf(ratio, sizeof(ratio), "%10.3g", r.static_long.sigma[i] / r.qh_design.sigma[i]);
    }
    std::printf("%-9s %-7s %13.3g%s %13.3g%s %13.3g%s %s\n", p.name.c_str(), p.unit.c_str(),
                r.qh_design.sigma[i] / f, held(r.qh_design), r.static_long.sigma[i] / f,
                held(r.static_long), r.static_design.sigma[i] / f, held(r.static_design), ratio);
  }
  std::printf(
      "(ratio: static %g s sigma / quasi-harmonic %g s sigma; -: not determined by one of them)\n",
      Ts, Td);
}

}  // namespace

nlohmann::json DesignJson(const Scenario& s, const ParameterLayout& layout,
                          const DesignStudyOptions& options, const DesignStudy& r,
                          const DesignReportSettings& settings) {
  nlohmann::json out;
  out["command"] = "design";
  out["scenario"] = settings.scenario_path;
  nlohmann::json units = nlohmann::json::object();
  for (int i = 0; i < layout.size(); ++i) units[layout.info(i).name] = layout.info(i).unit;
  out["units"] = units;
  out["settings"] = SettingsJson(s, r, settings);
  out["duration"] = {{"durations_s", r.durations_s},
                     {"quasi_harmonic", SigmaSeriesJson(layout, r, r.quasi_harmonic)},
                     {"static", SigmaSeriesJson(layout, r, r.static_test)}};
  out["profiles"] = GridJson(layout, r);
  out["targets"] = TargetsJson(layout, options, r);
  out["comparison"] = ComparisonJson(layout, r, settings);
  // What the HTML report draws (--report, or `triadcal report`): per group
  // the worst and best sigma of both methods against duration, from
  // "duration" above (null where the method does not determine a member).
  nlohmann::json groups = nlohmann::json::array();
  for (const ParameterGroup& g : ParameterGroups()) {
    std::vector<std::string> members;
    for (int i : g.members) members.push_back(layout.info(i).name);
    groups.push_back({{"name", g.name},
                      {"label", g.label},
                      {"unit", layout.info(g.members[0]).unit},
                      {"members", members}});
  }
  out["duration"]["groups"] = groups;
  out["duration"]["static_positions"] = settings.static_positions;
  return out;
}


void PrintDesign(const Scenario& s, const ParameterLayout& layout,
                 const DesignStudyOptions& options, const DesignStudy& r,
                 const DesignReportSettings& settings) {
  std::printf("design: %s, %g Hz, declared noise %g mV, %g arcsec; static test: %d positions\n",
              settings.scenario_path.c_str(), s.profile.rate_hz, s.run.noise_mV,
              s.run.angle_noise_rad / kArcsecToRad, settings.static_positions);
  PrintDurationTable(layout, r, "quasi-harmonic profile", r.quasi_harmonic);
  PrintDurationTable(layout, r, "static multi-position test", r.static_test);
  std::printf("(slope: log-log over durations >= 60 s; -0.5 is 1/sqrt(T))\n");
  PrintGrid(layout, r);
  PrintTargets(layout, options, r);
  PrintComparison(layout, r, settings);
}

}  // namespace triadcal
