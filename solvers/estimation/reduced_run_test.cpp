// One run with its trajectory solved for: the gradient against a numeric
// difference of the reduced cost, and at a converged fit a zero gradient and
// the fit's own covariance.
#include <cmath>

#include <gtest/gtest.h>

#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/reduced_run.h"
#include "solvers/estimation/run_problem.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

TEST(ReduceRun, GradientMatchesANumericDifferenceOfTheCost) {
  const Scenario s = PaperScenario(50.0, 20.0, 2.0, 15.0, 3);
  const RunData data = Simulate(s);
  const ParameterLayout layout;
  const RunProblem p = BuildRunProblem(s.run, data, layout, 0.5, {});
  // Away from the optimum, so that the gradient is large.
  Eigen::VectorXd theta = s.truth;
  theta[kKx] += 0.3;
  theta[kW0y] -= 1.0;
  theta[kAlphaX] += 2e-4;
  theta[kDx2] += 2e-3;
  const ReducedRun red = ReduceRun(p, theta, 2);
  ASSERT_EQ(red.gradient.size(), layout.size());
  for (int i : {kKx, kKz, kW0y, kAlphaX, kGammaZ, kKxy, kDpsi, kDlambda2, kDx2, kDz2}) {
    const double h = 1e-3 * p.prior.sigma[i];
    Eigen::VectorXd a = theta, b = theta;
    a[i] += h;
    b[i] -= h;
    const double numeric = (ReduceRun(p, a, 2).cost - ReduceRun(p, b, 2).cost) / (2.0 * h);
    // In units of the cost change over one prior sigma. The measurement
    // weights (angle noise through the lever arm, B2) depend on the lever
    // arm; the batch problem holds the weights at the linearisation point
    // (iterative reweighting), and so does this gradient, which then differs
    // from the numeric one by that part: 0.1-0.2 % here.
    const bool weights_move = i >= kDx2 && i <= kDz2;
    const double scale = std::abs(numeric) * p.prior.sigma[i] + 1.0;
    EXPECT_NEAR(red.gradient[i] * p.prior.sigma[i], numeric * p.prior.sigma[i],
                (weights_move ? 1e-2 : 1e-3) * scale)
        << layout.info(i).name;
  }
}

TEST(ReduceRun, AtAConvergedFitTheGradientVanishesAndTheInformationIsTheCovariance) {
  const Scenario s = PaperScenario(50.0, 40.0, 2.0, 15.0, 5);
  const RunData data = Simulate(s);
  const ParameterLayout layout;
  BatchOptions opt;
  opt.threads = 2;
  const BatchResult fit = SolveBatch(s.run, data, layout, opt);
  ASSERT_TRUE(fit.converged);
  ASSERT_TRUE(fit.held.empty());
  RunProblem p = BuildRunProblem(s.run, data, layout, opt.epoch_s, {});
  p.noise_mV = fit.noise_used_mV;
  const Eigen::VectorXd& theta = fit.estimate.theta;
  const ReducedRun red = ReduceRun(p, theta, 2);
  const int n = layout.size();
  // Add the priors and the constraint, as the batch problem has them.
  Eigen::VectorXd g = red.gradient;
  Eigen::MatrixXd H = red.information;
  for (int i = 0; i < n; ++i) {
    const double s2 = p.prior.sigma[i] * p.prior.sigma[i];
    g[i] += (theta[i] - p.prior.mean[i]) / s2;
    H(i, i) += 1.0 / s2;
  }
  for (const ConstraintRow& c : p.constraints) {
    g += c.c * (c.c.dot(theta) - c.value) / (c.sigma * c.sigma);
    H += c.c * c.c.transpose() / (c.sigma * c.sigma);
  }
  const Eigen::MatrixXd cov = H.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  for (int i = 0; i < n; ++i) {
    const double sigma = std::sqrt(fit.estimate.cov(i, i));
    // The gradient in units of 1/sigma: the step it implies is < 0.02 sigma.
    EXPECT_LT(std::abs((cov * g)[i]) / sigma, 0.02) << layout.info(i).name;
    EXPECT_NEAR(std::sqrt(cov(i, i)) / sigma, 1.0, 0.01) << layout.info(i).name;
  }
  EXPECT_NEAR(2.0 * red.cost / red.degrees_of_freedom, fit.chi2_per_dof, 0.01);
}

}  // namespace
}  // namespace triadcal
