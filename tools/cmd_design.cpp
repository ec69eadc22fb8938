// `triadcal design SCENARIO.yaml -o OUT.json`: experiment design from the
// Cramer-Rao bound of the scenario's profile (solvers/analysis/experiment_design.h):
//   - sigma of every parameter against the run duration (15 s ... 40 min by
//     default), for the quasi-harmonic profile and for a static multi-position
//     test of the same total time;
//   - sigma against the profile's periods and amplitudes (a small grid);
//   - the shortest duration that reaches a target sigma (--target K=0.5);
//   - the scenario's design (the paper's 1.5 min) against the static method
//     (40 min) as a table, and all of it as a log-log SVG plot.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/model/errors.h"
#include "core/io/file_util.h"
#include "core/simulation/simulator.h"
#include "solvers/analysis/experiment_design.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/svg_plot.h"

namespace triadcal {
namespace {

struct DesignArgs {
  std::string scenario, out_json, plot_svg, effects;
  std::string durations = "15,30,60,90,300,600,2400";
  std::string periods, amplitudes;  // default: the scenario's x 0.5, 1, 2 / x 0.25, 0.5, 1
  std::string targets = "K=0.5";
  double design_duration_s = 0.0;  // 0: the scenario's
  double static_duration_s = 2400.0;
  int static_positions = 12;
  double epoch_s = 0.2;
  int threads = 0;
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

std::vector<double> ParseList(const std::string& text, const std::string& option) {
  std::vector<double> out;
  for (const std::string& item : SplitComma(text)) out.push_back(ParsePositive(item, option));
  if (out.empty()) throw InputError(option + ": expected a comma-separated list, got nothing");
  return out;
}

// "30:12,60:24" -> pairs.
std::vector<std::array<double, 2>> ParsePairs(const std::string& text, const std::string& option) {
  std::vector<std::array<double, 2>> out;
  for (const std::string& item : SplitComma(text)) {
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

struct Target {
  std::string key;
  double sigma_file = 0.0;
  std::vector<int> indices;
};

std::vector<Target> ParseTargets(const std::string& text, const ParameterLayout& layout) {
  std::vector<Target> out;
  for (const std::string& item : SplitComma(text)) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      throw InputError("--target: expected NAME=SIGMA (file units) such as K=0.5, got '" + item +
                       "'");
    }
    Target t;
    t.key = item.substr(0, eq);
    t.sigma_file = ParsePositive(item.substr(eq + 1), "--target");
    t.indices = TargetIndices(layout, t.key);
    out.push_back(t);
  }
  return out;
}

double Worst(const DesignPoint& d, const std::vector<int>& idx) {
  double w = 0.0;
  for (int i : idx) w = std::max(w, d.sigma[i]);
  return w;
}

double Best(const DesignPoint& d, const std::vector<int>& idx) {
  double b = 1e300;
  for (int i : idx) b = std::min(b, d.sigma[i]);
  return b;
}

bool Held(const DesignPoint& d, const std::string& name) {
  return std::find(d.unobservable.begin(), d.unobservable.end(), name) != d.unobservable.end();
}

bool AnyHeld(const DesignPoint& d, const ParameterLayout& L, const std::vector<int>& idx) {
  const std::set<std::string> held(d.unobservable.begin(), d.unobservable.end());
  for (int i : idx) {
    if (held.count(L.info(i).name)) return true;
  }
  return false;
}

// Least-squares slope of log sigma against log T over the points with T >= t_from.
double LogSlope(const std::vector<double>& T, const std::vector<double>& s, double t_from) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = 0; k < T.size(); ++k) {
    if (T[k] < t_from || !(s[k] > 0)) continue;  // also skips NaN (not determined)
    const double x = std::log(T[k]), y = std::log(s[k]);
    n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  if (n < 2) return std::nan("");
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

std::string PairText(double a, double b) {
  char t[48];
  std::snprintf(t, sizeof(t), "%g:%g", a, b);
  return t;
}

std::string DefaultSvgPath(const std::string& out_json) {
  const std::string ext = ".json";
  if (out_json.size() > ext.size() &&
      out_json.compare(out_json.size() - ext.size(), ext.size(), ext) == 0) {
    return out_json.substr(0, out_json.size() - ext.size()) + ".svg";
  }
  return out_json + ".svg";
}

int RunDesign(const DesignArgs& a) {
  const auto t_start = std::chrono::steady_clock::now();
  CheckOutputPath(a.out_json);
  CheckOutputPath(a.plot_svg.empty() ? DefaultSvgPath(a.out_json) : a.plot_svg);
  const Scenario s = LoadScenario(a.scenario);
  const ParameterLayout layout(ParseEffectList(a.effects));
  const int n = layout.size();
  std::vector<double> durations = ParseList(a.durations, "--durations");
  std::sort(durations.begin(), durations.end());
  const std::vector<Target> targets = ParseTargets(a.targets, layout);
  const std::vector<std::array<double, 2>> positions = StaticPositions(a.static_positions);
  const double Td = a.design_duration_s > 0 ? a.design_duration_s : s.profile.duration_s;
  const double Ts = a.static_duration_s;
  if (!(Ts > 0)) throw InputError("--static-duration: must be > 0");
  const double max_samples = durations.back() * s.profile.rate_hz;
  if (max_samples > static_cast<double>(kMaxSimulatedSamples)) {
    throw InputError("--durations: " + FormatDouble(durations.back()) + " s at " +
                     FormatDouble(s.profile.rate_hz) + " Hz is more than " +
                     std::to_string(kMaxSimulatedSamples) + " samples");
  }
  std::vector<std::array<double, 2>> periods, amplitudes;
  if (a.periods.empty()) {
    for (double f : {0.5, 1.0, 2.0}) periods.push_back({f * s.profile.period_s[0], f * s.profile.period_s[1]});
  } else {
    periods = ParsePairs(a.periods, "--periods");
  }
  if (a.amplitudes.empty()) {
    for (double f : {0.25, 0.5, 1.0}) {
      amplitudes.push_back({f * s.profile.amplitude_rad[0] / kDegToRad,
                            f * s.profile.amplitude_rad[1] / kDegToRad});
    }
  } else {
    amplitudes = ParsePairs(a.amplitudes, "--amplitudes");
  }
  DesignOptions opt;
  opt.epoch_s = a.epoch_s;
  opt.observability.threads = a.threads;
  const ObservabilityThresholds& thr = opt.observability.thresholds;

  const std::size_t total_steps = 2 * durations.size() + periods.size() * amplitudes.size() + 3;
  std::size_t step = 0;
  auto progress = [&](const std::string& what) {
    ShowProgress("design: " + what, static_cast<double>(step++) / total_steps);
  };

  // 1. sigma against duration, both methods.
  std::vector<DesignPoint> qh, st;
  for (double T : durations) {
    progress("quasi-harmonic " + FormatDouble(T) + " s");
    HarmonicProfile p = s.profile;
    p.duration_s = T;
    qh.push_back(EvaluateProfile(s, p, layout, opt));
    progress("static " + FormatDouble(T) + " s");
    st.push_back(EvaluateStatic(s, layout, positions, T, thr));
  }
  // 2. periods x amplitudes at the design duration.
  struct GridPoint {
    std::array<double, 2> period, amplitude;
    DesignPoint d;
  };
  std::vector<GridPoint> grid;
  for (const auto& per : periods) {
    for (const auto& amp : amplitudes) {
      progress("profile " + PairText(per[0], per[1]) + " s");
      HarmonicProfile p = s.profile;
      p.duration_s = Td;
      for (int i = 0; i < 2; ++i) {
        p.period_s[i] = per[i];
        p.amplitude_rad[i] = amp[i] * kDegToRad;
      }
      grid.push_back({per, amp, EvaluateProfile(s, p, layout, opt)});
    }
  }
  // 3. the comparison: the scenario's design against the static method.
  progress("comparison");
  HarmonicProfile pd = s.profile;
  pd.duration_s = Td;
  const DesignPoint qh_design = EvaluateProfile(s, pd, layout, opt);
  const DesignPoint st_long = EvaluateStatic(s, layout, positions, Ts, thr);
  const DesignPoint st_design = EvaluateStatic(s, layout, positions, Td, thr);
  // 4. targets.
  std::vector<TargetResult> target_results;
  const double t_min = std::max(1.0, 3.0 * a.epoch_s);
  const double t_max = std::max(durations.back(), Td);
  for (const Target& t : targets) {
    progress("target " + t.key);
    const double si = t.sigma_file * layout.info(t.indices[0]).si_per_unit;
    target_results.push_back(DurationForTarget(s, layout, t.indices, si, t_min, t_max, opt));
  }
  EndProgress();

  // ---- OUT.json
  nlohmann::json out;
  out["command"] = "design";
  out["scenario"] = a.scenario;
  nlohmann::json units = nlohmann::json::object();
  for (int i = 0; i < n; ++i) units[layout.info(i).name] = layout.info(i).unit;
  out["units"] = units;
  out["settings"] = {{"rate_hz", s.profile.rate_hz},
                     {"declared_noise_mV", s.run.noise_mV},
                     {"declared_angle_noise_arcsec", s.run.angle_noise_rad / kArcsecToRad},
                     {"epoch_s", a.epoch_s},
                     {"design_duration_s", Td},
                     {"static_duration_s", Ts},
                     {"static_positions", a.static_positions},
                     {"effects", a.effects}};
  nlohmann::json pos = nlohmann::json::array();
  for (const auto& p : positions) pos.push_back({p[0] / kDegToRad, p[1] / kDegToRad});
  out["settings"]["static_positions_deg"] = pos;

  auto sigma_series = [&](const std::vector<DesignPoint>& pts) {
    nlohmann::json sig = nlohmann::json::object(), slope = nlohmann::json::object();
    for (int i = 0; i < n; ++i) {
      std::vector<double> v;
      for (const DesignPoint& d : pts) {
        v.push_back(Held(d, layout.info(i).name) ? std::nan("") : d.sigma[i] / layout.info(i).si_per_unit);
      }
      sig[layout.info(i).name] = v;
      const double sl = LogSlope(durations, v, 60.0);
      slope[layout.info(i).name] = std::isfinite(sl) ? nlohmann::json(sl) : nlohmann::json();
    }
    nlohmann::json unobs = nlohmann::json::array();
    for (const DesignPoint& d : pts) unobs.push_back(d.unobservable);
    return nlohmann::json{{"sigma", sig}, {"slope_log_log_from_60s", slope}, {"unobservable", unobs}};
  };
  out["duration"] = {{"durations_s", durations},
                     {"quasi_harmonic", sigma_series(qh)},
                     {"static", sigma_series(st)}};

  nlohmann::json jgrid = nlohmann::json::array();
  for (const GridPoint& g : grid) {
    nlohmann::json sig = nlohmann::json::object(), worst = nlohmann::json::object();
    for (int i = 0; i < n; ++i) sig[layout.info(i).name] = g.d.sigma[i] / layout.info(i).si_per_unit;
    for (const ParameterGroup& grp : ParameterGroups()) {
      worst[grp.name] = Worst(g.d, grp.members) / layout.info(grp.members[0]).si_per_unit;
    }
    jgrid.push_back({{"period_s", g.period},
                     {"amplitude_deg", g.amplitude},
                     {"duration_s", Td},
                     {"sigma", sig},
                     {"worst_in_group", worst},
                     {"unobservable", g.d.unobservable}});
  }
  out["profiles"] = jgrid;

  nlohmann::json jt = nlohmann::json::array();
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const Target& t = targets[k];
    const TargetResult& r = target_results[k];
    const double f = layout.info(t.indices[0]).si_per_unit;
    jt.push_back({{"target", t.key},
                  {"sigma", t.sigma_file},
                  {"unit", layout.info(t.indices[0]).unit},
                  {"reached", r.reached},
                  {"duration_s", r.duration_s},
                  {"sigma_at_duration", r.sigma_at_duration / f},
                  {"searched_s", {t_min, t_max}},
                  {"evaluations", r.evaluations}});
  }
  out["targets"] = jt;

  nlohmann::json rows = nlohmann::json::object();
  for (int i = 0; i < n; ++i) {
    const double f = layout.info(i).si_per_unit;
    rows[layout.info(i).name] = {{"unit", layout.info(i).unit},
                                 {"quasi_harmonic", qh_design.sigma[i] / f},
                                 {"static", st_long.sigma[i] / f},
                                 {"static_same_duration", st_design.sigma[i] / f},
                                 {"ratio_static_over_quasi_harmonic",
                                  Held(st_long, layout.info(i).name) || Held(qh_design, layout.info(i).name)
                                      ? nlohmann::json()
                                      : nlohmann::json(st_long.sigma[i] / qh_design.sigma[i])}};
  }
  out["comparison"] = {{"quasi_harmonic_duration_s", Td},
                       {"static_duration_s", Ts},
                       {"static_positions", a.static_positions},
                       {"rows", rows},
                       {"quasi_harmonic_not_determined", qh_design.unobservable},
                       {"static_not_determined", st_long.unobservable}};

  // ---- the plot: worst sigma of each group against duration, both methods.
  std::vector<PlotPanel> panels;
  for (const ParameterGroup& g : ParameterGroups()) {
    PlotPanel panel;
    panel.title = g.label;
    panel.y_label = "sigma [" + layout.info(g.members[0]).unit + "]";
    PlotSeries sq{"quasi-harmonic " + PairText(s.profile.period_s[0], s.profile.period_s[1]) + " s",
                  "#1f77b4", false, {}, {}};
    PlotSeries ss{"static, " + std::to_string(a.static_positions) + " positions", "#d62728", true,
                  {}, {}};
    PlotSeries sq_best = sq, ss_best = ss;
    for (PlotSeries* b : {&sq_best, &ss_best}) {
      b->width = 1.0;
      b->opacity = 0.5;
      b->in_legend = false;
    }
    bool static_held = false, qh_held = false;
    for (std::size_t k = 0; k < durations.size(); ++k) {
      const double f = layout.info(g.members[0]).si_per_unit;
      for (PlotSeries* p : {&sq, &ss, &sq_best, &ss_best}) p->x.push_back(durations[k]);
      // A sigma of a parameter the test does not determine is the prior's:
      // not plotted.
      const bool qh_k = AnyHeld(qh[k], layout, g.members), st_k = AnyHeld(st[k], layout, g.members);
      sq.y.push_back(qh_k ? std::nan("") : Worst(qh[k], g.members) / f);
      ss.y.push_back(st_k ? std::nan("") : Worst(st[k], g.members) / f);
      sq_best.y.push_back(qh_k ? std::nan("") : Best(qh[k], g.members) / f);
      ss_best.y.push_back(st_k ? std::nan("") : Best(st[k], g.members) / f);
      static_held = static_held || st_k;
      qh_held = qh_held || qh_k;
    }
    if (static_held) panel.note = "static: not determined at some or all durations";
    if (qh_held) {
      panel.note += std::string(panel.note.empty() ? "" : "; ") +
                    "quasi-harmonic: not determined at some durations";
    }
    panel.series = {sq_best, ss_best, sq, ss};
    panels.push_back(panel);
  }
  char title[200];
  std::snprintf(title, sizeof(title),
                "Cramer-Rao sigma against run duration, %s (%g Hz, %g mV); thick: worst of "
                "the group, thin: best",
                a.scenario.substr(a.scenario.find_last_of('/') + 1).c_str(), s.profile.rate_hz,
                s.run.noise_mV);
  const std::string svg = LogLogPanelsSvg(
      title, "run duration [s]", panels,
      {{Td, FormatDouble(Td) + " s design"}, {Ts, FormatDouble(Ts) + " s static"}}, 3);
  const std::string svg_path = a.plot_svg.empty() ? DefaultSvgPath(a.out_json) : a.plot_svg;
  out["plot"] = svg_path;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  out["time_s"] = seconds;
  // JSON first: when it cannot be written no SVG is left behind, and when the
  // SVG cannot be written the JSON that names it is taken back.
  WriteJson(out, a.out_json);
  try {
    WriteFileAtomically(svg_path, svg);
  } catch (...) {
    std::filesystem::remove(a.out_json);
    throw;
  }

  // ---- stdout
  auto print_duration_table = [&](const char* what, const std::vector<DesignPoint>& pts) {
    std::printf("\n%s: sigma against run duration [s] (* not determined: the prior's)\n", what);
    std::printf("%-9s %-7s", "parameter", "unit");
    for (double T : durations) std::printf(" %9g", T);
    std::printf(" %7s\n", "slope");
    for (int i = 0; i < n; ++i) {
      const double f = layout.info(i).si_per_unit;
      std::printf("%-9s %-7s", layout.info(i).name.c_str(), layout.info(i).unit.c_str());
      std::vector<double> v;
      for (const DesignPoint& d : pts) {
        const bool held = Held(d, layout.info(i).name);
        std::printf(" %8.3g%s", d.sigma[i] / f, held ? "*" : " ");
        v.push_back(held ? std::nan("") : d.sigma[i] / f);
      }
      const double slope = LogSlope(durations, v, 60.0);
      if (std::isfinite(slope)) {
        std::printf(" %7.3f\n", slope);
      } else {
        std::printf(" %7s\n", "-");
      }
    }
  };
  std::printf("design: %s, %g Hz, declared noise %g mV, %g arcsec; static test: %d positions\n",
              a.scenario.c_str(), s.profile.rate_hz, s.run.noise_mV,
              s.run.angle_noise_rad / kArcsecToRad, a.static_positions);
  print_duration_table("quasi-harmonic profile", qh);
  print_duration_table("static multi-position test", st);
  std::printf("(slope: log-log over durations >= 60 s; -0.5 is 1/sqrt(T))\n");

  std::printf("\nprofiles at %g s: worst sigma per group (* not determined)\n", Td);
  std::printf("%-12s %-12s", "periods s", "ampl. deg");
  for (const ParameterGroup& g : ParameterGroups()) std::printf(" %10s", g.name.c_str());
  std::printf("  unobservable\n");
  for (const GridPoint& g : grid) {
    std::printf("%-12s %-12s", PairText(g.period[0], g.period[1]).c_str(),
                PairText(g.amplitude[0], g.amplitude[1]).c_str());
    for (const ParameterGroup& grp : ParameterGroups()) {
      std::printf(" %9.3g%s", Worst(g.d, grp.members) / layout.info(grp.members[0]).si_per_unit,
                  AnyHeld(g.d, layout, grp.members) ? "*" : " ");
    }
    std::string held;
    for (const std::string& h : g.d.unobservable) held += (held.empty() ? "" : " ") + h;
    std::printf("  %s\n", held.empty() ? "-" : held.c_str());
  }

  std::printf("\n");
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const Target& t = targets[k];
    const TargetResult& r = target_results[k];
    const std::string unit = layout.info(t.indices[0]).unit;
    if (r.reached) {
      std::printf("target sigma(%s) <= %g %s: reached after %.3g s of the profile (sigma %.3g; %d CRB evaluations)\n",
                  t.key.c_str(), t.sigma_file, unit.c_str(), r.duration_s,
                  r.sigma_at_duration / layout.info(t.indices[0]).si_per_unit, r.evaluations);
    } else {
      std::printf("target sigma(%s) <= %g %s: NOT reached within %g s (sigma %.3g there)\n",
                  t.key.c_str(), t.sigma_file, unit.c_str(), r.duration_s,
                  r.sigma_at_duration / layout.info(t.indices[0]).si_per_unit);
    }
  }

  std::printf("\nquasi-harmonic %g s against the static %d-position method, %g s (* not determined)\n",
              Td, a.static_positions, Ts);
  std::printf("%-9s %-7s %14s %14s %14s %10s\n", "parameter", "unit", "quasi-harm.", "static",
              "static same T", "ratio");
  for (int i = 0; i < n; ++i) {
    const ParameterInfo& p = layout.info(i);
    const double f = p.si_per_unit;
    auto held = [&](const DesignPoint& d) {
      return std::find(d.unobservable.begin(), d.unobservable.end(), p.name) != d.unobservable.end()
                 ? "*"
                 : " ";
    };
    char ratio[32];
    if (Held(st_long, p.name) || Held(qh_design, p.name)) {
      std::snprintf(ratio, sizeof(ratio), "%10s", "-");
    } else {
      std::snprintf(ratio, sizeof(ratio), "%10.3g", st_long.sigma[i] / qh_design.sigma[i]);
    }
    std::printf("%-9s %-7s %13.3g%s %13.3g%s %13.3g%s %s\n", p.name.c_str(), p.unit.c_str(),
                qh_design.sigma[i] / f, held(qh_design), st_long.sigma[i] / f, held(st_long),
                st_design.sigma[i] / f, held(st_design), ratio);
  }
  std::printf("(ratio: static %g s sigma / quasi-harmonic %g s sigma; -: not determined by one of them)\n", Ts, Td);
  std::printf("time %.1f s; wrote %s and %s\n", seconds, a.out_json.c_str(), svg_path.c_str());
  return 0;
}

}  // namespace

Command AddDesignCommand(CLI::App& app) {
  auto a = std::make_shared<DesignArgs>();
  Command c;
  c.app = app.add_subcommand(
      "design", "Experiment design: Cramer-Rao sigma against duration, periods, amplitudes; "
                "quasi-harmonic against static");
  c.app->add_option("scenario", a->scenario, "SCENARIO.yaml (profile, truth, declared noise)")
      ->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--plot", a->plot_svg, "SVG plot (default: OUT with .svg)");
  c.app->add_option("--durations", a->durations, "run durations [s], comma-separated")
      ->capture_default_str();
  c.app->add_option("--periods", a->periods,
                    "profile periods OUTER:INNER [s], comma-separated (default: the scenario's "
                    "x 0.5, 1, 2)");
  c.app->add_option("--amplitudes", a->amplitudes,
                    "profile amplitudes OUTER:INNER [deg], comma-separated (default: the "
                    "scenario's x 0.25, 0.5, 1)");
  c.app->add_option("--target", a->targets,
                    "NAME=SIGMA in file units, comma-separated; NAME a parameter or a group "
                    "(K, W0, angles, K_ij, bench, dR: the worst member)")
      ->capture_default_str();
  c.app->add_option("--design-duration", a->design_duration_s,
                    "duration of the profile grid and the comparison [s] (default: the "
                    "scenario's)");
  c.app->add_option("--static-duration", a->static_duration_s,
                    "total time of the static method in the comparison [s]")
      ->capture_default_str();
  c.app->add_option("--static-positions", a->static_positions, "static orientations: 6, 12 or 18")
      ->capture_default_str();
  c.app->add_option("--effects", a->effects, "catalogue effects to include, e.g. a,b");
  c.app->add_option("--epoch-s", a->epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app->add_option("--threads", a->threads, "threads (0: all cores)")->capture_default_str();
  c.run = [a] { return RunDesign(*a); };
  return c;
}

}  // namespace triadcal
