#include "core/io/calibration_io.h"

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "core/model/errors.h"
#include "core/io/file_util.h"

namespace triadcal {
namespace {

using nlohmann::json;

// The object holding the parameters, and its name for messages.
const json* FindParameters(const json& root, std::string* section) {
  if (root.contains("parameters") && root["parameters"].is_object()) {
    *section = "parameters";
    return &root["parameters"];
  }
  for (const char* s : {"rts", "batch"}) {
    if (root.contains(s) && root[s].is_object() && root[s].contains("parameters") &&
        root[s]["parameters"].is_object()) {
      *section = std::string(s) + ".parameters";
      return &root[s]["parameters"];
    }
  }
  return nullptr;
}

// The key under which effect parameter p of effect e is written, if any.
const json* FindEffectParameter(const json& params, const EffectSpec& e, const ParamSpec& p,
                                std::string* key) {
  for (const std::string& k : {e.name + "." + p.name, e.name + "." + UnitSuffixedKey(p)}) {
    if (params.contains(k)) {
      *key = k;
      return &params[k];
    }
  }
  return nullptr;
}

// The value of one entry in file units; checks its unit when given.
double EntryValue(const json& entry, const std::string& where, const std::string& unit) {
  const json* v = &entry;
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
                         "\" (SPEC section 3)");
      }
    }
  }
  if (!v->is_number()) throw InputError(where + ": value is not a number: " + v->dump());
  const double x = v->get<double>();
  if (!std::isfinite(x)) throw InputError(where + ": value is not finite");
  return x;
}

}  // namespace

Calibration LoadCalibration(const std::string& path) {
  json root;
  try {
    root = json::parse(ReadFile(path));
  } catch (const json::exception& e) {  // syntax, or a number like 1e309
    throw InputError(path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  Calibration cal;
  cal.path = path;
  if (root.is_object() && root.contains("command") && root["command"].is_string()) {
    cal.command = root["command"].get<std::string>();
  }
  const json* params = root.is_object() ? FindParameters(root, &cal.section) : nullptr;
  if (!params) {
    throw InputError(path +
                     ": no \"parameters\" object (expected an OUT of fit, static, filter "
                     "(\"rts\"), compare (\"batch\") or a truth.json)");
  }

  // Effects named by the parameters.
  std::vector<Effect> effects;
  for (const EffectSpec& e : EffectCatalogue()) {
    for (const ParamSpec& p : e.params) {
      std::string key;
      if (FindEffectParameter(*params, e, p, &key)) {
        effects.push_back(e.id);
        break;
      }
    }
  }
  cal.layout = ParameterLayout(effects);
  cal.theta = Eigen::VectorXd::Zero(cal.layout.size());
  const std::string at = path + ": " + cal.section + ".";
  for (int i = 0; i < cal.layout.size(); ++i) {
    const ParameterInfo& info = cal.layout.info(i);
    std::string key = info.name;
    const json* entry = params->contains(key) ? &(*params)[key] : nullptr;
    if (info.effect) {
      const EffectSpec& e = GetEffectSpec(*info.effect);
      const ParamSpec& p = e.params[i - cal.layout.offset(*info.effect)];
      entry = FindEffectParameter(*params, e, p, &key);
    }
    if (!entry) {
      if (i <= kKzz || info.effect) {
        throw InputError(at + info.name +
                         ": missing (a calibration needs the 21 sensor parameters Kx..Kzz of "
                         "SPEC section 3, and every parameter of an effect it names)");
      }
      continue;  // bench and lever arm: not used by the inverse
    }
    cal.theta[i] = EntryValue(*entry, at + key, info.unit) * info.si_per_unit;
  }
  for (int i = 0; i < 3; ++i) {
    if (cal.theta[kKx + i] == 0.0) {
      throw InputError(at + cal.layout.info(kKx + i).name + ": scale factor 0");
    }
  }
  return cal;
}

}  // namespace triadcal
