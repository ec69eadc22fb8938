// The effect catalogue (docs/method.md): every effect that the base model of
// docs/method.md lacks, each with its own parameters and units.
//
// An effect is switched on by adding it to a ParameterLayout; its parameters are
// then appended to the parameter vector theta and every model function in
// bench_model.h takes them into account. The same definitions generate data in
// the simulator and are estimated by the solvers.
//
// Each effect acts at one stage of the measurement chain:
//
//   bench angles --[angle stage]--> recorded angles
//   bench angles --[geometry stage]--> motion of the sensing points
//   specific force --[sensor stage]--> readings
//
// angle stage
//   angle_latency      lambda_rec(t) = lambda(t - tau)                 tau [ms]
//   encoder_harmonic   lambda_rec_i = lambda_i + s_i sin(lambda_i) + c_i cos(lambda_i)
//                                                                       [arcmin]
// geometry stage
//   axis_nonintersection      the inner axis passes at d along z1 from the
//                             outer axis: S = C_L1 (d e_z + C_12 R)     d [mm]
//   axis_nonperpendicularity  inner axis n = Rz(eps) e_x in frame 1:
//                             C_12 = Rz(eps) Rx(lambda2 + dlambda2) Rz(-eps)
//                                                                       eps [arcmin]
//   size_effect        the y and z accelerometers sense at R + r_y, R + r_z
//                      (the x accelerometer defines O)        r_y, r_z [mm]
// sensor stage
//   thermal_drift      W0_i(t) = W0_i + rate_i * t                     [mV/min]
//   thermal_drift_temp W0_i(T) = W0_i + coef_i * (temp_C - T_ref)      [mV/degC]
//   scale_asymmetry    Wpr_i = K_i u_i + dK_i |u_i| + W0_i: scale K_i + dK_i for
//                      positive input, K_i - dK_i for negative        [mV/g]
#pragma once

#include <string>
#include <vector>

namespace triadcal {

enum class Effect {
  kAngleLatency,
  kEncoderHarmonic,
  kAxisNonintersection,
  kAxisNonperpendicularity,
  kSizeEffect,
  kThermalDrift,
  kThermalDriftTemp,
  kScaleAsymmetry,
};
constexpr int kNumEffects = 8;

// One scalar parameter as it appears in files: value_file * si_per_unit gives
// the internal value.
struct ParamSpec {
  std::string name;  // e.g. "tau"; full name in files is "effect.name"
  std::string unit;  // unit in files, e.g. "ms"
  double si_per_unit;
};

struct EffectSpec {
  Effect id;
  std::string name;         // e.g. "angle_latency"
  std::string description;  // one line, for listings and reports
  std::vector<ParamSpec> params;
};

// The whole catalogue, in the order of the Effect enum.
const std::vector<EffectSpec>& EffectCatalogue();
const EffectSpec& GetEffectSpec(Effect id);
// Throws std::invalid_argument naming the effect and the known ones.
Effect EffectFromName(const std::string& name);

// The key under which a parameter may be written in a scenario or truth file:
// the name with its unit appended ("tau" + "ms" -> "tau_ms",
// "rate_x" + "mV/min" -> "rate_x_mV_per_min"). Both forms are accepted on input.
std::string UnitSuffixedKey(const ParamSpec& p);

}  // namespace triadcal
