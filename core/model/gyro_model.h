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

// Input rate [rad/s] and specific force at O [g] -> gyro readings [rad/s].
template <typename T>
Vec3<T> GyroReadings(const ModelConfig& cfg, const T* theta, const Vec3<T>& w_2,
                     const Vec3<T>& W_g) {
  const T* g = theta + cfg.layout.gyro_offset();
  const Vec3<T> m = GyroMisalignmentMatrix(g) * w_2;
  Vec3<T> out;
  for (int i = 0; i < 3; ++i) out[i] = g[kGKx + i] * m[i] + g[kGW0x + i];
  return out + GyroGSensitivity(g) * W_g;
}

// Exact inverse: gyro readings [rad/s] and W [g] -> input rate in frame 2 [rad/s].
template <typename T>
Vec3<T> GyroRateFromReadings(const ModelConfig& cfg, const T* theta, const Vec3<T>& readings,
                             const Vec3<T>& W_g) {
  const T* g = theta + cfg.layout.gyro_offset();
  Vec3<T> u = readings - GyroGSensitivity(g) * W_g;
  for (int i = 0; i < 3; ++i) u[i] = (u[i] - g[kGW0x + i]) / g[kGKx + i];
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
