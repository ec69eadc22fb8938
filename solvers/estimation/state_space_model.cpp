#include "solvers/estimation/state_space_model.h"

#include <cmath>

#include <Eigen/Cholesky>

namespace triadcal {

Mat6 ProcessStep::F() const {
  Mat6 F = Mat6::Identity();
  F.block<3, 3>(3, 0) = T_s * Eigen::Matrix3d::Identity();
  return F;
}

StateSpaceModel::StateSpaceModel(const RunProblem& problem)
    : StateSpaceModel(problem, problem.noise_mV) {}

StateSpaceModel::StateSpaceModel(const RunProblem& problem, const Eigen::Vector3d& noise_mV)
    : p_(problem), noise_mV_(noise_mV), acc_cfg_(problem.cfg) {
  if (acc_cfg_.layout.has_gyro()) acc_cfg_.layout = acc_cfg_.layout.WithGyro(false);
  n_acc_ = acc_cfg_.layout.size();
}

Eigen::MatrixXd StateSpaceModel::Widen(const Eigen::MatrixXd& J) const {
  if (J.cols() == p_.n) return J;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(J.rows(), p_.n);
  out.leftCols(J.cols()) = J;
  return out;
}

Mat6 LowerInverse(const Mat6& L) {
  // Forward substitution, column by column, written out: Eigen's triangular
  // solve takes its general (blocked, run-time sized) path for 6 x 6, which
  // cost more than the substitution itself (a fifth of a reduction).
  double inv_diag[6];
  for (int r = 0; r < 6; ++r) inv_diag[r] = 1.0 / L(r, r);
  Mat6 W = Mat6::Zero();
  for (int c = 0; c < 6; ++c) {
    W(c, c) = inv_diag[c];
    for (int r = c + 1; r < 6; ++r) {
      double sum = 0.0;
      for (int k = c; k < r; ++k) sum += L(r, k) * W(k, c);
      W(r, c) = -sum * inv_diag[r];
    }
  }
  return W;
}

Mat6 WhiteningOf(const Mat6& cov, double* half_log_det) {
  const Eigen::LLT<Mat6> llt(cov);
  const Mat6& Lc = llt.matrixLLT();  // its lower triangle is chol(cov)
  if (half_log_det) *half_log_det = Lc.diagonal().array().log().sum();
  return LowerInverse(Lc);
}

Eigen::Vector3d StateSpaceModel::ChannelVariance(const Eigen::VectorXd& theta) const {
  Eigen::Vector3d var;
  for (int i = 0; i < 3; ++i) {
    const double s = p_.cfg.g_mps2 * noise_mV_[i] / std::abs(theta[kKx + i]);
    var[i] = s * s;
  }
  return var;
}

Eigen::VectorXd StateSpaceModel::Expand(const Eigen::VectorXd& theta_free) const {
  Eigen::VectorXd theta = p_.theta_held;
  for (std::size_t j = 0; j < p_.free.size(); ++j) theta[p_.free[j]] = theta_free[j];
  return theta;
}

Eigen::MatrixXd StateSpaceModel::ExpandCovariance(const Eigen::MatrixXd& cov_free) const {
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(p_.n, p_.n);
  for (std::size_t a = 0; a < p_.free.size(); ++a)
    for (std::size_t b = 0; b < p_.free.size(); ++b) cov(p_.free[a], p_.free[b]) = cov_free(a, b);
  return cov;
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
                                     bool with_jacobian, bool with_noise, bool with_values) const {
  const Eigen::VectorXd theta_acc = theta.head(n_acc_);
  const IntervalIncrement inc =
      IntegrateInterval(acc_cfg_, theta_acc, p_.series, p_.epochs[e], p_.epochs[e + 1],
                        with_jacobian, with_noise, with_values);
  ProcessStep s;
  s.T_s = inc.T_s;
  s.u << inc.dv_mps, inc.ds_m;
  if (with_jacobian) {
    Eigen::MatrixXd U(6, n_acc_);
    U << inc.ddv_dtheta, inc.dds_dtheta;
    s.U = FreeColumns(Widen(U));
  }
  if (!with_noise) return s;
  auto noise = std::make_shared<ProcessNoise>();
  ProcessNoise& q = *noise;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  q.Q.block<3, 3>(0, 0) = p_.isotropic_var * inc.sum_alpha2 * I;
  q.Q.block<3, 3>(0, 3) = q.Q.block<3, 3>(3, 0) = p_.isotropic_var * inc.sum_alpha_beta * I;
  q.Q.block<3, 3>(3, 3) = p_.isotropic_var * inc.sum_beta2 * I;
  q.Q_iso = q.Q;
  q.first_channel = inc.first_channel;
  q.last_channel = inc.last_channel;
  q.first_weight = inc.first_weight;
  q.last_weight = inc.last_weight;
  const Eigen::Vector3d var = ChannelVariance(theta);
  for (int i = 0; i < 3; ++i) {
    q.channel_weight[i] = inc.channel_weight[i];
    q.Q += var[i] * inc.channel_weight[i];
  }
  s.noise = std::move(noise);
  return s;
}

MeasurementStep StateSpaceModel::Measurement(std::size_t e, const Eigen::VectorXd& theta,
                                             bool with_jacobian, bool with_noise) const {
  const BenchAngles<double> recorded = p_.series.Recorded(p_.epochs[e]);
  const Eigen::VectorXd theta_acc = theta.head(n_acc_);
  const ReferenceSample ref = EvaluateReference(acc_cfg_, theta_acc, recorded, with_jacobian);
  MeasurementStep m;
  m.h << ref.v_mps, ref.p_m;
  if (with_jacobian) m.H = FreeColumns(Widen(ref.dref_dtheta));
  if (with_noise) {
    m.R = ReferenceNoiseCovariance(acc_cfg_, theta_acc, recorded, p_.sigma_angle, p_.sigma_rate);
  }
  return m;
}

Mat6 StateSpaceModel::ProcessCrossCovariance(const ProcessStep& a, const ProcessStep& b,
                                             const Eigen::VectorXd& theta) const {
  const Eigen::Vector3d var = ChannelVariance(theta);
  Mat6 C = Mat6::Zero();
  const ProcessNoise& qa = *a.noise;
  const ProcessNoise& qb = *b.noise;
  for (int i = 0; i < 3; ++i) C += var[i] * qa.last_channel[i] * qb.first_channel[i].transpose();
  const Eigen::Matrix2d w = qa.last_weight * qb.first_weight.transpose();
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
    const ProcessNoise& q = *steps[e].noise;
    Mat6 Q = q.Q_iso;
    for (int i = 0; i < 3; ++i) Q += var[i] * q.channel_weight[i];
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
