// What a fit says of its solution, in the OUT (app/fit_report.h) and in the
// printed table (tools/report/fit_table.h), from one made-up solution each.
#include "app/fit_report.h"

#include <cmath>

#include <gtest/gtest.h>

#include "tools/report/fit_table.h"

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

// A parameter far from its nominal value is named with how far; one the
// covariance finds undetermined is named not separable; the table gives an
// undetermined parameter no value of its own.
TEST(FitReport, NamesWhatIsBeyondThePriorAndWhatIsNotSeparable) {
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
  EXPECT_NE(rep.verdict.find("NOT SEPARABLE in this run: Kx Ky"), std::string::npos) << rep.verdict;
  const nlohmann::json j = FitJson(layout, r, rep, false);
  EXPECT_EQ(j["verdict"]["beyond_prior"], (std::vector<std::string>{"Kx", "W0x"}));
  EXPECT_EQ(j["at_prior_bound"], (std::vector<std::string>{"Kx", "W0x"}));
  ::testing::internal::CaptureStdout();
  PrintParameterTable(layout, r, rep);
  const std::string table = ::testing::internal::GetCapturedStdout();
  const std::size_t ky = table.find("\nKy ");
  ASSERT_NE(ky, std::string::npos) << table;
  const std::string ky_line = table.substr(ky, table.find('\n', ky + 1) - ky);
  EXPECT_NE(ky_line.find("(not estimable on its own)"), std::string::npos) << table;
}

TEST(FitReport, NothingBeyondThePriorSaysSo) {
  const ParameterLayout layout;
  BatchResult r = Solution(layout);
  r.estimate.theta.setZero();
  const FitReport rep = MakeFitReport(layout, r);
  EXPECT_TRUE(rep.beyond_prior.empty());
  EXPECT_NE(rep.verdict.find("no parameter beyond 3 prior sigma"), std::string::npos);
}

// A parameter the run does not determine (considered) is shown as not
// determined: at its nominal value, no sigma of its own in the table, its
// prior sigma in OUT with "determined": false, and the consider model.
TEST(FitReport, ConsideredParameterIsShownAsNotDetermined) {
  const ParameterLayout layout;
  BatchResult r = Solution(layout);
  r.estimate.theta.setZero();
  const int kx = layout.IndexOf("Kx"), kxy = layout.IndexOf("Kxy"), dy2 = layout.IndexOf("dy2");
  for (int i : {kxy, dy2}) {
    r.estimate.cov.row(i).setZero();
    r.estimate.cov.col(i).setZero();
  }
  r.prior.sigma[kxy] = 0.02 * layout.info(kxy).si_per_unit;
  r.estimate.cov(kx, kx) = 1e-4;  // determined: sigma 1 % of the prior
  r.held = {"dy2"};
  r.consider = {"Kxy"};
  r.conditional_information = Eigen::VectorXd::Zero(layout.size());
  r.conditional_information[kxy] = 0.21;
  r.cov_given_consider = 0.25 * r.estimate.cov;
  // Kx follows Kxy by 2 mV/g per 1/g.
  r.consider_sensitivity = Eigen::MatrixXd::Zero(layout.size(), 1);
  r.consider_sensitivity(kx, 0) = 2.0 * layout.info(kx).si_per_unit / layout.info(kxy).si_per_unit;
  r.consider_cov = Eigen::MatrixXd::Constant(1, 1, std::pow(r.prior.sigma[kxy], 2));
  const FitReport rep = MakeFitReport(layout, r);
  EXPECT_NE(rep.verdict.find("NOT DETERMINED by this run (kept at nominal, their prior "
                             "uncertainty carried into the other parameters' sigma): Kxy"),
            std::string::npos)
      << rep.verdict;
  EXPECT_NE(rep.verdict.find("held at nominal: dy2"), std::string::npos) << rep.verdict;
  const nlohmann::json j = FitJson(layout, r, rep, false);
  EXPECT_EQ(j["verdict"]["not_determined"], (std::vector<std::string>{"Kxy"}));
  ASSERT_EQ(j["consider"].size(), 1u);
  EXPECT_EQ(j["consider"][0]["parameter"], "Kxy");
  EXPECT_NEAR(j["consider"][0]["prior_sigma"].get<double>(), 0.02, 1e-15);
  EXPECT_DOUBLE_EQ(j["consider"][0]["data_information"].get<double>(), 0.21);
  EXPECT_NEAR(j["consider"][0]["sensitivity"]["Kx"].get<double>(), 2.0, 1e-12);
  EXPECT_FALSE(j["parameters"]["Kxy"]["determined"].get<bool>());
  EXPECT_TRUE(j["parameters"]["Kxy"]["considered"].get<bool>());
  EXPECT_FALSE(j["parameters"]["Kxy"]["estimable"].get<bool>());
  EXPECT_NEAR(j["parameters"]["Kxy"]["sigma"].get<double>(), 0.02, 1e-15);
  EXPECT_TRUE(j["parameters"]["dy2"]["sigma"].is_null());
  EXPECT_TRUE(j["parameters"]["Kx"]["determined"].get<bool>());
  EXPECT_DOUBLE_EQ(j["parameters"]["Kx"]["sigma_given_consider"].get<double>(),
                   0.5 * j["parameters"]["Kx"]["sigma"].get<double>());
  const nlohmann::json jc = FitJson(layout, r, rep, true);
  ASSERT_TRUE(jc.contains("correlation_given_consider"));
  ::testing::internal::CaptureStdout();
  PrintParameterTable(layout, r, rep);
  const std::string table = ::testing::internal::GetCapturedStdout();
  const std::size_t at = table.find("\nKxy ");
  ASSERT_NE(at, std::string::npos) << table;
  const std::string line = table.substr(at, table.find('\n', at + 1) - at);
  EXPECT_NE(line.find(" - "), std::string::npos) << line;
  EXPECT_NE(line.find("(not determined: nominal, prior +-0.02 carried)"), std::string::npos) << line;
}

// An estimated parameter whose sigma is above prior / sqrt(min_information)
// and mostly the considered one's prior uncertainty is determined only with
// it: said in the verdict, the JSON and the table, never "determined".
TEST(FitReport, ParameterCarriedByAConsideredOneIsNamedWithIt) {
  const ParameterLayout layout;
  BatchResult r = Solution(layout);
  r.estimate.theta.setZero();
  const int gz = layout.IndexOf("gamma_z"), gy = layout.IndexOf("gamma_y");
  const int kz = layout.IndexOf("Kz");
  r.estimate.cov.row(gy).setZero();
  r.estimate.cov.col(gy).setZero();
  r.consider = {"gamma_y"};
  r.cov_given_consider = r.estimate.cov;
  // gamma_z follows gamma_y one for one (sigma = the prior's); Kz a little
  // (its sigma 1e-3 of the prior: determined whatever the share).
  r.consider_sensitivity = Eigen::MatrixXd::Zero(layout.size(), 1);
  r.consider_sensitivity(gz, 0) = 1.0;
  r.consider_sensitivity(kz, 0) = 1e-3;
  r.consider_cov = Eigen::MatrixXd::Constant(1, 1, 1.0);
  r.estimate.cov(gz, gz) += 1.0;
  r.estimate.cov(kz, kz) += 1e-6;
  const FitReport rep = MakeFitReport(layout, r);
  ASSERT_EQ(rep.with_considered.size(), 1u);
  EXPECT_EQ(rep.with_considered.at("gamma_z"), (std::vector<std::string>{"gamma_y"}));
  EXPECT_NE(rep.verdict.find("DETERMINED ONLY WITH the considered parameters at nominal (their "
                             "prior uncertainty is most of the sigma): gamma_z (with gamma_y)"),
            std::string::npos)
      << rep.verdict;
  EXPECT_EQ(rep.verdict.find("; every estimated parameter determined"), std::string::npos);
  const nlohmann::json j = FitJson(layout, r, rep, false);
  EXPECT_FALSE(j["parameters"]["gamma_z"]["determined"].get<bool>());
  EXPECT_EQ(j["parameters"]["gamma_z"]["determined_with_considered"],
            (std::vector<std::string>{"gamma_y"}));
  EXPECT_TRUE(j["parameters"]["Kz"]["determined"].get<bool>());
  EXPECT_FALSE(j["parameters"]["gamma_y"].contains("held"));
  ::testing::internal::CaptureStdout();
  PrintParameterTable(layout, r, rep);
  const std::string table = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(table.find("(only with considered gamma_y at nominal)"), std::string::npos) << table;
}

}  // namespace
}  // namespace triadcal
