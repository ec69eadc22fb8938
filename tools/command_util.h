// What several commands share: loading a run with its warnings on stderr,
// the --effects list, a progress line, and writing JSON outputs whole.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>
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

// Bounds of --epoch-s [s]: below 10 ms an epoch holds about one sample and the
// problem grows past what a run needs (and past minutes of solving); above 10 s
// the bench (periods of seconds) turns by more than one swing between epochs.
inline const CLI::Range kEpochRange(0.01, 10.0);

// Serialises with 2-space indentation and writes atomically.
void WriteJson(const nlohmann::json& j, const std::string& path);

}  // namespace triadcal
