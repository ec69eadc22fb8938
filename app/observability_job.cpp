#include "app/observability_job.h"

#include <cmath>
#include <utility>

#include "app/diagnose_job.h"
#include "app/estimate_json.h"
#include "app/option_lists.h"
#include "app/run_loading.h"
#include "core/io/column_mapping.h"
#include "core/io/parameters_json.h"
#include "core/io/yaml_fields.h"
#include "core/model/errors.h"
#include "core/model/sample_noise.h"
#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "solvers/analysis/experiment_design.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

void ObservabilitySettings::Validate() const {
  ParseEffectList(effects);
  if (!(unobservable_below > 0.0) || !(weak_below >= unobservable_below)) {
    throw InputError("--unobservable-below, --weak-below: expected 0 < unobservable <= weak");
  }
  AngleDerivativeOptions window;
  window.half_window_s = rate_window_s;
  WithFlags({{"half_window_s", "--rate-window-s"}}, [&] { window.Check(); });
  if (threads < 0 || threads > 1024) {
    throw InputError("--threads: Value " + std::to_string(threads) + " not in range 0 to 1024");
  }
  if (!(alpha > 0.0 && alpha < 1.0)) throw InputError("--alpha: must be in (0, 1)");
}

std::set<std::string> UnobservableNames(const ObservabilityVariant& v) {
  std::vector<WeakDirection> dirs;
  for (const Direction& d : v.unobservable) dirs.push_back(d.named);
  const std::vector<std::string> names = ParametersIn(dirs);
  return {names.begin(), names.end()};
}

nlohmann::json DirectionJson(const ParameterLayout& layout, const Direction& d) {
  nlohmann::json j = WeakDirectionsJson({d.named})[0];
  if (d.data_sigma.size() > 0) {
    nlohmann::json s = nlohmann::json::object();
    for (const auto& [name, w] : d.named.weights) {
      const int i = layout.IndexOf(name);
      s[name] = d.data_sigma[i] / layout.info(i).si_per_unit;
    }
    j["data_sigma"] = s;
  }
  return j;
}

nlohmann::json VariantJson(const ParameterLayout& layout, const ObservabilityVariant& v) {
  nlohmann::json j;
  j["constraints"] = v.constraints;
  nlohmann::json crb = nlohmann::json::object();
  for (int i = 0; i < layout.size(); ++i) {
    crb[layout.info(i).name] = std::sqrt(std::max(0.0, v.cov(i, i))) / layout.info(i).si_per_unit;
  }
  j["crb"] = crb;
  j["unobservable"] = nlohmann::json::array();
  for (const Direction& d : v.unobservable) j["unobservable"].push_back(DirectionJson(layout, d));
  j["weakly_observable"] = nlohmann::json::array();
  for (const Direction& d : v.weak) j["weakly_observable"].push_back(DirectionJson(layout, d));
  const std::set<std::string> held = UnobservableNames(v);
  j["not_estimable"] = std::vector<std::string>(held.begin(), held.end());
  j["information_eigenvalues_prior_units"] =
      std::vector<double>(v.eigenvalues.data(), v.eigenvalues.data() + v.eigenvalues.size());
  return j;
}

nlohmann::json ObservabilityJson(const ObservabilityResult& r) {
  const ParameterLayout& L = r.layout;
  nlohmann::json out;
  const nlohmann::json with = VariantJson(L, r.with_constraints);
  out["crb"] = with["crb"];
  nlohmann::json units = nlohmann::json::object();
  for (int i = 0; i < L.size(); ++i) units[L.info(i).name] = L.info(i).unit;
  out["units"] = units;
  out["constraints"] = r.with_constraints.constraints;
  out["unobservable"] = with["unobservable"];
  out["weakly_observable"] = with["weakly_observable"];
  out["not_estimable"] = with["not_estimable"];
  out["correlation"] = CorrelationJson(L, r.with_constraints.cov);
  const std::set<std::string> held = UnobservableNames(r.with_constraints);
  // the OUT form of docs/file-formats.md: value = the point of evaluation, sigma = the CRB.
  out["parameters"] = ParametersJson(L, r.theta, r.with_constraints.cov, held);
  nlohmann::json prior = nlohmann::json::object();
  for (int i = 0; i < L.size(); ++i)
    prior[L.info(i).name] = r.prior.sigma[i] / L.info(i).si_per_unit;
  out["prior_sigma"] = prior;
  out["with_constraints"] = with;
  out["without_constraints"] = VariantJson(L, r.without_constraints);
  nlohmann::json each = nlohmann::json::object();
  for (std::size_t j = 0; j < r.without_each.size(); ++j) {
    each[r.without_each[j].dropped] = VariantJson(L, r.without_each[j]);  // key: the one dropped
  }
  out["without_each_constraint"] = each;
  out["run"] = {{"samples", r.samples}, {"epochs", r.epochs}, {"duration_s", r.duration_s}};
  out["time_s"] = r.seconds;
  return out;
}

bool IsScenarioFile(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  return root.IsMap() && root["profile"];
}

ObservabilityInput LoadObservabilityInput(const std::string& path, const std::string& effects,
                                          Session* session, int threads) {
  ObservabilityInput in;
  in.path = path;
  in.scenario = IsScenarioFile(path);
  if (in.scenario) {
    const Scenario s = NoiseFreeScenario(LoadScenario(path));
    session->RecordInput("scenario", path);
    in.data = Simulate(s);
    in.run = s.run;
    in.layout =
        ParameterLayout(ParseEffectList(effects), in.run.gyro.has_value() && in.data.has_gyro(),
                        ReadingsUnit(in.run));
    in.theta = TruthInLayout(s, in.layout);
    return in;
  }
  LoadedRun loaded = LoadRun(path, session, threads);
  in.data = std::move(loaded.data);
  in.layout = ParameterLayout(ParseEffectList(effects),
                              loaded.description.gyro.has_value() && in.data.has_gyro(),
                              ReadingsUnit(loaded.description));
  // noise_mV: auto: the readings' own noise, as `fit` starts from (not the
  // default 2 mV, which gave a CRB 36 times below the fit's sigma).
  in.noise_auto = loaded.description.noise_auto;
  in.run = WithReadingNoise(loaded.description, in.data);
  in.theta = NominalTheta(in.run, in.layout);
  return in;
}

namespace {

void Stage(const Session& session, const std::string& stage, double fraction) {
  if (session.stage) session.stage(stage);
  if (session.fraction) session.fraction(fraction);
}

// "parameters" of a fit/filter OUT ({"Kx": {"value": ...}}), of its "rts"
// section, or of a truth.json ({"Kx": 171.5}). Unknown names are ignored.
NamedValues ReadParameterValues(const std::string& path) {
  return FileValues(ReadParametersJson(path, {"", "rts"}, "a fit or filter OUT, or truth.json"));
}

}  // namespace

ObservabilityOutcome ObservabilityRun(const ObservabilitySettings& s, const ObservabilityInput& in,
                                      const Session& session) {
  s.Validate();
  ObservabilityOutcome o;
  o.source = in.scenario ? "scenario (simulated without noise)" : "run";
  o.at = in.scenario ? "truth" : "nominal";
  Eigen::VectorXd theta = in.theta;
  if (!s.at.empty()) {
    SetFromFileUnits(in.layout, ReadParameterValues(s.at), &theta);
    session.NoteInput(s.at);
    o.at = s.at;
  }
  if (s.could_hide && !in.scenario) {
    throw InputError(
        "--could-hide: needs a SCENARIO.yaml (a planned profile); for a recorded "
        "run, `diagnose` reports what could hide");
  }
  ObservabilityOptions oo;
  oo.threads = s.threads;
  oo.thresholds = {s.unobservable_below, s.weak_below};
  AngleDerivativeOptions derivatives;
  derivatives.half_window_s = s.rate_window_s;
  // Stages, none reporting from inside. Measured shares (paper's run 90 s at
  // 1 kHz; a 25-min real run at 100 Hz): loading the run 64 % / 29 %,
  // building the problem 8 % / 1 %, the Fisher information 28 % / 70 %.
  Stage(session, "building the problem", 0.35);
  RunProblem p =
      BuildRunProblem(in.run, in.data, in.layout, s.epoch_s, derivatives, nullptr, s.threads);
  // The Fisher information of a recorded run is that of the readings the
  // model predicts at theta for its recorded motion (SampleSeries::readings;
  // the angles' derivatives at every sample): the recorded readings' noise
  // is no information (in the Jacobian it would be taken for the specific
  // force a parameter multiplies). A scenario's readings are simulated
  // without noise: its own.
  if (!in.scenario) ReadPredictedReadingsInMotion(&p, in.data, derivatives, s.threads);
  Stage(session, "Fisher information", 0.4);
  o.result = AnalyseObservability(in.run, p, theta, oo);
  if (s.could_hide) {
    Stage(session, "what could hide (fit and score analysis)", 0.8);
    DiagnoseOptions d;
    d.alpha = s.alpha;
    d.fit.epoch_s = s.epoch_s;
    d.fit.derivatives = derivatives;
    d.fit.threads = s.threads;
    o.could_hide = CouldHideOnProfile(in.run, in.data, in.layout, theta, d);
  }

  const Eigen::Vector3d noise = in.run.ChannelNoise_mV();
  o.json = ObservabilityJson(o.result);
  o.json["command"] = "observability";
  o.json["input"] = in.path;
  o.json["source"] = o.source;
  o.json["evaluated_at"] = o.at;
  o.json["settings"] = {{"epoch_s", s.epoch_s},
                        {"rate_window_half_s", s.rate_window_s},
                        {"effects", s.effects},
                        {"unobservable_below", s.unobservable_below},
                        {"weak_below", s.weak_below},
                        {"declared_noise_mV",
                         in.noise_auto ? nlohmann::json(nullptr) : nlohmann::json(in.run.noise_mV)},
                        {"noise_auto", in.noise_auto},
                        {"noise_mV", {noise[0], noise[1], noise[2]}},
                        {"declared_angle_noise_arcsec", in.run.angle_noise_rad / kArcsecToRad}};
  if (s.could_hide) {
    o.json["could_hide"] = CouldHideJson(o.could_hide);
    o.json["settings"]["could_hide_alpha"] = s.alpha;
  }
  return o;
}

JointObservabilityOutcome JointObservabilityRun(const ObservabilitySettings& s, JointInput* in,
                                                const Session& session) {
  s.Validate();
  if (!s.at.empty()) throw InputError("--at: not available for several runs yet");
  // noise_mV: auto: each run's readings' own noise, as `fit` starts from.
  for (JointRun& r : in->runs) r.run = WithReadingNoise(r.run, r.data);
  const JointLayout& jl = *in->layout;
  JointOptions opt;
  opt.batch.epoch_s = s.epoch_s;
  opt.batch.derivatives.half_window_s = s.rate_window_s;
  opt.batch.threads = s.threads;
  Stage(session, "Fisher information of the runs together", 0.3);
  JointObservabilityOutcome o;
  o.info = JointInformationAtNominal(in->runs, jl, opt);
  const JointInformation& info = o.info;

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
  nlohmann::json& out = o.json;
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
                  {"run", in->file.runs[r].run_yaml},
                  {"samples", in->runs[r].data.size()},
                  {"held_alone", info.held_alone[r]}});
  }
  out["runs"] = jr;
  out["gyro_not_calibrated"] = GyroNotCalibratedJson(in->gyro_not_calibrated);
  out["settings"] = {{"epoch_s", s.epoch_s}, {"effects", s.effects}};
  return o;
}

}  // namespace triadcal
