#include "tools/command_util.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <unistd.h>

#include "core/model/errors.h"
#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/io/run_description_io.h"
#include "tools/provenance.h"
#include "tools/report/html_report.h"
#include "solvers/static/mounting_search.h"

namespace triadcal {

LoadedRun LoadRunOrThrow(const std::string& run_yaml) {
  LoadedRun r;
  r.description = LoadRunDescription(run_yaml);
  SetReadingsUnitName(ReadingsUnit(r.description));  // output units named for what was read
  RecordInput("run", run_yaml);
  RecordSensor(r.description.sensor_serial, r.description.sensor_model);
  RunWarnings warnings;
  r.data = LoadRunData(r.description, &warnings);
  const std::string mounting = MountingWarning(r.description, r.data);
  if (!mounting.empty()) warnings.lines.push_back(mounting);
  for (const std::string& w : warnings.lines) std::cerr << "triadcal: warning: " << OneLine(w) << "\n";
  RecordInput("data", r.description.data_path);
  return r;
}

std::vector<std::string> SplitList(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

std::vector<Effect> ParseEffectList(const std::string& list, const std::string& option) {
  std::vector<Effect> out;
  for (const std::string& item : SplitList(list)) {
    try {
      out.push_back(EffectFromName(item));
    } catch (const std::invalid_argument& e) {
      throw InputError(option + ": " + e.what());
    }
  }
  return out;
}

std::vector<Effect> ParseEffectList(const std::string& list, const RunData& data,
                                    const std::string& option) {
  const std::vector<Effect> effects = ParseEffectList(list, option);
  for (Effect e : effects) {
    const EffectSpec& spec = GetEffectSpec(e);
    if (spec.needs.temp_C && !data.has_temp()) {
      throw InputError(option + ": " + spec.name +
                       " needs a temp_C column, which this run does not have (columns.temp_C "
                       "in run.yaml)");
    }
  }
  return effects;
}

namespace {

struct ProgressState {
  bool quiet = false;
  bool shown = false;  // a terminal line is on screen
  bool started = false;
  std::chrono::steady_clock::time_point last;
};

ProgressState& Progress() {
  static ProgressState state;
  return state;
}

double PipedIntervalSeconds() {
  const char* env = std::getenv("TRIADCAL_PROGRESS_INTERVAL_S");
  if (env && *env) {
    char* end = nullptr;
    const double v = std::strtod(env, &end);
    if (end != env && v >= 0.0) return v;
  }
  return 5.0;
}

}  // namespace

void SetQuiet(bool quiet) { Progress().quiet = quiet; }

void ShowProgress(const std::string& what, double fraction) {
  ProgressState& p = Progress();
  if (p.quiet) return;
  const auto now = std::chrono::steady_clock::now();
  const bool tty = isatty(fileno(stderr));
  if (!p.started) {
    p.started = true;
    // Piped: the first line after one interval, so short commands stay silent.
    p.last = tty ? now - std::chrono::seconds(1) : now;
  }
  const double since = std::chrono::duration<double>(now - p.last).count();
  char pct[16] = "";
  if (fraction >= 0.0) {
    std::snprintf(pct, sizeof(pct), "  %3.0f%%", 100.0 * std::min(1.0, fraction));
  }
  if (tty) {
    if (since < 0.1) return;
    std::fprintf(stderr, "\r%-72.72s%s", what.c_str(), pct);
    p.shown = true;
  } else {
    if (since < PipedIntervalSeconds()) return;
    std::fprintf(stderr, "%s%s\n", what.c_str(), pct);
  }
  std::fflush(stderr);
  p.last = now;
}

void EndProgress() {
  ProgressState& p = Progress();
  if (p.shown) {
    std::fprintf(stderr, "\r%80s\r", "");
    std::fflush(stderr);
    p.shown = false;
  }
  p.started = false;
}

void CheckOutputPath(const std::string& path) {
  namespace fs = std::filesystem;
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir) || access(dir.c_str(), W_OK) != 0) {
    throw InputError(path + ": cannot write (folder missing or not writable)");
  }
  NoteOutputFile(path);
}

void WriteJson(const nlohmann::json& j, const std::string& path) {
  CheckOverwrite(path);
  nlohmann::json stamped = j;
  stamped["provenance"] = CurrentProvenance();
  WriteFileAtomically(path, stamped.dump(2) + "\n");
}

void WriteReportIfAsked(const std::string& report_html, const nlohmann::json& out,
                        const std::string& out_json) {
  if (report_html.empty()) return;
  ReportInput in;
  in.name = std::filesystem::path(out_json).filename().string();
  in.out = out;
  WriteHtmlReport({in}, report_html);
  std::printf("wrote %s\n", report_html.c_str());
}

}  // namespace triadcal
