// What several commands share: loading a run with its warnings on stderr,
// the --effects list, a progress line, and writing JSON outputs whole.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/model/effects.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

struct LoadedRun {
  RunDescription description;
  RunData data;
};

// Loads run.yaml and its data; prints each validation warning to stderr as
// "triadcal: warning: ...".
LoadedRun LoadRunOrThrow(const std::string& run_yaml);

// "a,b" -> {"a", "b"} (empty items dropped).
std::vector<std::string> SplitList(const std::string& list);

// "a,b" -> effects; throws InputError("OPTION: unknown effect ...").
std::vector<Effect> ParseEffectList(const std::string& list,
                                    const std::string& option = "--effects");

// Fails early (before long work) when an output file's folder is missing or
// not writable: InputError("PATH: cannot write (folder missing or not writable)").
void CheckOutputPath(const std::string& path);

// A progress line on stderr ("filter: pass 1/2  37%"), only on a terminal.
void ShowProgress(const std::string& what, double fraction);
void EndProgress();

// `--report FILE` of the long commands: the HTML report of `out` (to be
// written as out_json) into report_html; nothing when report_html is empty.
void WriteReportIfAsked(const std::string& report_html, const nlohmann::json& out,
                        const std::string& out_json);

// Serialises with 2-space indentation and writes atomically.
void WriteJson(const nlohmann::json& j, const std::string& path);

}  // namespace triadcal
