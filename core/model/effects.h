// The effect catalogue (docs/method.md): every effect that the base model of
// docs/method.md lacks, each with its own parameters and units.
//
// Every effect is declared once, in EffectCatalogue() (effects.cpp): its stage,
// its parameters with their file units, default prior sigma, plausible range
// (with the reason) and a typical size, the data it needs, and whether block B1
// has its analytic Jacobian. The priors, the choice of rates at every sample,
// the B1 Jacobian, the zero-offset sum, effect discovery and scenario checks all
// read that description; bench_model.h holds the templated physics of each
// effect. Adding an effect: an Effect id, one catalogue entry, its physics in
// bench_model.h; effect_catalogue_test.cpp and effect_recovery_test.cpp then
// test it (Jacobian against numeric, model <-> inverse, simulate -> fit).
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
//   input rate --[gyro stage]--> gyro readings (only with the gyro block)
//
// angle stage
//   angle_latency      lambda_rec(t) = lambda(t - tau)                 tau [ms]
//   encoder_harmonic   lambda_rec_i = lambda_i + s_i sin(lambda_i) + c_i cos(lambda_i)
//                                                                       [arcmin]
//   angle_scale        lambda_rec_i = (1 + k_i) lambda_i (the recorder's counts-to-
//                      angle factor off by k_i; applied after the harmonic)   [ppm]
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
//   cross_quadratic    u_i += d_i (W_j^2 - W_k^2) + p_i W_j W_k, (j, k) the two other
//                      axes (j < k): the second-order response to the cross axes
//                      that the paper's K_ij (every term has W_i) lack (IEEE Std
//                      1293's K_pp - K_oo and K_po; K_pp + K_oo is W0_i and K_ii
//                      while |W| = 1 g)                                [1/g]
// gyro stage (the gyro's readings model, gyro_model.h; read only when the layout
// has the gyro block)
//   gyro_scale_asymmetry  G_i = K_i m_i + dK_i |m_i| + ...: scale K_i + dK_i for
//                         positive input rate, K_i - dK_i for negative     [ppm]
//   gyro_nonlinearity     scale K_i (1 + k2_i m_i^2): the scale factor's quadratic
//                         term in rate (IEEE Std 952's K_2-of-scale, an odd, cubic
//                         term of the output)                    [ppm/(deg/s)^2]
//                         (m = Mg w, the misaligned input rate)
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
  kAngleScale,
  kCrossQuadratic,
  kThermalDriftQuadratic,
  kGyroScaleAsymmetry,
  kGyroNonlinearity,
};
constexpr int kNumEffects = 13;

// Where in the measurement chain an effect acts (see the diagram above).
enum class EffectStage { kAngle, kGeometry, kSensor, kGyro };
constexpr int kNumEffectStages = 4;
const char* StageName(EffectStage stage);

// A sensor-stage effect that adds to the zero offsets as
//   W0_i(sample) += theta_i * x(sample)
// names its signal x here; bench_model.h (ZeroOffset_mV) and the analytic B1
// Jacobian (b1_jacobian.cpp, column T_i x / K_i) dispatch on it.
enum class ZeroOffsetSignal {
  kNone,
  kTime_s,      // x = t [s] from the start of the run
  kTempRise_C,  // x = temp_C - temp_C of the first sample [degC]
  kTimeCurvature_s2,  // x = (t - t0)^2 less its constant and line over the run [s^2]
};

// One scalar parameter as it appears in files: value_file * si_per_unit gives
// the internal value. Sizes are in file units, or fractions of the run's
// nominal scale factor (mV/g) when the effect is scale_relative.
struct ParamSpec {
  std::string name;  // e.g. "tau"; full name in files is "effect.name"
  std::string unit;  // unit in files, e.g. "ms"
  double si_per_unit;
  double prior_sigma = 0.0;    // default prior sigma (priors.h)
  double plausible_min = 0.0;  // physically plausible range, see EffectSpec::plausible_reason
  double plausible_max = 0.0;
  double typical = 0.0;        // a typical size on a real bench (simulations, tests)
};

// What a run must carry for the effect to be simulated or estimated.
struct EffectNeeds {
  bool temp_C = false;                 // a temp_C column (a temperature section to simulate)
  bool rates_at_every_sample = false;  // lambda', lambda'' at every sample, not only at epochs
  // Parameter i belongs to axis i and needs that axis's reading to leave its
  // zero offset clearly on both sides (beyond 4 noise sigma, on at least 5 %
  // of the samples each way): scale_asymmetry, whose |u| is otherwise K u or
  // a function of the noise's sign (effect_information.cpp).
  bool both_signs_per_axis = false;
};

struct EffectSpec {
  Effect id;
  std::string name;         // e.g. "angle_latency"
  std::string description;  // one line, for listings and reports
  EffectStage stage;
  std::vector<ParamSpec> params;
  bool scale_relative = false;   // prior_sigma, plausible range, typical x nominal scale
  std::string plausible_reason{};  // why values outside the plausible range are implausible
  EffectNeeds needs{};
  bool b1_analytic_jacobian = false;  // AccelerationWithJacobian covers it (b1_jacobian.h)
  ZeroOffsetSignal zero_offset_signal = ZeroOffsetSignal::kNone;
};

// The whole catalogue, in the order of the Effect enum.
const std::vector<EffectSpec>& EffectCatalogue();
const EffectSpec& GetEffectSpec(Effect id);
// Throws std::invalid_argument naming the effect and the known ones.
Effect EffectFromName(const std::string& name);

// Sizes of parameter p of effect e in file units, for a run whose nominal
// scale factor is nominal_scale_mV_per_g (largest |K_i|).
double DefaultPriorSigma(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g);
double PlausibleMin(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g);
double PlausibleMax(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g);
double TypicalValue(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g);

// The key under which a parameter may be written in a scenario or truth file:
// the name with its unit appended ("tau" + "ms" -> "tau_ms",
// "rate_x" + "mV/min" -> "rate_x_mV_per_min"). Both forms are accepted on input.
std::string UnitSuffixedKey(const ParamSpec& p);

}  // namespace triadcal
