#include "core/model/b1_jacobian.h"

#include <Eigen/LU>

namespace triadcal {

bool B1HasAnalyticJacobian(const ParameterLayout& layout) {
  for (Effect e : layout.effects()) {
    if (!GetEffectSpec(e).b1_analytic_jacobian) return false;
  }
  return true;
}

void AccelerationWithJacobian(const ModelConfig& cfg, const double* th,
                              const BenchAngles<double>& rec, const Eigen::Vector3d& z,
                              const SampleContext& ctx, Eigen::Vector3d* a_out,
                              Eigen::Ref<Eigen::MatrixXd> J) {
  const double g = cfg.g_mps2;
  const Mat3<double> Rzp = Rz(th[kDpsi]);
  const Mat3<double> Ryp = Ry(rec.axis[0].angle + th[kDthetaC]);
  const Mat3<double> Rxp = Rx(rec.axis[1].angle + th[kDlambda2]);
  const Mat3<double> C = Rzp * Ryp * Rxp;

  const Vec3<double> W = SpecificForceFromReadings_g(cfg, th, Vec3<double>(z), ctx);
  const Mat3<double> M = MisalignmentMatrix(th);
  const Mat3<double> K = NonlinearityMatrix(th);
  const Vec3<double> w0 = ZeroOffset_mV(cfg, th, ctx);
  Vec3<double> u, Ks;
  for (int i = 0; i < 3; ++i) {
    Ks[i] = th[kKx + i];
    u[i] = (z[i] - w0[i]) / Ks[i];
  }
  Mat3<double> Jf = M;
  Jf.diagonal() += K * W;
  Jf += W.asDiagonal() * K;
  // gC J^-1: each column of dF/dtheta maps to da by -gC J^-1.
  const Mat3<double> T = -g * C * Jf.inverse();

  const Vec3<double> CW = C * W;
  *a_out = g * CW;
  (*a_out).x() -= g;

  J.setZero();
  J.col(kDpsi) = g * Vec3<double>::UnitZ().cross(CW);
  J.col(kDthetaC) = g * Rzp * Vec3<double>::UnitY().cross(Ryp * Rxp * W);
  J.col(kDlambda2) = g * C * Vec3<double>::UnitX().cross(W);
  for (int i = 0; i < 3; ++i) {
    J.col(kKx + i) = T.col(i) * (u[i] / Ks[i]);
    J.col(kW0x + i) = T.col(i) * (1.0 / Ks[i]);
  }
  J.col(kAlphaX) = T.col(1) * W.x();
  J.col(kAlphaY) = -T.col(0) * W.y();
  J.col(kBetaX) = -T.col(2) * W.x();
  J.col(kBetaZ) = T.col(0) * W.z();
  J.col(kGammaY) = T.col(2) * W.y();
  J.col(kGammaZ) = -T.col(1) * W.z();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) J.col(kKxx + 3 * i + j) = T.col(i) * (W[i] * W[j]);
  }
  // Zero-offset effects (catalogue): dF/d theta_e,i = x_e / K_i e_i.
  for (const ParameterLayout::ZeroOffsetTerm& term : cfg.layout.zero_offset_terms()) {
    const double x = ZeroOffsetSignalValue(cfg, term.signal, ctx);
    for (int i = 0; i < 3; ++i) J.col(term.offset + i) = T.col(i) * (x / Ks[i]);
  }
}

}  // namespace triadcal
