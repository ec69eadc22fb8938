#include "solvers/analysis/monte_carlo_records.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "core/model/errors.h"

namespace triadcal {
namespace {

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Text and back must give the same bits, held (NaN) and failed runs included:
// the merged Monte Carlo is only equal to the whole if this holds.
TEST(MonteCarloRecords, ReadBackBitForBit) {
  MonteCarloRun r;
  r.seed = 42;
  r.truth = Eigen::VectorXd(3);
  r.truth << 1.0 / 3.0, -2.5e-300, 174.8 * 9.80665;
  Eigen::VectorXd e(3), s(3);
  e << std::nan(""), 1e-17 / 7.0, -0.1;
  s << 0.3, std::numeric_limits<double>::infinity(), 5e-324;
  r.error = {e, Eigen::VectorXd()};
  r.sigma = {s, Eigen::VectorXd()};
  r.failure = {"", "Ceres: no convergence"};
  const std::string text = MonteCarloRunsJson({r}).dump();
  const std::vector<MonteCarloRun> back =
      MonteCarloRunsFromJson(nlohmann::json::parse(text), 2, 3, "shard.json");
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].seed, 42u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(SameBits(back[0].truth[i], r.truth[i])) << i;
    EXPECT_TRUE(SameBits(back[0].sigma[0][i], s[i])) << i;
  }
  EXPECT_TRUE(std::isnan(back[0].error[0][0]));
  EXPECT_TRUE(SameBits(back[0].error[0][1], e[1]));
  EXPECT_EQ(back[0].error[1].size(), 0);
  EXPECT_EQ(back[0].failure[1], "Ceres: no convergence");
}

TEST(MonteCarloRecords, WrongShapeNamesTheFile) {
  MonteCarloRun r;
  r.seed = 1;
  r.truth = Eigen::VectorXd::Zero(2);
  r.error = {Eigen::VectorXd::Zero(2)};
  r.sigma = {Eigen::VectorXd::Zero(2)};
  r.failure = {""};
  const nlohmann::json j = MonteCarloRunsJson({r});
  try {
    MonteCarloRunsFromJson(j, 1, 3, "s1.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "s1.json: records[0].truth: expected a list of 3 numbers");
  }
}

}  // namespace
}  // namespace triadcal
