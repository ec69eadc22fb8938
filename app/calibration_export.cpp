#include "app/calibration_export.h"

#include <Eigen/LU>
#include <cctype>
#include <cstdio>
#include <cstdlib>

#include "core/model/bench_model.h"
#include "core/model/errors.h"
#include "core/model/gyro_model.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

// Shortest text that reads back as exactly x (C99 accepts it as a double).
std::string Exact(double x) {
  char buf[40];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof(buf), "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  std::string s = buf;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

std::string Array3(const double* v) {
  return "{" + Exact(v[0]) + ", " + Exact(v[1]) + ", " + Exact(v[2]) + "}";
}

// Row by row, one row per line.
std::string Matrix3(const Eigen::Matrix3d& m) {
  std::string s = "{";
  for (int r = 0; r < 3; ++r) {
    s += (r ? ",\n    " : "") + Exact(m(r, 0)) + ", " + Exact(m(r, 1)) + ", " + Exact(m(r, 2));
  }
  return s + "}";
}

// The three parameters of a sensor-stage effect (zeros when it is off).
Eigen::Vector3d EffectTriple(const Calibration& cal, Effect e) {
  const int o = cal.layout.offset(e);
  return o < 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(cal.theta.segment<3>(o));
}

std::string Commented(const std::string& comment) {
  std::string out;
  std::size_t start = 0;
  while (start <= comment.size() && !comment.empty()) {
    std::size_t end = comment.find('\n', start);
    if (end == std::string::npos) end = comment.size();
    std::string line = comment.substr(start, end - start);
    for (std::size_t p; (p = line.find("*/")) != std::string::npos;) line.replace(p, 2, "* /");
    out += " * " + line + "\n";
    start = end + 1;
  }
  return out;
}

nlohmann::ordered_json Rows(const Eigen::Matrix3d& m) {
  nlohmann::ordered_json j = nlohmann::ordered_json::array();
  for (int r = 0; r < 3; ++r) j.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return j;
}

nlohmann::ordered_json Vec(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

// cross_quadratic's (d_i, p_i) per reading i (zeros when it is off).
Eigen::Matrix<double, 6, 1> CrossQuadratic(const Calibration& cal) {
  const int o = cal.layout.offset(Effect::kCrossQuadratic);
  return o < 0 ? Eigen::Matrix<double, 6, 1>::Zero()
               : Eigen::Matrix<double, 6, 1>(cal.theta.segment<6>(o));
}

// The gyro block in deg/s (SPEC section 10): G = S w + b + Gs W with the
// readings G and rate w in deg/s, W in g; S = diag(K) Mg (dimensionless).
// With the gyro-stage effects (gyro_model.h) each axis's response to m = Mg w
// is f_i(m) = K_i m (1 + k2_i m^2) + dK_i |m|; in deg/s k2_i is per (deg/s)^2.
struct GyroMatrices {
  Eigen::Matrix3d S;            // diag(K) Mg [1]
  Eigen::Matrix3d S_inverse;    // Mg^-1 diag(K)^-1 [1]: the correction matrix
  Eigen::Matrix3d Mg_inverse;   // Mg^-1 [1]
  Eigen::Vector3d K;            // scale factors [1]
  Eigen::Vector3d b_dps;        // W0 [deg/s]
  Eigen::Matrix3d G_dps_per_g;  // g-sensitivity [(deg/s)/g]
  Eigen::Vector3d dK;           // gyro_scale_asymmetry [1] (0 when off)
  Eigen::Vector3d k2_per_dps2;  // gyro_nonlinearity [1/(deg/s)^2] (0 when off)
  bool nonlinear = false;       // gyro_nonlinearity is on: the inverse takes Newton's steps
};

GyroMatrices GyroForm(const Calibration& cal) {
  const double* g = cal.theta.data() + cal.layout.gyro_offset();
  GyroMatrices m;
  m.K = Eigen::Vector3d(g[kGKx], g[kGKy], g[kGKz]);
  m.S = m.K.asDiagonal() * GyroMisalignmentMatrix(g);
  m.S_inverse = m.S.inverse();
  m.Mg_inverse = GyroMisalignmentMatrix(g).inverse();
  m.b_dps = Eigen::Vector3d(g[kGW0x], g[kGW0y], g[kGW0z]) / kDegToRad;
  m.G_dps_per_g = GyroGSensitivity(g) / kDegToRad;
  for (int i = 0; i < 3; ++i) {
    const GyroAxisResponse<double> a = GyroAxis(cal.layout, cal.theta.data(), i);
    m.dK[i] = a.dK;
    m.k2_per_dps2[i] = a.k2 * kDegToRad * kDegToRad;  // k2 m^2 is the same number
    m.nonlinear = a.nonlinear;
  }
  return m;
}

// The gyro-stage effects of `cal` as the catalogue names them: per effect its
// description and its parameters in file units, {"dKx": {"value", "unit"}, ...}
// as in the calibration file.
nlohmann::ordered_json GyroEffectsJson(const Calibration& cal) {
  nlohmann::ordered_json effects = nlohmann::ordered_json::object();
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kGyro || !cal.layout.has(e.id)) continue;
    const int o = cal.layout.offset(e.id);
    nlohmann::ordered_json params = nlohmann::ordered_json::object();
    for (std::size_t q = 0; q < e.params.size(); ++q) {
      const ParamSpec& p = e.params[q];
      params[p.name] = {{"value", cal.theta[o + static_cast<int>(q)] / p.si_per_unit},
                        {"unit", p.unit}};
    }
    effects[e.name] = {{"description", e.description}, {"parameters", params}};
  }
  return effects;
}

// The unit of the readings the calibration was estimated from ("mV", "mg" or
// "counts", as its OUT file's units say; mV when none does, e.g. truth.json):
// the unit of its scale factors (per g), offsets and drifts, and of the z the
// exported forms take.
std::string ReadingsUnitOf(const Calibration& cal) {
  return cal.readings_unit.empty() ? "mV" : cal.readings_unit;
}

void RefuseUncarried(const Calibration& cal) {
  const std::string why = ExportRefusal(cal);
  if (!why.empty()) throw InputError(why);
}

}  // namespace

bool ExportCarries(const EffectSpec& effect) {
  // The gyro's per-axis response f_i(m) = K_i m (1 + k2_i m^2) + dK_i |m|
  // (gyro_model.h): the C inverts it as GyroAxisRate does, the matrix forms
  // give its coefficients. Another gyro-stage effect would need its own.
  if (effect.stage == EffectStage::kGyro) {
    return effect.id == Effect::kGyroScaleAsymmetry || effect.id == Effect::kGyroNonlinearity;
  }
  if (effect.stage != EffectStage::kSensor) return true;  // does not act on W: left out
  switch (effect.zero_offset_signal) {
    case ZeroOffsetSignal::kTime_s:      // kDriftPerS * t_s
    case ZeroOffsetSignal::kTempRise_C:  // kDriftPerC * (temp_C - temp_ref_C)
      return true;
    case ZeroOffsetSignal::kTimeCurvature_s2:  // needs the span of the run
      return false;
    case ZeroOffsetSignal::kNone:
      break;
  }
  return effect.id == Effect::kScaleAsymmetry || effect.id == Effect::kCrossQuadratic;
}

std::string ExportRefusal(const Calibration& cal) {
  for (const EffectSpec& e : EffectCatalogue()) {
    if (!cal.layout.has(e.id) || ExportCarries(e)) continue;
    const std::string why =
        e.zero_offset_signal == ZeroOffsetSignal::kTimeCurvature_s2
            ? "its zero-offset curvature is defined over the span of the run it is applied to"
            : "this build's export does not implement it";
    return cal.path + ": " + e.name +
           ": the exported forms (c, yaml, json-matrix) cannot carry this effect (" + why +
           "); `triadcal apply` applies it, or export a fit without it";
  }
  return "";
}

CExport ExportC(const Calibration& cal, const std::string& name, const std::string& comment,
                const std::string& file_base) {
  RefuseUncarried(cal);
  const std::string base = file_base.empty() ? name : file_base;
  const double* th = cal.theta.data();
  const Eigen::Matrix3d M = MisalignmentMatrix(th);
  const Eigen::Matrix3d K = NonlinearityMatrix(th);
  const std::string u = ReadingsUnitOf(cal);  // of z, K_i, W0_i and the drifts
  const Eigen::Vector3d drift_per_s = EffectTriple(cal, Effect::kThermalDrift);
  const Eigen::Vector3d drift_per_C = EffectTriple(cal, Effect::kThermalDriftTemp);
  const Eigen::Vector3d asymmetry = EffectTriple(cal, Effect::kScaleAsymmetry);
  const Eigen::Matrix<double, 6, 1> cross = CrossQuadratic(cal);
  const std::string guard = [&] {
    std::string g;
    for (char c : name) g += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return g + "_H_";
  }();

  CExport out;
  out.header =
      "/* " + base + ".h: apply a triadcal calibration (generated by triadcal export).\n" +
      Commented(comment) +
      " */\n"
      "#ifndef " +
      guard + "\n#define " + guard +
      "\n\n"
      "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n"
      "/* Raw readings z [" +
      u +
      "] of the x, y, z accelerometers (in the triad's axes,\n"
      " * after the unit conversion and mounting of run.yaml) -> specific force W [g]\n"
      " * in the triad frame (an axis pointing up reads +1 g at rest): the exact\n"
      " * inverse of the readings model (paper eq. 1)\n"
      " *   u_i = (z_i - W0_i(t, T)) / (K_i +- dK_i),   M W + diag(W) Kij W + Q(W) = u\n"
      " *   (Q_i = d_i (W_j^2 - W_k^2) + p_i W_j W_k, j < k the other axes: cross_quadratic)\n"
      " * solved by Newton's method (`triadcal apply` finds the same root by chord\n"
      " * steps).\n"
      " * t_s [s]: time of the sample, counted as in the run (thermal_drift);\n"
      " * temp_C, temp_ref_C [degC]: temperature and its reference, the run's first\n"
      " * temperature (thermal_drift_temp). Unused when the calibration has neither\n"
      " * effect. */\n"
      "void " +
      name + "_apply(const double z_" + u +
      "[3], double t_s, double temp_C,\n"
      "    double temp_ref_C, double W_g[3]);\n\n";
  if (cal.layout.has_gyro()) {
    out.header +=
        "/* Gyro readings g [deg/s] of the x, y, z gyros (in the triad's axes, after\n"
        " * the unit conversion and mounting of run.yaml) and the specific force W_g [g]\n"
        " * of the same sample (from " +
        name +
        "_apply) -> angular rate omega [deg/s] in the\n"
        " * triad frame: the exact inverse of the gyro's readings model (SPEC section 10)\n"
        " *   u_i = g_i - W0_i - (G W)_i,   K_i m_i (1 + k2_i m_i^2) + dK_i |m_i| = u_i,\n"
        " *   omega = Mg^-1 m\n"
        " * (dK_i: gyro_scale_asymmetry, k2_i: gyro_nonlinearity, zero when absent; without\n"
        " * them omega = Mg^-1 diag(K)^-1 (g - W0 - G W)), with Newton's steps on m_i as\n"
        " * `triadcal apply` computes it. */\n"
        "void " +
        name + "_apply_gyro(const double g_dps[3], const double W_g[3], double omega_dps[3]);\n\n";
  }
  out.header += "#ifdef __cplusplus\n}\n#endif\n\n#endif /* " + guard + " */\n";

  std::string s =
      "/* " + base + ".c: apply a triadcal calibration (generated by triadcal export).\n" +
      Commented(comment) + " * C99, no library functions. */\n" + "#include \"" + base + ".h\"\n\n";
  s += "/* Scale factors K_i [" + u + "/g] and zero offsets W0_i [" + u + "]. */\n";
  s += "static const double kScale[3] = " + Array3(th + kKx) + ";\n";
  s += "static const double kBias[3] = " + Array3(th + kW0x) + ";\n";
  s += "/* Non-orthogonality matrix M (angles in rad), row by row:\n"
       " *   [[1, -alpha_y, beta_z], [alpha_x, 1, -gamma_z], [-beta_x, gamma_y, 1]] */\n";
  s += "static const double kM[9] = " + Matrix3(M) + ";\n";
  s += "/* Nonlinearity and cross-coupling K_ij [1/g], row by row. */\n";
  s += "static const double kK[9] = " + Matrix3(K) + ";\n";
  s += "/* Sensor-stage effects (zero when absent): zero drift [" + u + "/s] and [" + u +
       "/degC],\n * scale asymmetry dK_i [" + u +
       "/g] (scale K_i + dK_i for u_i > 0, K_i - dK_i below). */\n";
  s += "static const double kDriftPerS[3] = " + Array3(drift_per_s.data()) + ";\n";
  s += "static const double kDriftPerC[3] = " + Array3(drift_per_C.data()) + ";\n";
  s += "static const double kAsymmetry[3] = " + Array3(asymmetry.data()) + ";\n";
  s += std::string("static const int kHasAsymmetry = ") +
       (cal.layout.has(Effect::kScaleAsymmetry) ? "1" : "0") + ";\n";
  s += "/* Cross-axis quadratic response [1/g] (cross_quadratic; zero when absent): (d_i, p_i)\n"
       " * of reading i, whose cross axes are j < k: Q_i = d_i (W_j^2 - W_k^2) + p_i W_j W_k. */\n";
  s += "static const double kCross[6] = {" + Exact(cross[0]) + ", " + Exact(cross[1]) + ", " +
       Exact(cross[2]) + ", " + Exact(cross[3]) + ", " + Exact(cross[4]) + ", " +
       Exact(cross[5]) + "};\n";
  s += "static const int kCrossAxes[3][2] = {";
  for (int i = 0; i < 3; ++i) {
    s += std::string(i ? ", " : "") + "{" + std::to_string(kCrossAxes[i][0]) + ", " +
         std::to_string(kCrossAxes[i][1]) + "}";
  }
  s += "};\n\n";
  s += R"(static double Abs(double x) { return x < 0.0 ? -x : x; }

/* 3x3 matrices are stored row by row: a[3 * row + column]. */

/* Inverse of a 3x3 matrix by its cofactors. */
static void Inverse3(const double* a, double* inv) {
  double c[9], det;
  int r, k;
  c[0] = a[4] * a[8] - a[5] * a[7];
  c[1] = a[5] * a[6] - a[3] * a[8];
  c[2] = a[3] * a[7] - a[4] * a[6];
  c[3] = a[2] * a[7] - a[1] * a[8];
  c[4] = a[0] * a[8] - a[2] * a[6];
  c[5] = a[1] * a[6] - a[0] * a[7];
  c[6] = a[1] * a[5] - a[2] * a[4];
  c[7] = a[2] * a[3] - a[0] * a[5];
  c[8] = a[0] * a[4] - a[1] * a[3];
  det = a[0] * c[0] + a[1] * c[1] + a[2] * c[2];
  for (r = 0; r < 3; ++r) {
    for (k = 0; k < 3; ++k) inv[3 * r + k] = c[3 * k + r] / det;
  }
}

static void MulVec(const double* m, const double* v, double* out) {
  int r;
  for (r = 0; r < 3; ++r) out[r] = m[3 * r] * v[0] + m[3 * r + 1] * v[1] + m[3 * r + 2] * v[2];
}

/* F(W) = M W + diag(W) Kij W + Q(W) - u and its Jacobian
 * J = M + diag(Kij W) + diag(W) Kij + dQ/dW. */
static void Residual(const double* W, const double* u, double* F, double* J) {
  double MW[3], KW[3];
  int r, k;
  MulVec(kM, W, MW);
  MulVec(kK, W, KW);
  for (r = 0; r < 3; ++r) {
    const int j = kCrossAxes[r][0], l = kCrossAxes[r][1];
    const double d = kCross[2 * r], p = kCross[2 * r + 1];
    F[r] = MW[r] + W[r] * KW[r] + d * (W[j] * W[j] - W[l] * W[l]) + p * W[j] * W[l] - u[r];
    for (k = 0; k < 3; ++k) J[3 * r + k] = kM[3 * r + k] + W[r] * kK[3 * r + k];
    J[3 * r + r] += KW[r];
    J[3 * r + j] += 2.0 * d * W[j] + p * W[l];
    J[3 * r + l] += -2.0 * d * W[l] + p * W[j];
  }
}

)";
  s += "void " + name + "_apply(const double z_" + u +
       "[3], double t_s, double temp_C,\n"
       "    double temp_ref_C, double W_g[3]) {\n";
  s += R"(  double u[3], W[3], F[3], J[9], Jinv[9], Minv[9], step[3];
  int i, it;
  for (i = 0; i < 3; ++i) {
    const double w0 = kBias[i] + kDriftPerS[i] * t_s + kDriftPerC[i] * (temp_C - temp_ref_C);
    const double v = z_)" + u + R"([i] - w0;
    double scale = kScale[i];
    if (kHasAsymmetry) scale += v < 0.0 ? -kAsymmetry[i] : kAsymmetry[i];
    u[i] = v / scale;
  }
  /* Newton from the linear solution W = M^-1 u: 2-3 steps for |K_ij| ~ 1e-3. */
  Inverse3(kM, Minv);
  MulVec(Minv, u, W);
  for (it = 0; it < 8; ++it) {
    double largest_step = 0.0, largest_W = 0.0;
    Residual(W, u, F, J);
    Inverse3(J, Jinv);
    MulVec(Jinv, F, step);
    for (i = 0; i < 3; ++i) W[i] -= step[i];
    for (i = 0; i < 3; ++i) {
      if (Abs(step[i]) > largest_step) largest_step = Abs(step[i]);
      if (Abs(W[i]) > largest_W) largest_W = Abs(W[i]);
    }
    if (largest_step <= 1e-15 * (1.0 + largest_W)) break;
  }
  /* One last step, as the C++ inverse takes. */
  Residual(W, u, F, J);
  Inverse3(J, Jinv);
  MulVec(Jinv, F, step);
  for (i = 0; i < 3; ++i) W_g[i] = W[i] - step[i];
}
)";
  if (cal.layout.has_gyro()) {
    const GyroMatrices gm = GyroForm(cal);
    s += "\n/* The gyro: scale factors K_i (dimensionless), inverse misalignment Mg^-1,\n"
         " * bias W0 [deg/s] and g-sensitivity G [(deg/s)/g], matrices row by row. */\n";
    s += "static const double kGyroScale[3] = " + Array3(gm.K.data()) + ";\n";
    s += "static const double kGyroMgInverse[9] = " + Matrix3(gm.Mg_inverse) + ";\n";
    s += "static const double kGyroBias[3] = " + Array3(gm.b_dps.data()) + ";\n";
    s += "static const double kGyroG[9] = " + Matrix3(gm.G_dps_per_g) + ";\n";
    s += "/* The gyro-stage effects (zero when absent): scale asymmetry dK_i (dimensionless;\n"
         " * gyro_scale_asymmetry) and the scale's quadratic term k2_i [1/(deg/s)^2]\n"
         " * (gyro_nonlinearity). */\n";
    s += "static const double kGyroAsymmetry[3] = " + Array3(gm.dK.data()) + ";\n";
    s += "static const double kGyroK2[3] = " + Array3(gm.k2_per_dps2.data()) + ";\n";
    s += std::string("static const int kGyroHasNonlinearity = ") + (gm.nonlinear ? "1" : "0") +
         ";\n\n";
    s += "void " + name +
         "_apply_gyro(const double g_dps[3], const double W_g[3], double omega_dps[3]) {\n";
    s += R"(  double GW[3], m[3];
  int i, it;
  MulVec(kGyroG, W_g, GW);
  for (i = 0; i < 3; ++i) {
    const double u = g_dps[i] - kGyroBias[i] - GW[i];
    /* m takes the sign of u / K (the response is monotonic while |dK| < |K|). */
    const double s = ((u < 0.0) != (kGyroScale[i] < 0.0)) ? -1.0 : 1.0;
    const double lin = kGyroScale[i] + s * kGyroAsymmetry[i];
    const double Kk2 = kGyroScale[i] * kGyroK2[i];
    m[i] = u / lin;
    if (kGyroHasNonlinearity) {
      for (it = 0; it < 6; ++it) {
        m[i] -= (lin * m[i] + Kk2 * m[i] * m[i] * m[i] - u) / (lin + 3.0 * Kk2 * m[i] * m[i]);
      }
    }
  }
  MulVec(kGyroMgInverse, m, omega_dps);
}
)";
  }
  out.source = s;
  return out;
}

nlohmann::ordered_json MatrixForm(const Calibration& cal) {
  RefuseUncarried(cal);
  const double* th = cal.theta.data();
  const double g0 = kStandardGravity;
  const Eigen::Vector3d K = cal.theta.segment<3>(kKx);
  const Eigen::Matrix3d S_g = K.asDiagonal() * MisalignmentMatrix(th);
  const Eigen::Matrix3d N_g = K.asDiagonal() * NonlinearityMatrix(th);
  const std::string u = ReadingsUnitOf(cal);  // the keys name it: S_counts_per_mps2, ...
  nlohmann::ordered_json j;
  j["model"] =
      "z = S a + b + diag(a) N a: z readings [" + u +
      "] of the x, y, z accelerometers, a specific "
      "force [m/s^2] in the triad frame (an axis pointing up reads +g at rest); S = diag(K) M "
      "/ g0, N = diag(K) Kij / g0^2, b = W0, g0 = 9.80665 m/s^2 (paper eq. 1 with W = a / g0)";
  j["readings_unit"] = u;
  j["g0_mps2"] = g0;
  j["S_" + u + "_per_mps2"] = Rows(S_g / g0);
  j["b_" + u] = Vec(cal.theta.segment<3>(kW0x));
  j["N_" + u + "_per_mps2_sq"] = Rows(N_g / (g0 * g0));
  j["S_inverse_mps2_per_" + u] = Rows((S_g / g0).inverse());
  j["in_g"] = {{"S_" + u + "_per_g", Rows(S_g)}, {"N_" + u + "_per_g_sq", Rows(N_g)}};
  j["source"] = {{"calibration", cal.path}, {"section", cal.section}, {"command", cal.command}};
  nlohmann::ordered_json effects = nlohmann::ordered_json::object();
  if (cal.layout.has(Effect::kThermalDrift)) {
    effects["thermal_drift"] = {{"model", "b_i(t) = b_i + rate_i t, t [s] as counted in the run"},
                                {"rate_" + u + "_per_s", Vec(EffectTriple(cal, Effect::kThermalDrift))}};
  }
  if (cal.layout.has(Effect::kThermalDriftTemp)) {
    effects["thermal_drift_temp"] = {
        {"model", "b_i(T) = b_i + coef_i (T - T_ref), T_ref the run's first temperature"},
        {"coef_" + u + "_per_degC", Vec(EffectTriple(cal, Effect::kThermalDriftTemp))}};
  }
  if (cal.layout.has(Effect::kScaleAsymmetry)) {
    effects["scale_asymmetry"] = {
        {"model",
         "row i of S and N scaled by (K_i + dK_i sgn(u_i)) / K_i, u_i = (M a / g0 + "
         "diag(a) Kij a / g0^2)_i"},
        {"dK_" + u + "_per_g", Vec(EffectTriple(cal, Effect::kScaleAsymmetry))}};
  }
  if (cal.layout.has(Effect::kCrossQuadratic)) {
    const Eigen::Matrix<double, 6, 1> q = CrossQuadratic(cal);
    effects["cross_quadratic"] = {
        {"model",
         "u_i += d_i (W_j^2 - W_k^2) + p_i W_j W_k, W = a / g0, (j, k) = (y, z), (x, z), (x, y) "
         "for i = x, y, z; z_i = K_i u_i + b_i"},
        {"d_per_g", {q[0], q[2], q[4]}},
        {"p_per_g", {q[1], q[3], q[5]}}};
  }
  j["effects"] = effects;
  if (cal.layout.has_gyro()) {
    const GyroMatrices gm = GyroForm(cal);
    j["gyro"] = {
        {"model",
         "g = S omega + b + G W: g readings [deg/s] of the x, y, z gyros, omega angular rate "
         "[deg/s] in the triad frame, W specific force [g] (a / g0, the accelerometer's "
         "corrected); S = diag(K) Mg (dimensionless), b = W0; correction: omega = S^-1 (g - b - "
         "G W), S^-1 = Mg^-1 diag(K)^-1 (SPEC section 10)"},
        {"S", Rows(gm.S)},
        {"S_inverse", Rows(gm.S_inverse)},
        {"b_dps", Vec(gm.b_dps)},
        {"G_dps_per_g", Rows(gm.G_dps_per_g)}};
    const nlohmann::ordered_json effects = GyroEffectsJson(cal);
    if (!effects.empty()) {
      // The per-axis response the effects change (S and S_inverse above are
      // the model without them).
      j["gyro"]["effects_model"] =
          "g_i = f_i(m_i) + b_i + (G W)_i, m = Mg omega [deg/s], f_i(m) = K_i m (1 + k2_i m^2) + "
          "dK_i |m| (dK_i = 1e-6 x gyro_scale_asymmetry.dK_i [ppm], k2_i = 1e-6 x "
          "gyro_nonlinearity.k2_i [ppm/(deg/s)^2], 0 when absent); correction: u_i = g_i - b_i "
          "- (G W)_i, m_i = f_i^-1(u_i) (monotonic while |dK_i| < |K_i|), omega = Mg_inverse m";
      j["gyro"]["K"] = Vec(gm.K);
      j["gyro"]["Mg_inverse"] = Rows(gm.Mg_inverse);
      j["gyro"]["effects"] = effects;
    }
  }
  return j;
}

}  // namespace triadcal
