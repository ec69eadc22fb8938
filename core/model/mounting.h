// The IMU's mounting on the platform (run.yaml `mounting`) as a map of the
// parameters: a calibration in the IMU's own axes (the axes of the readings
// columns) -> the same triad described in the platform's axes, in which a
// run's readings and its fit live.
//
// With P the signed permutation of the mounting (platform reading i = s_i
// times IMU reading src_i, so the specific force in IMU axes is P^T W_p):
//   K_p = |P| K,   W0_p = P W0,   M_p = P M P^T,   K_ij,p = |P| K_ij P^T,
// and the per-axis sensor-stage effects as W0 (the sign follows the
// reading); the gyro block (SPEC section 10: one IMU, one set of axes) as
// gyro.K_p = |P| gyro.K, gyro.W0_p = P gyro.W0, Mg_p = P Mg P^T, G_p = P G P^T. Exact: Readings_mV(map theta, W_p) = P Readings_mV(theta, P^T W_p)
// (joint_solver_test.cpp MountingMap.*). P is orthogonal and the map a signed
// permutation of the parameters, so its transpose is its inverse.
#pragma once

#include <Eigen/Core>

#include "core/model/parameters.h"
#include "core/model/run_description.h"

namespace triadcal {

// n x n for the layout: identity on everything that is not a triad parameter
// or a sensor-stage effect. Throws InputError naming the effect when a
// sensor-stage effect has no per-axis form.
Eigen::MatrixXd MountingMap(const RunDescription& run, const ParameterLayout& layout);

// True for the 21 triad parameters, the sensor- and gyro-stage effects and the gyro
// block: what belongs to the IMU rather than to the bench or the set-up.
bool IsTriadParameter(const ParameterLayout& layout, int index);

}  // namespace triadcal
