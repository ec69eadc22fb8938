#include "solvers/estimation/batch_linearization.h"

#include <algorithm>

#include "solvers/estimation/parallel.h"
#include "solvers/estimation/schur_covariance.h"

namespace triadcal {

BatchLinearization Linearize(const RunProblem& p, const Eigen::VectorXd& theta,
                             bool with_jacobian, int threads) {
  const StateSpaceModel model(p);
  const std::size_t E = p.epochs.size();
  BatchLinearization lin;
  lin.theta_lin = theta;
  lin.theta_lin_free = model.Free(theta);
  lin.process.resize(E - 1);
  lin.LQ.resize(E - 1);
  lin.LR.resize(E);
  ParallelFor(E - 1, threads, [&](std::size_t e) {
    lin.process[e] = model.Process(e, theta, with_jacobian);
    lin.LQ[e] = WhiteningOf(lin.process[e].Q);
  });
  ParallelFor(E, threads, [&](std::size_t e) {
    lin.LR[e] = WhiteningOf(model.Measurement(e, theta, false, true).R);
  });
  return lin;
}

void ThetaRows(const RunProblem& p, bool with_constraints, Eigen::MatrixXd* A,
               Eigen::VectorXd* b) {
  StateSpaceModel(p).ThetaRows(with_constraints, A, b);
}

void SchurBlocks(const RunProblem& p, const BatchLinearization& lin, const Eigen::VectorXd& theta,
                 int threads, const std::vector<Eigen::MatrixXd>* process_theta_jacobians,
                 std::vector<ProcessBlock>* pb, std::vector<MeasurementBlock>* mb) {
  const StateSpaceModel model(p);
  const std::size_t E = p.epochs.size();
  pb->assign(E - 1, ProcessBlock{});
  mb->assign(E, MeasurementBlock{});
  ParallelFor(E, threads, [&](std::size_t e) {
    if (e + 1 < E) {
      const ProcessStep& s = lin.process[e];
      (*pb)[e].A = lin.LQ[e] * StateSpaceModel::ProcessJacobianXa(s);
      (*pb)[e].B = lin.LQ[e];
      (*pb)[e].C = process_theta_jacobians ? (*process_theta_jacobians)[e]
                                           : Eigen::MatrixXd(-lin.LQ[e] * s.U);
    }
    const MeasurementStep m = model.Measurement(e, theta, true, false);
    (*mb)[e].M = lin.LR[e];
    (*mb)[e].N = -lin.LR[e] * m.H;
  });
}

Eigen::MatrixXd ThetaCovariance(const RunProblem& p, const BatchLinearization& lin,
                                const Eigen::VectorXd& theta, const Eigen::MatrixXd& A,
                                int threads,
                                const std::vector<Eigen::MatrixXd>* process_theta_jacobians) {
  std::vector<ProcessBlock> pb;
  std::vector<MeasurementBlock> mb;
  SchurBlocks(p, lin, theta, threads, process_theta_jacobians, &pb, &mb);
  return ThetaCovarianceBySchur(pb, mb, A);
}

Eigen::MatrixXd ExpandCovariance(const RunProblem& p, const Eigen::MatrixXd& cov_free) {
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(p.n, p.n);
  for (std::size_t a = 0; a < p.free.size(); ++a)
    for (std::size_t b = 0; b < p.free.size(); ++b) cov(p.free[a], p.free[b]) = cov_free(a, b);
  return cov;
}

std::array<std::vector<double>, 6> ExpectedProcessAutocorrelation(
    const std::vector<Eigen::MatrixXd>& C, const Eigen::MatrixXd& cov_free, int lags) {
  std::array<std::vector<double>, 6> rho;
  const std::size_t T = C.size();
  if (T == 0 || cov_free.rows() == 0) return rho;
  for (int c = 0; c < 6; ++c) {
    std::vector<Eigen::VectorXd> a(T);  // cov j_t
    double trace_rest = 0.0;
    for (std::size_t t = 0; t < T; ++t) {
      a[t] = cov_free * C[t].row(c).transpose();
      trace_rest += 1.0 - C[t].row(c).dot(a[t]);
    }
    rho[c].assign(lags, 0.0);
    // When the fit takes most of a channel's residual (few epochs for the
    // parameters: a 10-s run has 20), its share is not a small correction
    // and the ratio below is unstable (it reached -200): nothing is
    // subtracted then.
    if (trace_rest < 0.5 * static_cast<double>(T)) continue;
    for (int k = 1; k <= lags && static_cast<std::size_t>(k) < T; ++k) {
      double h = 0.0;
      for (std::size_t t = 0; t + k < T; ++t) h += C[t + k].row(c).dot(a[t]);
      rho[c][k - 1] = std::clamp(-h / trace_rest, -1.0, 1.0);
    }
  }
  return rho;
}

}  // namespace triadcal
