// The block forward elimination (schur_covariance.h) against the dense normal
// equations of the same problem: the information of theta with the states
// eliminated, and the reduced cost, gradient and optimal states.
#include "solvers/estimation/schur_covariance.h"

#include <random>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "tests/block_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::BlockProblem;
using testing_fixtures::DrawResiduals;
using testing_fixtures::RandomBlocks;

// The whole Jacobian [J_x J_theta] and r0: rows of the measurements, then of
// the process steps; the states x_0..x_{E-1} (6 each), then theta.
struct Dense {
  Eigen::MatrixXd J;
  Eigen::VectorXd r0;
};

Dense Assemble(const BlockProblem& b, int n) {
  const int E = static_cast<int>(b.measurement.size());
  const int rows = 6 * E + 6 * (E - 1), cols = 6 * E + n;
  Dense d{Eigen::MatrixXd::Zero(rows, cols), Eigen::VectorXd::Zero(rows)};
  for (int e = 0; e < E; ++e) {
    d.J.block(6 * e, 6 * e, 6, 6) = b.measurement[e].M;
    d.J.block(6 * e, 6 * E, 6, n) = b.measurement[e].N;
    d.r0.segment<6>(6 * e) = b.measurement[e].r0;
  }
  for (int e = 0; e + 1 < E; ++e) {
    const int r = 6 * E + 6 * e;
    d.J.block(r, 6 * e, 6, 6) = b.process[e].A;
    d.J.block(r, 6 * (e + 1), 6, 6) = b.process[e].B;
    d.J.block(r, 6 * E, 6, n) = b.process[e].C;
    d.r0.segment<6>(r) = b.process[e].r0;
  }
  return d;
}

TEST(SchurElimination, InformationIsTheDenseSchurComplement) {
  std::mt19937_64 rng(11);
  for (int n : {1, 5, 30}) {
    const int E = 40;
    const BlockProblem b = RandomBlocks(E, n, &rng);
    const Dense d = Assemble(b, n);
    const Eigen::MatrixXd H = d.J.transpose() * d.J;
    const int m = 6 * E;
    const Eigen::MatrixXd expected =
        H.bottomRightCorner(n, n) -
        H.bottomLeftCorner(n, m) * H.topLeftCorner(m, m).ldlt().solve(H.topRightCorner(m, n));
    // The rows on theta alone (a prior) add their own information.
    const Eigen::MatrixXd prior = Eigen::MatrixXd::Identity(n, n) * 0.5;
    const Eigen::MatrixXd got = ThetaInformationBySchur(b.process, b.measurement, prior);
    const Eigen::MatrixXd want = expected + prior.transpose() * prior;
    EXPECT_LT((got - want).norm(), 1e-9 * want.norm()) << "n = " << n;
    EXPECT_LT((got - got.transpose()).norm(), 1e-12 * got.norm());
  }
}

// On two threads the data's sum and the eliminated one are formed at once:
// the same sums in the same order, so the same bits as on one, over several
// chunks of 64 epochs (and the dense complement).
TEST(SchurElimination, TwoThreadsGiveTheOneThreadInformation) {
  std::mt19937_64 rng(13);
  const int E = 150, n = 7;
  const BlockProblem b = RandomBlocks(E, n, &rng);
  const Eigen::MatrixXd prior = Eigen::MatrixXd::Identity(n, n) * 0.5;
  Eigen::VectorXd scale1, scale2;
  const Eigen::MatrixXd one = ThetaInformationBySchur(b.process, b.measurement, prior, &scale1, 1);
  const Eigen::MatrixXd two = ThetaInformationBySchur(b.process, b.measurement, prior, &scale2, 2);
  EXPECT_EQ(one, two);
  EXPECT_EQ(scale1, scale2);
  const Dense d = Assemble(b, n);
  const Eigen::MatrixXd H = d.J.transpose() * d.J;
  const int m = 6 * E;
  const Eigen::MatrixXd want =
      H.bottomRightCorner(n, n) -
      H.bottomLeftCorner(n, m) * H.topLeftCorner(m, m).ldlt().solve(H.topRightCorner(m, n)) +
      prior.transpose() * prior;
  EXPECT_LT((two - want).norm(), 1e-9 * want.norm());
  // The scale is the diagonal before the elimination.
  EXPECT_LT((scale2 - (H.bottomRightCorner(n, n).diagonal() + prior.colwise().squaredNorm().transpose())).norm(),
            1e-12 * scale2.norm());
}

TEST(SchurElimination, ReducedCostGradientAndStatesAreTheDenseOnes) {
  std::mt19937_64 rng(12);
  const int E = 25, n = 4;
  BlockProblem b = RandomBlocks(E, n, &rng);
  DrawResiduals(&b, &rng);
  const Dense d = Assemble(b, n);
  const int m = 6 * E;
  const Eigen::MatrixXd Jx = d.J.leftCols(m), Jt = d.J.rightCols(n);
  // theta fixed (at 0 here): the states minimise 0.5 |r0 + Jx x|^2.
  const Eigen::VectorXd x = -(Jx.transpose() * Jx).ldlt().solve(Jx.transpose() * d.r0);
  const Eigen::VectorXd r = d.r0 + Jx * x;
  const ReducedOverStates got = ReduceOverStates(b.process, b.measurement, true);
  EXPECT_NEAR(got.cost, 0.5 * r.squaredNorm(), 1e-10 * r.squaredNorm());
  const Eigen::VectorXd g = Jt.transpose() * r;  // Jx^T r = 0 at the optimal states
  EXPECT_LT((got.gradient - g).norm(), 1e-9 * g.norm());
  ASSERT_EQ(got.states.size(), static_cast<std::size_t>(E));
  for (int e = 0; e < E; ++e) {
    EXPECT_LT((got.states[e] - x.segment<6>(6 * e)).norm(), 1e-9 * x.norm()) << "epoch " << e;
  }
  const Eigen::MatrixXd H = d.J.transpose() * d.J;
  const Eigen::MatrixXd info =
      H.bottomRightCorner(n, n) -
      H.bottomLeftCorner(n, m) * H.topLeftCorner(m, m).ldlt().solve(H.topRightCorner(m, n));
  EXPECT_LT((got.information - info).norm(), 1e-9 * info.norm());
}

}  // namespace
}  // namespace triadcal
