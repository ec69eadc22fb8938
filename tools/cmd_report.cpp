// `triadcal report OUT.json [OUT2.json ...] -o report.html`: one
// self-contained HTML page from the outputs of the other commands
// (tools/report/html_report.h).
#include <cstdio>
#include <memory>

#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/html_report.h"

namespace triadcal {
namespace {

struct ReportArgs {
  std::vector<std::string> inputs;
  std::string out_html;
};

int RunReport(const ReportArgs& a, Session& session) {
  CheckOutputPath(a.out_html, session);
  const std::vector<ReportInput> inputs = LoadReportInputs(a.inputs);
  for (const std::string& in : a.inputs) session.NoteInput(in);
  WriteHtmlReport(inputs, a.out_html, session.write_options());
  std::printf("wrote %s (%zu output%s)\n", a.out_html.c_str(), inputs.size(),
              inputs.size() == 1 ? "" : "s");
  return 0;
}

}  // namespace

Command AddReportCommand(CLI::App& app) {
  auto a = std::make_shared<ReportArgs>();
  Command c;
  c.app = app.add_subcommand(
      "report", "Self-contained HTML report (opens offline) from one or more OUT.json files");
  c.app->add_option("outputs", a->inputs, "OUT.json files of fit, diagnose, compare, ...")
      ->required();
  c.app->add_option("-o,--output", a->out_html, "output HTML")->required();
  c.run = [a](Session& session) { return RunReport(*a, session); };
  return c;
}

}  // namespace triadcal
