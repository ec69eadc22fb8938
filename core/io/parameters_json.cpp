#include "core/io/parameters_json.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/parameters.h"

namespace triadcal {
namespace {

using nlohmann::json;

// The value of one entry in file units; checks its unit when given.
double EntryValue(const json& entry, const std::string& where, const std::string& unit) {
  const json* v = &entry;
  if (!entry.is_object() && !entry.is_number()) {
    throw InputError(where + ": expected a number or {\"value\": number}");
  }
  if (entry.is_object()) {
    if (!entry.contains("value")) throw InputError(where + ": no \"value\"");
    v = &entry["value"];
    if (entry.contains("unit")) {
      // Readings-based units may name any readings unit: mV/g, mg/g, counts/g.
      const auto same = [&](const std::string& u) {
        if (u == unit) return true;
        const std::size_t at = unit.find("mV");
        if (at == std::string::npos) return false;
        for (const char* r : {"mV", "mg", "counts"}) {
          if (u == unit.substr(0, at) + r + unit.substr(at + 2)) return true;
        }
        return false;
      };
      if (!entry["unit"].is_string() || !same(entry["unit"].get<std::string>())) {
        throw InputError(where + ": unit " + entry["unit"].dump() + ", expected \"" + unit +
                         "\" (docs/file-formats.md)");
      }
    }
  }
  if (!v->is_number()) throw InputError(where + ": value is not a number: " + v->dump());
  const double x = v->get<double>();
  if (!std::isfinite(x)) throw InputError(where + ": value is not finite");
  return x;
}

// Every parameter the files may name: the base ones and every effect's.
const ParameterLayout& EveryParameter() {
  static const ParameterLayout every = [] {
    std::vector<Effect> all;
    for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
    return ParameterLayout(all);
  }();
  return every;
}

}  // namespace

ParametersFile ReadParametersJson(const std::string& path, const std::vector<std::string>& sections,
                                  const std::string& expected_what) {
  json root;
  try {
    root = json::parse(ReadFile(path));
  } catch (const json::exception& e) {  // syntax, or a number like 1e309
    throw InputError(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  return ParametersFromJson(root, path, sections, expected_what);
}

ParametersFile ParametersFromJson(const nlohmann::json& root, const std::string& path,
                                  const std::vector<std::string>& sections,
                                  const std::string& expected_what) {
  ParametersFile out;
  out.path = path;
  if (root.is_object() && root.contains("command") && root["command"].is_string()) {
    out.command = root["command"].get<std::string>();
  }
  const json* params = nullptr;
  for (const std::string& s : sections) {
    const json* holder =
        s.empty() ? &root : (root.is_object() && root.contains(s) ? &root[s] : nullptr);
    if (holder && holder->is_object() && holder->contains("parameters") &&
        (*holder)["parameters"].is_object()) {
      params = &(*holder)["parameters"];
      out.section = s.empty() ? "parameters" : s + ".parameters";
      break;
    }
  }
  if (!params) throw InputError(path + ": parameters: missing (expected " + expected_what + ")");

  const ParameterLayout& every = EveryParameter();
  for (int i = 0; i < every.size(); ++i) {
    const ParameterInfo& info = every.info(i);
    std::vector<std::string> keys = {info.name};
    if (info.effect) {
      const EffectSpec& e = GetEffectSpec(*info.effect);
      keys.push_back(e.name + "." + UnitSuffixedKey(e.params[i - every.offset(e.id)]));
    }
    for (const std::string& key : keys) {
      if (!params->contains(key)) continue;
      out.entries[info.name] = {key, EntryValue((*params)[key], out.At() + key, info.unit)};
      break;
    }
  }
  return out;
}

std::map<std::string, double> FileValues(const ParametersFile& p) {
  std::map<std::string, double> out;
  for (const auto& [name, entry] : p.entries) out[name] = entry.value_file;
  return out;
}

}  // namespace triadcal
