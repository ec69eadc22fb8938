#include "solvers/diagnosis/effect_information.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "solvers/estimation/gyro_term.h"
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

namespace {

// The score tests of a round (AnalyseCandidates), step by step: the run
// linearised with every candidate at zero, the base parameters, then per
// candidate what the run supports of it and its score test.
class CandidateAnalysis {
 public:
  CandidateAnalysis(const RunDescription& run, const RunData& data,
                    const std::vector<Effect>& current, const BatchResult& fit,
                    const std::vector<Effect>& candidates, const BatchOptions& options)
      : run_(run), data_(data), current_(current), fit_(fit), candidates_(candidates),
        options_(options) {}

  EffectInformation Run() {
    Linearise();
    Base();
    for (Effect e : candidates_) out_.candidates.push_back(Candidate(e));
    return std::move(out_);
  }

 private:
  // The model with every candidate added at zero, evaluated at the fit as
  // the fit evaluates it (run_evaluation.h): the same noise weights (their
  // shape at the nominal values, the fit's reading noise), the trajectory
  // solved for; the Jacobian's columns of the candidates come with it. Every
  // parameter free: information and gradient of the data, the priors and the
  // constraints.
  void Linearise() {
    const int threads = options_.threads > 0 ? options_.threads : DefaultThreads();
    gyro_ = fit_.gyro.present;
    const ParameterLayout cur(current_, gyro_);
    std::vector<Effect> all = current_;
    all.insert(all.end(), candidates_.begin(), candidates_.end());
    full_ = ParameterLayout(all, gyro_);
    p_ = BuildRunProblem(run_, data_, full_, options_.epoch_s, options_.derivatives,
                         options_.shared, threads);
    if (fit_.noise_used_mV.minCoeff() > 0.0) p_.noise_mV = fit_.noise_used_mV;
    const std::size_t E = p_.epochs.size();
    if (fit_.process_residual.size() != E || fit_.measurement_residual.size() != E) {
      throw std::logic_error("AnalyseCandidates: the fit's epochs are not the run problem's");
    }
    Eigen::VectorXd theta = p_.prior.mean;
    for (int i = 0; i < cur.size(); ++i) {
      theta[full_.IndexOf(cur.info(i).name)] = fit_.estimate.theta[i];
    }
    for (Effect e : candidates_) {
      const int k = static_cast<int>(GetEffectSpec(e).params.size());
      for (int q = 0; q < k; ++q) theta[full_.offset(e) + q] = 0.0;
    }
    // The accelerometer's part on the layout of what acts on it: without the
    // gyro block and the gyro-stage effects (their columns there are zero),
    // within the 64 parameters of its Jacobian (inertial_increments.cpp); the
    // whole catalogue and the gyro block are 87.
    std::vector<Effect> accel_effects;
    for (Effect e : all) {
      if (GetEffectSpec(e).stage != EffectStage::kGyro) accel_effects.push_back(e);
    }
    const bool split = gyro_ || accel_effects.size() != all.size();
    RunProblem pa;
    if (split) {
      pa = BuildRunProblem(run_, data_, ParameterLayout(accel_effects), options_.epoch_s,
                           options_.derivatives, options_.shared, threads);
      pa.noise_mV = p_.noise_mV;
    }
    const RunProblem& accel = split ? pa : p_;
    std::vector<int> to_full(accel.cfg.layout.size());
    Eigen::VectorXd theta_accel(accel.cfg.layout.size());
    for (int i = 0; i < accel.cfg.layout.size(); ++i) {
      to_full[i] = full_.IndexOf(accel.cfg.layout.info(i).name);
      theta_accel[i] = theta[to_full[i]];
    }
    const std::shared_ptr<const RunPass> weights =
        options_.shared ? options_.shared->Weights(accel, threads)
                        : std::make_shared<const RunPass>(
                              WeightsPass(accel, accel.prior.mean, threads));
    const RunReduction red =
        Reduce(accel, EvaluatePass(accel, theta_accel, true, threads), *weights, accel.noise_mV,
               threads, ThetaPart::kGradientAndInformationAtFixedNoise);
    const int nf = full_.size();
    I_ = Eigen::MatrixXd::Zero(nf, nf);
    g_ = Eigen::VectorXd::Zero(nf);
    for (std::size_t i = 0; i < to_full.size(); ++i) {
      g_[to_full[i]] = red.gradient[i];
      for (std::size_t j = 0; j < to_full.size(); ++j) {
        I_(to_full[i], to_full[j]) = red.information(i, j);
      }
    }
    for (int i = 0; i < nf; ++i) {
      I_(i, i) += 1.0 / (p_.prior.sigma[i] * p_.prior.sigma[i]);
      g_[i] += (theta[i] - p_.prior.mean[i]) / (p_.prior.sigma[i] * p_.prior.sigma[i]);
    }
    for (const ConstraintRow& c : p_.constraints) {
      I_ += c.c * c.c.transpose() / (c.sigma * c.sigma);
      g_ += c.c * (c.c.dot(theta) - c.value) / (c.sigma * c.sigma);
    }
    // The gyro's part (gyro_term.h) as the fit has it: its negative
    // log-likelihood at the noise of its maximum (from the fit's), with the
    // weights' derivatives in the gradient. The gyro-stage candidates' columns
    // are only here; the others reach it through W, the angles and dlambda2.
    if (gyro_ && RunHasGyro(p_)) {
      const GyroReduction gr = ReduceGyroAtBestNoise(EvaluateGyroPass(p_, theta, true, threads),
                                                     fit_.gyro.noise_rad_s, kNumGyroParams,
                                                     true, threads);
      I_ += gr.information;
      g_ += gr.gradient;
    }
  }

  // The base parameters: the current layout's free ones (the fit's held and
  // considered parameters are not, the tests hold them), and every base
  // parameter with its prior (anchored: for the check that an effect does not
  // ride on them, LooseConditional). With a gyro, its block is among them.
  void Base() {
    const ParameterLayout cur(current_, gyro_);
    std::vector<int> held;
    for (const std::vector<std::string>* names : {&fit_.held, &fit_.consider}) {
      for (const std::string& h : *names) {
        if (full_.IndexOf(h) >= 0) held.push_back(full_.IndexOf(h));
      }
    }
    std::sort(held.begin(), held.end());
    for (const std::string& h : fit_.consider) {
      if (full_.IndexOf(h) >= 0) considered_.push_back(full_.IndexOf(h));
    }
    out_.chi2_per_dof = fit_.chi2_per_dof;
    for (int i = 0; i < cur.size(); ++i) {
      const int f = full_.IndexOf(cur.info(i).name);
      if (std::binary_search(held.begin(), held.end(), f)) continue;
      base_.push_back(f);
      out_.base_names.push_back(cur.info(i).name);
    }
    anchored_ = base_;
    anchored_names_ = out_.base_names;
    for (int i : held) {
      anchored_.push_back(i);
      anchored_names_.push_back(full_.info(i).name);
    }
    anchored_prior_info_.resize(anchored_.size());
    for (std::size_t a = 0; a < anchored_.size(); ++a) {
      anchored_prior_info_[a] = 1.0 / std::pow(p_.prior.sigma[anchored_[a]], 2);
    }
    bb_.compute(Rows(I_, base_, base_));
    const Eigen::MatrixXd Cbb =
        bb_.solve(Eigen::MatrixXd::Identity(base_.size(), base_.size()));
    out_.base_sigma = Cbb.diagonal().cwiseSqrt();
    const Eigen::VectorXd gb = Entries(g_, base_);
    out_.base_gradient_sigma = std::sqrt(std::max(0.0, gb.dot(Cbb * gb)));
  }

  // One candidate: its columns, what the run supports of it, and its score test.
  CandidateInformation Candidate(Effect e) {
    CandidateInformation c;
    c.effect = e;
    const int k_all = static_cast<int>(GetEffectSpec(e).params.size());
    cols_.assign(k_all, 0);
    prior_sigma_.resize(k_all);
    for (int q = 0; q < k_all; ++q) {
      cols_[q] = full_.offset(e) + q;
      prior_sigma_[q] = p_.prior.sigma[full_.offset(e) + q];
    }
    Support(&c);
    if (!c.supported.empty()) Score(&c);
    return c;
  }

  // The base parameter whose loosening alone removes the most of component
  // q's conditional information: the one it leans on.
  std::string LeansOn(int q) const {
    double least = std::numeric_limits<double>::infinity();
    std::string on;
    for (std::size_t a = 0; a < anchored_.size(); ++a) {
      const double left =
          LooseConditional(I_, anchored_, anchored_prior_info_, {static_cast<int>(a)},
                           {cols_[q]}, prior_sigma_.segment(q, 1))(0, 0);
      if (left < least) {
        least = left;
        on = anchored_names_[a];
      }
    }
    return on;
  }

  // What the run supports of the candidate: supported (by the data apart from
  // what the base parameters' priors and holds supply, LooseConditional), not
  // separable, held (and why), weak.
  void Support(CandidateInformation* cp) {
    CandidateInformation& c = *cp;
    const int k_all = static_cast<int>(cols_.size());
    // Conditional data information (the prior's 1/sigma^2 removed) in prior units.
    const Eigen::MatrixXd Ibe_all = Rows(I_, base_, cols_);
    N_all_ = Rows(I_, cols_, cols_) - Ibe_all.transpose() * bb_.solve(Ibe_all);
    N_all_.diagonal() -= prior_sigma_.cwiseInverse().cwiseAbs2();
    const Eigen::MatrixXd Np = prior_sigma_.asDiagonal() * N_all_ * prior_sigma_.asDiagonal();
    // A component that only the base parameters' priors and holds determine
    // is held, with the base parameter it leans on named.
    const std::vector<int> by_data = Supported(Np, kMinInformationSupported);
    // Components whose axis never reverses are left out before the rest is
    // decided (their information is that of the noise's sign, or of K u).
    const std::vector<std::string> one_sided =
        OneSidedAxes(GetEffectSpec(c.effect), data_, p_.noise_mV, fit_.estimate.theta);
    std::vector<int> two_sided;
    for (int q = 0; q < k_all; ++q) {
      if (one_sided[q].empty()) two_sided.push_back(q);
    }
    const Eigen::MatrixXd Nloose =
        LooseConditional(I_, anchored_, anchored_prior_info_, {}, cols_, prior_sigma_);
    for (int q : Supported(Rows(Nloose, two_sided, two_sided), kMinInformationSupported)) {
      c.supported.push_back(two_sided[q]);
    }
    // Not separable from the base parameters (its multiple correlation with
    // them, their priors loosened, at least 0.99: it keeps less than
    // kMinSeparableShare of its own data information): what it would fit,
    // they fit (cross_quadratic.z_xx_yy and Kzz on a single-axis run, rho
    // 0.9993). Not tested; in a refit it stays at zero, considered.
    std::vector<int> separable;
    for (int q : c.supported) {
      const double sq = prior_sigma_[q] * prior_sigma_[q];
      const double own = (I_(cols_[q], cols_[q]) - 1.0 / sq) * sq;
      if (own > 0.0 && Nloose(q, q) < kMinSeparableShare * own) {
        const double rho = std::sqrt(std::max(0.0, 1.0 - Nloose(q, q) / own));
        c.not_separable.push_back({q, LeansOn(q), rho});
      } else {
        separable.push_back(q);
      }
    }
    c.supported = separable;
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
      const std::string on = LeansOn(q);
      c.held_because.emplace_back(q, "this run determines it only through " + on +
                                         "'s prior or hold (" + on +
                                         " is not determined by this run)");
    }
    const Eigen::MatrixXd Ns = Rows(Nloose, c.supported, c.supported);
    const std::vector<int> strong = Supported(Ns, kMinInformationFound);
    for (std::size_t i = 0; i < c.supported.size(); ++i) {
      if (std::find(strong.begin(), strong.end(), static_cast<int>(i)) == strong.end()) {
        c.weak.emplace_back(c.supported[i], Ns(i, i));
      }
    }
  }

  // The score test of the supported components, scaled by the predicted
  // chi^2/dof with them added, the Gauss-Newton step to their refit, and the
  // test of the well-determined ones alone.
  void Score(CandidateInformation* cp) const {
    CandidateInformation& c = *cp;
    const int k = static_cast<int>(c.supported.size());
    std::vector<int> sc;
    for (int q : c.supported) sc.push_back(cols_[q]);
    const Eigen::MatrixXd Ibe = Rows(I_, base_, sc);
    c.B = bb_.solve(Ibe);
    const Eigen::MatrixXd with_prior = Rows(I_, sc, sc) - Ibe.transpose() * c.B;
    // Considered in its refit: the fit's considered parameters and its own
    // components not separable from the base parameters.
    std::vector<int> considered = considered_;
    for (const NotSeparable& ns : c.not_separable) considered.push_back(cols_[ns.component]);
    const Eigen::MatrixXd N_given = Rows(N_all_, c.supported, c.supported);
    c.N = WithConsidered(N_given, sc, c.B, considered);
    // The refit's covariance to first order: its prior too.
    Eigen::MatrixXd N_post = N_given;
    for (int a = 0; a < k; ++a) N_post(a, a) += std::pow(prior_sigma_[c.supported[a]], -2);
    ConsideredShares shares;
    const Eigen::MatrixXd N_wald = WithConsidered(N_post, sc, c.B, considered, &shares);
    const Eigen::VectorXd ge = Entries(g_, sc);
    c.score = std::max(0.0, ge.dot(with_prior.ldlt().solve(ge)));
    // Newton step on (theta_b, theta_e): the block solve with the base
    // gradient (~0) included.
    std::vector<int> bs = base_;
    bs.insert(bs.end(), sc.begin(), sc.end());
    const Eigen::VectorXd step = -Rows(I_, bs, bs).ldlt().solve(Entries(g_, bs));
    c.step_base = step.head(base_.size());
    c.step_effect = step.tail(k);
    c.wald_one_step = std::max(0.0, c.step_effect.dot(N_wald * c.step_effect));
    c.wald_one_step_given = std::max(0.0, c.step_effect.dot(N_post * c.step_effect));
    for (std::size_t j = 0; j < considered.size(); ++j) {
      if (shares.share.size() > 0 && shares.share[j] > c.most_considered_share) {
        c.most_considered_share = shares.share[j];
        c.most_considered = full_.info(considered[j]).name;
      }
    }
    // The accelerometer's chi2/dof predicted with the effect; a gyro-stage
    // effect's score is the gyro's, whose noise is at its maximum likelihood
    // (its whitened residual unit by construction): not scaled.
    const double chi2_aug =
        GetEffectSpec(c.effect).stage == EffectStage::kGyro
            ? 1.0
            : (2.0 * fit_.final_cost - c.score) / std::max(1, fit_.degrees_of_freedom - k);
    c.statistic = c.score / std::max(1.0, chi2_aug);
    c.p_value = ChiSquareSurvival(c.statistic, k);
    std::vector<int> strong;
    for (int q : c.supported) {
      if (std::none_of(c.weak.begin(), c.weak.end(),
                       [&](const std::pair<int, double>& w) { return w.first == q; })) {
        strong.push_back(cols_[q]);
      }
    }
    if (strong.size() == sc.size()) {
      c.statistic_strong = c.statistic;
      c.p_value_strong = c.p_value;
    } else if (!strong.empty()) {
      const Eigen::MatrixXd Ibs = Rows(I_, base_, strong);
      const Eigen::MatrixXd ws = Rows(I_, strong, strong) - Ibs.transpose() * bb_.solve(Ibs);
      const Eigen::VectorXd gs = Entries(g_, strong);
      c.statistic_strong = std::max(0.0, gs.dot(ws.ldlt().solve(gs))) / std::max(1.0, chi2_aug);
      c.p_value_strong = ChiSquareSurvival(c.statistic_strong, static_cast<int>(strong.size()));
    }
  }

  // N as the refit's Wald test sees it: a considered parameter (the fit's,
  // or a component of the candidate's own not separable from the base
  // parameters) stays at its nominal value there, its prior uncertainty
  // carried into the effect's variance through the effect's sensitivity to
  // it (the consider term, batch_solver.h): the inverse of N^-1 + S P S^T,
  // S = -N^-1 N_ec, N_ec the information between the effect and the
  // considered parameters given the free base ones. Without it a minimal
  // detectable effect is the one given those parameters exactly at nominal
  // (real fast roll run with its gyro, dlambda2 then considered:
  // angle_latency 0.28 ms, where the refit's sigma of tau was 9.7 ms, nearly
  // all of it dlambda2's +-180 arcmin).
  // B: the candidate's base coupling I_bb^-1 I_be (CandidateInformation::B).
  // shares (may be null): each considered parameter's share of the effect's
  // variance, sum_a S_aj^2 P_j / (k cov_aa) (cov the inverse returned).
  struct ConsideredShares {
    Eigen::VectorXd share;  // per considered parameter; empty without any
  };
  Eigen::MatrixXd WithConsidered(const Eigen::MatrixXd& N, const std::vector<int>& sc,
                                 const Eigen::MatrixXd& B, const std::vector<int>& considered,
                                 ConsideredShares* shares = nullptr) const {
    if (considered.empty()) return N;
    const int k = static_cast<int>(sc.size());
    const Eigen::MatrixXd Nec =
        Rows(I_, sc, considered) - B.transpose() * Rows(I_, base_, considered);
    const Eigen::LDLT<Eigen::MatrixXd> n(N);
    const Eigen::MatrixXd S = -n.solve(Nec);
    Eigen::VectorXd P(considered.size());
    for (std::size_t j = 0; j < considered.size(); ++j) {
      P[j] = p_.prior.sigma[considered[j]] * p_.prior.sigma[considered[j]];
    }
    const Eigen::MatrixXd cov =
        n.solve(Eigen::MatrixXd::Identity(k, k)) + S * P.asDiagonal() * S.transpose();
    if (shares) {
      shares->share = Eigen::VectorXd::Zero(considered.size());
      for (std::size_t j = 0; j < considered.size(); ++j) {
        for (int a = 0; a < k; ++a) {
          shares->share[j] += S(a, j) * S(a, j) * P[j] / (k * cov(a, a));
        }
      }
    }
    return cov.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
  }

  const RunDescription& run_;
  const RunData& data_;
  const std::vector<Effect>& current_;
  const BatchResult& fit_;
  const std::vector<Effect>& candidates_;
  const BatchOptions& options_;
  bool gyro_ = false;     // the fit has the gyro block (its part is in I_ and g_)
  ParameterLayout full_;  // current + candidates
  RunProblem p_;          // of full_, every parameter free
  Eigen::MatrixXd I_;     // information of data, priors and constraints (full_)
  Eigen::VectorXd g_;     // their gradient
  std::vector<int> base_, anchored_;
  std::vector<int> considered_;  // the fit's considered parameters (batch_solver.h)
  std::vector<std::string> anchored_names_;
  Eigen::VectorXd anchored_prior_info_;
  Eigen::LDLT<Eigen::MatrixXd> bb_;  // I over the base parameters
  // The candidate at hand: its columns in full_, their prior sigma, its
  // conditional data information given the base parameters.
  std::vector<int> cols_;
  Eigen::VectorXd prior_sigma_;
  Eigen::MatrixXd N_all_;
  EffectInformation out_;
};

}  // namespace

EffectInformation AnalyseCandidates(const RunDescription& run, const RunData& data,
                                    const std::vector<Effect>& current, const BatchResult& fit,
                                    const std::vector<Effect>& candidates,
                                    const BatchOptions& options) {
  return CandidateAnalysis(run, data, current, fit, candidates, options).Run();
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
