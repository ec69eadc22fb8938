#include "core/model/mounting.h"

#include "core/model/bench_model.h"
#include "core/model/errors.h"

namespace triadcal {
namespace {

using M3 = Eigen::Matrix3d;

// The misalignment angles (alpha_x, alpha_y, beta_x, beta_z, gamma_y, gamma_z)
// as the off-diagonal part of M (bench_model.h MisalignmentMatrix).
M3 AnglesToOffDiagonal(const Eigen::Matrix<double, 6, 1>& a) {
  M3 m = M3::Zero();
  m(1, 0) = a[0];
  m(0, 1) = -a[1];
  m(2, 0) = -a[2];
  m(0, 2) = a[3];
  m(2, 1) = a[4];
  m(1, 2) = -a[5];
  return m;
}

Eigen::Matrix<double, 6, 1> OffDiagonalToAngles(const M3& m) {
  Eigen::Matrix<double, 6, 1> a;
  a << m(1, 0), -m(0, 1), -m(2, 0), m(0, 2), m(2, 1), -m(1, 2);
  return a;
}

M3 SignedPermutation(const RunDescription& run) {
  M3 P = M3::Zero();
  for (int i = 0; i < 3; ++i) P(i, run.axis_source[i]) = run.axis_sign[i];
  return P;
}

}  // namespace

Eigen::MatrixXd MountingMap(const RunDescription& run, const ParameterLayout& layout) {
  const int n = layout.size();
  Eigen::MatrixXd T = Eigen::MatrixXd::Identity(n, n);
  bool identity = true;
  for (int i = 0; i < 3; ++i) identity = identity && run.axis_source[i] == i && run.axis_sign[i] == 1.0;
  if (identity) return T;
  const M3 P = SignedPermutation(run);
  const M3 Pabs = P.cwiseAbs();
  T.block<3, 3>(kKx, kKx) = Pabs;
  T.block<3, 3>(kW0x, kW0x) = P;
  for (int a = 0; a < 6; ++a) {
    Eigen::Matrix<double, 6, 1> unit = Eigen::Matrix<double, 6, 1>::Zero();
    unit[a] = 1.0;
    T.block<6, 1>(kAlphaX, kAlphaX + a) =
        OffDiagonalToAngles(P * AnglesToOffDiagonal(unit) * P.transpose());
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const M3 Kp = Pabs.col(r) * P.col(c).transpose();
      for (int i = 0; i < 9; ++i) T(kKxx + i, kKxx + 3 * r + c) = Kp(i / 3, i % 3);
    }
  }
  for (Effect e : layout.effects()) {
    const EffectSpec& spec = GetEffectSpec(e);
    if (spec.stage == EffectStage::kGyro) {
      // Platform reading i = s_i x IMU reading a with m_i = s_i m_a: s_i (K m_a +
      // dK |m_a|) = K m_i + s_i dK |m_i|, and K m (1 + k2 m^2) keeps k2.
      const int o = layout.offset(e);
      T.block<3, 3>(o, o) = e == Effect::kGyroNonlinearity ? Pabs : P;
      continue;
    }
    if (spec.stage != EffectStage::kSensor) continue;
    if (e == Effect::kCrossQuadratic) {
      // Platform reading i is s_i times IMU reading a = source(i); IMU a's
      // cross axes (j', k') are platform i's cross axes, possibly in the
      // other order (then W_j^2 - W_k^2 changes sign), each with its sign.
      const int o = layout.offset(e);
      T.block<6, 6>(o, o).setZero();
      int platform_of[3];
      for (int i = 0; i < 3; ++i) platform_of[run.axis_source[i]] = i;
      for (int i = 0; i < 3; ++i) {
        const int a = run.axis_source[i];
        const int j = platform_of[kCrossAxes[a][0]], k = platform_of[kCrossAxes[a][1]];
        const double s = run.axis_sign[i];
        T(o + 2 * i, o + 2 * a) = j < k ? s : -s;
        T(o + 2 * i + 1, o + 2 * a + 1) = s * run.axis_sign[j] * run.axis_sign[k];
      }
      continue;
    }
    if (spec.params.size() != 3) {
      throw InputError(run.yaml_path + ": mounting: the effect " + spec.name +
                       " has no per-axis form to carry through a mounting");
    }
    const int o = layout.offset(e);
    T.block<3, 3>(o, o) = P;
  }
  if (layout.has_gyro()) {
    // The gyro shares the IMU's axes (SPEC section 10): its readings and its
    // input rate turn as the accelerometer's, so K, W0 and Mg map as theirs,
    // and the g-sensitivity, linear in both, as G_p = P G P^T.
    const int g = layout.gyro_offset();
    T.block<3, 3>(g + kGKx, g + kGKx) = Pabs;
    T.block<3, 3>(g + kGW0x, g + kGW0x) = P;
    T.block<6, 6>(g + kGAlphaX, g + kGAlphaX) = T.block<6, 6>(kAlphaX, kAlphaX);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const M3 Gp = P.col(r) * P.col(c).transpose();
        for (int i = 0; i < 9; ++i) T(g + kGGxx + i, g + kGGxx + 3 * r + c) = Gp(i / 3, i % 3);
      }
    }
  }
  return T;
}

bool IsTriadParameter(const ParameterLayout& layout, int i) {
  if (i < kDpsi) return true;
  if (i < kNumBaseParams) return false;
  if (layout.is_gyro(i)) return true;
  if (!layout.info(i).effect) return false;
  const EffectStage s = GetEffectSpec(*layout.info(i).effect).stage;
  return s == EffectStage::kSensor || s == EffectStage::kGyro;
}

}  // namespace triadcal
