#include "solvers/estimation/observability.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "solvers/estimation/gyro_term.h"
#include "solvers/estimation/run_evaluation.h"
#include "solvers/estimation/parallel.h"

namespace triadcal {
namespace {

Eigen::MatrixXd Symmetric(const Eigen::MatrixXd& m) { return 0.5 * (m + m.transpose()); }

// Weights >= 0.2 of a unit vector (prior units), largest first, the first positive.
std::vector<std::pair<std::string, double>> NamedWeights(const ParameterLayout& layout,
                                                         const Eigen::VectorXd& v) {
  std::vector<std::pair<std::string, double>> w;
  for (int i = 0; i < v.size(); ++i) {
    if (std::abs(v[i]) >= 0.2) w.push_back({layout.info(i).name, v[i]});
  }
  std::sort(w.begin(), w.end(),
            [](const auto& a, const auto& b) { return std::abs(a.second) > std::abs(b.second); });
  if (!w.empty() && w.front().second < 0) {
    for (auto& p : w) p.second = -p.second;
  }
  return w;
}

Direction MakeDirection(const ParameterLayout& layout, const Eigen::VectorXd& v_unit,
                        double lambda, const Eigen::VectorXd& prior_sigma, bool observable) {
  Direction d;
  d.v_prior = v_unit;
  // Sign convention: the largest weight positive.
  Eigen::Index imax = 0;
  v_unit.cwiseAbs().maxCoeff(&imax);
  if (v_unit[imax] < 0) d.v_prior = -v_unit;
  d.named.weights = NamedWeights(layout, d.v_prior);
  d.named.data_information = std::max(0.0, lambda);
  d.named.sigma_ratio = 1.0 / std::sqrt(1.0 + std::max(0.0, lambda));
  d.named.description = DescribeDirection(d.named.weights);
  if (observable) {
    d.data_sigma = d.v_prior.cwiseAbs().cwiseProduct(prior_sigma) / std::sqrt(lambda);
  }
  return d;
}

// Reduced row-echelon form of the rows of B (k x n), pivoting on the largest
// entry left: each row ends with 1 in its own pivot column and 0 in the others'.
Eigen::MatrixXd RowEchelon(Eigen::MatrixXd B) {
  const int k = static_cast<int>(B.rows());
  for (int r = 0; r < k; ++r) {
    Eigen::Index pr = 0, pc = 0;
    B.bottomRows(k - r).cwiseAbs().maxCoeff(&pr, &pc);
    pr += r;
    if (std::abs(B(pr, pc)) < 1e-12) break;
    B.row(r).swap(B.row(pr));
    B.row(r) /= B(r, pc);
    for (int o = 0; o < k; ++o) {
      if (o != r) B.row(o) -= B(o, pc) * B.row(r);
    }
  }
  return B;
}

}  // namespace

Eigen::MatrixXd DataInformation(const RunProblem& p, const Eigen::VectorXd& theta, int threads) {
  if (threads <= 0) threads = DefaultThreads();
  // The noise weights' shape at the nominal values, as the fit's (run_evaluation.h).
  const RunPass weights = WeightsPass(p, p.prior.mean, threads);
  const RunPass pass = EvaluatePass(p, theta, true, threads);
  Eigen::MatrixXd info =
      Reduce(p, pass, weights, p.noise_mV, threads, ThetaPart::kGradientAndInformationAtFixedNoise)
          .information;
  if (RunHasGyro(p)) {  // the gyro's increments at its noise (gyro_term.h)
    // The information only: no gradient terms of the weights, no scores.
    info += ReduceGyro(EvaluateGyroPass(p, theta, true, threads), p.gyro_noise_rad_s, 1.0,
                       /*theta_part=*/true, /*with_scores=*/false)
                .information;
  }
  return Symmetric(info);
}

void ClassifyDirections(const ParameterLayout& layout, const Eigen::MatrixXd& information,
                        const Eigen::VectorXd& prior_sigma, const ObservabilityThresholds& t,
                        std::vector<Direction>* unobservable, std::vector<Direction>* weak) {
  const Eigen::MatrixXd In =
      Symmetric(prior_sigma.asDiagonal() * information * prior_sigma.asDiagonal());
  if (!In.allFinite()) {  // a fit whose cost is not finite: nothing to classify
    if (unobservable) unobservable->clear();
    if (weak) weak->clear();
    return;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(In);
  const Eigen::VectorXd& lam = es.eigenvalues();  // ascending
  const int n = static_cast<int>(lam.size());
  int k = 0;
  while (k < n && lam[k] < t.unobservable) ++k;
  if (unobservable) {
    unobservable->clear();
    if (k > 0) {
      const Eigen::MatrixXd B = RowEchelon(es.eigenvectors().leftCols(k).transpose());
      // In the layout's order of their main parameters (the first of those
      // with at least half the largest weight): the null space's basis from
      // the eigensolver turns with rounding (exact nulls share one
      // eigenvalue), the directions it spans do not.
      std::vector<std::pair<int, int>> order;  // main parameter, row
      for (int r = 0; r < k; ++r) {
        if (B.row(r).norm() < 1e-9) continue;  // cannot happen for a basis; guards normalized()
        const double big = B.row(r).cwiseAbs().maxCoeff();
        int first = 0;
        while (std::abs(B(r, first)) < 0.5 * big) ++first;
        order.push_back({first, r});
      }
      std::stable_sort(order.begin(), order.end());
      for (const auto& [first, r] : order) {
        const Eigen::VectorXd v = B.row(r).transpose().normalized();
        unobservable->push_back(MakeDirection(layout, v, v.dot(In * v), prior_sigma, false));
      }
    }
  }
  if (weak) {
    weak->clear();
    for (int j = k; j < n && lam[j] < t.weak; ++j) {
      weak->push_back(MakeDirection(layout, es.eigenvectors().col(j), lam[j], prior_sigma, true));
    }
  }
}

ObservabilityVariant MakeVariant(const ParameterLayout& layout, const Eigen::MatrixXd& data_info,
                                 const Prior& prior, const std::vector<ConstraintRow>& rows,
                                 const std::vector<std::string>& exprs, const std::string& name,
                                 const ObservabilityThresholds& t) {
  ObservabilityVariant v;
  v.name = name;
  v.constraints = exprs;
  v.information = data_info;
  for (const ConstraintRow& r : rows) {
    v.information.noalias() += r.c * r.c.transpose() / (r.sigma * r.sigma);
  }
  const Eigen::VectorXd& s = prior.sigma;
  const int n = static_cast<int>(s.size());
  const Eigen::MatrixXd In = Symmetric(s.asDiagonal() * v.information * s.asDiagonal());
  const Eigen::MatrixXd Cn = Eigen::LDLT<Eigen::MatrixXd>(In + Eigen::MatrixXd::Identity(n, n))
                                 .solve(Eigen::MatrixXd::Identity(n, n));
  v.cov = Symmetric(s.asDiagonal() * Cn * s.asDiagonal());
  v.eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(In, Eigen::EigenvaluesOnly)
                      .eigenvalues();
  ClassifyDirections(layout, v.information, s, t, &v.unobservable, &v.weak);
  return v;
}

ObservabilityResult AnalyseObservability(const RunDescription& run, const RunProblem& p,
                                         const Eigen::VectorXd& theta,
                                         const ObservabilityOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  ObservabilityResult r;
  r.layout = p.cfg.layout;
  r.theta = theta;
  r.prior = p.prior;
  const RunData& data = *p.series.run;
  r.samples = data.size();
  r.epochs = p.epochs.size();
  r.duration_s = data.t_s.back() - data.t_s.front();
  r.data_information = DataInformation(p, theta, opt.threads);

  std::vector<std::string> exprs;
  for (const Constraint& c : run.constraints) exprs.push_back(c.expr);
  const ObservabilityThresholds& t = opt.thresholds;
  r.with_constraints = MakeVariant(r.layout, r.data_information, r.prior, p.constraints, exprs,
                                   "with constraints", t);
  r.without_constraints =
      MakeVariant(r.layout, r.data_information, r.prior, {}, {}, "without constraints", t);
  for (std::size_t j = 0; j < p.constraints.size(); ++j) {
    std::vector<ConstraintRow> rows;
    std::vector<std::string> names;
    for (std::size_t o = 0; o < p.constraints.size(); ++o) {
      if (o == j) continue;
      rows.push_back(p.constraints[o]);
      names.push_back(exprs[o]);
    }
    r.without_each.push_back(MakeVariant(r.layout, r.data_information, r.prior, rows, names,
                                         "without '" + exprs[j] + "'", t));
    r.without_each.back().dropped = exprs[j];
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

std::vector<WeakDirection> UnsupportedDirections(const RunProblem& p, const Eigen::VectorXd& theta,
                                                 const ObservabilityThresholds& t) {
  Eigen::MatrixXd info = DataInformation(p, theta, 0);
  for (const ConstraintRow& r : p.constraints) {
    info.noalias() += r.c * r.c.transpose() / (r.sigma * r.sigma);
  }
  std::vector<Direction> dirs;
  ClassifyDirections(p.cfg.layout, info, p.prior.sigma, t, &dirs, nullptr);
  std::vector<WeakDirection> out;
  for (const Direction& d : dirs) out.push_back(d.named);
  return out;
}

std::vector<WeakDirection> UnsupportedDirections(const ParameterLayout& layout,
                                                 const Eigen::MatrixXd& posterior_cov,
                                                 const Eigen::VectorXd& prior_sigma,
                                                 const ObservabilityThresholds& t) {
  // Held parameters (zero posterior variance) are not estimated: they are
  // left out, so that their infinite information cannot mix into the weak
  // directions of the estimated ones.
  std::vector<int> est;
  for (int i = 0; i < posterior_cov.rows(); ++i) {
    if (posterior_cov(i, i) > 0.0) est.push_back(i);
  }
  const int m = static_cast<int>(est.size());
  const int n = static_cast<int>(prior_sigma.size());
  Eigen::MatrixXd P(m, m);
  Eigen::VectorXd sinv(m);
  for (int a = 0; a < m; ++a) {
    sinv[a] = 1.0 / prior_sigma[est[a]];
    for (int b = 0; b < m; ++b) P(a, b) = posterior_cov(est[a], est[b]);
  }
  const Eigen::MatrixXd Pn = Symmetric(sinv.asDiagonal() * P * sinv.asDiagonal());
  // A fit whose cost was not finite has no covariance to read (NaN variances:
  // nothing counts as estimated, and Eigen's solver crashes on an empty
  // matrix): nothing is named.
  if (m == 0 || !Pn.allFinite()) return {};
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Pn);
  const Eigen::VectorXd info = es.eigenvalues().cwiseMax(1e-300).cwiseInverse().array() - 1.0;
  const Eigen::MatrixXd In = es.eigenvectors() * info.asDiagonal() * es.eigenvectors().transpose();
  const Eigen::MatrixXd Ie = sinv.asDiagonal() * In * sinv.asDiagonal();
  // Back to all n parameters; a held one carries no information here and
  // gets a direction of its own that ClassifyDirections would report, so it
  // is given an information far above any threshold instead.
  Eigen::MatrixXd I = Eigen::MatrixXd::Zero(n, n);
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) I(est[a], est[b]) = Ie(a, b);
  for (int i = 0; i < n; ++i) {
    if (!(posterior_cov(i, i) > 0.0)) I(i, i) = 1e12 / (prior_sigma[i] * prior_sigma[i]);
  }
  std::vector<Direction> dirs;
  ClassifyDirections(layout, I, prior_sigma, t, &dirs, nullptr);
  std::vector<WeakDirection> out;
  for (const Direction& d : dirs) out.push_back(d.named);
  return out;
}

}  // namespace triadcal
