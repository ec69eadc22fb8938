// `triadcal design SCENARIO.yaml -o OUT.json`: experiment design from the
// Cramer-Rao bound of the scenario's profile. The study itself is
// solvers/analysis/design_study.h, its reports tools/report/design_report.h:
//   - sigma of every parameter against the run duration (15 s ... 40 min by
//     default), for the quasi-harmonic profile and for a static multi-position
//     test of the same total time;
//   - sigma against the profile's periods and amplitudes (a small grid);
//   - the shortest duration that reaches a target sigma (--target K=0.5);
//   - the scenario's design (the paper's 1.5 min) against the static method
//     (40 min) as a table; the curves are drawn by the HTML report (--report).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/simulation/simulator.h"
#include "solvers/analysis/design_study.h"
#include "tools/command_util.h"
#include "solvers/estimation/run_problem.h"
#include "tools/commands.h"
#include "app/output_guard.h"
#include "tools/report/design_report.h"

namespace triadcal {
namespace {

struct DesignArgs {
  std::string scenario, out_json, report_html, effects;
  std::string durations = "15,30,60,90,300,600,2400";
  std::string periods, amplitudes;  // default: the scenario's x 0.5, 1, 2 / x 0.25, 0.5, 1
  std::string targets = "K=0.5";
  double design_duration_s = 0.0;  // 0: the scenario's
  double static_duration_s = 2400.0;
  int static_positions = 12;
  double epoch_s = kDefaultEpoch_s;
  int threads = 0;
};

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

std::vector<DesignTarget> ParseTargets(const std::string& text, const ParameterLayout& layout) {
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
    t.indices = TargetIndices(layout, t.key);
    out.push_back(t);
  }
  return out;
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

DesignStudyOptions StudyOptions(const DesignArgs& a, const ParameterLayout& layout) {
  DesignStudyOptions o;
  o.durations_s = ParseList(a.durations, "--durations");
  std::sort(o.durations_s.begin(), o.durations_s.end());
  o.targets = ParseTargets(a.targets, layout);
  o.static_positions = a.static_positions;
  StaticPositions(a.static_positions);  // fails early on a bad count
  o.static_duration_s = a.static_duration_s;
  o.design_duration_s = a.design_duration_s;
  if (!a.periods.empty()) o.periods_s = ParsePairs(a.periods, "--periods");
  if (!a.amplitudes.empty()) o.amplitudes_deg = ParsePairs(a.amplitudes, "--amplitudes");
  o.design.epoch_s = a.epoch_s;
  o.design.observability.threads = a.threads;
  o.progress = [](const std::string& what, double fraction) {
    ShowProgress("design: " + what, fraction);
  };
  return o;
}

int RunDesign(const DesignArgs& a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html);
  const auto t_start = std::chrono::steady_clock::now();
  CheckOutputPath(a.out_json);
  const Scenario s = LoadScenario(a.scenario);
  session.provenance.RecordInput("scenario", a.scenario);
  CheckOverwrite(a.out_json, session);  // before the long work
  const ParameterLayout layout(ParseEffectList(a.effects));
  return WithFlags(DesignFlags(), [&] {
    const DesignStudyOptions options = StudyOptions(a, layout);
    const DesignStudy r = RunDesignStudy(s, layout, options);
    EndProgress();

    const DesignReportSettings settings{a.scenario, a.effects, a.epoch_s, a.static_positions};
    nlohmann::json out = DesignJson(s, layout, options, r, settings);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    out["time_s"] = seconds;
    WriteJson(out, a.out_json, session);
    WriteReportIfAsked(a.report_html, out, a.out_json, session);

    PrintDesign(s, layout, options, r, settings);
    std::printf("time %.1f s; wrote %s\n", seconds, a.out_json.c_str());
    return 0;
  });
}

}  // namespace

Command AddDesignCommand(CLI::App& app) {
  auto a = std::make_shared<DesignArgs>();
  Command c;
  c.app = app.add_subcommand(
      "design",
      "Experiment design: Cramer-Rao sigma against duration, periods, amplitudes; "
      "quasi-harmonic against static");
  c.app->add_option("scenario", a->scenario, "SCENARIO.yaml (profile, truth, declared noise)")
      ->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--report", a->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  c.app->add_option("--durations", a->durations, "run durations [s], comma-separated")
      ->capture_default_str();
  c.app->add_option("--periods", a->periods,
                    "profile periods OUTER:INNER [s], comma-separated (default: the scenario's "
                    "x 0.5, 1, 2)");
  c.app->add_option("--amplitudes", a->amplitudes,
                    "profile amplitudes OUTER:INNER [deg], comma-separated (default: the "
                    "scenario's x 0.25, 0.5, 1)");
  c.app
      ->add_option("--target", a->targets,
                   "NAME=SIGMA in file units, comma-separated; NAME a parameter or a group "
                   "(K, W0, angles, K_ij, bench, dR: the worst member)")
      ->capture_default_str();
  c.app->add_option("--design-duration", a->design_duration_s,
                    "duration of the profile grid and the comparison [s] (default: the "
                    "scenario's)");
  c.app
      ->add_option("--static-duration", a->static_duration_s,
                   "total time of the static method in the comparison [s]")
      ->capture_default_str();
  c.app->add_option("--static-positions", a->static_positions, "static orientations: 6, 12 or 18")
      ->capture_default_str();
  c.app->add_option("--effects", a->effects, "catalogue effects to include, e.g. a,b");
  c.app->add_option("--epoch-s", a->epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app->add_option("--threads", a->threads, "threads (0: all cores)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.run = [a](Session& session) { return RunDesign(*a, session); };
  return c;
}

}  // namespace triadcal
