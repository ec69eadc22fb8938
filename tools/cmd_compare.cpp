// `triadcal compare RUN.yaml -o OUT.json`: EKF, RTS smoother and batch solution
// of the same run side by side, with their differences in sigma units.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "core/model/errors.h"
#include "solvers/estimation/batch_solver.h"
#include "app/estimate_json.h"
#include "solvers/estimation/kalman_smoother.h"
#include "tools/command_util.h"
#include "solvers/estimation/run_problem.h"
#include "tools/commands.h"
#include "app/output_guard.h"
#include "core/io/column_mapping.h"
#include "app/fit_report.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

struct CompareArgs {
  std::string run_yaml, out_json, report_html, effects;
  double epoch_s = kDefaultEpoch_s;
};

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int RunCompare(const CompareArgs& a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html);
  CheckOutputPath(a.out_json);
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  CheckOverwrite(a.out_json, session);  // before the long work
  const ParameterLayout layout(ParseEffectList(a.effects, run.data), /*gyro=*/false,
                               ReadingsUnit(run.description));

  // One decision of what the run determines, for both estimators: the filter
  // holds what fit holds or considers (at nominal).
  BatchOptions bo;
  bo.epoch_s = a.epoch_s;
  const HoldDecision hd = ChooseHeldParameters(run.description, run.data, layout, bo.holding,
                                               bo.epoch_s, bo.derivatives, bo.init_decimation_hz,
                                               bo.threads);
  bo.decision = &hd;
  FilterOptions fo;
  fo.epoch_s = a.epoch_s;
  fo.held = hd.held;
  fo.held.insert(fo.held.end(), hd.consider.begin(), hd.consider.end());
  // Progress: the filter's passes the first half, the batch the second.
  StageProgress progress("compare: ");
  const int passes = std::max(1, fo.smoother_iterations);
  fo.progress = [&](int pass, double f) {
    progress.Stage("filter pass " + std::to_string(pass));
    progress.Fraction(0.5 * (pass - 1 + f) / passes);
  };
  auto t0 = std::chrono::steady_clock::now();
  const FilterResult fr = RunFilterSmoother(run.description, run.data, layout, fo);
  const double filter_s = Seconds(t0);

  bo.init = BatchInit::kGiven;  // start the batch at the smoother's answer
  bo.init_theta = fr.rts.theta;
  bo.progress = [&](const std::string& s) { progress.Stage("fit " + s); };
  bo.fraction = [&](double f) { progress.Fraction(0.5 + 0.5 * f); };
  t0 = std::chrono::steady_clock::now();
  BatchResult br = SolveBatch(run.description, run.data, layout, bo);
  br.initial = fr.rts;
  const double fit_s = Seconds(t0);
  EndProgress();
  const FitReport rep = MakeFitReport(layout, br);

  nlohmann::json out;
  out["command"] = "compare";
  out["run"] = a.run_yaml;
  out["ekf"] = {{"parameters", ParametersJson(layout, fr.ekf.theta, fr.ekf.cov, rep.not_estimable)}};
  out["rts"] = {{"parameters", ParametersJson(layout, fr.rts.theta, fr.rts.cov, rep.not_estimable)}};
  out["batch"] = {{"parameters",
                   ParametersJson(layout, br.estimate.theta, br.estimate.cov, rep.not_estimable)},
                  {"verdict", rep.verdict},
                  {"chi2_per_dof", br.chi2_per_dof}};
  out["not_estimable"] = std::vector<std::string>(ParametersIn(rep.weak));
  out["time_s"] = {{"filter", filter_s}, {"fit_from_rts", fit_s}};
  nlohmann::json diff = nlohmann::json::object();
  double max_abs = 0.0;
  std::string max_name;
  // Each estimate to the digit of its own sigma; the batch's sigma printed.
  std::printf("%-26s %16s %16s %16s %10s %9s %9s  %s\n", "parameter", "EKF", "RTS", "batch",
              "sigma", "RTS-EKF", "bat-RTS", "unit");
  const std::set<std::string> nominal(fo.held.begin(), fo.held.end());
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& p = layout.info(i);
    const double f = p.si_per_unit;
    if (nominal.count(p.name)) {
      // Held at nominal by all three: no estimate, no difference.
      diff[p.name] = {{"rts_minus_ekf", nullptr}, {"batch_minus_rts", nullptr},
                      {"batch_minus_ekf", nullptr}, {"unit", "batch sigma"}};
      const ValueText v = FormatWithSigma(br.estimate.theta[i] / f, 0.0);
      std::printf("%-26s %16s %16s %16s %10s %9s %9s  %s (not determined: nominal)\n",
                  p.name.c_str(), v.value.c_str(), v.value.c_str(), v.value.c_str(), "-", "-", "-",
                  p.unit.c_str());
      continue;
    }
    const double s = std::sqrt(std::max(br.estimate.cov(i, i), 1e-300));
    const double d_re = (fr.rts.theta[i] - fr.ekf.theta[i]) / s;
    const double d_br = (br.estimate.theta[i] - fr.rts.theta[i]) / s;
    const double d_be = (br.estimate.theta[i] - fr.ekf.theta[i]) / s;
    diff[p.name] = {{"rts_minus_ekf", d_re}, {"batch_minus_rts", d_br}, {"batch_minus_ekf", d_be},
                    {"unit", "batch sigma"}};
    if (!rep.not_estimable.count(p.name) && std::abs(d_br) > max_abs) {
      max_abs = std::abs(d_br);
      max_name = p.name;
    }
    auto own = [&](const Estimate& e) {
      return FormatWithSigma(e.theta[i] / f, std::sqrt(std::max(e.cov(i, i), 0.0)) / f);
    };
    const ValueText b = FormatWithSigma(br.estimate.theta[i] / f, s / f);
    std::printf("%-26s %16s %16s %16s %10s %9.3f %9.3f  %s%s\n", p.name.c_str(),
                own(fr.ekf).value.c_str(), own(fr.rts).value.c_str(), b.value.c_str(),
                b.sigma.c_str(), d_re, d_br, p.unit.c_str(),
                rep.not_estimable.count(p.name) ? " (not estimable)" : "");
  }
  out["differences_in_sigma"] = diff;
  out["largest_batch_minus_rts"] = {{"parameter", max_name}, {"sigma", max_abs}};
  WriteJson(out, a.out_json, session);
  WriteReportIfAsked(a.report_html, out, a.out_json, session);
  std::printf("differences in units of the batch sigma; largest |batch - RTS| among estimable: "
              "%.3f (%s)\n",
              max_abs, max_name.c_str());
  std::printf("time: filter %.2f s, batch from the RTS answer %.2f s\nwrote %s\n", filter_s,
              fit_s, a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddCompareCommand(CLI::App& app) {
  auto a = std::make_shared<CompareArgs>();
  Command c;
  c.app = app.add_subcommand("compare", "EKF, RTS smoother and batch side by side");
  c.app->add_option("run", a->run_yaml, "run description (run.yaml)")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--report", a->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  c.app->add_option("--effects", a->effects, "catalogue effects to estimate too, e.g. a,b");
  c.app->add_option("--epoch-s", a->epoch_s, "interval between epochs [s]")->capture_default_str()
      ->check(kEpochRange);
  c.run = [a](Session& session) { return RunCompare(*a, session); };
  return c;
}

}  // namespace triadcal
