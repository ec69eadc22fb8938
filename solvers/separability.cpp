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
  const Eigen::VectorXd dinv = prior_sigma.cwiseInverse();
  const Eigen::MatrixXd Pn = dinv.asDiagonal() * posterior_cov * dinv.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Pn + Pn.transpose()));
  std::vector<WeakDirection> out;
  for (int j = static_cast<int>(Pn.rows()) - 1; j >= 0; --j) {  // largest mu first
    const double mu = std::max(es.eigenvalues()[j], 1e-300);
    const double info = 1.0 / mu - 1.0;
    if (info >= min_information) break;
    WeakDirection d;
    d.data_information = std::max(0.0, info);
    d.sigma_ratio = std::sqrt(mu);
    const Eigen::VectorXd v = es.eigenvectors().col(j);
    for (int i = 0; i < v.size(); ++i) {
      if (std::abs(v[i]) >= 0.2) d.weights.push_back({layout.info(i).name, v[i]});
    }
    std::sort(d.weights.begin(), d.weights.end(),
              [](const auto& a, const auto& b) { return std::abs(a.second) > std::abs(b.second); });
    if (!d.weights.empty() && d.weights.front().second < 0) {
      for (auto& p : d.weights) p.second = -p.second;
    }
    d.description = Describe(d.weights);
    out.push_back(std::move(d));
  }
  return out;
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
