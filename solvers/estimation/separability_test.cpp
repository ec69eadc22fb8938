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

// The gyro's parameters are named for what they do, as the accelerometer's
// (observability printed a single-axis run's "gyro.gamma_z [gyro.gamma_z 1]").
TEST(DescribeDirection, NamesTheGyrosParameters) {
  EXPECT_EQ(DescribeDirection({{"gyro.Kz", 1.0}}),
            "gyro scale factor gyro.Kz (gain of the z rate reading)");
  EXPECT_EQ(DescribeDirection({{"gyro.W0x", -1.0}}), "gyro bias gyro.W0x");
  EXPECT_EQ(DescribeDirection({{"gyro.gamma_z", 1.0}}),
            "gyro misalignment gyro.gamma_z (the rate about z into the y reading)");
  EXPECT_EQ(DescribeDirection({{"gyro.Gyx", 1.0}}),
            "gyro g-sensitivity gyro.Gyx (Wx into the y rate reading)");
  EXPECT_EQ(DescribeDirection({{"Kz", 1.0}}), "scale factor Kz (gain of the z reading)");
}

}  // namespace
}  // namespace triadcal
