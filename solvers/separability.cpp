#include "solvers/separability.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <set>

namespace triadcal {
namespace {

bool Has(const std::vector<std::pair<std::string, double>>& w, const std::string& name) {
  for (const auto& p : w) {
    if (p.first == name) return true;
  }
  return false;
}

std::string Describe(const std::vector<std::pair<std::string, double>>& w) {
  if (Has(w, "dlambda2") && (Has(w, "gamma_y") || Has(w, "gamma_z"))) {
    return "common rotation of the triad about the inner bench axis (dlambda2 with gamma_y, "
           "gamma_z)";
  }
  if (Has(w, "dpsi") && (Has(w, "alpha_x") || Has(w, "alpha_y") || Has(w, "beta_z"))) {
    return "rotation of the triad and the bench about the vertical";
  }
  std::string s = "combination of ";
  for (std::size_t i = 0; i < w.size(); ++i) s += (i ? ", " : "") + w[i].first;
  return s;
}

}  // namespace

std::vector<WeakDirection> FindWeakDirections(const ParameterLayout& layout,
                                              const Eigen::MatrixXd& posterior_cov,
                                              const Eigen::VectorXd& prior_sigma,
                                              double min_information) {
  std::vector<int> all(prior_sigma.size());
  for (int i = 0; i < static_cast<int>(all.size()); ++i) all[i] = i;
  return FindWeakDirections(layout, posterior_cov, prior_sigma, all, min_information);
}

std::vector<WeakDirection> FindWeakDirections(const ParameterLayout& layout,
                                              const Eigen::MatrixXd& posterior_cov,
                                              const Eigen::VectorXd& prior_sigma,
                                              const std::vector<int>& subset,
                                              double min_information) {
  const int m = static_cast<int>(subset.size());
  Eigen::MatrixXd cov(m, m);
  Eigen::VectorXd sig(m);
  for (int a = 0; a < m; ++a) {
    sig[a] = prior_sigma[subset[a]];
    for (int b = 0; b < m; ++b) cov(a, b) = posterior_cov(subset[a], subset[b]);
  }
  // Directions in the subset's coordinates, then renamed through the layout.
  std::vector<WeakDirection> dirs;
  const Eigen::VectorXd dinv = sig.cwiseInverse();
  const Eigen::MatrixXd Pn = dinv.asDiagonal() * cov * dinv.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Pn + Pn.transpose()));
  for (int j = m - 1; j >= 0; --j) {
    const double mu = std::max(es.eigenvalues()[j], 1e-300);
    const double info = 1.0 / mu - 1.0;
    if (info >= min_information) break;
    WeakDirection d;
    d.data_information = std::max(0.0, info);
    d.sigma_ratio = std::sqrt(mu);
    const Eigen::VectorXd v = es.eigenvectors().col(j);
    for (int a = 0; a < m; ++a) {
      if (std::abs(v[a]) >= 0.2) d.weights.push_back({layout.info(subset[a]).name, v[a]});
    }
    std::sort(d.weights.begin(), d.weights.end(),
              [](const auto& x, const auto& y) { return std::abs(x.second) > std::abs(y.second); });
    if (!d.weights.empty() && d.weights.front().second < 0) {
      for (auto& w : d.weights) w.second = -w.second;
    }
    d.description = Describe(d.weights);
    dirs.push_back(std::move(d));
  }
  return dirs;
}

std::string DescribeDirection(const std::vector<std::pair<std::string, double>>& weights) {
  return Describe(weights);
}

std::vector<std::string> ParametersIn(const std::vector<WeakDirection>& dirs) {
  std::set<std::string> seen;
  std::vector<std::string> out;
  for (const WeakDirection& d : dirs) {
    for (const auto& p : d.weights) {
      if (seen.insert(p.first).second) out.push_back(p.first);
    }
  }
  return out;
}

}  // namespace triadcal
