#include "solvers/estimation/state_space_model.h"

#include <cmath>

#include <Eigen/Cholesky>

namespace triadcal {

Mat6 ProcessStep::F() const {
  Mat6 F = Mat6::Identity();
  F.block<3, 3>(3, 0) = T_s * Eigen::Matrix3d::Identity();
  return F;
}

Mat6 WhiteningOf(const Mat6& cov) {
  const Eigen::LLT<Mat6> llt(cov);
  const Mat6 Lc = llt.matrixL();
  return Lc.triangularView<Eigen::Lower>().solve(Mat6::Identity());
}

Eigen::Vector3d StateSpaceModel::ChannelVariance(const Eigen::VectorXd& theta) const {
  Eigen::Vector3d var;
  for (int i = 0; i < 3; ++i) {
    const double s = p_.cfg.g_mps2 * p_.noise_mV[i] / std::abs(theta[kKx + i]);
    var[i] = s * s;
  }
  return var;
}

Eigen::VectorXd StateSpaceModel::Expand(const Eigen::VectorXd& theta_free) const {
  Eigen::VectorXd theta = p_.theta_held;
  for (std::size_t j = 0; j < p_.free.size(); ++j) theta[p_.free[j]] = theta_free[j];
  return theta;
}

Eigen::VectorXd StateSpaceModel::Free(const Eigen::VectorXd& theta) const {
  Eigen::VectorXd f(p_.free.size());
  for (std::size_t j = 0; j < p_.free.size(); ++j) f[j] = theta[p_.free[j]];
  return f;
}

Eigen::MatrixXd StateSpaceModel::FreeColumns(const Eigen::MatrixXd& J) const {
  if (static_cast<int>(p_.free.size()) == J.cols()) return J;
  Eigen::MatrixXd out(J.rows(), p_.free.size());
  for (std::size_t j = 0; j < p_.free.size(); ++j) out.col(j) = J.col(p_.free[j]);
  return out;
}

ProcessStep StateSpaceModel::Process(std::size_t e, const Eigen::VectorXd& theta,
                                     bool with_jacobian) const {
  const IntervalIncrement inc =
      IntegrateInterval(p_.cfg, theta, p_.series, p_.epochs[e], p_.epochs[e + 1], with_jacobian);
  ProcessStep s;
  s.T_s = inc.T_s;
  s.u << inc.dv_mps, inc.ds_m;
  if (with_jacobian) {
    Eigen::MatrixXd U(6, theta.size());
    U << inc.ddv_dtheta, inc.dds_dtheta;
    s.U = FreeColumns(U);
    for (std::size_t j = 0; j < p_.free.size(); ++j) {
      const int i = p_.free[j];
      if (i >= kKx && i <= kKz) s.scale_col[i - kKx] = static_cast<int>(j);
      if (i >= kW0x && i <= kW0z) s.zero_col[i - kW0x] = static_cast<int>(j);
    }
    for (int i = 0; i < 3; ++i) s.scale_lin[i] = theta[kKx + i];
  }
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  s.Q.block<3, 3>(0, 0) = p_.isotropic_var * inc.sum_alpha2 * I;
  s.Q.block<3, 3>(0, 3) = s.Q.block<3, 3>(3, 0) = p_.isotropic_var * inc.sum_alpha_beta * I;
  s.Q.block<3, 3>(3, 3) = p_.isotropic_var * inc.sum_beta2 * I;
  s.Q_iso = s.Q;
  s.first_channel = inc.first_channel;
  s.last_channel = inc.last_channel;
  s.first_weight = inc.first_weight;
  s.last_weight = inc.last_weight;
  const Eigen::Vector3d var = ChannelVariance(theta);
  for (int i = 0; i < 3; ++i) {
    s.channel_weight[i] = inc.channel_weight[i];
    s.channel_Q[i] = var[i] * inc.channel_weight[i];
    s.Q += s.channel_Q[i];
  }
  return s;
}

MeasurementStep StateSpaceModel::Measurement(std::size_t e, const Eigen::VectorXd& theta,
                                             bool with_jacobian, bool with_noise) const {
  const BenchAngles<double>& recorded = p_.series.recorded[p_.epochs[e]];
  const ReferenceSample ref = EvaluateReference(p_.cfg, theta, recorded, with_jacobian);
  MeasurementStep m;
  m.h << ref.v_mps, ref.p_m;
  if (with_jacobian) m.H = FreeColumns(ref.dref_dtheta);
  if (with_noise) {
    m.R = ReferenceNoiseCovariance(p_.cfg, theta, recorded, p_.sigma_angle, p_.sigma_rate);
  }
  return m;
}

Mat6 StateSpaceModel::ProcessWhitening(const ProcessStep& s, const Eigen::VectorXd& theta,
                                       std::vector<Mat6>* dL) const {
  const Eigen::Vector3d var = ChannelVariance(theta);
  Mat6 Q = s.Q_iso;
  for (int i = 0; i < 3; ++i) Q += var[i] * s.channel_weight[i];
  const Mat6 L = WhiteningOf(Q);
  if (!dL) return L;
  dL->assign(p_.free.size(), Mat6::Zero());
  for (std::size_t j = 0; j < p_.free.size(); ++j) {
    const int i = p_.free[j] - kKx;
    if (i < 0 || i > 2) continue;
    // d var_i / d K_i = -2 var_i / K_i; dL / d var_i by a central difference
    // of the 6 x 6 whitening (exact to ~1e-8 relative).
    const double h = 1e-4 * var[i];
    const Mat6 Lp = WhiteningOf(Q + h * s.channel_weight[i]);
    const Mat6 Lm = WhiteningOf(Q - h * s.channel_weight[i]);
    (*dL)[j] = (Lp - Lm) / (2.0 * h) * (-2.0 * var[i] / theta[kKx + i]);
  }
  return L;
}

Mat6 StateSpaceModel::ProcessCrossCovariance(const ProcessStep& a, const ProcessStep& b,
                                             const Eigen::VectorXd& theta) const {
  const Eigen::Vector3d var = ChannelVariance(theta);
  Mat6 C = Mat6::Zero();
  for (int i = 0; i < 3; ++i) C += var[i] * a.last_channel[i] * b.first_channel[i].transpose();
  const Eigen::Matrix2d w = a.last_weight * b.first_weight.transpose();
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  C.block<3, 3>(0, 0) += p_.isotropic_var * w(0, 0) * I;
  C.block<3, 3>(0, 3) += p_.isotropic_var * w(0, 1) * I;
  C.block<3, 3>(3, 0) += p_.isotropic_var * w(1, 0) * I;
  C.block<3, 3>(3, 3) += p_.isotropic_var * w(1, 1) * I;
  return C;
}

std::vector<Vec6> StateSpaceModel::WhitenProcessSequence(const std::vector<ProcessStep>& steps,
                                                         const std::vector<Vec6>& residuals,
                                                         const Eigen::VectorXd& theta) const {
  const Eigen::Vector3d var = ChannelVariance(theta);
  std::vector<Vec6> out(residuals.size(), Vec6::Zero());
  Mat6 S_prev = Mat6::Zero();
  Vec6 nu_prev = Vec6::Zero();
  for (std::size_t e = 0; e < residuals.size(); ++e) {
    Mat6 Q = steps[e].Q_iso;
    for (int i = 0; i < 3; ++i) Q += var[i] * steps[e].channel_weight[i];
    Mat6 S = Q;
    Vec6 nu = residuals[e];
    if (e > 0) {
      const Mat6 C = ProcessCrossCovariance(steps[e - 1], steps[e], theta);
      const Eigen::LDLT<Mat6> ldlt(S_prev);
      const Mat6 Gt = ldlt.solve(C);  // S_prev^-1 C = G^T
      S -= Gt.transpose() * C;
      nu -= Gt.transpose() * nu_prev;
    }
    out[e] = WhiteningOf(S) * nu;
    S_prev = S;
    nu_prev = nu;
  }
  return out;
}

Vec6 StateSpaceModel::PredictLinear(const ProcessStep& s, const Vec6& xa,
                                    const Eigen::VectorXd& dtheta_free) {
  Vec6 x = s.F() * xa + s.u;
  if (s.U.size() > 0 && dtheta_free.size() > 0) x += s.U * dtheta_free;
  return x;
}

Vec6 StateSpaceModel::Predict(const ProcessStep& s, const Vec6& xa,
                              const Eigen::VectorXd& dtheta_free) {
  Vec6 x = PredictLinear(s, xa, dtheta_free);
  if (s.U.size() == 0 || dtheta_free.size() == 0) return x;
  for (int i = 0; i < 3; ++i) {
    const int k = s.scale_col[i];
    if (k < 0) continue;
    const double K0 = s.scale_lin[i];
    const double dK = dtheta_free[k];
    const double f = K0 / (K0 + dK);
    x += (f - 1.0 + dK / K0) * (-K0 * s.U.col(k));
    const int z = s.zero_col[i];
    if (z >= 0) x += (f - 1.0) * dtheta_free[z] * s.U.col(z);
  }
  return x;
}

Eigen::MatrixXd StateSpaceModel::PredictThetaJacobian(const ProcessStep& s,
                                                      const Eigen::VectorXd& dtheta_free) {
  Eigen::MatrixXd J = s.U;
  if (s.U.size() == 0 || dtheta_free.size() == 0) return J;
  for (int i = 0; i < 3; ++i) {
    const int k = s.scale_col[i];
    if (k < 0) continue;
    const double K0 = s.scale_lin[i];
    const double K = K0 + dtheta_free[k];
    const double f = K0 / K;
    const double df = -K0 / (K * K);  // d f / d K
    J.col(k) += (df + 1.0 / K0) * (-K0 * s.U.col(k));
    const int z = s.zero_col[i];
    if (z >= 0) {
      J.col(k) += df * dtheta_free[z] * s.U.col(z);
      J.col(z) += (f - 1.0) * s.U.col(z);
    }
  }
  return J;
}

Vec6 StateSpaceModel::ProcessResidual(const ProcessStep& s, const Vec6& xa, const Vec6& xb,
                                      const Eigen::VectorXd& dtheta_free) {
  return xb - Predict(s, xa, dtheta_free);
}

void StateSpaceModel::ThetaRows(bool with_constraints, Eigen::MatrixXd* A,
                                Eigen::VectorXd* b) const {
  const int nf = num_free();
  // A constraint over held parameters only carries no information on the
  // free ones: it is dropped. Held terms move to the right-hand side.
  std::vector<std::pair<Eigen::VectorXd, double>> rows;  // (c_free / sigma, rhs / sigma)
  if (with_constraints) {
    for (const ConstraintRow& k : p_.constraints) {
      const Eigen::VectorXd c_free = Free(k.c);
      if (c_free.cwiseAbs().maxCoeff() == 0.0) continue;
      double rhs = k.value;
      for (int i : p_.held) rhs -= k.c[i] * p_.theta_held[i];
      rows.emplace_back(c_free / k.sigma, rhs / k.sigma);
    }
  }
  const int nc = static_cast<int>(rows.size());
  A->setZero(nf + nc, nf);
  b->resize(nf + nc);
  for (int j = 0; j < nf; ++j) {
    const int i = p_.free[j];
    (*A)(j, j) = 1.0 / p_.prior.sigma[i];
    (*b)[j] = p_.prior.mean[i] / p_.prior.sigma[i];
  }
  for (int k = 0; k < nc; ++k) {
    A->row(nf + k) = rows[k].first.transpose();
    (*b)[nf + k] = rows[k].second;
  }
}

}  // namespace triadcal
