// The gyro part of the static method: Ferraris et al. (1995), as imucal
// computes it, on the positions the accelerometer's static method averaged
// (static_method.h) and on full turns of the IMU by hand. No bench: the input
// rate is known only as 0 in a still position and as one full turn, in sum,
// over a labelled turn.
//
// Readings model (gyro_model.h, SPEC section 10), reading unit r, rad/s inside:
//
//   G = A w + W0 + G_W W,      A = diag(K) Mg
//
// 1. Still positions p (w = 0, Earth's rate neglected, as Ferraris does), each
//    the mean gyro reading g_p over the accelerometer's still intervals and the
//    specific force W_p of the accelerometer's calibration (the exact inverse
//    of its readings model at the position's mean reading): per axis i the
//    weighted least squares over the positions
//      g_p,i = W0_i + sum_j G_W,ij W_p,j,     weight N_p / sigma_i^2
//    (sigma_i the declared gyro noise per sample). With the six Ferraris
//    positions W_p = +-e_j: W0 is the mean of the six, G_W's column j is
//    (g_j+ - g_j-) / 2 (Ferraris eq. 9). Four unknowns per axis on six
//    positions leave 2 degrees of freedom per axis; the reported sigma is the
//    declared one x max(1, sqrt(chi2/dof)), chi2 pooled over the axes.
// 2. Turns j (x_rot, y_rot, z_rot): the readings corrected for W0 and G_W
//    (W per sample from the accelerometer's inverse model) and integrated,
//      I_j = sum_k (g_k - W0 - G_W W_k) dt = A (integral of w) = A s_j 2 pi u_j
//    u_j the turn's axis in the IMU frame (Ferraris: the IMU axis that points
//    up, e_j) and s_j = +-1 its sense. The sense is not observable without a
//    reference (turning the other way is reversing every gyro axis); it is
//    taken so that the nominal scale (run.yaml gyro.scale) reads the turn with
//    its own sign. So A = [I_1 I_2 I_3] [s_1 u_1 s_2 u_2 s_3 u_3]^-1 / (2 pi),
//    K_i = A_ii, Mg = diag(K)^-1 A (its six angles read off the form of M).
//    Nine unknowns from nine integrals: no residual, so no sigma from the data.
//    sigma_noise is what the white noise and the uncertainty of W0 and G_W
//    propagate into I_j; the error of the turn itself (a hand turn that is not
//    exactly 360 deg about u_j) is not in it.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/model/parameters.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/static/static_method.h"

namespace triadcal {

struct GyroTurn {
  std::string label;              // the samples of the turn (run.yaml columns.label)
  Eigen::Vector3d axis_platform;  // u_j: unit, the sense is found (s_j above)
};

struct StaticGyroOptions {
  std::vector<GyroTurn> turns = {{"x_rot", Eigen::Vector3d::UnitX()},
                                 {"y_rot", Eigen::Vector3d::UnitY()},
                                 {"z_rot", Eigen::Vector3d::UnitZ()}};
  double turn_deg = 360.0;  // the angle of each turn
};

struct StaticGyroPosition {
  std::string name;
  std::size_t samples = 0;
  Eigen::Vector3d mean_rad_s = Eigen::Vector3d::Zero();      // g_p
  Eigen::Vector3d W_g = Eigen::Vector3d::Zero();             // from the accelerometer
  Eigen::Vector3d residual_rad_s = Eigen::Vector3d::Zero();  // g_p - W0 - G_W W_p
};

struct StaticGyroTurnResult {
  std::string label;
  std::size_t samples = 0;
  double duration_s = 0.0;                                 // samples x dt
  int sense = 1;                                           // s_j
  Eigen::Vector3d integral_rad = Eigen::Vector3d::Zero();  // I_j, reading unit x s (rad)
  Eigen::Vector3d mean_W_g = Eigen::Vector3d::Zero();      // mean specific force over the turn
};

struct StaticGyroResult {
  // gyro.Kx .. gyro.Gzz in the order of GyroParam, SI (gyro_model.h).
  Eigen::Matrix<double, kNumGyroParams, 1> theta;
  // 1 sigma, SI: W0 and G_W from the positions (declared x max(1, scatter));
  // NaN for K and the angles (exactly determined), whose noise-only sigma is
  // sigma_noise (0 for W0 and G_W).
  Eigen::Matrix<double, kNumGyroParams, 1> sigma;
  Eigen::Matrix<double, kNumGyroParams, 1> sigma_noise;
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();  // diag(K) Mg
  std::vector<StaticGyroPosition> positions;
  std::vector<StaticGyroTurnResult> turns;
  double chi2 = 0.0, dof = 0.0, sigma_scale = 1.0;
  std::string sigma_source;  // "declared noise" | "residual scatter"
};

// Throws InputError when the run has no gyro, fewer than four positions, or a
// turn label has no samples.
StaticGyroResult SolveStaticGyro(const RunDescription& run, const RunData& data,
                                 const StaticResult& accel, const StaticGyroOptions& options);

}  // namespace triadcal
