#include "core/model/effects.h"

#include <stdexcept>

#include "core/model/units.h"

namespace triadcal {

const std::vector<EffectSpec>& EffectCatalogue() {
  static const std::vector<EffectSpec> catalogue = {
      {Effect::kAngleLatency,
       "angle_latency",
       "recorded angles lag the bench by tau (both angle sensors)",
       {{"tau", "ms", kMsToS}}},
      {Effect::kEncoderHarmonic,
       "encoder_harmonic",
       "angle-sensor error periodic in the angle (first harmonic, both axes)",
       {{"l1_sin", "arcmin", kArcminToRad},
        {"l1_cos", "arcmin", kArcminToRad},
        {"l2_sin", "arcmin", kArcminToRad},
        {"l2_cos", "arcmin", kArcminToRad}}},
      {Effect::kAxisNonintersection,
       "axis_nonintersection",
       "inner bench axis passes at a distance d (along z1) from the outer axis",
       {{"d", "mm", kMmToM}}},
      {Effect::kAxisNonperpendicularity,
       "axis_nonperpendicularity",
       "inner bench axis tilted by eps towards the outer axis (about z1)",
       {{"eps", "arcmin", kArcminToRad}}},
      {Effect::kSizeEffect,
       "size_effect",
       "y and z accelerometers sense at their own points R + r_y, R + r_z (frame 2)",
       {{"ry_x", "mm", kMmToM},
        {"ry_y", "mm", kMmToM},
        {"ry_z", "mm", kMmToM},
        {"rz_x", "mm", kMmToM},
        {"rz_y", "mm", kMmToM},
        {"rz_z", "mm", kMmToM}}},
      {Effect::kThermalDrift,
       "thermal_drift",
       "zero offsets drift linearly in time: W0_i + rate_i * t",
       {{"rate_x", "mV/min", 1.0 / 60.0},
        {"rate_y", "mV/min", 1.0 / 60.0},
        {"rate_z", "mV/min", 1.0 / 60.0}}},
      {Effect::kThermalDriftTemp,
       "thermal_drift_temp",
       "zero offsets linear in temp_C: W0_i + coef_i * (temp_C - first temp_C)",
       {{"coef_x", "mV/degC", 1.0}, {"coef_y", "mV/degC", 1.0}, {"coef_z", "mV/degC", 1.0}}},
      {Effect::kScaleAsymmetry,
       "scale_asymmetry",
       "scale K_i + dK_i for positive input, K_i - dK_i for negative",
       {{"dKx", "mV/g", 1.0}, {"dKy", "mV/g", 1.0}, {"dKz", "mV/g", 1.0}}},
  };
  return catalogue;
}

const EffectSpec& GetEffectSpec(Effect id) { return EffectCatalogue()[static_cast<int>(id)]; }

Effect EffectFromName(const std::string& name) {
  std::string known;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.name == name) return e.id;
    known += (known.empty() ? "" : ", ") + e.name;
  }
  throw std::invalid_argument("unknown effect '" + name + "' (known: " + known + ")");
}

std::string UnitSuffixedKey(const ParamSpec& p) {
  std::string unit;
  for (size_t i = 0; i < p.unit.size(); ++i) {
    if (p.unit[i] == '/') {
      unit += "_per_";
    } else {
      unit += p.unit[i];
    }
  }
  return p.name + "_" + unit;
}

}  // namespace triadcal
