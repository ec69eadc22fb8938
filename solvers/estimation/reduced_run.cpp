#include "solvers/estimation/reduced_run.h"

#include "solvers/estimation/batch_costs.h"
#include "solvers/estimation/batch_linearization.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/schur_covariance.h"
#include "solvers/estimation/state_space_model.h"

namespace triadcal {

ReducedRun ReduceRun(const RunProblem& p, const Eigen::VectorXd& theta, int threads,
                     bool with_states) {
  if (threads <= 0) threads = DefaultThreads();
  const StateSpaceModel model(p);
  const std::size_t E = p.epochs.size();
  const int nf = model.num_free();
  const BatchLinearization lin = Linearize(p, theta, true, threads);
  const Eigen::VectorXd theta_free = model.Free(theta);
  std::vector<ProcessBlock> pb(E - 1);
  std::vector<MeasurementBlock> mb(E);
  // About the reference motion of B2 rather than x = 0: the cost is then
  // formed from small residuals (at x = 0 it would be the difference of two
  // numbers ~1e10 times larger, losing digits).
  std::vector<Vec6> x_ref(E);
  ParallelFor(E, threads, [&](std::size_t e) {
    x_ref[e] = model.Measurement(e, theta, false, false).h;
  });
  ParallelFor(E, threads, [&](std::size_t e) {
    using RowJ6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
    using RowJ = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor>;
    if (e + 1 < E) {
      const ProcessCost cost(&lin.process[e], &lin.theta_lin_free, &model, false, e);
      RowJ6 A, B;
      RowJ C(6, nf);
      const double* params[3] = {x_ref[e].data(), x_ref[e + 1].data(), theta_free.data()};
      double* jac[3] = {A.data(), B.data(), C.data()};
      cost.Evaluate(params, pb[e].r0.data(), jac);
      pb[e].A = A;
      pb[e].B = B;
      pb[e].C = C;
    }
    const MeasurementCost cost(&model, e, lin.LR[e]);
    RowJ6 M;
    RowJ N(6, nf);
    const double* params[2] = {x_ref[e].data(), theta_free.data()};
    double* jac[2] = {M.data(), N.data()};
    cost.Evaluate(params, mb[e].r0.data(), jac);
    mb[e].M = M;
    mb[e].N = N;
  });
  ReducedOverStates red = ReduceOverStates(pb, mb, true);
  // The residuals at the optimal states, formed directly: cost and gradient
  // J_theta^T r without the cancellation of the elimination's own.
  ReducedRun out;
  out.gradient = Eigen::VectorXd::Zero(nf);
  for (std::size_t e = 0; e < E; ++e) {
    const Vec6 rm = mb[e].r0 + mb[e].M * red.states[e];
    out.cost += 0.5 * rm.squaredNorm();
    out.gradient.noalias() += mb[e].N.transpose() * rm;
    if (e + 1 < E) {
      const Vec6 rp = pb[e].r0 + pb[e].A * red.states[e] + pb[e].B * red.states[e + 1];
      out.cost += 0.5 * rp.squaredNorm();
      out.gradient.noalias() += pb[e].C.transpose() * rp;
    }
  }
  out.information = std::move(red.information);
  if (with_states) {
    out.states.resize(E);
    for (std::size_t e = 0; e < E; ++e) out.states[e] = x_ref[e] + red.states[e];
  }
  out.degrees_of_freedom = static_cast<int>(6 * (E - 1));
  return out;
}

}  // namespace triadcal
