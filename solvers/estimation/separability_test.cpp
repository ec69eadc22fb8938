#include "solvers/estimation/separability.h"

#include <gtest/gtest.h>

namespace triadcal {
namespace {

TEST(BeyondPrior, NamesParametersFarFromTheirPriorMeanLargestFirst) {
  const ParameterLayout layout;
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(layout.size());
  Eigen::VectorXd sigma = Eigen::VectorXd::Ones(layout.size());
  Eigen::VectorXd theta = mean;
  theta[layout.IndexOf("Kx")] = 9.5;
  theta[layout.IndexOf("dpsi")] = -25.31;
  theta[layout.IndexOf("W0y")] = 3.0;  // exactly 3: not beyond
  theta[layout.IndexOf("Kz")] = 4.0;
  sigma[layout.IndexOf("Kz")] = 0.0;  // no prior: never judged
  const std::vector<PriorExcursion> e = BeyondPrior(layout, theta, mean, sigma);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].name, "dpsi");
  EXPECT_DOUBLE_EQ(e[0].z, -25.31);
  EXPECT_EQ(e[1].name, "Kx");
  EXPECT_EQ(DescribeExcursions(e), "dpsi (-25.3) Kx (+9.5)");
  EXPECT_TRUE(BeyondPrior(layout, theta, mean, sigma, 30.0).empty());
  EXPECT_EQ(DescribeExcursions({}), "");
}

}  // namespace
}  // namespace triadcal
