#include "app/design_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "app/option_lists.h"
#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

double ParsePositive(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v) || !(v > 0.0)) {
    throw InputError(option + ": expected a positive number, got '" + text + "'");
  }
  return v;
}

// The flags of the DesignStudyOptions settings, for errors found below.
const std::map<std::string, std::string>& DesignFlags() {
  static const std::map<std::string, std::string> flags = {
      {"durations_s", "--durations"},
      {"targets", "--target"},
      {"static_duration_s", "--static-duration"},
      {"static_positions", "--static-positions"}};
  return flags;
}

nlohmann::json SettingsJson(const Scenario& s, const DesignStudy& r,
                            const DesignSettings& settings) {
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
                              const DesignSettings& settings) {
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

nlohmann::json DesignJson(const Scenario& s, const std::string& scenario_path,
                          const ParameterLayout& layout, const DesignStudyOptions& options,
                          const DesignStudy& r, const DesignSettings& settings) {
  nlohmann::json out;
  out["command"] = "design";
  out["scenario"] = scenario_path;
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

}  // namespace

std::vector<double> ParsePositiveList(const std::string& text, const std::string& option) {
  std::vector<double> out;
  for (const std::string& item : SplitList(text)) out.push_back(ParsePositive(item, option));
  if (out.empty()) throw InputError(option + ": expected a comma-separated list, got nothing");
  return out;
}

// "30:12,60:24" -> pairs.
std::vector<std::array<double, 2>> ParsePairs(const std::string& text, const std::string& option) {
  std::vector<std::array<double, 2>> out;
  for (const std::string& item : SplitList(text)) {
    const std::size_t colon = item.find(':');
    if (colon == std::string::npos) {
      throw InputError(option + ": expected OUTER:INNER pairs such as 30:12, got '" + item + "'");
    }
    out.push_back({ParsePositive(item.substr(0, colon), option),
                   ParsePositive(item.substr(colon + 1), option)});
  }
  if (out.empty()) throw InputError(option + ": expected OUTER:INNER pairs, got nothing");
  return out;
}

std::vector<DesignTarget> ParseDesignTargets(const std::string& text) {
  std::vector<DesignTarget> out;
  for (const std::string& item : SplitList(text)) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      throw InputError("--target: expected NAME=SIGMA (file units) such as K=0.5, got '" + item +
                       "'");
    }
    DesignTarget t;
    t.key = item.substr(0, eq);
    t.sigma_file = ParsePositive(item.substr(eq + 1), "--target");
    out.push_back(t);
  }
  return out;
}

std::string ListText(const std::vector<double>& values) {
  std::string text;
  char v[32];
  for (double x : values) {
    std::snprintf(v, sizeof(v), "%g", x);
    text += (text.empty() ? "" : ",") + std::string(v);
  }
  return text;
}

std::string TargetsText(const std::vector<DesignTarget>& targets) {
  std::string text;
  char v[32];
  for (const DesignTarget& t : targets) {
    std::snprintf(v, sizeof(v), "%g", t.sigma_file);
    text += (text.empty() ? "" : ",") + t.key + "=" + v;
  }
  return text;
}

void DesignSettings::Validate() const {
  // Targets may name the gyro's parameters (a scenario with a gyro block).
  const ParameterLayout layout(ParseEffectList(effects), true);
  if (durations_s.empty()) {
    throw InputError("--durations: expected a comma-separated list, got nothing");
  }
  for (double d : durations_s) {
    if (!std::isfinite(d) || !(d > 0.0)) {
      throw InputError("--durations: expected a positive number, got '" + ListText({d}) + "'");
    }
  }
  WithFlags(DesignFlags(), [&] {
    for (const DesignTarget& t : targets) TargetIndices(layout, t.key);
    StaticPositions(static_positions);
  });
  if (threads < 0 || threads > 1024) {
    throw InputError("--threads: Value " + std::to_string(threads) + " not in range 0 to 1024");
  }
}

DesignOutcome DesignRun(const DesignSettings& settings, const std::string& scenario_path,
                        const Scenario& s, const Session& session) {
  settings.Validate();
  const auto t_start = std::chrono::steady_clock::now();
  DesignOutcome o;
  // The gyro's parameters when the scenario's run has a gyro block (its
  // noise-free run then has gx gy gz, and the information their increments).
  o.layout = ParameterLayout(ParseEffectList(settings.effects), s.run.gyro.has_value(),
                             ReadingsUnit(s.run));
  DesignStudyOptions& opt = o.options;
  opt.durations_s = settings.durations_s;
  std::sort(opt.durations_s.begin(), opt.durations_s.end());
  opt.targets = settings.targets;
  WithFlags(DesignFlags(), [&] {
    for (DesignTarget& t : opt.targets) t.indices = TargetIndices(o.layout, t.key);
  });
  opt.static_positions = settings.static_positions;
  opt.static_duration_s = settings.static_duration_s;
  opt.design_duration_s = settings.design_duration_s;
  opt.periods_s = settings.periods_s;
  opt.amplitudes_deg = settings.amplitudes_deg;
  opt.design.epoch_s = settings.epoch_s;
  opt.design.observability.threads = settings.threads;
  opt.progress = [&session](const std::string& what, double fraction) {
    if (session.stage) session.stage(what);
    if (session.fraction) session.fraction(fraction);
  };
  o.study = WithFlags(DesignFlags(), [&] { return RunDesignStudy(s, o.layout, opt); });
  o.json = DesignJson(s, scenario_path, o.layout, opt, o.study, settings);
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  o.json["time_s"] = o.seconds;
  return o;
}

}  // namespace triadcal
