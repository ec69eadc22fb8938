// The one reader of the "parameters" object of triadcal's JSON files (SPEC
// section 7): the OUT of fit/static ("parameters"), filter ("rts.parameters"),
// compare ("batch.parameters"), and truth.json ("parameters" with plain
// numbers). Used by `apply` (LoadCalibration), `diagnose --truth` and
// `observability --at`.
//
// An entry is {"value": v, "unit": u, ...} with u the unit of docs/file-formats.md
// (checked when given), or a plain number in that unit. Effect parameters are
// keyed "effect.name" or, as truth.json writes them, "effect.name_unit"
// ("angle_latency.tau_ms"); both are read under the layout name
// ("angle_latency.tau"). The gyro's parameters (SPEC section 10) are keyed by
// their names, "gyro.Kx" ... "gyro.Gzz". Names of no parameter are listed in
// unknown_keys.
#pragma once

#include <map>
#include <string>

#include <nlohmann/json.hpp>
#include <vector>

namespace triadcal {

struct ParametersFile {
  std::string path;
  std::string section;  // where the parameters were: "parameters", "rts.parameters", ...
  std::string command;  // the file's "command", or ""
  struct Entry {
    std::string key;    // as written in the file (for messages)
    double value_file;  // in the unit of docs/file-formats.md
    std::string unit;   // the entry's "unit" as written, "" when not given
  };
  std::map<std::string, Entry> entries;  // by parameter name (ParameterLayout names)
  // Keys of the parameters object that name no parameter of this build (nor
  // a temperature coefficient "NAME.tK"): ignored by truth readers (SPEC
  // section 7), refused by LoadCalibration.
  std::vector<std::string> unknown_keys;
  // "PATH: SECTION." for messages about one entry.
  std::string At() const { return path + ": " + section + "."; }
};

// Reads PATH and the first of `sections` that holds a "parameters" object
// ("" for the top level, "rts", "batch"). Throws InputError:
//   "PATH: not valid JSON: LINE, COLUMN: ...", "PATH: KEY: given twice ...",
//   "PATH: parameters: missing (expected WHAT)",
//   "PATH: SECTION.KEY: expected a number or {\"value\": number}" / "no \"value\"" /
//   "unit U, expected \"V\" (docs/file-formats.md)" / "value is not a number: X" /
//   "value is not finite".
ParametersFile ReadParametersJson(const std::string& path, const std::vector<std::string>& sections,
                                  const std::string& expected_what);

// The same from JSON already read; `path` names it in messages.
ParametersFile ParametersFromJson(const nlohmann::json& root, const std::string& path,
                                  const std::vector<std::string>& sections,
                                  const std::string& expected_what);

// Parses JSON text like json::parse, and also refuses a key given twice in
// one object (json::parse keeps the last): InputError "PATH: not valid JSON
// (...)" or "PATH: KEY.PATH: given twice (each key once per object)".
nlohmann::json ParseJsonStrict(const std::string& text, const std::string& path);

// name -> value in file units (the form SetFromFileUnits takes).
std::map<std::string, double> FileValues(const ParametersFile& p);

}  // namespace triadcal
