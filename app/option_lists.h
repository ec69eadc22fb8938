// The lists the settings of the jobs hold as text ("a,b"): split, the effect
// names checked against the catalogue (and the run's data), --hold/--free
// against the layout; and the renaming of a solver's setting to its flag.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/model/effects.h"
#include "core/model/errors.h"
#include "core/model/parameters.h"
#include "core/model/run_data.h"

namespace triadcal {

// "a,b" -> {"a", "b"} (empty items dropped, blanks around an item trimmed).
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

// --hold and --free against the parameters of `layout`: a name given to both
// is a contradiction ("--hold/--free: 'X' given to both: hold it or free
// it"), and holding every parameter leaves nothing to estimate ("--hold:
// holds every parameter; nothing left to estimate"). Unknown names are left
// to the solver (OptionError "hold_free").
void CheckHoldFree(const std::vector<std::string>& held, const std::vector<std::string>& freed,
                   const ParameterLayout& layout);

}  // namespace triadcal
