// The report's JavaScript and CSS, inlined at build time from
// tools/report/assets/ (uPlot 1.6.32 from npm, MIT licence in
// assets/uPlot.LICENSE; report.js and report.css are triadcal's own).
#pragma once

namespace triadcal {

extern const char* const kUplotJs;
extern const char* const kUplotCss;
extern const char* const kReportJs;
extern const char* const kReportCss;

}  // namespace triadcal
