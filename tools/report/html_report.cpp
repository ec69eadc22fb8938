#include "tools/report/html_report.h"

#include <algorithm>
#include <filesystem>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/version/version.h"
#include "tools/report/report_assets.h"

namespace triadcal {
namespace {

// JSON inside <script type="application/json">: '<' occurs only inside JSON
// strings, where "\u003c" means the same, so no "</script>" or "<!--" can end
// the element early.
std::string ScriptSafeJson(const nlohmann::json& j) {
  const std::string s = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

std::string HtmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

std::vector<ReportInput> LoadReportInputs(const std::vector<std::string>& paths) {
  std::vector<ReportInput> inputs;
  for (const std::string& p : paths) {
    const std::string text = ReadFile(p);
    ReportInput in;
    in.name = std::filesystem::path(p).filename().string();
    try {
      in.out = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
      const std::size_t end = std::min<std::size_t>(e.byte, text.size());
      const long line = 1 + std::count(text.begin(), text.begin() + end, '\n');
      throw InputError(p + ":" + std::to_string(line) + ": not valid JSON");
    }
    if (!in.out.is_object() || !in.out.contains("command") || !in.out["command"].is_string()) {
      throw InputError(p + ": command: missing; not a triadcal output file");
    }
    inputs.push_back(std::move(in));
  }
  return inputs;
}

std::string HtmlReport(const std::vector<ReportInput>& inputs) {
  nlohmann::json data = nlohmann::json::array();
  std::string title = "triadcal report:";
  for (const ReportInput& in : inputs) {
    data.push_back({{"name", in.name}, {"out", in.out}});
    title += " " + in.name;
  }
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  h += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  h += std::string("<meta name=\"generator\" content=\"triadcal ") + ToolVersion() + "\">\n";
  h += "<title>" + HtmlEscape(title) + "</title>\n";
  h += "<style>\n/* uPlot 1.6.32, MIT licence (c) Leon Sorokin */\n";
  h += kUplotCss;
  h += "\n</style>\n<style>\n";
  h += kReportCss;
  h += "\n</style>\n</head>\n<body>\n";
  // Before any other script: record script errors and console errors or
  // warnings, for the page's self-check (assets/report.js).
  h += "<script>window.triadcalErrors=[];window.addEventListener('error',function(e){"
       "window.triadcalErrors.push(String(e.message||e));});['error','warn'].forEach(function(k){"
       "var f=console[k];console[k]=function(){window.triadcalErrors.push('console.'+k+': '+"
       "Array.prototype.join.call(arguments,' '));return "
       "f.apply(console,arguments);};});</script>\n";
  h += "<div id=\"triadcal-status\" data-status=\"loading\">loading</div>\n";
  h += "<main id=\"report\"><noscript>This report draws its tables and charts with JavaScript."
       "</noscript></main>\n";
  h += "<script type=\"application/json\" id=\"triadcal-data\">";
  h += ScriptSafeJson(data);
  h += "</script>\n<script>\n/* uPlot 1.6.32, MIT licence (c) Leon Sorokin, "
       "https://github.com/leeoniya/uPlot */\n";
  h += kUplotJs;
  h += "\n</script>\n<script>\n";
  h += kReportJs;
  h += "\n</script>\n</body>\n</html>\n";
  return h;
}

void WriteHtmlReport(const std::vector<ReportInput>& inputs, const std::string& path,
                     const WriteOptions& options) {
  WriteFileAtomically(path, HtmlReport(inputs), options);
}

}  // namespace triadcal
