#include "solvers/estimation/separability.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

namespace triadcal {
namespace {

using Weights = std::vector<std::pair<std::string, double>>;

double WeightOf(const Weights& w, const std::string& name) {
  for (const auto& p : w) {
    if (p.first == name) return p.second;
  }
  return 0.0;
}

// Share of the listed squared weight carried by `names`, when all of those
// present have the sign of the first present one (a common motion of them).
double CommonShare(const Weights& w, const std::vector<std::string>& names) {
  double in = 0.0, all = 0.0, sign = 0.0;
  for (const auto& p : w) all += p.second * p.second;
  for (const std::string& n : names) {
    const double v = WeightOf(w, n);
    if (v == 0.0) continue;
    if (sign == 0.0) sign = v > 0 ? 1.0 : -1.0;
    if (v * sign < 0) return 0.0;
    in += v * v;
  }
  return all > 0 ? in / all : 0.0;
}

// M = [[1, -alpha_y, beta_z], [alpha_x, 1, -gamma_z], [-beta_x, gamma_y, 1]]:
// each angle carries input `input` into reading `reading` (the gyro's M has
// the same form, SPEC section 10).
struct AngleEntry {
  const char* name;
  int reading, input;
};
constexpr AngleEntry kAngles[] = {{"alpha_x", 1, 0}, {"alpha_y", 0, 1}, {"beta_x", 2, 0},
                                  {"beta_z", 0, 2},  {"gamma_y", 2, 1}, {"gamma_z", 1, 2}};

// The gyro block's parameters (gyro.Kx ...), in a few words.
std::string GyroParameterPhrase(const std::string& n) {
  static const char* const axis[3] = {"x", "y", "z"};
  const std::string b = n.substr(5);
  if (b.size() == 2 && b[0] == 'K') return "gyro scale factor " + n + " (gain of the " + b.substr(1) + " rate reading)";
  if (b.rfind("W0", 0) == 0) return "gyro bias " + n;
  if (b.size() == 3 && b[0] == 'G') {
    return "gyro g-sensitivity " + n + " (W" + b.substr(2) + " into the " + b.substr(1, 1) +
           " rate reading)";
  }
  for (const AngleEntry& a : kAngles) {
    if (b == a.name) {
      return "gyro misalignment " + n + " (the rate about " + axis[a.input] + " into the " +
             axis[a.reading] + " reading)";
    }
  }
  return n;
}

// What a parameter does, in a few words (base parameters; effects by name).
std::string ParameterPhrase(const std::string& n) {
  static const char* const axis[3] = {"x", "y", "z"};
  if (n.rfind("gyro.", 0) == 0) return GyroParameterPhrase(n);
  if (n.size() == 2 && n[0] == 'K' && n[1] >= 'x' && n[1] <= 'z') {
    return "scale factor " + n + " (gain of the " + n.substr(1) + " reading)";
  }
  if (n.size() == 3 && n[0] == 'K' && n[1] >= 'x' && n[1] <= 'z' && n[2] >= 'x' && n[2] <= 'z') {
    const std::string i = n.substr(1, 1), j = n.substr(2, 1);
    return (i == j ? "nonlinearity " : "cross-coupling ") + n + " (the " + i + " reading's W" + i +
           "*W" + j + " term)";
  }
  if (n.rfind("W0", 0) == 0) return "zero offset " + n;
  for (const AngleEntry& a : kAngles) {
    if (n == a.name) {
      return "non-orthogonality angle " + n + " (W" + axis[a.input] + " into the " +
             axis[a.reading] + " reading)";
    }
  }
  if (n == "dpsi") return "dpsi (tilt of the outer bench axis out of the horizontal)";
  if (n == "dtheta_c") return "dtheta_c (bench tilt about the outer axis and outer angle zero)";
  if (n == "dlambda2") return "dlambda2 (zero of the inner angle sensor)";
  return n;
}

bool IsLeverArm(const std::string& n) { return n == "dx2" || n == "dy2" || n == "dz2"; }

std::string Describe(const Weights& w) {
  if (w.empty()) return "no parameter dominates this direction";
  // A common rotation of the triad about a bench axis: the axis's angle
  // offset with the two misalignment angles about the same axis (and a little
  // lever arm), all of one sign.
  auto rotation = [&](const char* axis, const std::string& offset, const std::string& a,
                      const std::string& b, const std::vector<std::string>& lever) {
    std::vector<std::string> set = {offset, a, b};
    set.insert(set.end(), lever.begin(), lever.end());
    const bool has_a = WeightOf(w, a) != 0.0, has_b = WeightOf(w, b) != 0.0;
    if (WeightOf(w, offset) == 0.0 || !(has_a || has_b) || CommonShare(w, set) < 0.6) return std::string();
    return std::string("common rotation of the triad about the ") + axis + " bench axis (" +
           offset + " with " + (has_a ? a : "") + (has_a && has_b ? ", " : "") + (has_b ? b : "") +
           ")";
  };
  const std::string inner = rotation("inner", "dlambda2", "gamma_y", "gamma_z", {"dy2", "dz2"});
  if (!inner.empty()) return inner;
  const std::string outer = rotation("outer", "dtheta_c", "beta_x", "beta_z", {"dx2", "dz2"});
  if (!outer.empty()) return outer;
  if (WeightOf(w, "dpsi") != 0.0 &&
      (WeightOf(w, "alpha_x") != 0.0 || WeightOf(w, "alpha_y") != 0.0 ||
       WeightOf(w, "beta_z") != 0.0)) {
    return "rotation of the triad and the bench about the vertical";
  }
  for (const char* a : {"x", "y", "z"}) {
    const std::string k = std::string("K") + a, b = std::string("W0") + a;
    double share = 0.0, all = 0.0;
    for (const auto& p : w) {
      all += p.second * p.second;
      if (p.first == k || p.first == b) share += p.second * p.second;
    }
    if (WeightOf(w, k) != 0.0 && WeightOf(w, b) != 0.0 && share >= 0.8 * all) {
      return std::string("scale factor and zero offset of the ") + a +
             " axis together (told apart only by a specific force along " + a + " that varies)";
    }
  }
  bool lever_only = true;
  for (const auto& p : w) lever_only = lever_only && IsLeverArm(p.first);
  if (lever_only) {
    std::string names;
    for (const auto& p : w) names += (names.empty() ? "" : ", ") + p.first;
    return "lever-arm error " + names +
           " (acts only through rotations about axes across it; none along a rotation axis, "
           "none at rest)";
  }
  if (std::abs(w.front().second) >= 0.9) {
    std::string s = ParameterPhrase(w.front().first);
    for (std::size_t i = 1; i < w.size(); ++i) s += (i == 1 ? ", with a little " : ", ") + w[i].first;
    return s;
  }
  std::string s = "combination of ";
  for (std::size_t i = 0; i < w.size(); ++i) s += (i ? ", " : "") + w[i].first;
  return s;
}

}  // namespace

namespace {

// Weak directions among the parameters in `subset` (the others marginalised).
std::vector<WeakDirection> WeakDirectionsOf(const ParameterLayout& layout,
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

}  // namespace

std::string DescribeDirection(const std::vector<std::pair<std::string, double>>& weights) {
  return Describe(weights);
}

std::vector<WeakDirection> FindWeakDirections(const ParameterLayout& layout,
                                              const Eigen::MatrixXd& posterior_cov,
                                              const Eigen::VectorXd& prior_sigma,
                                              double min_information) {
  std::vector<int> all(prior_sigma.size());
  for (int i = 0; i < static_cast<int>(all.size()); ++i) all[i] = i;
  return WeakDirectionsOf(layout, posterior_cov, prior_sigma, all, min_information);
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

std::vector<PriorExcursion> BeyondPrior(const ParameterLayout& layout,
                                        const Eigen::VectorXd& theta,
                                        const Eigen::VectorXd& prior_mean,
                                        const Eigen::VectorXd& prior_sigma, double n_sigma) {
  std::vector<PriorExcursion> out;
  for (int i = 0; i < layout.size(); ++i) {
    if (!(prior_sigma[i] > 0.0)) continue;
    const double z = (theta[i] - prior_mean[i]) / prior_sigma[i];
    if (std::abs(z) > n_sigma) out.push_back({layout.info(i).name, z});
  }
  std::stable_sort(out.begin(), out.end(), [](const PriorExcursion& a, const PriorExcursion& b) {
    return std::abs(a.z) > std::abs(b.z);
  });
  return out;
}

std::string DescribeExcursions(const std::vector<PriorExcursion>& excursions) {
  std::string s;
  for (const PriorExcursion& e : excursions) {
    char z[32];
    std::snprintf(z, sizeof(z), " (%+.1f)", e.z);
    s += (s.empty() ? "" : " ") + e.name + z;
  }
  return s;
}

}  // namespace triadcal
