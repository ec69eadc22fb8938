// Random block problems of the batch problem's shape (schur_covariance.h) for
// the tests of the state elimination, the epoch scores and the HAC covariance.
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/schur_covariance.h"

namespace triadcal {
namespace testing_fixtures {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// A random block problem of the batch's shape: E epochs, n parameters,
// state-to-state coupling like a step of the dynamics (A near -I, B near I).
struct BlockProblem {
  std::vector<ProcessBlock> process;
  std::vector<MeasurementBlock> measurement;
};

inline BlockProblem RandomBlocks(int E, int n, std::mt19937_64* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  auto random = [&](int r, int c, double s) {
    Eigen::MatrixXd m(r, c);
    for (int i = 0; i < r; ++i)
      for (int j = 0; j < c; ++j) m(i, j) = s * g(*rng);
    return m;
  };
  BlockProblem b;
  b.process.resize(E - 1);
  b.measurement.resize(E);
  for (int e = 0; e < E; ++e) {
    if (e + 1 < E) {
      b.process[e].A = -Mat6::Identity() + Mat6(random(6, 6, 0.2));
      b.process[e].B = Mat6::Identity() + Mat6(random(6, 6, 0.2));
      b.process[e].C = random(6, n, 1.0);
    }
    b.measurement[e].M = Mat6::Identity() * 0.3 + Mat6(random(6, 6, 0.1));
    b.measurement[e].N = random(6, n, 0.5);
  }
  return b;
}

inline void DrawResiduals(BlockProblem* b, std::mt19937_64* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  for (ProcessBlock& p : b->process)
    for (int i = 0; i < 6; ++i) p.r0[i] = g(*rng);
  for (MeasurementBlock& m : b->measurement)
    for (int i = 0; i < 6; ++i) m.r0[i] = g(*rng);
}

}  // namespace testing_fixtures
}  // namespace triadcal
