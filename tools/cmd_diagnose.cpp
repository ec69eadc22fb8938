// `triadcal diagnose RUN.yaml -o OUT.json [--truth truth.json]`: the closed
// loop of docs/method.md (solvers/diagnosis/effect_discovery.h).
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "core/model/errors.h"
#include "core/io/file_util.h"
#include "core/io/parameters_json.h"
#include "core/simulation/simulator.h"
#include "solvers/diagnosis/effect_discovery.h"
#include "app/estimate_json.h"
#include "tools/command_util.h"
#include "solvers/estimation/run_problem.h"
#include "tools/commands.h"
#include "app/output_guard.h"
#include "app/diagnose_job.h"
#include "app/fit_report.h"
#include "app/residual_plot_json.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

struct DiagnoseArgs {
  std::string run_yaml, out_json, report_html, truth_json;
  DiagnoseSettings settings;
};

// Truth values in file units keyed by layout parameter name; keys the file
// has that we do not know are ignored (docs/file-formats.md).
std::map<std::string, double> ReadTruth(const std::string& path) {
  return FileValues(ReadParametersJson(path, {""}, "{\"parameters\": {name: value}}"));
}

int RunDiagnose(const DiagnoseArgs& a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session);
  CheckOutputPath(a.out_json, session);
  const LoadedRun run = LoadRun(a.run_yaml, &session, a.settings.threads);
  CheckOverwrite(a.out_json, session);  // before the long work
  a.settings.Validate();
  std::map<std::string, double> truth;
  // Read the truth first: a bad truth file must fail before the work.
  if (!a.truth_json.empty()) {
    truth = ReadTruth(a.truth_json);
    session.RecordInput("truth", a.truth_json);
  }
  const std::map<std::string, double>* tp = a.truth_json.empty() ? nullptr : &truth;
  StageProgress progress("diagnose: ");
  const Session diagnosing = WithProgress(session, &progress);
  const DiagnoseOutcome outcome = DiagnoseRun(a.settings, a.run_yaml, run, tp, diagnosing);
  EndProgress();
  const DiagnosisResult& d = outcome.result;
  const nlohmann::json& out = outcome.json;
  WriteJson(out, a.out_json, session);
  WriteReportIfAsked(a.report_html, out, a.out_json, session);

  // The readable report.
  std::printf("diagnose: %s\n", d.verdict.c_str());
  for (const std::string& n : d.notes) std::printf("note: %s\n", n.c_str());
  std::printf("\n");
  std::printf(
      "candidates, round 1 (likelihood ratio, scaled, and refitted the Wald test against the "
      "refit's sigma; selected when both p < %.2g):\n",
      d.ranking.empty() ? 0.0 : d.ranking.front().threshold);
  for (const CandidateTest& t : d.ranking) {
    char wald[40] = "";
    if (t.refit) std::snprintf(wald, sizeof(wald), "Wald p %-10.3g ", t.wald_p_value);
    std::printf("  %-26s stat %10.2f  dof %d  p %-10.3g %s%s%s\n",
                GetEffectSpec(t.effect).name.c_str(), t.statistic, t.dof, t.p_value, wald,
                t.selected ? "SELECTED" : "", t.note.empty() ? "" : ("(" + t.note + ")").c_str());
  }
  for (const CandidateTest& t : d.absorbing) {
    std::printf("  round %d: %s NOT a finding (p %.3g): %s\n", t.round,
                GetEffectSpec(t.effect).name.c_str(), t.p_value, t.absorbs.c_str());
  }
  for (const EffectCorrelation& c : d.correlations) {
    std::printf("  %s correlates with %s at %+.2f\n", c.parameter.c_str(), c.with.c_str(), c.rho);
  }
  for (const CandidateTest& t : d.tests) {
    if (t.round > 1 && t.selected) {
      std::printf("  round %d: %s selected (p %.3g, Wald p %.3g)\n", t.round,
                  GetEffectSpec(t.effect).name.c_str(), t.p_value, t.wald_p_value);
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
  std::printf("\n%-26s %16s %9s %16s %9s %8s", "parameter", "before", "sigma", "after", "sigma",
              "shift/s");
  if (tp) std::printf(" %9s %9s", "err/s bef", "err/s aft");
  std::printf("  unit\n");
  for (int i = 0; i < d.after_layout.size(); ++i) {
    const ParameterInfo& p = d.after_layout.info(i);
    const double f = p.si_per_unit;
    const int ib = d.before_layout.IndexOf(p.name);
    const double va = d.after.estimate.theta[i] / f;
    const double sa = std::sqrt(std::max(0.0, d.after.estimate.cov(i, i))) / f;
    const bool considered = ra.consider.count(p.name) > 0;
    const bool held = ra.held.count(p.name) > 0 || considered;
    if (ib >= 0) {
      const double vb = d.before.estimate.theta[ib] / f;
      const double sb = std::sqrt(std::max(0.0, d.before.estimate.cov(ib, ib))) / f;
      const ValueText tb = FormatWithSigma(vb, sb), ta = FormatWithSigma(va, sa);
      std::printf("%-26s %16s %9s %16s %9s %8.2f", p.name.c_str(), tb.value.c_str(),
                  tb.sigma.c_str(), ta.value.c_str(), ta.sigma.c_str(), held ? 0.0 : (va - vb) / sa);
      if (tp) {
        auto it = truth.find(p.name);
        if (it != truth.end() && !held) {
          std::printf(" %9.2f %9.2f", (vb - it->second) / sb, (va - it->second) / sa);
        } else {
          std::printf(" %9s %9s", "-", "-");
        }
      }
    } else {
      const ValueText ta = FormatWithSigma(va, sa);
      std::printf("%-26s %16s %9s %16s %9s %8s", p.name.c_str(), "-", "-", ta.value.c_str(),
                  ta.sigma.c_str(), "new");
      if (tp) {
        auto it = truth.find(p.name);
        if (it != truth.end()) std::printf(" %9s %9.2f", "-", (va - it->second) / sa);
        else std::printf(" %9s %9s", "-", "-");
      }
    }
    std::printf("  %s%s\n", p.unit.c_str(),
                considered ? " (not determined)" : held ? " (held)" : "");
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
  c.app->add_option("--report", a->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  c.app->add_option("--truth", a->truth_json, "truth.json of a simulated run: errors before/after");
  c.app->add_option("--candidates", a->settings.candidates,
                    "effects to test (default: the whole catalogue), e.g. a,b");
  c.app->add_option("--alpha", a->settings.alpha, "false-selection rate per round, in (0, 1)")
      ->capture_default_str();
  c.app->add_option("--max-effects", a->settings.max_effects, "at most this many effects")
      ->capture_default_str()
      ->check(BoundedInt(0, 20));
  c.app->add_option("--epoch-s", a->settings.epoch_s, "interval between epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.app->add_option("--rate-window-s", a->settings.rate_window_s,
                    "half window of the local cubic fit giving lambda' from the angles [s]")
      ->capture_default_str()
      ->check(kRateWindowRange);
  c.app->add_option("--threads", a->settings.threads, "threads (0: all cores)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.run = [a](Session& session) { return RunDiagnose(*a, session); };
  return c;
}

}  // namespace triadcal
