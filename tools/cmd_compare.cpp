// `triadcal compare RUN.yaml -o OUT.json`: EKF, RTS smoother and batch solution
// of the same run side by side, with their differences in sigma units.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "app/compare_job.h"
#include "app/output_guard.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/value_format.h"

namespace triadcal {
namespace {

struct CompareArgs {
  std::string run_yaml, out_json, report_html;
  CompareSettings settings;  // filled by CLI11 directly
};

// Each estimate to the digit of its own sigma; the batch's sigma printed.
void PrintCompare(const CompareOutcome& c) {
  const ParameterLayout& layout = c.filter.layout;
  const FilterResult& fr = c.filter.result;
  const BatchResult& br = c.batch;
  const nlohmann::json& diff = c.json["differences_in_sigma"];
  std::printf("%-26s %16s %16s %16s %10s %9s %9s  %s\n", "parameter", "EKF", "RTS", "batch",
              "sigma", "RTS-EKF", "bat-RTS", "unit");
  const std::set<std::string> nominal(c.filter.pinned.begin(), c.filter.pinned.end());
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& p = layout.info(i);
    const double f = p.si_per_unit;
    if (nominal.count(p.name)) {
      const ValueText v = FormatWithSigma(br.estimate.theta[i] / f, 0.0);
      std::printf("%-26s %16s %16s %16s %10s %9s %9s  %s (not determined: nominal)\n",
                  p.name.c_str(), v.value.c_str(), v.value.c_str(), v.value.c_str(), "-", "-", "-",
                  p.unit.c_str());
      continue;
    }
    const double s = std::sqrt(std::max(br.estimate.cov(i, i), 1e-300));
    auto own = [&](const Estimate& e) {
      return FormatWithSigma(e.theta[i] / f, std::sqrt(std::max(e.cov(i, i), 0.0)) / f);
    };
    const ValueText b = FormatWithSigma(br.estimate.theta[i] / f, s / f);
    std::printf("%-26s %16s %16s %16s %10s %9.3f %9.3f  %s%s\n", p.name.c_str(),
                own(fr.ekf).value.c_str(), own(fr.rts).value.c_str(), b.value.c_str(),
                b.sigma.c_str(), diff[p.name]["rts_minus_ekf"].get<double>(),
                diff[p.name]["batch_minus_rts"].get<double>(), p.unit.c_str(),
                c.report.not_estimable.count(p.name) ? " (not estimable)" : "");
  }
  const nlohmann::json& largest = c.json["largest_batch_minus_rts"];
  std::printf(
      "differences in units of the batch sigma; largest |batch - RTS| among estimable: "
      "%.3f (%s)\n",
      largest["sigma"].get<double>(), largest["parameter"].get<std::string>().c_str());
}

int RunCompare(const CompareArgs& a, Session& session) {
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session);
  CheckOutputPath(a.out_json, session);
  a.settings.Validate();
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  CheckOverwrite(a.out_json, session);  // before the long work
  StageProgress progress("compare: ");
  const Session comparing = WithProgress(session, &progress);
  const CompareOutcome c = CompareRun(a.settings, a.run_yaml, run, comparing);
  EndProgress();
  if (!c.error.empty()) {
    std::fprintf(stderr, "triadcal: error: %s\n", c.error.c_str());
    return kExitNotConverged;
  }
  PrintCompare(c);
  WriteJson(c.json, a.out_json, session);
  WriteReportIfAsked(a.report_html, c.json, a.out_json, session);
  std::printf("time: filter %.2f s, batch from the RTS answer %.2f s\nwrote %s\n", c.filter_s,
              c.fit_s, a.out_json.c_str());
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
  c.app->add_option("--effects", a->settings.effects,
                    "catalogue effects to estimate too, e.g. a,b");
  c.app->add_option("--epoch-s", a->settings.epoch_s, "interval between epochs [s]")
      ->capture_default_str()
      ->check(kEpochRange);
  c.run = [a](Session& session) { return RunCompare(*a, session); };
  return c;
}

}  // namespace triadcal
