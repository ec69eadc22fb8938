// The Levenberg-Marquardt loop on Rosenbrock's valley as least squares,
// r = (10 (y - x^2), 1 - x): from (-1.2, 1) it must reach (1, 1), and a
// projection onto bounds must be respected.
#include <gtest/gtest.h>

#include "solvers/estimation/levenberg_marquardt.h"

namespace triadcal {
namespace {

struct Point {
  Eigen::Vector2d x;
  double cost = 0.0;
  Eigen::VectorXd gradient;
  Eigen::MatrixXd information;
};

Point Rosenbrock(const Eigen::Vector2d& x) {
  const Eigen::Vector2d r(10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]);
  Eigen::Matrix2d J;
  J << -20.0 * x[0], 10.0, -1.0, 0.0;
  Point p;
  p.x = x;
  p.cost = 0.5 * r.squaredNorm();
  p.gradient = J.transpose() * r;
  p.information = J.transpose() * J;
  return p;
}

TEST(LevenbergMarquardt, ReachesTheBottomOfRosenbrocksValley) {
  Point at = Rosenbrock(Eigen::Vector2d(-1.2, 1.0));
  int reports = 0;
  const LmOutcome out = MinimiseLevenbergMarquardt(
      &at, Rosenbrock,
      [](const Point& p, const Eigen::VectorXd& step) { return Eigen::Vector2d(p.x + step); },
      [&](int, const Point&, double) { ++reports; }, 200, 1e-20);
  EXPECT_TRUE(out.converged);
  EXPECT_NEAR(at.x[0], 1.0, 1e-8);
  EXPECT_NEAR(at.x[1], 1.0, 1e-8);
  EXPECT_GT(reports, out.iterations);  // one report per step, the last one too
}

TEST(LevenbergMarquardt, StaysInsideItsProjection) {
  Point at = Rosenbrock(Eigen::Vector2d(-1.2, 1.0));
  MinimiseLevenbergMarquardt(
      &at, Rosenbrock,
      [](const Point& p, const Eigen::VectorXd& step) {
        Eigen::Vector2d x = p.x + step;
        x[0] = std::min(x[0], 0.5);  // the bound x <= 0.5
        return x;
      },
      [](int, const Point&, double) {}, 200, 1e-20);
  EXPECT_LE(at.x[0], 0.5);
  EXPECT_NEAR(at.x[0], 0.5, 1e-3);  // the constrained minimum lies on the bound
}

}  // namespace
}  // namespace triadcal
