// What several commands share: the checks of an output path, a progress
// line, bounded number options, and writing JSON outputs whole. (The run
// loading, the lists of the settings and the provenance are the jobs': app/.)
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "app/option_lists.h"
#include "app/output_guard.h"
#include "app/run_loading.h"
#include "app/session.h"
#include "core/model/errors.h"

namespace triadcal {

// Fails early (before any work) when an output cannot be written: an empty
// name ("OPTION: empty file name"), a path that exists and is not a regular
// file or a symbolic link to one (a directory, FIFO, device node, socket:
// core/io/file_util.h CheckOutputFile), or a folder that is missing or not
// writable ("PATH: cannot write (folder missing or not writable)"). Notes the
// output in the session's guard. `option` names the flag that gave it.
void CheckOutputPath(const std::string& path, const Session& session,
                     const std::string& option = "-o");

// Progress on stderr ("fit: relinearising pass 2  57%"). On a terminal one
// line rewritten in place (at most 10 times a second); otherwise (piped, in
// a log) one line every few seconds (TRIADCAL_PROGRESS_INTERVAL_S, default
// 5), each ending in a newline. Nothing with SetQuiet(true) (`--quiet`).
// A negative fraction prints the stage without a percentage.
void ShowProgress(const std::string& what, double fraction);
void EndProgress();
void SetQuiet(bool quiet);

// One progress line from a stage text and a fraction that solvers report
// through separate callbacks (e.g. BatchOptions::progress and ::fraction).
class StageProgress {
 public:
  explicit StageProgress(std::string prefix) : prefix_(std::move(prefix)) {}
  void Stage(const std::string& stage) {
    stage_ = stage;
    ShowProgress(prefix_ + stage_, fraction_);
  }
  void Fraction(double fraction) {
    fraction_ = std::max(fraction_, fraction);  // estimates never step back
    ShowProgress(prefix_ + stage_, fraction_);
  }

 private:
  std::string prefix_, stage_;
  double fraction_ = 0.0;
};

// The session with the job's stages and fraction shown on `progress` (which
// must outlive the returned session's use).
Session WithProgress(const Session& session, StageProgress* progress);

// `--report FILE` of the long commands: the HTML report of `out` (to be
// written as out_json, with the session's provenance) into report_html;
// nothing when report_html is empty.
void WriteReportIfAsked(const std::string& report_html, const nlohmann::json& out,
                        const std::string& out_json, const Session& session);

// A number option within [lo, hi] (inclusive; NaN and infinities are out,
// which CLI::Range lets through): "--flag: Value X not in range 0.010000 to
// 10.000000", as CLI::Range says it. --help shows the range, "in [0.01, 10]".
CLI::Validator Bounded(double lo, double hi);
// The same for an integer option (a number with a fraction or exponent,
// "1e9", is no integer).
CLI::Validator BoundedInt(long long lo, long long hi);

// Bounds of --epoch-s [s]: below 10 ms an epoch holds about one sample and the
// problem grows past what a run needs (and past minutes of solving); above 10 s
// the bench (periods of seconds) turns by more than one swing between epochs.
inline const CLI::Validator kEpochRange = Bounded(0.01, 10.0);
// Bounds of --rate-window-s [s] (AngleDerivativeOptions::Check gives the reasons).
extern const CLI::Validator kRateWindowRange;
// --threads: 0 (all cores) to 1024.
inline const CLI::Validator kThreadsRange = BoundedInt(0, 1024);

// A seed from the command line: a decimal integer 0 .. 2^64 - 1, nothing else
// (CLI11 wrapped -1 to 2^64 - 1 and saturated 2^64). Throws
// InputError("OPTION: expected an integer 0 to 18446744073709551615, got 'X'").
std::uint64_t ParseSeed(const std::string& text, const std::string& option);

// `-o -`: the output goes to stdout (apply, export --format yaml|json-matrix:
// text outputs that a pipe can take; the command then prints nothing else
// on stdout).
inline bool IsStdout(const std::string& path) { return path == "-"; }
// Writes content to stdout when IsStdout(path) (InputError when stdout
// fails: a closed pipe, a full disk), else WriteFileAtomically with the
// session's write options.
void WriteOutput(const std::string& path, const std::string& content, const Session& session);

// Adds the session's "provenance" (app/provenance.h), refuses to replace an
// output of other inputs (app/output_guard.h CheckOverwrite), serialises with
// 2-space indentation and writes atomically.
void WriteJson(const nlohmann::json& j, const std::string& path, const Session& session);

}  // namespace triadcal
