#include "app/output_guard.h"

#include <filesystem>
#include <set>
#include <sstream>
#include <utility>

#include "core/io/file_util.h"
#include "core/model/errors.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// How much of an existing output the guard reads, from its start and from its
// end: never the whole file (a copy of /dev/zero, a 10-GB file of one line).
constexpr std::size_t kGuardReadBytes = 1 << 20;

// The JSON object starting at text[at] ('{'), up to its matching '}' (strings
// and escapes skipped); "" when it does not end inside text.
std::string ObjectAt(const std::string& text, std::size_t at) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = at; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{') {
      ++depth;
    } else if (c == '}' && --depth == 0) {
      return text.substr(at, i - at + 1);
    }
  }
  return "";
}

// The top-level "provenance" of a JSON output written with 2-space indentation
// (WriteJson puts it first; outputs of earlier versions have it last), found
// in `text` (the file's start or end); null when it is not there.
json JsonProvenanceIn(const std::string& text) {
  const std::string key = "\n  \"provenance\": ";
  const std::size_t first = text.find(key);
  const std::size_t last = text.rfind(key);
  for (const std::size_t at : {first, last}) {
    if (at == std::string::npos) continue;
    const std::string object = ObjectAt(text, at + key.size());
    if (object.empty()) continue;
    const json j = json::parse(object, nullptr, /*allow_exceptions=*/false);
    if (j.is_object()) return j;
  }
  return nullptr;
}

// The provenance stored in an existing output: the JSON's "provenance", or
// the "# provenance: {...}" comment line of a CSV output. Null when none, or
// when the file is not a regular file. Reads at most kGuardReadBytes of its
// start and of its end.
json StoredProvenance(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return nullptr;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return nullptr;
  const std::string head = ReadFileRange(path, 0, kGuardReadBytes);
  const std::size_t start = head.find_first_not_of(" \t\r\n");
  if (start != std::string::npos && head[start] == '{') {
    if (size <= kGuardReadBytes) {  // small: the whole JSON, as it always was
      const json j = json::parse(head, nullptr, /*allow_exceptions=*/false);
      if (j.is_object() && j.contains("provenance")) return j["provenance"];
      return nullptr;
    }
    const json in_head = JsonProvenanceIn(head);
    if (!in_head.is_null()) return in_head;
    return JsonProvenanceIn(ReadFileRange(path, size - kGuardReadBytes, kGuardReadBytes));
  }
  std::istringstream in(head);
  std::string line;
  for (int n = 0; n < 40 && std::getline(in, line); ++n) {
    for (const std::string tag : {"# provenance: ", " * provenance: "}) {
      if (line.rfind(tag, 0) == 0) {
        const json j = json::parse(line.substr(tag.size()), nullptr, false);
        return j.is_discarded() ? json(nullptr) : j;
      }
    }
  }
  return nullptr;
}

using InputSet = std::set<std::pair<std::string, std::string>>;  // (role, path)

InputSet InputsOf(const json& provenance) {
  InputSet out;
  if (!provenance.is_object() || !provenance.contains("inputs")) return out;
  for (const json& in : provenance["inputs"]) {
    if (in.is_object() && in.value("role", json()).is_string() &&
        in.value("path", json()).is_string()) {
      out.insert({in["role"].get<std::string>(), in["path"].get<std::string>()});
    }
  }
  return out;
}

std::string Describe(const InputSet& inputs) {
  std::string s;
  for (const auto& [role, path] : inputs) s += (s.empty() ? "" : ", ") + role + " " + path;
  return s.empty() ? "none recorded" : s;
}

}  // namespace

void CheckOverwrite(const std::string& out_path, const Session& session) {
  if (session.output_guard) {
    session.output_guard->CheckOutputsAreNotInputs(out_path);  // the plainer error first
  }
  // Not even --force writes into a directory, FIFO, device node or socket.
  CheckOutputFile(out_path);
  std::error_code ec;
  if (session.force || !fs::exists(out_path, ec)) return;
  const json stored = StoredProvenance(out_path);
  if (stored.is_null()) {
    throw InputError(out_path +
                     ": exists and is not a triadcal output (no provenance); --force "
                     "overwrites it");
  }
  const InputSet old_inputs = InputsOf(stored), new_inputs = InputsOf(session.provenance.Json());
  if (old_inputs != new_inputs) {
    throw InputError(out_path + ": holds results of other inputs (" + Describe(old_inputs) +
                     "); --force overwrites it");
  }
}

void CheckSimulationFolder(const std::string& dir, const Session& session) {
  std::error_code ec;
  if (session.force || !fs::is_directory(dir, ec)) return;
  bool holds_results = false;
  for (const char* name : {"run.csv", "run.yaml", "truth.json"}) {
    holds_results = holds_results || fs::exists(fs::path(dir) / name, ec);
  }
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& p = it->path();
    if (p.extension() == ".json" && !StoredProvenance(p.string()).is_null()) {
      holds_results = true;
    }
  }
  if (!holds_results) return;
  const fs::path truth = fs::path(dir) / "truth.json";
  const InputSet old_inputs =
      fs::exists(truth, ec) ? InputsOf(StoredProvenance(truth.string())) : InputSet{};
  const InputSet new_inputs = InputsOf(session.provenance.Json());
  if (old_inputs != new_inputs) {
    throw InputError(dir + ": holds results of " +
                     (old_inputs.empty() ? std::string("another simulation or command")
                                         : "other inputs (" + Describe(old_inputs) + ")") +
                     "; --force writes into it");
  }
}

std::string StampedJson(const nlohmann::json& j, const Session& session) {
  nlohmann::ordered_json stamped = nlohmann::ordered_json::object();
  stamped["provenance"] = nlohmann::ordered_json::parse(session.provenance.Json().dump());
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      if (key != "provenance") stamped[key] = nlohmann::ordered_json::parse(value.dump());
    }
  }
  return stamped.dump(2) + "\n";
}

void WriteJsonFile(const nlohmann::json& j, const std::string& path, const Session& session) {
  CheckOverwrite(path, session);
  WriteFileAtomically(path, StampedJson(j, session), session.write_options());
}

}  // namespace triadcal
