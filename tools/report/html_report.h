// The HTML report (`triadcal report OUT.json... -o report.html`, and
// `--report FILE` on the long commands): one self-contained file with the
// verdict first, the parameter table with sigma and units, and the charts the
// OUT files carry (residual series and spectra, diagnose before/after,
// correlation heat map, observability, design and Monte Carlo curves), plus a
// per-run comparison when given several OUT files.
//
// The page is built in the browser by assets/report.js (charts by uPlot) from
// the OUT files embedded verbatim as JSON; both scripts are inlined, so the
// file opens offline. After drawing, the page checks its own canvases and
// records the result in <div id="triadcal-status" data-status=...> (what the
// browser test reads).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/io/file_util.h"

namespace triadcal {

struct ReportInput {
  std::string name;    // shown in the report (the OUT file's name)
  nlohmann::json out;  // the OUT file's content
};

// Reads OUT files; InputError "FILE: ..." when one is missing, not JSON, or
// not a triadcal output (no "command" key).
std::vector<ReportInput> LoadReportInputs(const std::vector<std::string>& paths);

// The whole page.
std::string HtmlReport(const std::vector<ReportInput>& inputs);

// Writes HtmlReport(inputs) atomically (WriteFileAtomically with `options`).
void WriteHtmlReport(const std::vector<ReportInput>& inputs, const std::string& path,
                     const WriteOptions& options);

}  // namespace triadcal
