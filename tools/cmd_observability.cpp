// `triadcal observability RUN.yaml|SCENARIO.yaml -o OUT.json`: Cramer-Rao sigma
// per parameter and the directions the run cannot determine, with and without
// the constraints (solvers/estimation/observability.h).
//
// RUN.yaml: the recorded motion and timing of the run, evaluated at the nominal
// values or at --at FILE (a fit/filter OUT or a truth.json; better for a real
// run). SCENARIO.yaml (recognised by its `profile` key): the scenario's profile
// simulated without noise (the declared noise kept), evaluated at its truth.
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/observability_job.h"
#include "app/output_guard.h"
#include "core/io/column_mapping.h"
#include "core/io/runs_file_io.h"
#include "core/model/errors.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/observability_report.h"

namespace triadcal {
namespace {

struct ObservabilityArgs {
  std::vector<std::string> inputs;
  std::string out_json, report_html;
  ObservabilitySettings settings;  // filled by CLI11 directly
};

void PrintJoint(const JointInput& in, const JointInformation& info) {
  const JointLayout& jl = *in.layout;
  std::vector<bool> held(jl.size(), false);
  for (int j : info.held) held[j] = true;
  std::printf(
      "observability: %zu runs together, at the nominal values, the runs' noise "
      "(declared, or the readings' own with noise_mV: auto)\n",
      in.runs.size());
  std::printf("%-26s %14s %14s %-10s", "parameter (IMU axes)", "CRB sigma", "prior sigma", "unit");
  for (int r = 0; r < jl.runs(); ++r) std::printf(" %8.8s", jl.run_name(r).c_str());
  std::printf("   (share of the information)\n");
  for (int j = 0; j < jl.size(); ++j) {
    const JointParam& p = jl.param(j);
    char crb[32] = "held";
    if (!held[j]) std::snprintf(crb, sizeof(crb), "%.4g", std::sqrt(info.cov(j, j)) / p.si_per_unit);
    std::printf("%-26s %14s %14.4g %-10s", p.name.c_str(), crb, p.prior_sigma / p.si_per_unit,
                p.unit.c_str());
    if (!held[j]) {
      for (int r = 0; r < jl.runs(); ++r) std::printf(" %8.2f", info.share(r, j));
    }
    std::printf("\n");
  }
  for (int r = 0; r < jl.runs(); ++r) {
    std::string h;
    for (const std::string& x : info.held_alone[r]) h += (h.empty() ? "" : ", ") + x;
    std::printf("run %s alone would hold: %s\n", jl.run_name(r).c_str(),
                h.empty() ? "none" : h.c_str());
  }
  std::string jo;
  for (const std::string& x : info.jointly_only) jo += (jo.empty() ? "" : ", ") + x;
  std::printf("determined only by the runs together: %s\n", jo.empty() ? "none" : jo.c_str());
}

// Several runs (or a runs file): the combined problem at the nominal values,
// as `fit` on several runs poses it (docs/multi-run.md).
int RunJointObservability(const ObservabilityArgs& a, Session& session) {
  if (!a.report_html.empty() || !a.settings.at.empty()) {
    throw InputError(std::string(a.settings.at.empty() ? "--report" : "--at") +
                     ": not available for several runs yet");
  }
  StageProgress progress("observability: ");
  progress.Stage("loading the runs");
  CheckOutputPath(a.out_json, session);
  JointInput in = LoadJointInput(a.inputs, a.settings.effects, &session, a.settings.threads);
  CheckOverwrite(a.out_json, session);
  const JointObservabilityOutcome o =
      JointObservabilityRun(a.settings, &in, WithProgress(session, &progress));
  EndProgress();
  WriteJson(o.json, a.out_json, session);
  PrintJoint(in, o.info);
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

void PrintCouldHide(const ObservabilitySettings& s, const std::vector<HideCase>& hide) {
  std::printf("could hide (alpha %.3g over %zu candidates, power 80 %%):\n", s.alpha, hide.size());
  for (const HideCase& h : hide) {
    if (h.direction.empty()) {
      std::printf("  %-26s this profile cannot detect it\n", GetEffectSpec(h.effect).name.c_str());
    } else {
      std::printf("  %-26s up to %10.4g %-7s undetected; moves %s by up to %.3g sigma\n",
                  GetEffectSpec(h.effect).name.c_str(), h.minimal_detectable, h.unit.c_str(),
                  h.parameter.c_str(), h.max_shift_sigma);
    }
  }
}

int RunObservability(const ObservabilityArgs& a, Session& session) {
  if (a.inputs.size() > 1 || IsRunsFile(a.inputs[0])) return RunJointObservability(a, session);
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session);
  a.settings.Validate();
  // The run (recorded or simulated), its description and the point of evaluation.
  StageProgress progress("observability: ");
  progress.Stage("loading the run");
  const ObservabilityInput in =
      LoadObservabilityInput(a.inputs[0], a.settings.effects, &session, a.settings.threads);
  const ObservabilityOutcome o = ObservabilityRun(a.settings, in, WithProgress(session, &progress));
  EndProgress();
  WriteJson(o.json, a.out_json, session);
  WriteReportIfAsked(a.report_html, o.json, a.out_json, session);

  const ObservabilityResult& r = o.result;
  std::printf("observability: %s, %zu samples over %.4g s, %zu epochs; evaluated at %s; %.2f s\n",
              o.source.c_str(), r.samples, r.duration_s, r.epochs, o.at.c_str(), r.seconds);
  const Eigen::Vector3d n = in.run.ChannelNoise_mV();
  std::printf("reading noise %.3g %.3g %.3g %s (%s)\n", n[0], n[1], n[2],
              ReadingsUnit(in.run).c_str(),
              in.noise_auto ? "the readings' own, noise_mV: auto" : "declared");
  PrintObservability(r);
  if (a.settings.could_hide) PrintCouldHide(a.settings, o.could_hide);
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddObservabilityCommand(CLI::App& app) {
  auto a = std::make_shared<ObservabilityArgs>();
  Command c;
  c.app = app.add_subcommand(
      "observability",
      "Cramer-Rao sigma and unobservable directions of a run or a scenario's profile");
  c.app->add_option("input", a->inputs,
                    "RUN.yaml (recorded motion) or SCENARIO.yaml (profile); several RUN.yaml "
                    "or a runs file: the runs together (docs/multi-run.md)")
      ->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--report", a->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  c.app->add_option("--at", a->settings.at,
                    "evaluate at these parameters (fit/filter OUT or truth.json) instead of the "
                    "nominal values (run) or the truth (scenario)");
  c.app->add_option("--effects", a->settings.effects, "catalogue effects to include, e.g. a,b");
  c.app->add_flag("--could-hide", a->settings.could_hide,
                  "SCENARIO.yaml only: also the catalogue effects that could go undetected on "
                  "this profile, their minimal detectable size and the largest parameter shift "
                  "they would cause (as diagnose's could_hide)");
  c.app
      ->add_option("--alpha", a->settings.alpha,
                   "with --could-hide: the loop's false-selection rate per round")
      ->capture_default_str()
      ->check(Bounded(1e-9, 0.5));
  c.app->add_option("--epoch-s", a->settings.epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app
      ->add_option("--rate-window-s", a->settings.rate_window_s,
                   "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  c.app
      ->add_option("--unobservable-below", a->settings.unobservable_below,
                   "information along a direction, in prior units, below which it is "
                   "unobservable")
      ->capture_default_str()
      ->check(Bounded(1e-12, 1e6));
  c.app
      ->add_option("--weak-below", a->settings.weak_below,
                   "information in prior units below which a direction is weakly observable")
      ->capture_default_str()
      ->check(Bounded(1e-12, 1e6));
  c.app->add_option("--threads", a->settings.threads, "threads (0: all cores)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.run = [a](Session& session) { return RunObservability(*a, session); };
  return c;
}

}  // namespace triadcal
