// `triadcal diagnose RUN.yaml -o OUT.json [--truth truth.json]`: the closed
// loop of SPEC section 8 (solvers/diagnosis/effect_discovery.h).
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "core/model/errors.h"
#include "core/io/file_util.h"
#include "core/simulation/simulator.h"
#include "solvers/diagnosis/effect_discovery.h"
#include "tools/report/estimate_json.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/fit_report.h"

namespace triadcal {
namespace {

struct DiagnoseArgs {
  std::string run_yaml, out_json, truth_json, candidates;
  double alpha = 0.01;
  int max_effects = 4;
  double epoch_s = 0.2;
};

// Truth values in file units keyed by layout parameter name; keys the file
// has that we do not know are ignored (SPEC section 7).
std::map<std::string, double> ReadTruth(const std::string& path) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadFile(path));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (!j.contains("parameters") || !j["parameters"].is_object()) {
    throw InputError(path + ": parameters: missing (expected {\"parameters\": {name: value}})");
  }
  std::map<std::string, double> out;
  // Every effect, so that injected effects not selected are known too.
  std::vector<Effect> all;
  for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
  const ParameterLayout every(all);
  for (int i = 0; i < every.size(); ++i) {
    for (const std::string& key : {every.info(i).name, TruthFileKey(every, i)}) {
      if (j["parameters"].contains(key) && j["parameters"][key].is_number()) {
        out[every.info(i).name] = j["parameters"][key].get<double>();
      }
    }
  }
  return out;
}

nlohmann::json StateJson(const ParameterLayout& layout, const BatchResult& r,
                         const ResidualReport& rr, const std::map<std::string, double>* truth) {
  const FitReport rep = MakeFitReport(layout, r);
  nlohmann::json j;
  j["effects"] = nlohmann::json::array();
  for (Effect e : layout.effects()) j["effects"].push_back(GetEffectSpec(e).name);
  j["parameters"] = ParametersJson(layout, r.estimate.theta, r.estimate.cov, rep.not_estimable);
  j["held"] = r.held;
  j["chi2_per_dof"] = r.chi2_per_dof;
  j["residual"] = ResidualReportJson(rr);
  nlohmann::json rms = nlohmann::json::object();
  nlohmann::json white = nlohmann::json::object();
  for (const ChannelReport& c : rr.channels) {
    rms[c.name] = c.rms;
    white[c.name] = c.whiteness.p_value;
  }
  j["residual_rms"] = rms;
  j["whiteness_p"] = white;
  if (truth) {
    nlohmann::json err = nlohmann::json::object();
    double sum2 = 0.0;
    int count = 0;
    for (int i = 0; i < layout.size(); ++i) {
      const ParameterInfo& p = layout.info(i);
      auto it = truth->find(p.name);
      if (it == truth->end() || rep.not_estimable.count(p.name)) continue;
      const double v = r.estimate.theta[i] / p.si_per_unit;
      const double s = std::sqrt(r.estimate.cov(i, i)) / p.si_per_unit;
      err[p.name] = {{"error", v - it->second}, {"error_in_sigma", (v - it->second) / s},
                     {"unit", p.unit}};
      sum2 += std::pow((v - it->second) / s, 2);
      ++count;
    }
    j["error_vs_truth"] = err;
    j["error_vs_truth_rms_sigma"] = count ? std::sqrt(sum2 / count) : 0.0;
  }
  return j;
}

int RunDiagnose(const DiagnoseArgs& a) {
  CheckOutputPath(a.out_json);
  const LoadedRun run = LoadRunOrThrow(a.run_yaml);
  DiagnoseOptions opt;
  opt.alpha = a.alpha;
  opt.max_effects = a.max_effects;
  opt.fit.epoch_s = a.epoch_s;
  opt.candidates = ParseEffectList(a.candidates, "--candidates");
  opt.progress = [](const std::string& s) { ShowProgress("diagnose: " + s, 0.0); };
  if (!(a.alpha > 0.0 && a.alpha < 1.0)) throw InputError("--alpha: must be in (0, 1)");
  std::map<std::string, double> truth;
  // Read the truth first: a bad truth file must fail before the work.
  if (!a.truth_json.empty()) truth = ReadTruth(a.truth_json);
  const DiagnosisResult d = Diagnose(run.description, run.data, opt);
  EndProgress();
  const std::map<std::string, double>* tp = a.truth_json.empty() ? nullptr : &truth;

  nlohmann::json out;
  out["command"] = "diagnose";
  out["run"] = a.run_yaml;
  nlohmann::json ranking = nlohmann::json::array();
  for (const CandidateTest& t : d.ranking) {
    ranking.push_back({{"effect", GetEffectSpec(t.effect).name},
                       {"statistic", t.statistic},
                       {"likelihood_ratio", t.lr},
                       {"dof", t.dof},
                       {"p_value", t.p_value},
                       {"threshold", t.threshold},
                       {"selected", t.selected},
                       {"note", t.note}});
  }
  out["ranking"] = ranking;
  nlohmann::json tests = nlohmann::json::array();
  for (const CandidateTest& t : d.tests) {
    tests.push_back({{"round", t.round}, {"effect", GetEffectSpec(t.effect).name},
                     {"statistic", t.statistic}, {"dof", t.dof}, {"p_value", t.p_value},
                     {"threshold", t.threshold}, {"selected", t.selected}});
  }
  out["tests"] = tests;
  out["selected"] = nlohmann::json::array();
  for (Effect e : d.selected) out["selected"].push_back(GetEffectSpec(e).name);
  out["selection_rule"] = "forward, one effect per round; selected when its p-value < alpha / "
                          "(candidates in the round), alpha = " + std::to_string(a.alpha);
  out["before"] = StateJson(d.before_layout, d.before, d.before_residuals, tp);
  out["after"] = StateJson(d.after_layout, d.after, d.after_residuals, tp);
  out["parameters"] = out["after"]["parameters"];
  out["unexplained_structure"] = d.unexplained;
  out["notes"] = d.notes;
  out["verdict"] = d.verdict;
  WriteJson(out, a.out_json);

  // The readable report.
  std::printf("diagnose: %s\n", d.verdict.c_str());
  for (const std::string& n : d.notes) std::printf("note: %s\n", n.c_str());
  std::printf("\n");
  std::printf("candidates, round 1 (likelihood ratio, scaled; selected when p < %.2g):\n",
              d.ranking.empty() ? 0.0 : d.ranking.front().threshold);
  for (const CandidateTest& t : d.ranking) {
    std::printf("  %-26s stat %10.2f  dof %d  p %-10.3g %s%s\n", GetEffectSpec(t.effect).name.c_str(),
                t.statistic, t.dof, t.p_value, t.selected ? "SELECTED" : "",
                t.note.empty() ? "" : ("(" + t.note + ")").c_str());
  }
  for (const CandidateTest& t : d.tests) {
    if (t.round > 1 && t.selected) {
      std::printf("  round %d: %s selected (p %.3g)\n", t.round, GetEffectSpec(t.effect).name.c_str(),
                  t.p_value);
    }
  }
  std::printf("\n%-32s %14s %14s\n", "residual", "before", "after");
  for (std::size_t c = 0; c < d.before_residuals.channels.size() && c < 3; ++c) {
    const ChannelReport& b = d.before_residuals.channels[c];
    const ChannelReport& f = d.after_residuals.channels[c];
    std::printf("%-32s %14.4g %14.4g  %s\n", (b.name + " RMS").c_str(), b.rms, f.rms, b.unit.c_str());
    std::printf("%-32s %14.3g %14.3g\n", ("  Ljung-Box p"), b.whiteness.p_value,
                f.whiteness.p_value);
  }
  std::printf("%-32s %14.4f %14.4f  (1 expected)\n", "chi2/dof", d.before.chi2_per_dof,
              d.after.chi2_per_dof);

  const FitReport ra = MakeFitReport(d.after_layout, d.after);
  std::printf("\n%-26s %13s %9s %13s %9s %8s", "parameter", "before", "sigma", "after", "sigma",
              "shift/s");
  if (tp) std::printf(" %9s %9s", "err/s bef", "err/s aft");
  std::printf("  unit\n");
  for (int i = 0; i < d.after_layout.size(); ++i) {
    const ParameterInfo& p = d.after_layout.info(i);
    const double f = p.si_per_unit;
    const int ib = d.before_layout.IndexOf(p.name);
    const double va = d.after.estimate.theta[i] / f;
    const double sa = std::sqrt(std::max(0.0, d.after.estimate.cov(i, i))) / f;
    const bool held = ra.held.count(p.name) > 0;
    if (ib >= 0) {
      const double vb = d.before.estimate.theta[ib] / f;
      const double sb = std::sqrt(std::max(0.0, d.before.estimate.cov(ib, ib))) / f;
      std::printf("%-26s %13.6g %9.3g %13.6g %9.3g %8.2f", p.name.c_str(), vb, sb, va, sa,
                  held ? 0.0 : (va - vb) / sa);
      if (tp) {
        auto it = truth.find(p.name);
        if (it != truth.end() && !held) {
          std::printf(" %9.2f %9.2f", (vb - it->second) / sb, (va - it->second) / sa);
        } else {
          std::printf(" %9s %9s", "-", "-");
        }
      }
    } else {
      std::printf("%-26s %13s %9s %13.6g %9.3g %8s", p.name.c_str(), "-", "-", va, sa, "new");
      if (tp) {
        auto it = truth.find(p.name);
        if (it != truth.end()) std::printf(" %9s %9.2f", "-", (va - it->second) / sa);
        else std::printf(" %9s %9s", "-", "-");
      }
    }
    std::printf("  %s%s\n", p.unit.c_str(), held ? " (held)" : "");
  }
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddDiagnoseCommand(CLI::App& app) {
  auto a = std::make_shared<DiagnoseArgs>();
  Command c;
  c.app = app.add_subcommand(
      "diagnose", "Fit, trace the residual to missing effects, add them, report before/after");
  c.app->add_option("run", a->run_yaml, "run description (run.yaml)")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--truth", a->truth_json, "truth.json of a simulated run: errors before/after");
  c.app->add_option("--candidates", a->candidates,
                    "effects to test (default: the whole catalogue), e.g. a,b");
  c.app->add_option("--alpha", a->alpha, "false-selection rate per round")->capture_default_str();
  c.app->add_option("--max-effects", a->max_effects, "at most this many effects")
      ->capture_default_str();
  c.app->add_option("--epoch-s", a->epoch_s, "interval between epochs [s]")->capture_default_str()
      ->check(kEpochRange);
  c.run = [a] { return RunDiagnose(*a); };
  return c;
}

}  // namespace triadcal
