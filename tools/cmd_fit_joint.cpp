// `triadcal fit RUN1.yaml RUN2.yaml ... -o OUT.json` and `triadcal fit
// runs.yaml -o OUT.json`: the joint fit of several runs (app/joint_fit_job.h),
// written and printed: the parameters, each run's part and whether the runs
// agree.
#include "tools/cmd_fit_joint.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/joint_fit_job.h"
#include "app/output_guard.h"
#include "core/model/errors.h"
#include "tools/command_util.h"
#include "app/fit_report.h"
#include "tools/report/result_plausibility.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

// "Kz: Q 48.1 for 3 (p 1.2e-10), spread 7.1 mg/g between the runs: sigma 0.074 -> 4.1 mg/g"
std::string BetweenText(const JointParam& p, const BetweenRuns& b, double sigma) {
  char buf[300];
  std::snprintf(buf, sizeof(buf),
                "%s: Q %.1f for %d (p %.2g), spread %.3g %s between the runs: sigma %.3g -> "
                "%.3g %s",
                p.name.c_str(), b.q, b.dof, b.p_value, b.tau / p.si_per_unit, p.unit.c_str(),
                sigma / b.sigma_factor / p.si_per_unit, sigma / p.si_per_unit, p.unit.c_str());
  return buf;
}

std::string Names(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
  return s.empty() ? "none" : s;
}

}  // namespace

int RunJointFit(const FitSettings& s, const std::vector<std::string>& inputs,
                const std::string& out_json, const std::string& report_html, Session& session) {
  s.Validate();
  if (!report_html.empty()) {
    throw InputError("--report: not available for a joint fit of several runs yet");
  }
  CheckOutputPath(out_json, session);
  const JointInput in = LoadJointInput(inputs, s.effects, &session, s.threads);
  CheckOverwrite(out_json, session);
  const std::vector<JointRun>& runs = in.runs;
  const JointLayout& jl = *in.layout;
  StageProgress progress("fit: ");
  const Session fitting = WithProgress(session, &progress);
  const JointFitOutcome f = JointFitRun(s, in, fitting);
  EndProgress();
  const JointResult& r = f.result;
  const nlohmann::json& out = f.json;
  for (const std::string& w : ImplausibleResultWarnings(out["parameters"], out_json)) {
    std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(w).c_str());
  }
  WriteJson(out, out_json, session);

  std::printf("fit: %zu runs of one IMU as one problem; %s\n", runs.size(),
              JointVerdict(jl, r).c_str());
  std::printf(
      "joint: chi2/dof %.3f over %d degrees of freedom, %d iterations, %.1f s (runs "
      "alone %.1f s)\n",
      r.chi2_per_dof, r.degrees_of_freedom, r.iterations, r.seconds_joint, r.seconds_alone);
  const std::vector<Treatment> treat = TreatmentOf(r, jl.size());
  std::vector<const BetweenRuns*> between(jl.size(), nullptr);
  for (const BetweenRuns& b : r.between) between[b.index] = &b;
  std::printf("%-26s %22s %-10s", "parameter (IMU axes)", "value ± sigma", "unit");
  for (int q = 0; q < jl.runs(); ++q) std::printf(" %8.8s", jl.run_name(q).c_str());
  std::printf("   (share of the information)\n");
  for (int j = 0; j < jl.size(); ++j) {
    const JointParam& p = jl.param(j);
    const double value = r.phi[j] / p.si_per_unit;
    const bool spread = between[j] && between[j]->sigma_factor > 1.0;
    const std::string text =
        treat[j] == Treatment::kHeld ? FormatDouble(value) + " (held)"
        : treat[j] == Treatment::kConsidered
            ? FormatDouble(value) + " (not determined)"
            : ValuePlusMinus(value, std::sqrt(std::max(0.0, r.cov(j, j))) / p.si_per_unit) +
                  (spread ? "*" : "");
    std::printf("%-26s %22s %-10s", p.name.c_str(), text.c_str(), p.unit.c_str());
    if (treat[j] == Treatment::kEstimated) {
      for (int q = 0; q < jl.runs(); ++q) std::printf(" %8.2f", r.share(q, j));
    }
    if (const auto w = r.with_considered.find(j); w != r.with_considered.end()) {
      std::printf("  (only with considered");
      for (int c : w->second) std::printf(" %s", jl.param(c).name.c_str());
      std::printf(" at nominal)");
    }
    std::printf("\n");
  }
  bool any_spread = false;
  for (const BetweenRuns& b : r.between) {
    if (b.sigma_factor <= 1.0) continue;
    if (!any_spread) std::printf("* sigma with the spread between the runs (random effects):\n");
    any_spread = true;
    const double sigma = std::sqrt(std::max(0.0, r.cov(b.index, b.index)));
    std::printf("  %s%s\n", BetweenText(jl.param(b.index), b, sigma).c_str(),
                b.disagree ? " -- the runs DISAGREE" : "");
  }
  if (!r.consider.empty()) {
    std::vector<std::string> names;
    for (int j : r.consider) names.push_back(jl.param(j).name);
    std::printf("not determined by the runs together (nominal, prior uncertainty carried): %s\n",
                Names(names).c_str());
  }
  for (const JointRunResult& rr : r.runs) {
    const RunConsistency& c = rr.consistency;
    std::vector<std::string> undetermined = rr.alone.held;
    undetermined.insert(undetermined.end(), rr.alone.consider.begin(), rr.alone.consider.end());
    std::printf(
        "run %s: chi2/dof %.3f at the joint solution, sigma %s; alone %s, not determined "
        "%s; ",
        rr.name.c_str(), rr.chi2_per_dof, rr.sigma_method.c_str(),
        rr.alone.converged ? "converged" : "NOT converged", Names(undetermined).c_str());
    if (c.tested) {
      std::printf("against the others chi2 %.1f for %d, p %.3g: %s\n", c.chi2, c.dof, c.p_value,
                  c.consistent ? "agrees" : "DISAGREES");
    } else {
      std::printf("not compared (nothing of its own to compare)\n");
    }
  }
  std::printf("determined only by the runs together: %s\n", Names(r.jointly_only).c_str());
  std::printf("wrote %s\n", out_json.c_str());
  if (!r.converged) {
    std::fprintf(stderr, "triadcal: error: the joint fit did not converge: %s (exit %d)\n",
                 r.termination.c_str(), kExitNotConverged);
    return kExitNotConverged;
  }
  return 0;
}

}  // namespace triadcal
