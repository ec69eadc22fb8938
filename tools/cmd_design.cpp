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
#include <cstdio>
#include <memory>

#include "app/design_job.h"
#include "app/output_guard.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/design_report.h"

namespace triadcal {
namespace {

struct DesignArgs {
  std::string scenario, out_json, report_html;
  // The lists as text, with the settings' defaults.
  std::string durations = ListText(DesignSettings().durations_s);
  std::string targets = TargetsText(DesignSettings().targets);
  std::string periods, amplitudes;
  DesignSettings settings;  // the numbers, filled by CLI11 directly
};

int RunDesign(DesignArgs a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session);
  CheckOutputPath(a.out_json, session);
  DesignSettings& settings = a.settings;
  settings.durations_s = ParsePositiveList(a.durations, "--durations");
  settings.targets = ParseDesignTargets(a.targets);
  if (!a.periods.empty()) settings.periods_s = ParsePairs(a.periods, "--periods");
  if (!a.amplitudes.empty()) settings.amplitudes_deg = ParsePairs(a.amplitudes, "--amplitudes");
  settings.Validate();
  const Scenario s = LoadScenario(a.scenario);
  session.RecordInput("scenario", a.scenario);
  CheckOverwrite(a.out_json, session);  // before the long work
  StageProgress progress("design: ");
  const Session designing = WithProgress(session, &progress);
  const DesignOutcome o = DesignRun(settings, a.scenario, s, designing);
  EndProgress();
  WriteJson(o.json, a.out_json, session);
  WriteReportIfAsked(a.report_html, o.json, a.out_json, session);
  PrintDesign(s, a.scenario, settings, o);
  std::printf("time %.1f s; wrote %s\n", o.seconds, a.out_json.c_str());
  return 0;
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
  c.app->add_option("--design-duration", a->settings.design_duration_s,
                    "duration of the profile grid and the comparison [s] (default: the "
                    "scenario's)");
  c.app
      ->add_option("--static-duration", a->settings.static_duration_s,
                   "total time of the static method in the comparison [s]")
      ->capture_default_str();
  c.app
      ->add_option("--static-positions", a->settings.static_positions,
                   "static orientations: 6, 12 or 18")
      ->capture_default_str();
  c.app->add_option("--effects", a->settings.effects, "catalogue effects to include, e.g. a,b");
  c.app->add_option("--epoch-s", a->settings.epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app->add_option("--threads", a->settings.threads, "threads (0: all cores)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.run = [a](Session& session) { return RunDesign(*a, session); };
  return c;
}

}  // namespace triadcal
