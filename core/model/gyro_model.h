// The gyro triad's physics (SPEC section 10), written once beside the
// accelerometer's (bench_model.h) and templated the same way: the input rate
// of frame 2 from the bench angles, the readings model and its exact inverse.
// The simulator writes gx gy gz with GyroReadings; the estimators compare the
// gyro, corrected by GyroRateFromReadings, with the angle sensors
// (solvers/estimation/gyro_term.h).
//
// Input rate, frame 2 relative to L, in frame 2 [rad/s]:
//
//   w_2 = Rx(l2 + dlambda2)^T (0, l1', 0)^T + (l2', 0, 0)^T  [+ C_L2^T Omega_L]
//
// Omega_L, Earth's rate in L, only when the run gives the bench's latitude phi
// and heading h (the azimuth of L's y axis, the outer bench axis, from north
// towards east; z = x cross y): Omega_L = Omega_E (sin phi, cos phi cos h,
// cos phi sin h).
//
// Readings, in the reading unit (rad/s inside; deg/s in files):
//
//   G_i = K_i (Mg w_2)_i + W0_i + sum_j G_ij W_j
//
// Mg has the form of the accelerometer's M with the gyro's six angles, W the
// specific force at O in g (bench_model.h). Inverse (exact: linear in w):
//
//   w_2 = Mg^-1 diag(K)^-1 (G - W0 - G W)
//
// The gyro-stage effects (effects.h) change the per-axis response to m = Mg w:
//
//   G_i = f_i(m_i) + W0_i + sum_j G_ij W_j,
//   f_i(m) = K_i m (1 + k2_i m^2) + dK_i |m|
//
// (dK_i: gyro_scale_asymmetry, k2_i: gyro_nonlinearity, each 0 when off).
// Inverse per axis, u_i = G_i - W0_i - (G W)_i: m takes the sign s of u / K
// (f is monotonic while |dK| < |K|), and without k2 m = u / (K + s dK) exactly;
// with k2, Newton's steps on K m + K k2 m^3 + s dK m = u from that start (k2 m^2
// below 0.1 on any plausible gyro: the error squares each step, rounding after
// 5, GyroAxisRate takes 6). Then w_2 = Mg^-1 m.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>

#include "core/model/bench_model.h"
#include "core/model/parameters.h"
#include "core/model/rotations.h"

namespace triadcal {

constexpr double kEarthRate_rad_s = 7.2921150e-5;

// Earth's rate in L for a bench at latitude phi with its outer axis (L's y)
// at azimuth h from north towards east [rad/s].
inline Eigen::Vector3d EarthRateInL(double latitude_rad, double heading_rad) {
  const double c = std::cos(latitude_rad);
  return kEarthRate_rad_s * Eigen::Vector3d(std::sin(latitude_rad), c * std::cos(heading_rad),
                                            c * std::sin(heading_rad));
}

// The gyro's misalignment matrix Mg (the accelerometer's form, bench_model.h).
template <typename T>
Mat3<T> GyroMisalignmentMatrix(const T* g) {
  Mat3<T> M;
  M << T(1.0), -g[kGAlphaY], g[kGBetaZ],  //
      g[kGAlphaX], T(1.0), -g[kGGammaZ],  //
      -g[kGBetaX], g[kGGammaY], T(1.0);
  return M;
}

template <typename T>
Mat3<T> GyroGSensitivity(const T* g) {
  return Eigen::Map<const Eigen::Matrix<T, 3, 3, Eigen::RowMajor>>(g + kGGxx);
}

// The angular rate of frame 2 relative to L, in frame 2 [rad/s] (above), with
// Earth's rate when cfg carries it (C_L2 from the bench motion).
template <typename T>
Vec3<T> GyroInputRate_2(const ModelConfig& cfg, const T* theta, const BenchAngles<T>& b,
                        const Mat3<T>& C_L2) {
  const T l2 = b.axis[1].angle + theta[kDlambda2];
  Vec3<T> w = Rx<T>(l2).transpose() * Vec3<T>(T(0.0), b.axis[0].rate, T(0.0));
  w.x() += b.axis[1].rate;
  if (!cfg.earth_rate_L.isZero()) w += C_L2.transpose() * cfg.earth_rate_L.template cast<T>();
  return w;
}

// Axis i's response coefficients: K_i, the effects' dK_i and k2_i (0 when off).
template <typename T>
struct GyroAxisResponse {
  T K, dK, k2;
  bool nonlinear;  // gyro_nonlinearity is on (k2 may be 0 and still be differentiated)
};
template <typename T>
GyroAxisResponse<T> GyroAxis(const ParameterLayout& layout, const T* theta, int i) {
  const int o_a = layout.offset(Effect::kGyroScaleAsymmetry);
  const int o_q = layout.offset(Effect::kGyroNonlinearity);
  return {theta[layout.gyro_offset() + kGKx + i], o_a >= 0 ? theta[o_a + i] : T(0.0),
          o_q >= 0 ? theta[o_q + i] : T(0.0), o_q >= 0};
}

// f_i(m) above, without bias and g-sensitivity.
template <typename T>
T GyroAxisReading(const GyroAxisResponse<T>& a, const T& m) {
  using std::abs;
  return a.K * m * (T(1.0) + a.k2 * m * m) + a.dK * abs(m);
}

// Its inverse: u -> m (exact without k2; Newton's steps to rounding with it).
template <typename T>
T GyroAxisRate(const GyroAxisResponse<T>& a, const T& u) {
  const T s = (u < T(0.0)) != (a.K < T(0.0)) ? T(-1.0) : T(1.0);  // m's sign
  const T lin = a.K + s * a.dK;  // the scale on u's side
  T m = u / lin;
  if (!a.nonlinear) return m;
  for (int step = 0; step < 6; ++step) {
    const T Kk2 = a.K * a.k2;
    m -= (lin * m + Kk2 * m * m * m - u) / (lin + T(3.0) * Kk2 * m * m);
  }
  return m;
}

// Input rate [rad/s] and specific force at O [g] -> gyro readings [rad/s].
template <typename T>
Vec3<T> GyroReadings(const ModelConfig& cfg, const T* theta, const Vec3<T>& w_2,
                     const Vec3<T>& W_g) {
  const T* g = theta + cfg.layout.gyro_offset();
  const Vec3<T> m = GyroMisalignmentMatrix(g) * w_2;
  Vec3<T> out;
  for (int i = 0; i < 3; ++i) {
    out[i] = GyroAxisReading(GyroAxis(cfg.layout, theta, i), m[i]) + g[kGW0x + i];
  }
  return out + GyroGSensitivity(g) * W_g;
}

// Its inverse (exact, or to rounding with gyro_nonlinearity): gyro readings
// [rad/s] and W [g] -> input rate in frame 2 [rad/s].
template <typename T>
Vec3<T> GyroRateFromReadings(const ModelConfig& cfg, const T* theta, const Vec3<T>& readings,
                             const Vec3<T>& W_g) {
  const T* g = theta + cfg.layout.gyro_offset();
  Vec3<T> u = readings - GyroGSensitivity(g) * W_g;
  for (int i = 0; i < 3; ++i) u[i] = GyroAxisRate(GyroAxis(cfg.layout, theta, i), u[i] - g[kGW0x + i]);
  return GyroMisalignmentMatrix(g).inverse() * u;
}

// The whole forward chain: bench angles -> gyro readings [rad/s], with W at O.
template <typename T>
Vec3<T> PredictGyroReadings(const ModelConfig& cfg, const T* theta, const BenchAngles<T>& bench) {
  const BenchMotion<T> m = ComputeBenchMotion(cfg, theta, bench);
  const Vec3<T> W = SpecificForce_g(cfg, m.C_L2, MotionOfPoint(m, LeverArm_m(cfg, theta)).a_L);
  return GyroReadings(cfg, theta, GyroInputRate_2(cfg, theta, bench, m.C_L2), W);
}

}  // namespace triadcal
