#include "tools/command_util.h"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "core/io/file_util.h"
#include "core/model/angle_derivatives.h"
#include "core/model/errors.h"
#include "tools/report/html_report.h"

namespace triadcal {

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

CLI::Validator Bounded(double lo, double hi) {
  char range[80];
  std::snprintf(range, sizeof(range), "in [%g, %g]", lo, hi);
  return CLI::Validator(
      [lo, hi](std::string& input) -> std::string {
        double v = 0.0;
        if (CLI::detail::lexical_cast(input, v) && std::isfinite(v) && v >= lo && v <= hi) {
          return "";
        }
        // The text of CLI::Range, which this replaces.
        return "Value " + Excerpt(input, 40) + " not in range " + std::to_string(lo) + " to " +
               std::to_string(hi);
      },
      range);
}

CLI::Validator BoundedInt(long long lo, long long hi) {
  const std::string range = "in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi](std::string& input) -> std::string {
        long long v = 0;
        const auto res = std::from_chars(input.data(), input.data() + input.size(), v);
        if (res.ec == std::errc() && res.ptr == input.data() + input.size() && v >= lo && v <= hi) {
          return "";
        }
        return "Value " + Excerpt(input, 40) + " not in range " + std::to_string(lo) + " to " +
               std::to_string(hi);
      },
      range);
}

const CLI::Validator kRateWindowRange =
    Bounded(AngleDerivativeOptions::kMinHalfWindow_s, AngleDerivativeOptions::kMaxHalfWindow_s);

std::uint64_t ParseSeed(const std::string& text, const std::string& option) {
  const bool digits = !text.empty() && text.size() <= 20 &&
                      text.find_first_not_of("0123456789") == std::string::npos;
  std::uint64_t v = 0;
  const auto res = std::from_chars(text.data(), text.data() + text.size(), v);
  if (!digits || res.ec != std::errc() || res.ptr != text.data() + text.size()) {
    throw InputError(option + ": expected an integer 0 to 18446744073709551615, got '" +
                     Excerpt(text, 40) + "'");
  }
  return v;
}

void CheckOutputPath(const std::string& path, const Session& session, const std::string& option) {
  namespace fs = std::filesystem;
  if (path.empty()) throw InputError(option + ": empty file name (give a file name)");
  if (IsStdout(path)) {
    throw InputError(option + " -: this command prints its summary on stdout; give a file name "
                              "(stdout takes the output of apply and export)");
  }
  CheckOutputFile(path);
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir) || access(dir.c_str(), W_OK) != 0) {
    throw InputError(path + ": cannot write (folder missing or not writable)");
  }
  session.NoteOutput(path);
}

void WriteOutput(const std::string& path, const std::string& content, const Session& session) {
  if (!IsStdout(path)) {
    WriteFileAtomically(path, content, session.write_options());
    return;
  }
  if (std::fwrite(content.data(), 1, content.size(), stdout) != content.size() ||
      std::fflush(stdout) != 0) {
    throw InputError("-o -: cannot write to stdout (closed pipe or full disk)");
  }
}

void WriteJson(const nlohmann::json& j, const std::string& path, const Session& session) {
  if (IsStdout(path)) {
    WriteOutput(path, StampedJson(j, session), session);
  } else {
    WriteJsonFile(j, path, session);
  }
}

void WriteReportIfAsked(const std::string& report_html, const nlohmann::json& out,
                        const std::string& out_json, const Session& session) {
  if (report_html.empty()) return;
  ReportInput in;
  in.name = std::filesystem::path(out_json).filename().string();
  in.out = out;
  // The provenance the OUT file carries (WriteJson stamps it), on the page too.
  if (in.out.is_object() && !in.out.contains("provenance")) {
    in.out["provenance"] = session.provenance.Json();
  }
  WriteHtmlReport({in}, report_html, session.write_options());
  std::printf("wrote %s\n", report_html.c_str());
}

Session WithProgress(const Session& session, StageProgress* progress) {
  Session s = session;
  s.stage = [progress](const std::string& x) { progress->Stage(x); };
  s.fraction = [progress](double x) { progress->Fraction(x); };
  return s;
}

}  // namespace triadcal
