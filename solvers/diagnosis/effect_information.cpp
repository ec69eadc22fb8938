#include "solvers/diagnosis/effect_information.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "solvers/estimation/run_evaluation.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/schur_covariance.h"
#include "solvers/estimation/state_space_model.h"
#include "solvers/statistics/statistics.h"

namespace triadcal {
namespace {

Eigen::MatrixXd Rows(const Eigen::MatrixXd& m, const std::vector<int>& r,
                     const std::vector<int>& c) {
  Eigen::MatrixXd out(r.size(), c.size());
  for (std::size_t i = 0; i < r.size(); ++i)
    for (std::size_t j = 0; j < c.size(); ++j) out(i, j) = m(r[i], c[j]);
  return out;
}

Eigen::VectorXd Entries(const Eigen::VectorXd& v, const std::vector<int>& r) {
  Eigen::VectorXd out(r.size());
  for (std::size_t i = 0; i < r.size(); ++i) out[i] = v[r[i]];
  return out;
}

// Pivoted Cholesky of an information matrix in prior units: the indices kept,
// most informative first, while what is left of each is at least min_info
// (batch_solver.cpp's SupportedParameters, for one effect given the base).
std::vector<int> Supported(Eigen::MatrixXd S, double min_info) {
  std::vector<int> kept;
  std::vector<bool> used(S.rows(), false);
  for (;;) {
    int best = -1;
    for (int j = 0; j < S.rows(); ++j) {
      if (!used[j] && S(j, j) >= min_info && (best < 0 || S(j, j) > S(best, best))) best = j;
    }
    if (best < 0) break;
    used[best] = true;
    kept.push_back(best);
    const Eigen::VectorXd col = S.col(best) / std::sqrt(S(best, best));
    S -= col * col.transpose();
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

// Leaning (issue 12): the conditional information of the columns `cols`
// (prior units: scaled by prior_sigma, their own prior removed) given the base
// parameters `anchored`, with the prior information of the anchored entries
// listed in `only` (all when empty) loosened kLoosen times -- and the held
// ones, which are free in I under their priors, released the same way. What
// survives is what the data determine apart from the base parameters' priors
// and holds; a component with (nearly) nothing left rides on a direction the
// run does not determine.
constexpr double kLoosen = 1e4;
Eigen::MatrixXd LooseConditional(const Eigen::MatrixXd& I, const std::vector<int>& anchored,
                                 const Eigen::VectorXd& anchored_prior_info,
                                 const std::vector<int>& only, const std::vector<int>& cols,
                                 const Eigen::VectorXd& prior_sigma) {
  Eigen::MatrixXd Iaa = Rows(I, anchored, anchored);
  const double keep = 1.0 / kLoosen;
  if (only.empty()) {
    Iaa.diagonal() -= (1.0 - keep) * anchored_prior_info;
  } else {
    for (int a : only) Iaa(a, a) -= (1.0 - keep) * anchored_prior_info[a];
  }
  const Eigen::MatrixXd Iac = Rows(I, anchored, cols);
  Eigen::MatrixXd N = Rows(I, cols, cols) - Iac.transpose() * Iaa.ldlt().solve(Iac);
  N.diagonal() -= prior_sigma.cwiseInverse().cwiseAbs2();
  return prior_sigma.asDiagonal() * N * prior_sigma.asDiagonal();
}

// For an effect whose parameter i belongs to axis i and needs it reversed
// (EffectNeeds::both_signs_per_axis): per parameter, why its axis does not
// reverse, or "" when it does (or the effect has no such need). The reading
// less the zero offset of the current fit must exceed 4 noise sigma on at
// least 5 % of the samples each way: below that, the sign of u that |u|
// needs is the noise's, and a one-signed axis makes |u| = +-u, the scale.
std::vector<std::string> OneSidedAxes(const EffectSpec& spec, const RunData& data,
                                      const Eigen::Vector3d& noise_mV,
                                      const Eigen::VectorXd& theta) {
  std::vector<std::string> why(spec.params.size());
  if (!spec.needs.both_signs_per_axis) return why;
  constexpr double kSigmas = 4.0, kShare = 0.05;
  static const char* const kAxis[3] = {"x", "y", "z"};
  for (std::size_t q = 0; q < spec.params.size() && q < 3; ++q) {
    const double w0 = theta[kW0x + static_cast<int>(q)], band = kSigmas * noise_mV[q];
    std::size_t pos = 0, neg = 0;
    for (double w : data.w_mV[q]) {
      pos += w - w0 > band ? 1 : 0;
      neg += w - w0 < -band ? 1 : 0;
    }
    const double n = static_cast<double>(std::max<std::size_t>(1, data.size()));
    if (pos < kShare * n || neg < kShare * n) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "the %s axis does not reverse (its reading leaves the zero offset by more "
                    "than %.0f noise sigma on %.1f %% of the samples upwards and %.1f %% "
                    "downwards; %.0f %% needed each way)",
                    kAxis[q], kSigmas, 100.0 * pos / n, 100.0 * neg / n, 100.0 * kShare);
      why[q] = buf;
    }
  }
  return why;
}


}  // namespace

EffectInformation AnalyseCandidates(const RunDescription& run, const RunData& data,
                                    const std::vector<Effect>& current, const BatchResult& fit,
                                    const std::vector<Effect>& candidates,
                                    const BatchOptions& options) {
  const int threads = options.threads > 0 ? options.threads : DefaultThreads();
  const ParameterLayout cur(current);
  std::vector<Effect> all = current;
  all.insert(all.end(), candidates.begin(), candidates.end());
  const ParameterLayout full(all);
  // The model with every candidate added at zero, evaluated at the fit as
  // the fit evaluates it (run_evaluation.h): the same noise weights (their
  // shape at the nominal values, the fit's reading noise), the trajectory
  // solved for; the Jacobian's columns of the candidates come with it.
  RunProblem p = BuildRunProblem(run, data, full, options.epoch_s, options.derivatives);
  if (fit.noise_used_mV.minCoeff() > 0.0) p.noise_mV = fit.noise_used_mV;
  const std::size_t E = p.epochs.size();
  if (fit.process_residual.size() != E || fit.measurement_residual.size() != E) {
    throw std::logic_error("AnalyseCandidates: the fit's epochs are not the run problem's");
  }
  Eigen::VectorXd theta = p.prior.mean;
  for (int i = 0; i < cur.size(); ++i) {
    theta[full.IndexOf(cur.info(i).name)] = fit.estimate.theta[i];
  }
  for (Effect e : candidates) {
    const int k = static_cast<int>(GetEffectSpec(e).params.size());
    for (int q = 0; q < k; ++q) theta[full.offset(e) + q] = 0.0;
  }
  const RunPass weights = WeightsPass(p, p.prior.mean, threads);
  const RunReduction red =
      Reduce(p, EvaluatePass(p, theta, true, threads), weights, p.noise_mV, threads);
  // The fit's held and considered parameters are not base parameters of the
  // tests below (the tests hold them), only of the check that an effect does
  // not ride on them (LooseConditional): free here, under their priors.
  // (The gyro's parameters are not in these layouts: the tests are on the
  // accelerometer's part, which they do not enter.)
  std::vector<int> held;
  for (const std::vector<std::string>* names : {&fit.held, &fit.consider}) {
    for (const std::string& h : *names) {
      if (full.IndexOf(h) >= 0) held.push_back(full.IndexOf(h));
    }
  }
  std::sort(held.begin(), held.end());
  const int nf = full.size();
  // Every parameter free: information and gradient of the data, the priors
  // and the constraints.
  Eigen::MatrixXd I = red.information;
  Eigen::VectorXd g = red.gradient;
  for (int i = 0; i < nf; ++i) {
    I(i, i) += 1.0 / (p.prior.sigma[i] * p.prior.sigma[i]);
    g[i] += (theta[i] - p.prior.mean[i]) / (p.prior.sigma[i] * p.prior.sigma[i]);
  }
  for (const ConstraintRow& c : p.constraints) {
    I += c.c * c.c.transpose() / (c.sigma * c.sigma);
    g += c.c * (c.c.dot(theta) - c.value) / (c.sigma * c.sigma);
  }
  p.free.resize(nf);
  for (int i = 0; i < nf; ++i) p.free[i] = i;

  // Free indices: base (the current layout's free parameters) and each candidate's.
  std::vector<int> free_of(full.size(), -1);
  for (int j = 0; j < nf; ++j) free_of[p.free[j]] = j;
  EffectInformation out;
  out.chi2_per_dof = fit.chi2_per_dof;
  std::vector<int> base;
  for (int i = 0; i < cur.size(); ++i) {
    const int f = full.IndexOf(cur.info(i).name);
    if (std::binary_search(held.begin(), held.end(), f)) continue;
    base.push_back(free_of[f]);
    out.base_names.push_back(cur.info(i).name);
  }
  // Every base parameter, free or held, with its prior's information (for LooseConditional).
  std::vector<int> anchored = base;
  std::vector<std::string> anchored_names = out.base_names;
  for (int i : held) {
    anchored.push_back(free_of[i]);
    anchored_names.push_back(full.info(i).name);
  }
  Eigen::VectorXd anchored_prior_info(anchored.size());
  for (std::size_t a = 0; a < anchored.size(); ++a) {
    anchored_prior_info[a] = 1.0 / std::pow(p.prior.sigma[p.free[anchored[a]]], 2);
  }
  const Eigen::MatrixXd Ibb = Rows(I, base, base);
  const Eigen::LDLT<Eigen::MatrixXd> bb(Ibb);
  const Eigen::MatrixXd Cbb = bb.solve(Eigen::MatrixXd::Identity(base.size(), base.size()));
  out.base_sigma = Cbb.diagonal().cwiseSqrt();
  const Eigen::VectorXd gb = Entries(g, base);
  out.base_gradient_sigma = std::sqrt(std::max(0.0, gb.dot(Cbb * gb)));

  for (Effect e : candidates) {
    CandidateInformation c;
    c.effect = e;
    const int k_all = static_cast<int>(GetEffectSpec(e).params.size());
    std::vector<int> cols(k_all);
    Eigen::VectorXd prior_sigma(k_all);
    for (int q = 0; q < k_all; ++q) {
      cols[q] = free_of[full.offset(e) + q];
      prior_sigma[q] = p.prior.sigma[full.offset(e) + q];
    }
    // Conditional data information (the prior's 1/sigma^2 removed) in prior units.
    const Eigen::MatrixXd Ibe_all = Rows(I, base, cols);
    Eigen::MatrixXd N_all = Rows(I, cols, cols) - Ibe_all.transpose() * bb.solve(Ibe_all);
    N_all.diagonal() -= prior_sigma.cwiseInverse().cwiseAbs2();
    const Eigen::MatrixXd Np = prior_sigma.asDiagonal() * N_all * prior_sigma.asDiagonal();
    // Supported: by the data apart from what the base parameters' priors and
    // holds supply (LooseConditional); a component that only those determine is
    // held, with the base parameter it leans on named.
    const std::vector<int> by_data = Supported(Np, kMinInformationSupported);
    // Components whose axis never reverses are left out before the rest is
    // decided (their information is that of the noise's sign, or of K u).
    const std::vector<std::string> one_sided =
        OneSidedAxes(GetEffectSpec(e), data, p.noise_mV, fit.estimate.theta);
    std::vector<int> two_sided;
    for (int q = 0; q < k_all; ++q) {
      if (one_sided[q].empty()) two_sided.push_back(q);
    }
    const Eigen::MatrixXd Nloose =
        LooseConditional(I, anchored, anchored_prior_info, {}, cols, prior_sigma);
    for (int q :
         Supported(Rows(Nloose, two_sided, two_sided), kMinInformationSupported)) {
      c.supported.push_back(two_sided[q]);
    }
    // The base parameter whose loosening alone removes the most of
    // component q's conditional information: the one it leans on.
    auto leans_on = [&](int q) {
      double least = std::numeric_limits<double>::infinity();
      std::string on;
      for (std::size_t a = 0; a < anchored.size(); ++a) {
        const double left =
            LooseConditional(I, anchored, anchored_prior_info, {static_cast<int>(a)}, {cols[q]},
                             prior_sigma.segment(q, 1))(0, 0);
        if (left < least) {
          least = left;
          on = anchored_names[a];
        }
      }
      return on;
    };
    // Not separable from the base parameters (its multiple correlation with
    // them, their priors loosened, at least 0.99: it keeps less than
    // kMinSeparableShare of its own data information): what it would fit,
    // they fit (cross_quadratic.z_xx_yy and Kzz on a single-axis run, rho
    // 0.9993). Not tested; in a refit it stays at zero, considered.
    {
      std::vector<int> separable;
      for (int q : c.supported) {
        const double sq = prior_sigma[q] * prior_sigma[q];
        const double own = (I(cols[q], cols[q]) - 1.0 / sq) * sq;
        if (own > 0.0 && Nloose(q, q) < kMinSeparableShare * own) {
          const double rho = std::sqrt(std::max(0.0, 1.0 - Nloose(q, q) / own));
          c.not_separable.push_back({q, leans_on(q), rho});
        } else {
          separable.push_back(q);
        }
      }
      c.supported = separable;
    }
    for (int q = 0; q < k_all; ++q) {
      if (std::find(c.supported.begin(), c.supported.end(), q) != c.supported.end()) continue;
      if (std::any_of(c.not_separable.begin(), c.not_separable.end(),
                      [q](const NotSeparable& n) { return n.component == q; })) {
        continue;
      }
      c.unsupported.push_back(q);
      if (std::find(by_data.begin(), by_data.end(), q) == by_data.end()) continue;
      if (!one_sided[q].empty()) {
        c.held_because.emplace_back(q, one_sided[q]);
        continue;
      }
      // Which base parameter's prior or hold supplies what q needs.
      const std::string on = leans_on(q);
      c.held_because.emplace_back(q, "this run determines it only through " + on +
                                         "'s prior or hold (" + on +
                                         " is not determined by this run)");
    }
    {
      const Eigen::MatrixXd Ns = Rows(Nloose, c.supported, c.supported);
      const std::vector<int> strong = Supported(Ns, kMinInformationFound);
      for (std::size_t i = 0; i < c.supported.size(); ++i) {
        if (std::find(strong.begin(), strong.end(), static_cast<int>(i)) == strong.end()) {
          c.weak.emplace_back(c.supported[i], Ns(i, i));
        }
      }
    }
    const int k = static_cast<int>(c.supported.size());
    if (k > 0) {
      std::vector<int> sc;
      for (int q : c.supported) sc.push_back(cols[q]);
      const Eigen::MatrixXd Ibe = Rows(I, base, sc);
      c.B = bb.solve(Ibe);
      const Eigen::MatrixXd with_prior = Rows(I, sc, sc) - Ibe.transpose() * c.B;
      c.N = Rows(N_all, c.supported, c.supported);
      const Eigen::VectorXd ge = Entries(g, sc);
      c.score = std::max(0.0, ge.dot(with_prior.ldlt().solve(ge)));
      // Newton step on (theta_b, theta_e): the block solve with the base
      // gradient (~0) included.
      std::vector<int> bs = base;
      bs.insert(bs.end(), sc.begin(), sc.end());
      const Eigen::VectorXd step = -Rows(I, bs, bs).ldlt().solve(Entries(g, bs));
      c.step_base = step.head(base.size());
      c.step_effect = step.tail(k);
      const double chi2_aug =
          (2.0 * fit.final_cost - c.score) / std::max(1, fit.degrees_of_freedom - k);
      c.statistic = c.score / std::max(1.0, chi2_aug);
      c.p_value = ChiSquareSurvival(c.statistic, k);
      std::vector<int> strong;
      for (int q : c.supported) {
        if (std::none_of(c.weak.begin(), c.weak.end(),
                         [&](const std::pair<int, double>& w) { return w.first == q; })) {
          strong.push_back(cols[q]);
        }
      }
      if (strong.size() == sc.size()) {
        c.statistic_strong = c.statistic;
        c.p_value_strong = c.p_value;
      } else if (!strong.empty()) {
        const Eigen::MatrixXd Ibs = Rows(I, base, strong);
        const Eigen::MatrixXd ws = Rows(I, strong, strong) - Ibs.transpose() * bb.solve(Ibs);
        const Eigen::VectorXd gs = Entries(g, strong);
        c.statistic_strong = std::max(0.0, gs.dot(ws.ldlt().solve(gs))) / std::max(1.0, chi2_aug);
        c.p_value_strong = ChiSquareSurvival(c.statistic_strong, static_cast<int>(strong.size()));
      }
    }
    out.candidates.push_back(c);
  }
  return out;
}

HideCase MinimalDetectable(const EffectInformation& info, const CandidateInformation& c,
                           double alpha, double power) {
  const EffectSpec& spec = GetEffectSpec(c.effect);
  HideCase h;
  h.effect = c.effect;
  h.alpha = alpha;
  h.power = power;
  h.unit = spec.params.front().unit;
  for (int q : c.unsupported) h.undetectable.push_back(spec.params[q].name);
  const int k = static_cast<int>(c.supported.size());
  if (k == 0) {
    h.minimal_detectable = std::numeric_limits<double>::infinity();
    return h;
  }
  h.lambda0 = NoncentralityForPower(alpha, k, power) * std::max(1.0, info.chi2_per_dof);
  // N in file units: theta_SI = v_file * si_per_unit.
  Eigen::VectorXd to_si(k);
  for (int q = 0; q < k; ++q) to_si[q] = spec.params[c.supported[q]].si_per_unit;
  const Eigen::MatrixXd Nf = to_si.asDiagonal() * c.N * to_si.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (Nf + Nf.transpose()));
  const double mu = std::max(es.eigenvalues()[0], 1e-300);
  h.minimal_detectable = std::sqrt(h.lambda0 / mu);
  Eigen::VectorXd v = es.eigenvectors().col(0);
  Eigen::Index largest = 0;
  v.cwiseAbs().maxCoeff(&largest);
  if (v[largest] < 0.0) v = -v;
  for (int q = 0; q < k; ++q) {
    h.direction.emplace_back(spec.params[c.supported[q]].name, h.minimal_detectable * v[q]);
  }
  // Largest shift over the undetected effects, parameter by parameter.
  const Eigen::MatrixXd Ninv = c.N.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
  for (int j = 0; j < c.B.rows(); ++j) {
    const Eigen::VectorXd bj = c.B.row(j).transpose();
    const double shift =
        std::sqrt(std::max(0.0, h.lambda0 * bj.dot(Ninv * bj))) / info.base_sigma[j];
    if (shift > h.max_shift_sigma) {
      h.max_shift_sigma = shift;
      h.parameter = info.base_names[j];
    }
  }
  return h;
}

}  // namespace triadcal
