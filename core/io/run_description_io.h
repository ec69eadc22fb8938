// Reading and writing run.yaml (the run description of docs/file-formats.md).
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "core/model/run_description.h"

namespace triadcal {

// Reads and checks run.yaml. Throws InputError with "FILE: key: what is wrong".
RunDescription LoadRunDescription(const std::string& yaml_path);

// The same, from a YAML map already parsed (the `run:` section of a scenario
// has this schema). `where` prefixes every message ("scen.yaml: run").
// Leaves data_path empty when the node has no `data` key.
RunDescription ParseRunDescription(const YAML::Node& node, const std::string& yaml_path,
                                   const std::string& where);

// run.yaml text for this description, with `data:` written as given (relative
// to the folder the YAML will be written to). Only the keys of docs/file-formats.md and
// those that differ from the defaults are written.
std::string RunDescriptionToYaml(const RunDescription& run, const std::string& data_relative);

}  // namespace triadcal
