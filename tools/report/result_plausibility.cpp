// Implausible results and their likely causes (result_plausibility.h).
#include "tools/report/result_plausibility.h"

#include <cmath>
#include <cstdio>

namespace triadcal {
namespace {

struct Rule {
  const char* name;
  double bound;
  const char* what;   // "what a triad's axes can be off"
  const char* cause;  // the likely cause
};

// M = [[1, -alpha_y, beta_z], [alpha_x, 1, -gamma_z], [-beta_x, gamma_y, 1]]:
// the gamma pair turns the triad about x, the inner axis (its sensor zero is
// dlambda2); the beta pair about y, the outer axis (dtheta_c); the alpha pair
// about z, across both.
const Rule kRules[] = {
    {"gamma_y", ResultBounds::kMaxMisalignment_arcmin, "a triad's axes can be off",
     "an inner angle-sensor zero (columns.lambda2.offset) held by a levelling constraint "
     "(dpsi - dlambda2) that does not hold for this bench, or a wrong mounting"},
    {"gamma_z", ResultBounds::kMaxMisalignment_arcmin, "a triad's axes can be off",
     "an inner angle-sensor zero (columns.lambda2.offset) held by a levelling constraint "
     "(dpsi - dlambda2) that does not hold for this bench, or a wrong mounting"},
    {"beta_x", ResultBounds::kMaxMisalignment_arcmin, "a triad's axes can be off",
     "an outer angle-sensor zero (columns.lambda1.offset) or a wrong mounting"},
    {"beta_z", ResultBounds::kMaxMisalignment_arcmin, "a triad's axes can be off",
     "an outer angle-sensor zero (columns.lambda1.offset) or a wrong mounting"},
    {"alpha_x", ResultBounds::kMaxMisalignment_arcmin, "a triad's axes can be off",
     "the IMU turned on the platform (mounting.axes) or readings mapped to the wrong axes"},
    {"alpha_y", ResultBounds::kMaxMisalignment_arcmin, "a triad's axes can be off",
     "the IMU turned on the platform (mounting.axes) or readings mapped to the wrong axes"},
    {"dpsi", ResultBounds::kMaxBenchAngle_arcmin, "a levelled bench can be off",
     "a tilted bench or a constraint (dpsi - dlambda2) that does not hold"},
    {"dtheta_c", ResultBounds::kMaxBenchAngle_arcmin, "a levelled bench can be off",
     "an outer angle-sensor zero (columns.lambda1.offset)"},
    {"dlambda2", ResultBounds::kMaxBenchAngle_arcmin, "a levelled bench can be off",
     "an inner angle-sensor zero (columns.lambda2.offset)"},
    {"dx2", ResultBounds::kMaxLeverArmError_mm, "the lever arm can differ from the drawings",
     "a wrong bench.lever_arm_mm (R0), or the readings' axes mapped wrongly"},
    {"dy2", ResultBounds::kMaxLeverArmError_mm, "the lever arm can differ from the drawings",
     "a wrong bench.lever_arm_mm (R0), or the readings' axes mapped wrongly"},
    {"dz2", ResultBounds::kMaxLeverArmError_mm, "the lever arm can differ from the drawings",
     "a wrong bench.lever_arm_mm (R0), or the readings' axes mapped wrongly"},
};

bool Estimated(const nlohmann::json& p) {
  if (!p.is_object()) return false;
  if (p.contains("held") && !(p["held"].is_boolean() && !p["held"].get<bool>())) return false;
  if (p.contains("estimable") && p["estimable"].is_boolean() && !p["estimable"].get<bool>()) {
    return false;
  }
  return p.contains("value") && p["value"].is_number();
}

}  // namespace

std::vector<std::string> ImplausibleResultWarnings(const nlohmann::json& parameters,
                                                   const std::string& where) {
  std::vector<std::string> out;
  if (!parameters.is_object()) return out;
  for (const Rule& rule : kRules) {
    if (!parameters.contains(rule.name)) continue;
    const nlohmann::json& p = parameters[rule.name];
    if (!Estimated(p)) continue;
    const double v = p["value"].get<double>();
    if (!(std::abs(v) > rule.bound)) continue;
    const std::string unit = p.value("unit", std::string());
    char text[600];
    if (unit == "arcmin") {
      std::snprintf(text, sizeof(text),
                    "%s: parameters.%s = %.4g arcmin (%.3g deg) is beyond what %s (%g deg): "
                    "likely %s; a result this far outside the plausible is no calibration",
                    where.c_str(), rule.name, v, v / 60.0, rule.what, rule.bound / 60.0,
                    rule.cause);
    } else {
      std::snprintf(text, sizeof(text),
                    "%s: parameters.%s = %.4g %s is beyond what %s (%g %s): likely %s; a result "
                    "this far outside the plausible is no calibration",
                    where.c_str(), rule.name, v, unit.c_str(), rule.what, rule.bound, unit.c_str(),
                    rule.cause);
    }
    out.push_back(text);
  }
  return out;
}

}  // namespace triadcal
