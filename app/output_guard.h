// The output guard of the session: an output of other inputs is not replaced
// unless the session says so (--force). The provenance an output carries
// (app/provenance.h) tells what it was made from.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "app/session.h"

namespace triadcal {

// Before writing OUT: when OUT exists and its provenance names other inputs
// (other roles or paths) than the session's, or it has none (it is not a
// triadcal output), throws InputError("OUT: holds results of other inputs
// (...); --force overwrites it") unless session.force. Outputs of the same
// inputs are replaced silently. OUT must be missing or a regular file (or a
// link to one), with --force too (core/io/file_util.h CheckOutputFile); the
// stored provenance is looked for in the first and last megabyte of OUT only
// (the writers put it first).
void CheckOverwrite(const std::string& out_path, const Session& session);

// OUT as written: the session's "provenance" first, then the other keys in
// their (sorted) order (the guard reads only the start of an existing
// output), 2-space indentation, a final newline.
std::string StampedJson(const nlohmann::json& j, const Session& session);

// CheckOverwrite, then StampedJson written atomically to `path`: how every
// job that files its outputs itself (batch) writes them.
void WriteJsonFile(const nlohmann::json& j, const std::string& path, const Session& session);

// The same for simulate's folder: a non-empty DIR holding results (run.csv,
// run.yaml, truth.json, or any JSON with a provenance) that do not come from
// the same scenario file is refused unless session.force.
void CheckSimulationFolder(const std::string& dir, const Session& session);

}  // namespace triadcal
