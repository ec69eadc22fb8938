#include "core/model/effects.h"

#include <stdexcept>

#include "core/model/units.h"

namespace triadcal {

// Each entry: stage, parameters {name, file unit, SI per unit, prior sigma,
// plausible min, plausible max, typical}, the reason for the plausible range,
// the data the effect needs, whether B1 has its analytic Jacobian, and the
// zero-offset signal of drift effects. Prior sigmas are a size scale that the
// data should beat; plausible ranges are physical limits (issue 12's loop
// checks estimates against them).
const std::vector<EffectSpec>& EffectCatalogue() {
  constexpr double kPerMin = 1.0 / 60.0;
  static const std::vector<EffectSpec> catalogue = [] {
    std::vector<EffectSpec> c;
    {
      EffectSpec e{Effect::kAngleLatency,
                   "angle_latency",
                   "recorded angles lag the bench by tau (both angle sensors)",
                   EffectStage::kAngle,
                   {{"tau", "ms", kMsToS, 20.0, -100.0, 100.0, 2.0}}};
      e.plausible_reason =
          "the angle and acceleration channels of a bench recorder agree to a few samples; a "
          "lag beyond 0.1 s is a broken time base, not a latency";
      e.needs.rates_at_every_sample = true;
      e.b1_analytic_jacobian = true;
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kEncoderHarmonic,
                   "encoder_harmonic",
                   "angle-sensor error periodic in the angle (first harmonic, both axes)",
                   EffectStage::kAngle,
                   {{"l1_sin", "arcmin", kArcminToRad, 10.0, -60.0, 60.0, 1.0},
                    {"l1_cos", "arcmin", kArcminToRad, 10.0, -60.0, 60.0, 1.0},
                    {"l2_sin", "arcmin", kArcminToRad, 10.0, -60.0, 60.0, 1.0},
                    {"l2_cos", "arcmin", kArcminToRad, 10.0, -60.0, 60.0, 1.0}}};
      e.plausible_reason =
          "encoder eccentricity on a calibration bench is arcseconds to a few arcmin; a degree "
          "would show on the bench's own dial";
      e.needs.rates_at_every_sample = true;
      e.b1_analytic_jacobian = true;
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kAxisNonintersection,
                   "axis_nonintersection",
                   "inner bench axis passes at a distance d (along z1) from the outer axis",
                   EffectStage::kGeometry,
                   {{"d", "mm", kMmToM, 10.0, -20.0, 20.0, 1.0}}};
      e.plausible_reason =
          "the axes of a two-axis bench meet to machining tolerance (below 1 mm); 20 mm is a "
          "mis-assembled bench";
      e.b1_analytic_jacobian = true;  // d moves O, not the triad's orientation: B2 only
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kAxisNonperpendicularity,
                   "axis_nonperpendicularity",
                   "inner bench axis tilted by eps towards the outer axis (about z1)",
                   EffectStage::kGeometry,
                   {{"eps", "arcmin", kArcminToRad, 30.0, -60.0, 60.0, 5.0}}};
      e.plausible_reason =
          "bench axes are perpendicular to machining tolerance (arcmin); a degree is a "
          "mis-assembled bench";
      e.b1_analytic_jacobian = true;
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kSizeEffect,
                   "size_effect",
                   "y and z accelerometers sense at their own points R + r_y, R + r_z (frame 2)",
                   EffectStage::kGeometry,
                   {{"ry_x", "mm", kMmToM, 20.0, -50.0, 50.0, 3.0},
                    {"ry_y", "mm", kMmToM, 20.0, -50.0, 50.0, 3.0},
                    {"ry_z", "mm", kMmToM, 20.0, -50.0, 50.0, 3.0},
                    {"rz_x", "mm", kMmToM, 20.0, -50.0, 50.0, 3.0},
                    {"rz_y", "mm", kMmToM, 20.0, -50.0, 50.0, 3.0},
                    {"rz_z", "mm", kMmToM, 20.0, -50.0, 50.0, 3.0}}};
      e.plausible_reason = "the sensing points of a triad lie inside its housing, a few cm across";
      e.needs.rates_at_every_sample = true;  // per-axis kinematics in block B1
      e.b1_analytic_jacobian = true;
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kThermalDrift,
                   "thermal_drift",
                   "zero offsets drift linearly in time: W0_i + rate_i * t",
                   EffectStage::kSensor,
                   {{"rate_x", "mV/min", kPerMin, 10.0, -30.0, 30.0, 0.5},
                    {"rate_y", "mV/min", kPerMin, 10.0, -30.0, 30.0, 0.5},
                    {"rate_z", "mV/min", kPerMin, 10.0, -30.0, 30.0, 0.5}}};
      e.plausible_reason =
          "MEMS zero offsets drift by mg per minute while warming (~0.2 mV/min at 175 mV/g); "
          "30 mV/min crosses a +-2 g range in 20 min: a failing sensor";
      e.b1_analytic_jacobian = true;
      e.zero_offset_signal = ZeroOffsetSignal::kTime_s;
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kThermalDriftTemp,
                   "thermal_drift_temp",
                   "zero offsets linear in temp_C: W0_i + coef_i * (temp_C - first temp_C)",
                   EffectStage::kSensor,
                   {{"coef_x", "mV/degC", 1.0, 10.0, -30.0, 30.0, 0.5},
                    {"coef_y", "mV/degC", 1.0, 10.0, -30.0, 30.0, 0.5},
                    {"coef_z", "mV/degC", 1.0, 10.0, -30.0, 30.0, 0.5}}};
      e.plausible_reason =
          "MEMS offset temperature coefficients are ~1 mg/degC (~0.2 mV/degC at 175 mV/g); "
          "30 mV/degC is a failing sensor";
      e.needs.temp_C = true;
      e.b1_analytic_jacobian = true;
      e.zero_offset_signal = ZeroOffsetSignal::kTempRise_C;
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kScaleAsymmetry,
                   "scale_asymmetry",
                   "scale K_i + dK_i for positive input, K_i - dK_i for negative",
                   EffectStage::kSensor,
                   {{"dKx", "mV/g", 1.0, 0.05, -0.1, 0.1, 0.005},
                    {"dKy", "mV/g", 1.0, 0.05, -0.1, 0.1, 0.005},
                    {"dKz", "mV/g", 1.0, 0.05, -0.1, 0.1, 0.005}}};
      e.scale_relative = true;
      e.plausible_reason =
          "the scale asymmetry of MEMS accelerometers is below 1 % of the scale; 10 % is a "
          "damaged sensor";
      e.needs.both_signs_per_axis = true;
      e.b1_analytic_jacobian = true;
      c.push_back(e);
    }
    {
      EffectSpec e{Effect::kAngleScale,
                   "angle_scale",
                   "recorded angles scaled by 1 + k_i (counts-to-angle factor of each angle sensor)",
                   EffectStage::kAngle,
                   {{"l1_scale", "ppm", 1e-6, 2000.0, -10000.0, 10000.0, 500.0},
                    {"l2_scale", "ppm", 1e-6, 2000.0, -10000.0, 10000.0, 500.0}}};
      e.plausible_reason =
          "an encoder's counts-to-angle factor is exact or off by a wrong count per turn "
          "(0.1-0.3 %, e.g. 4000 for 4096 counts); beyond 1 % the angles would visibly miss "
          "the bench's stops";
      e.needs.rates_at_every_sample = true;
      e.b1_analytic_jacobian = true;
      c.push_back(e);
    }
    {
      // Reading i, cross axes j < k (bench_model.h CrossQuadraticTerm). The sum
      // W_j^2 + W_k^2 = |W|^2 - W_i^2 is the zero offset and K_ii at rest, so
      // only the difference and the product are new.
      EffectSpec e{Effect::kCrossQuadratic,
                   "cross_quadratic",
                   "second-order response of each reading to the two other axes: "
                   "d_i (Wj^2 - Wk^2) + p_i Wj Wk",
                   EffectStage::kSensor,
                   {{"x_yy_zz", "1/g", 1.0, 0.02, -0.1, 0.1, 0.002},
                    {"x_yz", "1/g", 1.0, 0.02, -0.1, 0.1, 0.002},
                    {"y_xx_zz", "1/g", 1.0, 0.02, -0.1, 0.1, 0.002},
                    {"y_xz", "1/g", 1.0, 0.02, -0.1, 0.1, 0.002},
                    {"z_xx_yy", "1/g", 1.0, 0.02, -0.1, 0.1, 0.002},
                    {"z_xy", "1/g", 1.0, 0.02, -0.1, 0.1, 0.002}}};
      e.plausible_reason =
          "the cross-axis nonlinearity of MEMS accelerometers is below 1 % of the reading at "
          "1 g (0.01 /g); 0.1 /g is a tenth of the full response to a perpendicular g: a "
          "damaged or saturating sensor";
      e.b1_analytic_jacobian = true;
      c.push_back(e);
    }
    {
      // With thermal_drift, W0_i + rate_i t + quad_i t^2: a drift whose rate
      // changes over the run (a warm-up that slows). The real medium roll run
      // cut in quarters gives its z rate 0.42, 0.23, 0.19, 0.14 mg/min.
      EffectSpec e{Effect::kThermalDriftQuadratic,
                   "thermal_drift_quadratic",
                   "zero offsets bend in time: W0_i + quad_i * ((t - t0)^2 less its mean and "
                   "line over the run) (with thermal_drift: a drift whose rate changes)",
                   EffectStage::kSensor,
                   {{"quad_x", "mV/min^2", kPerMin * kPerMin, 1.0, -3.0, 3.0, 0.05},
                    {"quad_y", "mV/min^2", kPerMin * kPerMin, 1.0, -3.0, 3.0, 0.05},
                    {"quad_z", "mV/min^2", kPerMin * kPerMin, 1.0, -3.0, 3.0, 0.05}}};
      e.plausible_reason =
          "a MEMS zero offset's warm-up drift slows by ~0.01 mg/min per minute (~0.001 "
          "mV/min^2 at 175 mV/g); 3 mV/min^2 moves it by 1.2 V in 20 min: a failing sensor";
      e.b1_analytic_jacobian = true;
      e.zero_offset_signal = ZeroOffsetSignal::kTimeCurvature_s2;
      c.push_back(e);
    }
    {
      // G_i = K_i m_i + dK_i |m_i| + W0_i + (G W)_i (gyro_model.h), dK in the
      // gyro scale's unit (1, readings per input rate) x 1e-6.
      EffectSpec e{Effect::kGyroScaleAsymmetry,
                   "gyro_scale_asymmetry",
                   "gyro scale K_i + dK_i for positive input rate, K_i - dK_i for negative",
                   EffectStage::kGyro,
                   {{"dKx", "ppm", 1e-6, 5000.0, -50000.0, 50000.0, 1000.0},
                    {"dKy", "ppm", 1e-6, 5000.0, -50000.0, 50000.0, 1000.0},
                    {"dKz", "ppm", 1e-6, 5000.0, -50000.0, 50000.0, 1000.0}}};
      e.plausible_reason =
          "MEMS gyros give a scale asymmetry below 0.5 % (datasheets: 'scale factor "
          "asymmetry'); 5 % is a damaged or saturating sensor";
      e.b1_analytic_jacobian = true;  // the accelerometer's residual does not depend on it
      c.push_back(e);
    }
    {
      // Scale K_i (1 + k2_i m_i^2): G_i = K_i m_i (1 + k2_i m_i^2) + ...; k2 in
      // ppm per (deg/s)^2 (0.01: 900 ppm of scale at 300 deg/s).
      constexpr double kPpmPerDps2 = 1e-6 / (kDegToRad * kDegToRad);
      EffectSpec e{Effect::kGyroNonlinearity,
                   "gyro_nonlinearity",
                   "gyro scale rises with the input rate squared: K_i (1 + k2_i m_i^2)",
                   EffectStage::kGyro,
                   {{"k2_x", "ppm/(deg/s)^2", kPpmPerDps2, 0.1, -1.0, 1.0, 0.01},
                    {"k2_y", "ppm/(deg/s)^2", kPpmPerDps2, 0.1, -1.0, 1.0, 0.01},
                    {"k2_z", "ppm/(deg/s)^2", kPpmPerDps2, 0.1, -1.0, 1.0, 0.01}}};
      e.plausible_reason =
          "MEMS gyros give a scale nonlinearity of 0.1-0.2 % of full scale (0.01 ppm/(deg/s)^2 "
          "is 900 ppm at 300 deg/s); 1 ppm/(deg/s)^2 is 9 % at 300 deg/s";
      e.b1_analytic_jacobian = true;  // the accelerometer's residual does not depend on it
      c.push_back(e);
    }
    return c;
  }();
  return catalogue;
}

const char* StageName(EffectStage stage) {
  switch (stage) {
    case EffectStage::kAngle:
      return "angle";
    case EffectStage::kGeometry:
      return "geometry";
    case EffectStage::kSensor:
      return "sensor";
    case EffectStage::kGyro:
      return "gyro";
  }
  return "?";
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

namespace {
double Sized(const EffectSpec& e, double v, double nominal_scale_mV_per_g) {
  return e.scale_relative ? v * nominal_scale_mV_per_g : v;
}
}  // namespace

double DefaultPriorSigma(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g) {
  return Sized(e, p.prior_sigma, nominal_scale_mV_per_g);
}
double PlausibleMin(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g) {
  return Sized(e, p.plausible_min, nominal_scale_mV_per_g);
}
double PlausibleMax(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g) {
  return Sized(e, p.plausible_max, nominal_scale_mV_per_g);
}
double TypicalValue(const EffectSpec& e, const ParamSpec& p, double nominal_scale_mV_per_g) {
  return Sized(e, p.typical, nominal_scale_mV_per_g);
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
