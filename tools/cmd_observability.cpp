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

#include "core/model/errors.h"
#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/io/parameters_json.h"
#include "core/simulation/simulator.h"
#include "core/io/yaml_fields.h"
#include "core/model/sample_noise.h"
#include "solvers/analysis/experiment_design.h"
#include "solvers/estimation/observability.h"
#include "tools/command_util.h"
#include "solvers/estimation/run_problem.h"
#include "tools/commands.h"
#include "app/output_guard.h"
#include "tools/report/observability_report.h"
#include "core/io/runs_file_io.h"
#include "app/joint_fit_job.h"
#include "app/diagnose_job.h"

namespace triadcal {
namespace {

struct ObservabilityArgs {
  std::vector<std::string> inputs;
  std::string input, out_json, report_html, at, effects;
  double epoch_s = kDefaultEpoch_s, rate_window_s = AngleDerivativeOptions().half_window_s;
  double unobservable_below = ObservabilityThresholds{}.unobservable;
  double weak_below = ObservabilityThresholds{}.weak;
  int threads = 0;
  bool could_hide = false;
  double alpha = 0.01;
};

// "parameters" of a fit/filter OUT ({"Kx": {"value": ...}}), of its "rts"
// section, or of a truth.json ({"Kx": 171.5}). Unknown names are ignored.
NamedValues ReadParameterValues(const std::string& path) {
  return FileValues(
      ReadParametersJson(path, {"", "rts"}, "a fit or filter OUT, or truth.json"));
}

bool IsScenario(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  return root.IsMap() && root["profile"];
}

// Several runs (or a runs file): the combined problem at the nominal values,
// as `fit` on several runs poses it (docs/multi-run.md).
int RunJointObservability(const ObservabilityArgs& a, Session& session) {
  if (!a.report_html.empty() || !a.at.empty()) {
    throw InputError(std::string(a.at.empty() ? "--report" : "--at") +
                     ": not available for several runs yet");
  }
  ShowProgress("observability: loading the runs", 0.0);
  CheckOutputPath(a.out_json);
  JointInput in = LoadJointInput(a.inputs, a.effects, &session);
  CheckOverwrite(a.out_json, session);
  // noise_mV: auto: each run's readings' own noise, as `fit` starts from.
  for (JointRun& r : in.runs) r.run = WithReadingNoise(r.run, r.data);
  const RunsFile& file = in.file;
  const std::vector<JointRun>& runs = in.runs;
  const JointLayout& jl = *in.layout;
  JointOptions opt;
  opt.batch.epoch_s = a.epoch_s;
  opt.batch.derivatives.half_window_s = a.rate_window_s;
  opt.batch.threads = a.threads;
  ShowProgress("observability: Fisher information of the runs together", 0.3);
  const JointInformation info = JointInformationAtNominal(runs, jl, opt);
  EndProgress();

  std::vector<bool> held(jl.size(), false);
  for (int j : info.held) held[j] = true;
  nlohmann::json params = nlohmann::json::object();
  for (int j = 0; j < jl.size(); ++j) {
    const JointParam& p = jl.param(j);
    nlohmann::json e;
    e["crb_sigma"] = held[j] ? nlohmann::json(nullptr)
                             : nlohmann::json(std::sqrt(info.cov(j, j)) / p.si_per_unit);
    e["prior_sigma"] = p.prior_sigma / p.si_per_unit;
    e["unit"] = p.unit;
    e["estimable"] = !held[j];
    nlohmann::json share = nlohmann::json::object();
    for (int r = 0; r < jl.runs(); ++r) share[jl.run_name(r)] = info.share(r, j);
    if (!held[j]) e["information_share"] = share;
    params[p.name] = e;
  }
  nlohmann::json out;
  out["command"] = "observability";
  out["kind"] = "joint";
  out["axes"] = "imu";
  out["evaluated_at"] = "nominal";
  out["parameters"] = params;
  nlohmann::json held_names = nlohmann::json::array();
  for (int j : info.held) held_names.push_back(jl.param(j).name);
  out["held"] = held_names;
  out["determined_jointly_only"] = info.jointly_only;
  nlohmann::json jr = nlohmann::json::array();
  for (int r = 0; r < jl.runs(); ++r) {
    jr.push_back({{"name", jl.run_name(r)},
                  {"run", file.runs[r].run_yaml},
                  {"samples", runs[r].data.size()},
                  {"held_alone", info.held_alone[r]}});
  }
  out["runs"] = jr;
  out["settings"] = {{"epoch_s", a.epoch_s}, {"effects", a.effects}};
  WriteJson(out, a.out_json, session);

  std::printf("observability: %zu runs together, at the nominal values, the runs' noise "
              "(declared, or the readings' own with noise_mV: auto)\n",
              runs.size());
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
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

int RunObservability(ObservabilityArgs a, Session& session) {
  if (a.inputs.size() > 1 || IsRunsFile(a.inputs[0])) return RunJointObservability(a, session);
  a.input = a.inputs[0];
  if (!a.report_html.empty()) CheckOutputPath(a.report_html);
  if (!(a.unobservable_below > 0.0) || !(a.weak_below >= a.unobservable_below)) {
    throw InputError("--unobservable-below, --weak-below: expected 0 < unobservable <= weak");
  }
  ObservabilityOptions oo;
  oo.threads = a.threads;
  oo.thresholds = {a.unobservable_below, a.weak_below};
  AngleDerivativeOptions derivatives;
  derivatives.half_window_s = a.rate_window_s;

  // The run (recorded or simulated), its description and the point of evaluation.
  ShowProgress("observability: loading the run", 0.0);
  RunDescription run;
  RunData data;
  // Made once the readings unit is known: its units are named for it (mV/g,
  // counts/g, mg/g); made before, they said mV/g for a run read in counts.
  ParameterLayout layout;
  Eigen::VectorXd theta;
  std::string source, at;
  bool noise_auto = false;
  if (IsScenario(a.input)) {
    const Scenario s = NoiseFreeScenario(LoadScenario(a.input));
    session.provenance.RecordInput("scenario", a.input);
    data = Simulate(s);
    run = s.run;
    // The layout's units, named for the readings; the gyro's parameters with
    // a gyro block, as `fit` estimates them.
    layout = ParameterLayout(ParseEffectList(a.effects), run.gyro.has_value() && data.has_gyro(),
                             ReadingsUnit(run));
    theta = TruthInLayout(s, layout);
    source = "scenario (simulated without noise)";
    at = "truth";
  } else {
    LoadedRun loaded = LoadRun(a.input, &session);
    data = std::move(loaded.data);
    layout = ParameterLayout(ParseEffectList(a.effects),
                             loaded.description.gyro.has_value() && data.has_gyro(),
                             ReadingsUnit(loaded.description));
    // noise_mV: auto: the readings' own noise, as `fit` starts from (not the
    // default 2 mV, which gave a CRB 36 times below the fit's sigma).
    noise_auto = loaded.description.noise_auto;
    run = WithReadingNoise(loaded.description, data);
    theta = NominalTheta(run, layout);
    source = "run";
    at = "nominal";
  }
  if (!a.at.empty()) {
    SetFromFileUnits(layout, ReadParameterValues(a.at), &theta);
    at = a.at;
  }
  if (a.could_hide && source != "scenario (simulated without noise)") {
    throw InputError("--could-hide: needs a SCENARIO.yaml (a planned profile); for a recorded "
                     "run, `diagnose` reports what could hide");
  }
  // Stages, none reporting from inside. Measured shares (paper's run 90 s at
  // 1 kHz; a 25-min real run at 100 Hz): loading the run 64 % / 29 %,
  // building the problem 8 % / 1 %, the Fisher information 28 % / 70 %.
  ShowProgress("observability: building the problem", 0.35);
  const RunProblem p = BuildRunProblem(run, data, layout, a.epoch_s, derivatives);
  ShowProgress("observability: Fisher information", 0.4);
  const ObservabilityResult r = AnalyseObservability(run, p, theta, oo);
  std::vector<HideCase> hide;
  if (a.could_hide) {
    ShowProgress("observability: what could hide (fit and score analysis)", 0.8);
    DiagnoseOptions d;
    d.alpha = a.alpha;
    d.fit.epoch_s = a.epoch_s;
    d.fit.derivatives = derivatives;
    d.fit.threads = a.threads;
    hide = CouldHideOnProfile(run, data, layout, theta, d);
  }
  EndProgress();

  nlohmann::json out = ObservabilityJson(r);
  out["command"] = "observability";
  out["input"] = a.input;
  out["source"] = source;
  out["evaluated_at"] = at;
  out["settings"] = {{"epoch_s", a.epoch_s},
                     {"rate_window_half_s", a.rate_window_s},
                     {"effects", a.effects},
                     {"unobservable_below", a.unobservable_below},
                     {"weak_below", a.weak_below},
                     {"declared_noise_mV", noise_auto ? nlohmann::json(nullptr)
                                                      : nlohmann::json(run.noise_mV)},
                     {"noise_auto", noise_auto},
                     {"noise_mV", {run.ChannelNoise_mV()[0], run.ChannelNoise_mV()[1],
                                   run.ChannelNoise_mV()[2]}},
                     {"declared_angle_noise_arcsec", run.angle_noise_rad / kArcsecToRad}};
  if (a.could_hide) {
    out["could_hide"] = CouldHideJson(hide);
    out["settings"]["could_hide_alpha"] = a.alpha;
  }
  WriteJson(out, a.out_json, session);
  WriteReportIfAsked(a.report_html, out, a.out_json, session);

  std::printf("observability: %s, %zu samples over %.4g s, %zu epochs; evaluated at %s; %.2f s\n",
              source.c_str(), r.samples, r.duration_s, r.epochs, at.c_str(), r.seconds);
  {
    const Eigen::Vector3d n = run.ChannelNoise_mV();
    std::printf("reading noise %.3g %.3g %.3g %s (%s)\n", n[0], n[1], n[2],
                ReadingsUnit(run).c_str(),
                noise_auto ? "the readings' own, noise_mV: auto" : "declared");
  }
  PrintObservability(r);
  if (a.could_hide) {
    std::printf("could hide (alpha %.3g over %zu candidates, power 80 %%):\n", a.alpha, hide.size());
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
  c.app->add_option("--at", a->at,
                    "evaluate at these parameters (fit/filter OUT or truth.json) instead of the "
                    "nominal values (run) or the truth (scenario)");
  c.app->add_option("--effects", a->effects, "catalogue effects to include, e.g. a,b");
  c.app->add_flag("--could-hide", a->could_hide,
                  "SCENARIO.yaml only: also the catalogue effects that could go undetected on "
                  "this profile, their minimal detectable size and the largest parameter shift "
                  "they would cause (as diagnose's could_hide)");
  c.app
      ->add_option("--alpha", a->alpha,
                   "with --could-hide: the loop's false-selection rate per round")
      ->capture_default_str()
      ->check(Bounded(1e-9, 0.5));
  c.app->add_option("--epoch-s", a->epoch_s, "interval between trajectory epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app
      ->add_option("--rate-window-s", a->rate_window_s,
                   "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  c.app
      ->add_option("--unobservable-below", a->unobservable_below,
                   "information along a direction, in prior units, below which it is "
                   "unobservable")
      ->capture_default_str()
      ->check(Bounded(1e-12, 1e6));
  c.app
      ->add_option("--weak-below", a->weak_below,
                   "information in prior units below which a direction is weakly observable")
      ->capture_default_str()
      ->check(Bounded(1e-12, 1e6));
  c.app->add_option("--threads", a->threads, "threads (0: all cores)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.run = [a](Session& session) { return RunObservability(*a, session); };
  return c;
}

}  // namespace triadcal
