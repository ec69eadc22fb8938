// What several commands share: loading a run with its warnings on stderr,
// the --effects list, a progress line, and writing JSON outputs whole.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/model/effects.h"
#include "core/model/errors.h"
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

// Runs f. An OptionError (errors.h) whose option is a key of `flags` (setting
// -> flag, e.g. {"static_positions", "--static-positions"}) is rethrown as
// InputError("FLAG: problem"): solvers speak of the setting, the command of
// its flag.
template <typename F>
auto WithFlags(const std::map<std::string, std::string>& flags, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const OptionError& e) {
    const auto it = flags.find(e.option());
    if (it == flags.end()) throw;
    throw InputError(it->second + ": " + e.problem());
  }
}

// "a,b" -> effects; throws InputError("OPTION: unknown effect ...").
std::vector<Effect> ParseEffectList(const std::string& list,
                                    const std::string& option = "--effects");

// The same for effects to be estimated from `data`: also throws
// InputError("OPTION: EFFECT needs a temp_C column, which this run does not
// have (columns.temp_C in run.yaml)") when the data lack what the effect's
// catalogue entry needs (EffectSpec::needs).
std::vector<Effect> ParseEffectList(const std::string& list, const RunData& data,
                                    const std::string& option = "--effects");

// Fails early (before long work) when an output file's folder is missing or
// not writable: InputError("PATH: cannot write (folder missing or not writable)").
void CheckOutputPath(const std::string& path);

// A progress line on stderr ("filter: pass 1/2  37%"), only on a terminal.
void ShowProgress(const std::string& what, double fraction);
void EndProgress();

// Adds "provenance" (tools/provenance.h), refuses to replace an output of
// other inputs (CheckOverwrite), serialises with 2-space indentation and
// writes atomically.
void WriteJson(const nlohmann::json& j, const std::string& path);

}  // namespace triadcal
