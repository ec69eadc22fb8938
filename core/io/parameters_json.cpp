#include "core/io/parameters_json.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <vector>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/parameters.h"

namespace triadcal {
namespace {

using nlohmann::json;

// The value of one entry in file units; checks its unit when given (and
// returns it in *given).
double EntryValue(const json& entry, const std::string& where, const std::string& unit,
                  std::string* given) {
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
        throw InputError(where + ": unit " + Excerpt(entry["unit"].dump()) + ", expected \"" +
                         unit + "\" (docs/file-formats.md)");
      }
      *given = entry["unit"].get<std::string>();
    }
  }
  if (!v->is_number()) throw InputError(where + ": value is not a number: " + Excerpt(v->dump()));
  const double x = v->get<double>();
  if (!std::isfinite(x)) throw InputError(where + ": value is not finite");
  return x;
}

// Every parameter the files may name: the base ones, every effect's and the
// gyro's (SPEC section 10).
const ParameterLayout& EveryParameter() {
  static const ParameterLayout every = [] {
    std::vector<Effect> all;
    for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
    return ParameterLayout(all, /*gyro=*/true);
  }();
  return every;
}

}  // namespace

json ParseJsonStrict(const std::string& text, const std::string& path) {
  // The keys seen in each open object, and the key path to it, by depth.
  struct Open {
    std::set<std::string> keys;
    std::string path;
    std::string last_key;
  };
  std::vector<Open> open;
  const json::parser_callback_t callback = [&](int /*depth*/, json::parse_event_t event,
                                               json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start: {
        std::string at;
        if (!open.empty())
          at = open.back().path + (open.back().path.empty() ? "" : ".") + open.back().last_key;
        open.push_back({{}, at, ""});
        break;
      }
      case json::parse_event_t::object_end:
        if (!open.empty()) open.pop_back();
        break;
      case json::parse_event_t::key: {
        if (open.empty()) break;
        const std::string key = parsed.get<std::string>();
        Open& o = open.back();
        if (!o.keys.insert(key).second) {
          throw InputError(path + ": " + o.path + (o.path.empty() ? "" : ".") + Excerpt(key) +
                           ": given twice (each key once per object; a reader would keep only "
                           "one of them)");
        }
        o.last_key = key;
        break;
      }
      default:
        break;
    }
    return true;
  };
  try {
    return json::parse(text, callback);
  } catch (const json::exception& e) {  // syntax, or a number like 1e309
    // The library's "[json.exception.parse_error.101] parse error at line 1,
    // column 16: ..." said as "line 1, column 16: ...".
    std::string what = e.what();
    const std::size_t close = what.find("] ");
    if (what.rfind("[json.exception.", 0) == 0 && close != std::string::npos) {
      what = what.substr(close + 2);
    }
    if (what.rfind("parse error at ", 0) == 0) what = what.substr(15);
    const std::size_t first = text.find_first_not_of(" \t\r\n");
    const bool object = first != std::string::npos && text[first] == '{';
    throw InputError(path + ": not valid JSON: " + Excerpt(what, 300) +
                     (object ? "" : " (a calibration is a JSON object, the OUT of fit, static "
                                    "or diagnose; this file does not start with '{')"));
  }
}

ParametersFile ReadParametersJson(const std::string& path, const std::vector<std::string>& sections,
                                  const std::string& expected_what) {
  return ParametersFromJson(ParseJsonStrict(ReadFile(path), path), path, sections, expected_what);
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
  std::set<std::string> known;
  for (int i = 0; i < every.size(); ++i) {
    const ParameterInfo& info = every.info(i);
    std::vector<std::string> keys = {info.name};
    if (info.effect) {
      const EffectSpec& e = GetEffectSpec(*info.effect);
      keys.push_back(e.name + "." + UnitSuffixedKey(e.params[i - every.offset(e.id)]));
    }
    known.insert(keys.begin(), keys.end());
    for (const std::string& key : keys) {
      if (!params->contains(key)) continue;
      std::string unit;
      const double v = EntryValue((*params)[key], out.At() + key, info.unit, &unit);
      out.entries[info.name] = {key, v, unit};
      break;
    }
  }
  for (const auto& [key, value] : params->items()) {
    if (known.count(key)) continue;
    // A temperature coefficient of the joint fit: NAME.t1, NAME.t2, ...
    const std::size_t dot = key.rfind(".t");
    if (dot != std::string::npos && dot + 2 < key.size() &&
        key.find_first_not_of("0123456789", dot + 2) == std::string::npos &&
        every.IndexOf(key.substr(0, dot)) >= 0) {
      continue;
    }
    out.unknown_keys.push_back(key);
  }
  return out;
}

std::map<std::string, double> FileValues(const ParametersFile& p) {
  std::map<std::string, double> out;
  for (const auto& [name, entry] : p.entries) out[name] = entry.value_file;
  return out;
}

}  // namespace triadcal
