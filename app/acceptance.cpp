#include "app/acceptance.h"

#include <cstdio>

namespace triadcal {

std::string LimitViolation::Text() const {
  if (limit == "missing") return parameter + " not in the calibration";
  if (limit == "not_determined") {
    return parameter + " not determined by this run (kept at nominal): its limits cannot be judged";
  }
  char buf[160];
  const char* what = limit == "sigma_max" ? " sigma" : "";
  const char* op = limit == "min" ? "<" : ">";
  std::snprintf(buf, sizeof buf, "%s%s %.6g %s %s %.6g %s", parameter.c_str(), what, value, op,
                limit.c_str(), bound, unit.c_str());
  return buf;
}

std::vector<LimitViolation> CheckLimits(const std::vector<ParameterLimit>& limits,
                                        const nlohmann::json& parameters) {
  std::vector<LimitViolation> out;
  for (const ParameterLimit& l : limits) {
    if (!parameters.contains(l.parameter)) {
      out.push_back({l.parameter, "missing", 0.0, 0.0, ""});
      continue;
    }
    const nlohmann::json& p = parameters[l.parameter];
    // Held or considered (no sigma, or "determined": false): a nominal value,
    // no result to hold against a limit.
    if (!p.contains("sigma") || !p["sigma"].is_number() || !p.value("determined", true)) {
      out.push_back({l.parameter, "not_determined", 0.0, 0.0, p.value("unit", "")});
      continue;
    }
    const double value = p.value("value", 0.0), sigma = p["sigma"].get<double>();
    const std::string unit = p.value("unit", "");
    if (l.min && value < *l.min) out.push_back({l.parameter, "min", value, *l.min, unit});
    if (l.max && value > *l.max) out.push_back({l.parameter, "max", value, *l.max, unit});
    if (l.sigma_max && sigma > *l.sigma_max) {
      out.push_back({l.parameter, "sigma_max", sigma, *l.sigma_max, unit});
    }
  }
  return out;
}

nlohmann::json LimitsJson(const std::vector<ParameterLimit>& limits) {
  nlohmann::json out = nlohmann::json::array();
  for (const ParameterLimit& l : limits) {
    nlohmann::json jl = {{"parameter", l.parameter}};
    if (l.min) jl["min"] = *l.min;
    if (l.max) jl["max"] = *l.max;
    if (l.sigma_max) jl["sigma_max"] = *l.sigma_max;
    out.push_back(jl);
  }
  return out;
}

nlohmann::json ViolationJson(const LimitViolation& v) {
  return {{"parameter", v.parameter}, {"limit", v.limit}, {"value", v.value},
          {"bound", v.bound},         {"unit", v.unit},   {"text", v.Text()}};
}

LimitViolation ViolationFromJson(const nlohmann::json& j) {
  return {j.at("parameter").get<std::string>(), j.at("limit").get<std::string>(),
          j.at("value").get<double>(), j.at("bound").get<double>(),
          j.at("unit").get<std::string>()};
}

}  // namespace triadcal
