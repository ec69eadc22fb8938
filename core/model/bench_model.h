// The physics of triadcal, written once: bench kinematics (docs/method.md,
// paper eq. 2), the readings model (paper eq. 1) and its exact inverse, and the
// effects of the catalogue (effects.h). Everything is templated on the scalar so
// that Ceres Jets flow through; the simulator, the filter, the batch solver and
// the analyses all call these functions and nothing else.
//
// Frames (docs/method.md): L level (x up, g_L = (-g, 0, 0)), 1 outer-axis frame,
// 2 platform frame (= triad frame). Names carry frames: C_L2 rotates frame-2
// vectors into L, p_O_L is the position of O in L.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "core/model/effects.h"
#include "core/model/parameters.h"
#include "core/model/rotations.h"
#include "core/model/units.h"

namespace triadcal {

// What the model needs besides theta: fixed, known quantities of the run.
struct ModelConfig {
  Eigen::Vector3d lever_arm0_m{0.138, 0.020, 0.020};  // R0, nominal, frame 2
  double g_mps2 = kStandardGravity;
  double temp_ref_C = 0.0;  // reference of thermal_drift_temp (first temp_C of the run)
  // The run's first sample time and duration [s] (thermal_drift_quadratic's
  // signal is orthogonal over them to a constant and a linear drift).
  double time_start_s = 0.0;
  double time_span_s = 0.0;
  // Earth's rate in L [rad/s] (gyro_model.h): zero unless the run gives the
  // bench's latitude and heading.
  Eigen::Vector3d earth_rate_L = Eigen::Vector3d::Zero();
  ParameterLayout layout;
};

// Angle, rate and angular acceleration of one bench axis [rad, rad/s, rad/s^2].
template <typename T>
struct AxisState {
  T angle{0.0};
  T rate{0.0};
  T accel{0.0};
};

// Both bench axes: [0] the outer axis (lambda1), [1] the inner axis (lambda2).
template <typename T>
struct BenchAngles {
  AxisState<T> axis[2];
};

template <typename T>
BenchAngles<T> CastAngles(const BenchAngles<double>& a) {
  BenchAngles<T> out;
  for (int i = 0; i < 2; ++i) {
    out.axis[i].angle = T(a.axis[i].angle);
    out.axis[i].rate = T(a.axis[i].rate);
    out.axis[i].accel = T(a.axis[i].accel);
  }
  return out;
}

// Time and temperature of one sample, for the drifting effects.
struct SampleContext {
  double t_s = 0.0;
  double temp_C = 0.0;
};

// ---------------------------------------------------------------------------
// Angle stage: recorded angles <-> bench angles.
//
//   recorded(t) = (1 + k) E(bench(t - tau)),  E(l)_i = l_i + s_i sin(l_i) + c_i cos(l_i)
//
// (k_i: angle_scale, the recorder's counts-to-angle factor off by 1 + k_i.)
// The simulator evaluates the profile at t - tau and applies EncoderReading.
// The estimators invert the chain: undo the latency with a second-order Taylor
// step, bench(t) = recorded(t + tau), divide by 1 + k, then invert E by
// fixed-point iteration. (The time shift commutes with the static maps.)
// ---------------------------------------------------------------------------

template <typename T>
T AngleLatency_s(const ModelConfig& cfg, const T* theta) {
  const int o = cfg.layout.offset(Effect::kAngleLatency);
  return o < 0 ? T(0.0) : theta[o];
}

// Encoder error e(l) = s sin l + c cos l of axis i and its first two derivatives.
template <typename T>
void EncoderError(const ModelConfig& cfg, const T* theta, int i, const T& l, T* e, T* de,
                  T* dde) {
  using std::cos;
  using std::sin;
  const int o = cfg.layout.offset(Effect::kEncoderHarmonic);
  if (o < 0) {
    *e = *de = *dde = T(0.0);
    return;
  }
  const T& s = theta[o + 2 * i];
  const T& c = theta[o + 2 * i + 1];
  const T sl = sin(l), cl = cos(l);
  *e = s * sl + c * cl;
  *de = s * cl - c * sl;
  *dde = -*e;
}

// 1 + k_i of angle sensor i (angle_scale), 1 without the effect.
template <typename T>
T AngleScaleFactor(const ModelConfig& cfg, const T* theta, int i) {
  const int o = cfg.layout.offset(Effect::kAngleScale);
  return o < 0 ? T(1.0) : T(1.0) + theta[o + i];
}

// Bench angles -> what the angle sensors report (encoder error and scale).
//   r = (1 + k)(l + e(l)),  r' = (1 + k) l'(1 + e'),  r'' = (1 + k)(l''(1 + e') + l'^2 e'')
template <typename T>
BenchAngles<T> EncoderReading(const ModelConfig& cfg, const T* theta, const BenchAngles<T>& b) {
  BenchAngles<T> r = b;
  if (cfg.layout.has(Effect::kEncoderHarmonic)) {
    for (int i = 0; i < 2; ++i) {
      T e, de, dde;
      EncoderError(cfg, theta, i, b.axis[i].angle, &e, &de, &dde);
      r.axis[i].angle = b.axis[i].angle + e;
      r.axis[i].rate = b.axis[i].rate * (T(1.0) + de);
      r.axis[i].accel = b.axis[i].accel * (T(1.0) + de) + b.axis[i].rate * b.axis[i].rate * dde;
    }
  }
  if (cfg.layout.has(Effect::kAngleScale)) {
    for (int i = 0; i < 2; ++i) {
      const T f = AngleScaleFactor(cfg, theta, i);
      r.axis[i].angle = f * r.axis[i].angle;
      r.axis[i].rate = f * r.axis[i].rate;
      r.axis[i].accel = f * r.axis[i].accel;
    }
  }
  return r;
}

// The value of a scalar without its derivative part (double, or a Ceres Jet).
inline double ScalarPart(double x) { return x; }
template <typename J>
double ScalarPart(const J& x) {
  return x.a;
}

// Recorded angles (and the rates/accelerations derived from them) -> bench angles.
// |a - b| <= tol, and for Jets (a.a, a.v) every derivative too.
inline bool WithinOf(double a, double b, double tol) { return std::abs(a - b) <= tol; }
template <typename J>
bool WithinOf(const J& a, const J& b, double tol) {
  return std::abs(a.a - b.a) <= tol && ((a.v - b.v).cwiseAbs().array() <= tol).all();
}

template <typename T>
BenchAngles<T> BenchAnglesFromRecorded(const ModelConfig& cfg, const T* theta,
                                       const BenchAngles<double>& recorded) {
  BenchAngles<T> b = CastAngles<T>(recorded);
  if (!cfg.layout.has_stage(EffectStage::kAngle)) return b;
  if (cfg.layout.has(Effect::kAngleLatency)) {
    // bench(t) = recorded(t + tau) to second order in tau.
    const T tau = AngleLatency_s(cfg, theta);
    for (int i = 0; i < 2; ++i) {
      const AxisState<double>& r = recorded.axis[i];
      b.axis[i].angle = T(r.angle) + tau * r.rate + T(0.5) * tau * tau * r.accel;
      b.axis[i].rate = T(r.rate) + tau * r.accel;
      b.axis[i].accel = T(r.accel);
    }
  }
  if (cfg.layout.has(Effect::kAngleScale)) {
    for (int i = 0; i < 2; ++i) {
      const T f = AngleScaleFactor(cfg, theta, i);
      b.axis[i].angle = b.axis[i].angle / f;
      b.axis[i].rate = b.axis[i].rate / f;
      b.axis[i].accel = b.axis[i].accel / f;
    }
  }
  if (cfg.layout.has(Effect::kEncoderHarmonic)) {
    for (int i = 0; i < 2; ++i) {
      const AxisState<T> r = b.axis[i];
      // l = r - e(l) by fixed-point iteration (contraction factor |e'|, a
      // few 1e-3), until l no longer moves (below 1e-15 rad, its
      // derivatives alike). At zero harmonics (diagnose's score tests) e
      // is 0 wherever l is, so l = r - e(r) exactly, derivatives too (e's
      // by l are 0 there): no second evaluation to confirm it.
      T l = r.angle, e, de, dde;
      EncoderError(cfg, theta, i, l, &e, &de, &dde);
      const int o = cfg.layout.offset(Effect::kEncoderHarmonic);
      const bool zero = ScalarPart(theta[o + 2 * i]) == 0.0 &&
                        ScalarPart(theta[o + 2 * i + 1]) == 0.0;
      if (zero) l = r.angle - e;
      for (int it = 0; it < 6 && !zero; ++it) {
        const T next = r.angle - e;
        if (WithinOf(next, l, 1e-15)) break;
        l = next;
        EncoderError(cfg, theta, i, l, &e, &de, &dde);
      }
      b.axis[i].angle = l;
      b.axis[i].rate = r.rate / (T(1.0) + de);
      b.axis[i].accel =
          (r.accel - b.axis[i].rate * b.axis[i].rate * dde) / (T(1.0) + de);
    }
  }
  return b;
}

// ---------------------------------------------------------------------------
// Geometry stage: bench kinematics (docs/method.md, paper eq. 2).
//
//   C_L1 = Rz(dpsi) Ry(l1 + dtheta_c)
//   C_12 = Rz(eps) Rx(l2 + dlambda2) Rz(-eps)         (eps = 0 without the effect)
//   C_L2 = C_L1 C_12
//
// A point fixed at r in frame 2 (r measured from the inner-axis point, i.e. the
// bench centre when the axes intersect) is at
//
//   p_L = C_L1 d e_z + q,    q = C_L2 r               (d = 0 without the effect)
//
// Angular velocities in L: w1 = u1 l1' with u1 = Rz(dpsi) e_y (outer axis), and
// w12 = C_L1 n l2' with n = Rz(eps) e_x (inner axis); w = w1 + w12. Then
//
//   v_L = w1 x p_L + w12 x q
//   a_L = (u1 l1'') x p_L + w1 x v_L + (w1 x w12 + C_L1 n l2'') x q + w12 x (w x q)
//
// With d = 0 this is a = w' x q + w x (w x q): the normal, tangential and
// Coriolis terms of the paper's eq. 2 (w' = u1 l1'' + C_L1 n l2'' + w1 x w12).
// ---------------------------------------------------------------------------

template <typename T>
struct BenchMotion {
  Mat3<T> C_L1, C_L2;
  Vec3<T> axis_offset_L;  // C_L1 d e_z
  Vec3<T> w1_L, w12_L;    // angular velocities [rad/s]
  Vec3<T> dw1_L;          // u1 l1''
  Vec3<T> dw12_L;         // w1 x w12 + C_L1 n l2''
};

// The bench's rotations at angles b: C_L1 = Rpsi Ry, C_12 and C_L2, and n_1 =
// Rz(eps) e_x, the inner axis in frame 1 (the sines and cosines of a sample:
// B1's Jacobian forms them once for the motion and its own columns).
template <typename T>
struct BenchRotations {
  Mat3<T> Rpsi, Ry, C_12, C_L1, C_L2;
  Vec3<T> n_1;
};

template <typename T>
BenchRotations<T> ComputeBenchRotations(const ModelConfig& cfg, const T* theta,
                                        const BenchAngles<T>& b) {
  const int o_eps = cfg.layout.offset(Effect::kAxisNonperpendicularity);
  BenchRotations<T> r;
  r.Rpsi = Rz(theta[kDpsi]);
  r.Ry = Ry<T>(b.axis[0].angle + theta[kDthetaC]);
  r.C_L1 = r.Rpsi * r.Ry;
  r.C_12 = Rx<T>(b.axis[1].angle + theta[kDlambda2]);
  r.n_1 = Vec3<T>(T(1.0), T(0.0), T(0.0));
  if (o_eps >= 0) {
    const Mat3<T> Reps = Rz(theta[o_eps]);
    r.C_12 = Reps * r.C_12 * Reps.transpose();
    r.n_1 = Reps.col(0);
  }
  r.C_L2 = r.C_L1 * r.C_12;
  return r;
}

template <typename T>
BenchMotion<T> ComputeBenchMotion(const ModelConfig& cfg, const T* theta,
                                  const BenchAngles<T>& b, const BenchRotations<T>& r) {
  const int o_d = cfg.layout.offset(Effect::kAxisNonintersection);
  const T d = o_d < 0 ? T(0.0) : theta[o_d];
  BenchMotion<T> m;
  m.C_L1 = r.C_L1;
  m.C_L2 = r.C_L2;
  m.axis_offset_L = m.C_L1.col(2) * d;
  const Vec3<T> u1 = r.Rpsi.col(1);
  const Vec3<T> n_L = m.C_L1 * r.n_1;
  m.w1_L = u1 * b.axis[0].rate;
  m.w12_L = n_L * b.axis[1].rate;
  m.dw1_L = u1 * b.axis[0].accel;
  m.dw12_L = m.w1_L.cross(m.w12_L) + n_L * b.axis[1].accel;
  return m;
}

template <typename T>
BenchMotion<T> ComputeBenchMotion(const ModelConfig& cfg, const T* theta,
                                  const BenchAngles<T>& b) {
  return ComputeBenchMotion(cfg, theta, b, ComputeBenchRotations(cfg, theta, b));
}

template <typename T>
struct PointMotion {
  Vec3<T> p_L, v_L, a_L;  // [m, m/s, m/s^2]
};

// Motion in L of the point fixed at r_2 (frame 2, from the inner-axis point).
template <typename T>
PointMotion<T> MotionOfPoint(const BenchMotion<T>& m, const Vec3<T>& r_2) {
  PointMotion<T> pm;
  const Vec3<T> q = m.C_L2 * r_2;
  const Vec3<T> w = m.w1_L + m.w12_L;
  pm.p_L = m.axis_offset_L + q;
  pm.v_L = m.w1_L.cross(pm.p_L) + m.w12_L.cross(q);
  pm.a_L = m.dw1_L.cross(pm.p_L) + m.w1_L.cross(pm.v_L) + m.dw12_L.cross(q) +
           m.w12_L.cross(w.cross(q));
  return pm;
}

// R = R0 + dR, the position of O in frame 2 [m].
template <typename T>
Vec3<T> LeverArm_m(const ModelConfig& cfg, const T* theta) {
  return Vec3<T>(T(cfg.lever_arm0_m.x()) + theta[kDx2], T(cfg.lever_arm0_m.y()) + theta[kDy2],
                 T(cfg.lever_arm0_m.z()) + theta[kDz2]);
}

// Where accelerometer i senses, in frame 2: O, or O + r_i with the size effect.
template <typename T>
Vec3<T> SensingPoint_m(const ModelConfig& cfg, const T* theta, int i) {
  Vec3<T> r = LeverArm_m(cfg, theta);
  const int o = cfg.layout.offset(Effect::kSizeEffect);
  if (o >= 0 && i > 0) {
    const T* ri = theta + o + 3 * (i - 1);
    r += Vec3<T>(ri[0], ri[1], ri[2]);
  }
  return r;
}

// Specific force in the triad frame, in g, at a point moving with a_L:
//   W = C_L2^T (a_L - g_L) / g,   g_L = (-g, 0, 0)      (an axis up reads +1 g)
template <typename T>
Vec3<T> SpecificForce_g(const ModelConfig& cfg, const Mat3<T>& C_L2, const Vec3<T>& a_L) {
  Vec3<T> f = a_L;
  f.x() += T(cfg.g_mps2);
  return C_L2.transpose() * f / T(cfg.g_mps2);
}

// The specific force each accelerometer feels: column i is W at accelerometer
// i's sensing point (all three columns equal without the size effect).
template <typename T>
Mat3<T> SpecificForceAtAxes_g(const ModelConfig& cfg, const T* theta, const BenchMotion<T>& m) {
  Mat3<T> W;
  const bool size = cfg.layout.has(Effect::kSizeEffect);
  W.col(0) = SpecificForce_g(cfg, m.C_L2, MotionOfPoint(m, SensingPoint_m(cfg, theta, 0)).a_L);
  for (int i = 1; i < 3; ++i) {
    W.col(i) = size ? SpecificForce_g(cfg, m.C_L2,
                                      MotionOfPoint(m, SensingPoint_m(cfg, theta, i)).a_L)
                    : W.col(0);
  }
  return W;
}

// ---------------------------------------------------------------------------
// Sensor stage: the readings model (paper eq. 1), in mV.
//
//   u_i   = sum_j M_ij W_j + W_i sum_j K_ij W_j [+ Q_i(W): cross_quadratic]
//   Wpr_i = K_i u_i + dK_i |u_i| + W0_i(t)            (dK_i: scale_asymmetry)
//
//   M = [[ 1,       -alpha_y,  beta_z ],
//        [ alpha_x,  1,       -gamma_z],
//        [-beta_x,   gamma_y,  1      ]]
//
// W0_i(t) = W0_i + rate_i t + coef_i (temp_C - T_ref) with the drift effects
// (each declares its signal t or temp_C - T_ref in the catalogue).
// With the size effect, accelerometer i applies row i to the W at its own point.
// ---------------------------------------------------------------------------

template <typename T>
Mat3<T> MisalignmentMatrix(const T* theta) {
  Mat3<T> M;
  M << T(1.0), -theta[kAlphaY], theta[kBetaZ],  //
      theta[kAlphaX], T(1.0), -theta[kGammaZ],  //
      -theta[kBetaX], theta[kGammaY], T(1.0);
  return M;
}

template <typename T>
Mat3<T> NonlinearityMatrix(const T* theta) {
  return Eigen::Map<const Eigen::Matrix<T, 3, 3, Eigen::RowMajor>>(theta + kKxx);
}

// cross_quadratic: reading i's cross axes j < k, and its two coefficients
// (d_i, p_i) at theta[offset + 2 i ..]; the term is
//   Q_i(W) = d_i (W_j^2 - W_k^2) + p_i W_j W_k.
constexpr int kCrossAxes[3][2] = {{1, 2}, {0, 2}, {0, 1}};

template <typename T>
T CrossQuadraticTerm(const T* q, int i, const Vec3<T>& W) {
  const int j = kCrossAxes[i][0], k = kCrossAxes[i][1];
  return q[2 * i] * (W[j] * W[j] - W[k] * W[k]) + q[2 * i + 1] * W[j] * W[k];
}

// d Q_i / d W (row i of the term's Jacobian), values only.
inline Eigen::RowVector3d CrossQuadraticGradient(const double* q, int i,
                                                 const Vec3<double>& W) {
  const int j = kCrossAxes[i][0], k = kCrossAxes[i][1];
  Eigen::RowVector3d g = Eigen::RowVector3d::Zero();
  g[j] = 2.0 * q[2 * i] * W[j] + q[2 * i + 1] * W[k];
  g[k] = -2.0 * q[2 * i] * W[k] + q[2 * i + 1] * W[j];
  return g;
}

// The signal x(sample) of a zero-offset effect (effects.h ZeroOffsetSignal):
//   thermal_drift: x = t [s];  thermal_drift_temp: x = temp_C - T_ref [degC];
//   thermal_drift_quadratic: x = T^2 P2(u), u = (t - t0) / T over the run
//   [t0, t0 + T], P2(u) = u^2 - u + 1/6: (t - t0)^2 less the constant and the
//   line that W0 and thermal_drift carry, so that a linear drift gives it no
//   score (uniform sampling) and its coefficient is still half the drift's
//   second derivative.
inline double ZeroOffsetSignalValue(const ModelConfig& cfg, ZeroOffsetSignal signal,
                                    const SampleContext& ctx) {
  switch (signal) {
    case ZeroOffsetSignal::kTime_s: return ctx.t_s;
    case ZeroOffsetSignal::kTimeCurvature_s2: {
      const double d = ctx.t_s - cfg.time_start_s, T = cfg.time_span_s;
      return d * d - T * d + T * T / 6.0;
    }
    case ZeroOffsetSignal::kTempRise_C: return ctx.temp_C - cfg.temp_ref_C;
    case ZeroOffsetSignal::kNone: break;
  }
  return 0.0;
}

// Zero offsets at this sample [mV]: W0_i + sum over the zero-offset effects of
// theta_e,i x_e(sample), dispatched through the catalogue.
template <typename T>
Vec3<T> ZeroOffset_mV(const ModelConfig& cfg, const T* theta, const SampleContext& ctx) {
  Vec3<T> w0(theta[kW0x], theta[kW0y], theta[kW0z]);
  for (const ParameterLayout::ZeroOffsetTerm& term : cfg.layout.zero_offset_terms()) {
    const double x = ZeroOffsetSignalValue(cfg, term.signal, ctx);
    for (int i = 0; i < 3; ++i) w0[i] += theta[term.offset + i] * T(x);
  }
  return w0;
}

// Specific force at each axis (columns, g) -> readings [mV].
template <typename T>
Vec3<T> Readings_mV(const ModelConfig& cfg, const T* theta, const Mat3<T>& W_axes,
                    const SampleContext& ctx) {
  using std::abs;
  const Mat3<T> M = MisalignmentMatrix(theta);
  const Mat3<T> K = NonlinearityMatrix(theta);
  const Vec3<T> w0 = ZeroOffset_mV(cfg, theta, ctx);
  const int o_a = cfg.layout.offset(Effect::kScaleAsymmetry);
  const int o_q = cfg.layout.offset(Effect::kCrossQuadratic);
  Vec3<T> out;
  for (int i = 0; i < 3; ++i) {
    const Vec3<T> W = W_axes.col(i);
    T u = M.row(i).dot(W) + W[i] * K.row(i).dot(W);
    if (o_q >= 0) u += CrossQuadraticTerm(theta + o_q, i, W);
    out[i] = theta[kKx + i] * u + w0[i];
    if (o_a >= 0) out[i] += theta[o_a + i] * abs(u);
  }
  return out;
}

// Common-point form: one specific-force vector for all three axes.
template <typename T>
Vec3<T> Readings_mV(const ModelConfig& cfg, const T* theta, const Vec3<T>& W,
                    const SampleContext& ctx) {
  Mat3<T> W_axes;
  W_axes << W, W, W;
  return Readings_mV(cfg, theta, W_axes, ctx);
}

// Exact inverse of the common-point readings model: readings [mV] -> W [g].
//   u_i = (Wpr_i - W0_i) / (K_i + dK_i sgn)   (sgn(u_i) = sgn(Wpr_i - W0_i))
//   solve F(W) = M W + diag(W) K W + Q(W) - u = 0,
//   J = M + diag(K W) + diag(W) K + dQ/dW (Q: cross_quadratic, zero without it).
// Without nonlinearity (K = 0, no Q) F is linear and W = M^-1 u is exact.
// Else chord steps from W = u with J(u)^-1: the misalignments and the
// nonlinearity move W from u by ~1e-3, so J moves by ~|K| 1e-3 and each step
// shrinks the error ~1e6 times (two steps and a third to confirm, two 3 x 3
// inverses a sample instead of Newton's four: a fifth of B1's time). Where a
// step shrinks by less than 10x, J is formed again (Newton's step); no
// convergence in kInverseSteps gives NaN: the model does not invert there.
// The iterations run on the values only; one last Newton step in T with J0 =
// J at the last iterate gives the derivatives exactly (implicit function
// theorem: dW = -J0^-1 dF), at a fraction of the cost of iterating in Jets.
// The loop stops once a step is below 1e-9 of W, leaving ~1e-15, and the
// step in T takes what is left to rounding. jacobian_inverse (optional)
// receives J0^-1 (B1's Jacobian needs it too).
constexpr int kInverseSteps = 12;  // SpecificForceFromReadings_g

template <typename T>
Vec3<T> SpecificForceFromReadings_g(const ModelConfig& cfg, const T* theta,
                                    const Vec3<T>& readings_mV, const SampleContext& ctx,
                                    Mat3<double>* jacobian_inverse = nullptr) {
  const Mat3<T> M = MisalignmentMatrix(theta);
  const Mat3<T> K = NonlinearityMatrix(theta);
  const Vec3<T> w0 = ZeroOffset_mV(cfg, theta, ctx);
  const int o_a = cfg.layout.offset(Effect::kScaleAsymmetry);
  const int o_q = cfg.layout.offset(Effect::kCrossQuadratic);
  Vec3<T> u;
  for (int i = 0; i < 3; ++i) {
    const T v = readings_mV[i] - w0[i];
    T scale = theta[kKx + i];
    if (o_a >= 0) scale += v < T(0.0) ? -theta[o_a + i] : theta[o_a + i];
    u[i] = v / scale;
  }
  Mat3<double> M0, K0;
  Vec3<double> u0;
  for (int r = 0; r < 3; ++r) {
    u0[r] = ScalarPart(u[r]);
    for (int c = 0; c < 3; ++c) {
      M0(r, c) = ScalarPart(M(r, c));
      K0(r, c) = ScalarPart(K(r, c));
    }
  }
  double q0[6] = {0, 0, 0, 0, 0, 0};
  bool quadratic = false;  // cross_quadratic present and away from zero
  if (o_q >= 0) {
    for (int c = 0; c < 6; ++c) {
      q0[c] = ScalarPart(theta[o_q + c]);
      quadratic = quadratic || q0[c] != 0.0;
    }
  }
  auto cross = [&](const Vec3<double>& W) {
    Vec3<double> q = Vec3<double>::Zero();
    if (o_q >= 0) {
      for (int i = 0; i < 3; ++i) q[i] = CrossQuadraticTerm(q0, i, W);
    }
    return q;
  };
  auto jacobian = [&](const Vec3<double>& W) {
    Mat3<double> J = M0;
    J.diagonal() += K0 * W;
    J += W.asDiagonal() * K0;
    if (o_q >= 0) {
      for (int i = 0; i < 3; ++i) J.row(i) += CrossQuadraticGradient(q0, i, W);
    }
    return J;
  };
  Mat3<double> J0_inv;
  Vec3<double> W0;
  if (!quadratic && K0.isZero(0.0)) {
    // Linear (a score analysis's cross_quadratic at zero too): exact at once.
    J0_inv = M0.inverse();
    W0 = J0_inv * u0;
  } else {
    // Chord steps from W = u with J(u)^-1, J formed again where a step
    // shrinks by less than 10x (Newton's then); J0 at the last iterate.
    W0 = u0;
    J0_inv = jacobian(W0).inverse();
    double last = std::numeric_limits<double>::infinity();
    bool converged = false;
    for (int it = 0; it < kInverseSteps && !converged; ++it) {
      const Vec3<double> F = M0 * W0 + W0.cwiseProduct(K0 * W0) + cross(W0) - u0;
      const Vec3<double> step = J0_inv * F;
      W0 -= step;
      const double size = step.cwiseAbs().maxCoeff();
      converged = size <= 1e-9 * (1.0 + W0.cwiseAbs().maxCoeff());
      if (!converged && size > 0.1 * last) J0_inv = jacobian(W0).inverse();
      last = size;
    }
    // No inverse found: the readings model does not invert here (far
    // outside a sensor's nonlinearity): not a number, which a fit refuses
    // as a step and a filter reports as its divergence.
    if (!converged) W0.setConstant(std::numeric_limits<double>::quiet_NaN());
    J0_inv = jacobian(W0).inverse();
  }
  if (jacobian_inverse) *jacobian_inverse = J0_inv;
  const Vec3<T> W = W0.template cast<T>();
  Vec3<T> F = M * W + W.cwiseProduct(K * W) - u;
  if (o_q >= 0) {
    for (int i = 0; i < 3; ++i) F[i] += CrossQuadraticTerm(theta + o_q, i, W);
  }
  const Mat3<T> J_inv = J0_inv.template cast<T>();
  return W - J_inv * F;
}

// ---------------------------------------------------------------------------
// The whole forward chain: bench angles -> predicted readings [mV].
// ---------------------------------------------------------------------------
template <typename T>
Vec3<T> PredictReadings_mV(const ModelConfig& cfg, const T* theta, const BenchAngles<T>& bench,
                           const SampleContext& ctx) {
  const BenchMotion<T> m = ComputeBenchMotion(cfg, theta, bench);
  return Readings_mV(cfg, theta, SpecificForceAtAxes_g(cfg, theta, m), ctx);
}

// ---------------------------------------------------------------------------
// The paper's two blocks, on top of the chain above.
//
// B1: readings -> acceleration of O in L (paper eq. 3):
//   a_L = C_L2 W g + g_L,   W = inverse readings model of z
// With the size effect each accelerometer senses at its own point; the
// difference of the readings at those points and at O, predicted from the
// bench kinematics, is removed first, so W is the specific force at O.
//
// B2: the reference motion of O from the angles alone:
//   S_DU = p_O_L,   V_DU = v_O_L      (MotionOfPoint at R)
// ---------------------------------------------------------------------------
template <typename T>
Vec3<T> AccelerationFromReadings_L(const ModelConfig& cfg, const T* theta,
                                   const BenchAngles<double>& recorded,
                                   const Eigen::Vector3d& readings_mV, const SampleContext& ctx) {
  const BenchAngles<T> b = BenchAnglesFromRecorded<T>(cfg, theta, recorded);
  const BenchMotion<T> m = ComputeBenchMotion(cfg, theta, b);
  Vec3<T> z = readings_mV.template cast<T>();
  if (cfg.layout.has(Effect::kSizeEffect)) {
    const Mat3<T> W_axes = SpecificForceAtAxes_g(cfg, theta, m);
    const Vec3<T> W_O = W_axes.col(0);
    z -= Readings_mV(cfg, theta, W_axes, ctx) - Readings_mV(cfg, theta, W_O, ctx);
  }
  const Vec3<T> W = SpecificForceFromReadings_g(cfg, theta, z, ctx);
  Vec3<T> a = m.C_L2 * W * T(cfg.g_mps2);
  a.x() -= T(cfg.g_mps2);
  return a;
}

template <typename T>
PointMotion<T> ReferenceMotion(const ModelConfig& cfg, const T* theta,
                               const BenchAngles<double>& recorded) {
  const BenchAngles<T> b = BenchAnglesFromRecorded<T>(cfg, theta, recorded);
  return MotionOfPoint(ComputeBenchMotion(cfg, theta, b), LeverArm_m(cfg, theta));
}

}  // namespace triadcal
