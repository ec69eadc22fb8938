#include "solvers/estimation/reduced_run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "solvers/estimation/batch_costs.h"
#include "solvers/estimation/batch_linearization.h"
#include "solvers/estimation/levenberg_marquardt.h"
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

Eigen::VectorXd MinimiseReducedCost(const RunProblem& p, const Eigen::VectorXd& theta_free,
                                    int threads, int max_iterations, double tolerance,
                                    bool* converged, int* iterations,
                                    const std::function<void(const std::string&)>& say) {
  const StateSpaceModel model(p);
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  model.ThetaRows(true, &A, &b);
  struct Point {
    Eigen::VectorXd theta_free;
    double cost = 0.0;
    Eigen::VectorXd gradient;
    Eigen::MatrixXd information;
  };
  auto evaluate = [&](const Eigen::VectorXd& tf) {
    Point pt;
    pt.theta_free = tf;
    const ReducedRun red = ReduceRun(p, model.Expand(tf), threads);
    const Eigen::VectorXd r = A * tf - b;
    pt.cost = red.cost + 0.5 * r.squaredNorm();
    pt.gradient = red.gradient + A.transpose() * r;
    pt.information = red.information + A.transpose() * A;
    return pt;
  };
  // Scale factors stay within [1/5, 5] of nominal, as in the Ceres problem.
  auto clamp = [&](Eigen::VectorXd* tf) {
    for (std::size_t j = 0; j < p.free.size(); ++j) {
      const int i = p.free[j];
      if (i < kKx || i > kKz) continue;
      const double k0 = std::abs(p.prior.mean[i]);
      const bool negative = p.prior.mean[i] < 0.0;
      (*tf)[j] = std::clamp((*tf)[j], negative ? -5.0 * k0 : 0.2 * k0,
                            negative ? -0.2 * k0 : 5.0 * k0);
    }
  };
  Point at = evaluate(theta_free);
  const LmOutcome lm = MinimiseLevenbergMarquardt(
      &at, evaluate,
      [&](const Point& from, const Eigen::VectorXd& step) {
        Eigen::VectorXd trial = from.theta_free + step;
        clamp(&trial);
        return trial;
      },
      [&](int it, const Point& pt, double predicted) {
        if (!say) return;
        char line[160];
        std::snprintf(line, sizeof(line),
                      "Gauss-Newton on the exact increments: step %d, chi2 %.8g, predicted "
                      "decrease %.3g",
                      it + 1, 2.0 * pt.cost, predicted);
        say(line);
      },
      max_iterations, tolerance);
  *converged = lm.converged;
  *iterations = lm.iterations;
  return at.theta_free;
}

}  // namespace triadcal
