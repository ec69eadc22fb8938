#include "solvers/estimation/batch_linearization.h"

#include "solvers/estimation/parallel.h"
#include "solvers/estimation/schur_covariance.h"

namespace triadcal {

BatchLinearization Linearize(const RunProblem& p, const Eigen::VectorXd& theta,
                             bool with_jacobian, int threads) {
  const std::size_t E = p.epochs.size();
  BatchLinearization lin;
  lin.theta_lin = theta;
  lin.increments.resize(E - 1);
  lin.LQ.resize(E - 1);
  lin.LR.resize(E);
  ParallelFor(E - 1, threads, [&](std::size_t e) {
    lin.increments[e] =
        IntegrateInterval(p.cfg, theta, p.series, p.epochs[e], p.epochs[e + 1], with_jacobian);
    const IntervalIncrement& inc = lin.increments[e];
    Mat6 Q = Mat6::Zero();
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    Q.block<3, 3>(0, 0) = p.accel_var * inc.sum_alpha2 * I;
    Q.block<3, 3>(0, 3) = Q.block<3, 3>(3, 0) = p.accel_var * inc.sum_alpha_beta * I;
    Q.block<3, 3>(3, 3) = p.accel_var * inc.sum_beta2 * I;
    lin.LQ[e] = WhiteningOf(Q);
  });
  ParallelFor(E, threads, [&](std::size_t e) {
    lin.LR[e] = WhiteningOf(ReferenceNoiseCovariance(p.cfg, theta, p.series.recorded[p.epochs[e]],
                                                     p.sigma_angle, p.sigma_rate));
  });
  return lin;
}

void ThetaRows(const RunProblem& p, bool with_constraints, Eigen::MatrixXd* A,
               Eigen::VectorXd* b) {
  const int n = p.n;
  const int nc = with_constraints ? static_cast<int>(p.constraints.size()) : 0;
  A->setZero(n + nc, n);
  b->resize(n + nc);
  for (int i = 0; i < n; ++i) {
    (*A)(i, i) = 1.0 / p.prior.sigma[i];
    (*b)[i] = p.prior.mean[i] / p.prior.sigma[i];
  }
  for (int j = 0; j < nc; ++j) {
    A->row(n + j) = p.constraints[j].c.transpose() / p.constraints[j].sigma;
    (*b)[n + j] = p.constraints[j].value / p.constraints[j].sigma;
  }
}

Eigen::MatrixXd ThetaCovariance(const RunProblem& p, const BatchLinearization& lin,
                                const Eigen::VectorXd& theta, const Eigen::MatrixXd& A,
                                int threads) {
  const std::size_t E = p.epochs.size();
  const int n = p.n;
  std::vector<ProcessBlock> pb(E - 1);
  std::vector<MeasurementBlock> mb(E);
  ParallelFor(E, threads, [&](std::size_t e) {
    if (e + 1 < E) {
      const IntervalIncrement& inc = lin.increments[e];
      Mat6 D = -Mat6::Identity();
      D.block<3, 3>(3, 0) = -inc.T_s * Eigen::Matrix3d::Identity();
      pb[e].A = lin.LQ[e] * D;
      pb[e].B = lin.LQ[e];
      Eigen::MatrixXd J(6, n);
      J << inc.ddv_dtheta, inc.dds_dtheta;
      pb[e].C = -lin.LQ[e] * J;
    }
    const ReferenceSample ref = EvaluateReference(p.cfg, theta, p.series.recorded[p.epochs[e]], true);
    mb[e].M = lin.LR[e];
    mb[e].N = -lin.LR[e] * ref.dref_dtheta;
  });
  return ThetaCovarianceBySchur(pb, mb, A);
}

}  // namespace triadcal
