#include "tools/report/fit_report.h"

#include <gtest/gtest.h>

namespace triadcal {
namespace {

// A solution where the data determine every parameter to 1e-3 of its prior
// except Kx, which keeps its prior sigma: Kx ended 9.5 prior sigma from its
// nominal value (moved by the misfit through correlations, as on the real
// slow roll run), W0x (determined) 4 prior sigma, Ky (undetermined) at 0.5.
BatchResult Solution(const ParameterLayout& layout) {
  BatchResult r;
  const int n = layout.size();
  r.prior.mean = Eigen::VectorXd::Zero(n);
  r.prior.sigma = Eigen::VectorXd::Ones(n);
  r.estimate.theta = Eigen::VectorXd::Zero(n);
  r.estimate.cov = 1e-6 * Eigen::MatrixXd::Identity(n, n);
  const int kx = layout.IndexOf("Kx"), ky = layout.IndexOf("Ky");
  r.estimate.cov(kx, kx) = 1.0;
  r.estimate.cov(ky, ky) = 1.0;
  r.estimate.theta[kx] = 9.5;
  r.estimate.theta[ky] = 0.5;
  r.estimate.theta[layout.IndexOf("W0x")] = -4.0;
  r.initial = r.estimate;
  r.converged = true;
  return r;
}

TEST(FitReport, UndeterminedParameterFarFromItsPriorIsNotCalledThePriorsValue) {
  const ParameterLayout layout;
  const BatchResult r = Solution(layout);
  const FitReport rep = MakeFitReport(layout, r);
  ASSERT_EQ(rep.beyond_prior.size(), 2u);
  EXPECT_EQ(rep.beyond_prior[0].name, "Kx");
  EXPECT_DOUBLE_EQ(rep.beyond_prior[0].z, 9.5);
  EXPECT_EQ(rep.beyond_prior[1].name, "W0x");
  EXPECT_NE(rep.verdict.find("BEYOND 3 PRIOR SIGMA (value - nominal in prior sigma): Kx (+9.5) "
                             "W0x (-4.0)"),
            std::string::npos)
      << rep.verdict;
  EXPECT_NE(rep.verdict.find("NOT SEPARABLE in this run (values are the prior's): Ky;"),
            std::string::npos)
      << rep.verdict;
  EXPECT_NE(rep.verdict.find("MOVED beyond 3 prior sigma by the misfit (values neither the "
                             "prior's nor estimates): Kx"),
            std::string::npos)
      << rep.verdict;
  const nlohmann::json j = FitJson(layout, r, rep, false);
  EXPECT_EQ(j["verdict"]["beyond_prior"], (std::vector<std::string>{"Kx", "W0x"}));
  EXPECT_EQ(j["at_prior_bound"], (std::vector<std::string>{"Kx", "W0x"}));
  // The table: the misfit's value is not called the prior's.
  ::testing::internal::CaptureStdout();
  PrintParameterTable(layout, r, rep);
  const std::string table = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(table.find("(not estimable, moved +9.5 prior sigma by misfit)"), std::string::npos)
      << table;
  const std::size_t ky = table.find("\nKy ");
  ASSERT_NE(ky, std::string::npos) << table;
  const std::string ky_line = table.substr(ky, table.find('\n', ky + 1) - ky);
  EXPECT_NE(ky_line.find("(not estimable: prior value)"), std::string::npos) << table;
}

TEST(FitReport, NothingBeyondThePriorSaysSo) {
  const ParameterLayout layout;
  BatchResult r = Solution(layout);
  r.estimate.theta.setZero();
  const FitReport rep = MakeFitReport(layout, r);
  EXPECT_TRUE(rep.beyond_prior.empty());
  EXPECT_NE(rep.verdict.find("no parameter at a prior bound"), std::string::npos);
  EXPECT_EQ(rep.verdict.find("MOVED"), std::string::npos);
}

// A parameter pinned after a first fit is reported as pinned, with where that
// fit had moved it, not as held for want of motion.
TEST(FitReport, PinnedParameterIsNamedWithHowFarTheFirstFitMovedIt) {
  const ParameterLayout layout;
  BatchResult r = Solution(layout);
  r.estimate.theta.setZero();
  const int kxy = layout.IndexOf("Kxy"), dy2 = layout.IndexOf("dy2");
  for (int i : {kxy, dy2}) {
    r.estimate.cov.row(i).setZero();
    r.estimate.cov.col(i).setZero();
  }
  r.held = {"Kxy", "dy2"};
  r.pinned = {{"Kxy", -57.3, 0.21}};
  r.cov_given_pinned = 0.25 * r.estimate.cov;
  // The consider model in SI: Kx follows Kxy by 2 mV/g per 1/g (0.002 V/g
  // per 1/g), Kxy's posterior sigma 0.02 /g.
  const int kx = layout.IndexOf("Kx");
  r.pinned_sensitivity = Eigen::MatrixXd::Zero(layout.size(), 1);
  r.pinned_sensitivity(kx, 0) = 2.0 * layout.info(kx).si_per_unit / layout.info(kxy).si_per_unit;
  r.pinned_cov = Eigen::MatrixXd::Constant(1, 1, std::pow(0.02 * layout.info(kxy).si_per_unit, 2));
  const FitReport rep = MakeFitReport(layout, r);
  EXPECT_NE(rep.verdict.find("PINNED at nominal after a first fit (value - nominal there in prior "
                             "sigma, data information at the nominal values in prior units): "
                             "Kxy (-57.3, 0.21): "),
            std::string::npos)
      << rep.verdict;
  EXPECT_NE(rep.verdict.find("held at nominal (this run's motion does not determine them): dy2"),
            std::string::npos)
      << rep.verdict;
  const nlohmann::json j = FitJson(layout, r, rep, false);
  EXPECT_EQ(j["verdict"]["pinned"], (std::vector<std::string>{"Kxy"}));
  ASSERT_EQ(j["pinned"].size(), 1u);
  EXPECT_EQ(j["pinned"][0]["parameter"], "Kxy");
  EXPECT_DOUBLE_EQ(j["pinned"][0]["prior_sigmas"].get<double>(), -57.3);
  EXPECT_DOUBLE_EQ(j["pinned"][0]["data_information"].get<double>(), 0.21);
  EXPECT_NEAR(j["pinned"][0]["sigma"].get<double>(), 0.02, 1e-15);
  EXPECT_TRUE(j["pinned"][0]["correlation"].empty());
  ASSERT_EQ(j["pinned"][0]["sensitivity"].size(), 1u);
  EXPECT_NEAR(j["pinned"][0]["sensitivity"]["Kx"].get<double>(), 2.0, 1e-12);
  EXPECT_TRUE(j["parameters"]["Kxy"]["pinned"].get<bool>());
  EXPECT_TRUE(j["parameters"]["Kxy"]["sigma"].is_null());
  EXPECT_FALSE(j["parameters"]["dy2"].contains("pinned"));
  EXPECT_DOUBLE_EQ(j["parameters"]["Kx"]["sigma_given_pinned"].get<double>(),
                   0.5 * j["parameters"]["Kx"]["sigma"].get<double>());
  // --correlations: also the correlation given the pins (here the same
  // matrix, the covariance given the pins being a quarter of the reported).
  EXPECT_FALSE(j.contains("correlation_given_pinned"));
  const nlohmann::json jc = FitJson(layout, r, rep, true);
  ASSERT_TRUE(jc.contains("correlation_given_pinned"));
  EXPECT_EQ(jc["correlation_given_pinned"]["names"], jc["correlation"]["names"]);
  const auto& given = jc["correlation_given_pinned"]["matrix"];
  const auto& whole = jc["correlation"]["matrix"];
  for (int a : {0, kx, kxy}) {
    for (int b : {0, kx, 5}) {
      EXPECT_NEAR(given[a][b].get<double>(), whole[a][b].get<double>(), 1e-12) << a << " " << b;
    }
  }
  ::testing::internal::CaptureStdout();
  PrintParameterTable(layout, r, rep);
  const std::string table = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(table.find("(pinned at nominal: a first fit moved it -57.3 prior sigma)"),
            std::string::npos)
      << table;
}

}  // namespace
}  // namespace triadcal
