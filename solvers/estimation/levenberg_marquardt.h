// Levenberg-Marquardt for problems given as their cost, gradient and
// Gauss-Newton information at a point: the batch solver's finish on the
// reduced cost of one run (reduced_run.h) and the joint problem of several
// runs (solvers/multirun/joint_solver.h) both minimise this way, with every
// evaluation one linearisation of the runs.
//
// Step: (H + mu diag H) dx = -g. The predicted decrease of the quadratic model
// is -(g.dx + dx^T H dx / 2); converged when it falls below `tolerance` (in
// the cost's units). Damping by Nielsen's rule: after a step with gain ratio
// rho = actual / predicted decrease, mu *= max(1/3, 1 - (2 rho - 1)^3); after
// a rejected step mu *= nu, nu doubling (each rejected step costs an
// evaluation, so mu must not fall too fast).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <utility>

namespace triadcal {

struct LmOutcome {
  bool converged = false;
  int iterations = 0;  // evaluations after the first
};

// Point: has `double cost`, `Eigen::VectorXd gradient`, `Eigen::MatrixXd
// information`. evaluate(trial) -> Point; trial_of(const Point&, step) -> the
// argument of evaluate for a step from the point (projected onto bounds);
// report(iteration, const Point&, predicted decrease) before each step.
template <typename Point, typename Evaluate, typename TrialOf, typename Report>
LmOutcome MinimiseLevenbergMarquardt(Point* at, Evaluate evaluate, TrialOf trial_of,
                                     Report report, int max_iterations, double tolerance) {
  LmOutcome out;
  double mu = 1e-6, nu = 2.0;
  for (int it = 0; it < max_iterations; ++it) {
    Eigen::MatrixXd H = at->information;
    H.diagonal() += mu * at->information.diagonal();
    const Eigen::VectorXd step = -H.ldlt().solve(at->gradient);
    const double predicted =
        -(at->gradient.dot(step) + 0.5 * step.dot(at->information * step));
    report(it, *at, predicted);
    if (!std::isfinite(predicted) || predicted < 0.0) break;
    if (predicted < tolerance) {
      out.converged = true;
      break;
    }
    Point next = evaluate(trial_of(*at, step));
    out.iterations += 1;
    const double actual = at->cost - next.cost;
    if (std::isfinite(next.cost) && actual > 0.0) {
      *at = std::move(next);
      const double rho = actual / predicted;
      mu = std::max(mu * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)), 1e-9);
      nu = 2.0;
    } else {
      mu = std::max(mu * nu, 1e-6);
      nu *= 2.0;
      if (mu > 1e8) break;
    }
  }
  return out;
}

}  // namespace triadcal
