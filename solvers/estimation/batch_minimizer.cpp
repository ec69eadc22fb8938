#include "solvers/estimation/batch_minimizer.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

namespace triadcal {
namespace {

// Variance-component steps of the noise at the start (reductions only).
constexpr int kNoiseSteps = 30;
constexpr double kNoiseTolerance = 1e-6;  // in log sigma
// A Newton step of the noise below this is its last: applied without a
// reduction to confirm it, as its error is of the order of its square
// (sqrt(kNoiseTolerance): within the tolerance).
constexpr double kLastNoiseStep = 1e-3;
constexpr double kMaxNoiseStep = 2.0;     // in log sigma, one Newton step
// No reading is better than this share of its nominal scale factor (1 ug):
// keeps a noise-free run's estimated noise finite.
constexpr double kNoiseFloorOfScale = 1e-6;
// The damping beyond which no step is sought.
constexpr double kMaxDamping = 1e10;
constexpr const char* kNoDescent =
    "not converged: no step along the gradient lowers the cost (the damping reached 1e10; the "
    "cost is not smooth here, or a parameter has left the model's range)";

}  // namespace

BatchMinimizer::BatchMinimizer(const BatchObjective& objective, std::vector<int> free,
                               MinimizerOptions options)
    : objective_(objective), free_(std::move(free)), options_(std::move(options)) {
  formed_ = free_;
  formed_.insert(formed_.end(), options_.also_formed.begin(), options_.also_formed.end());
  std::sort(formed_.begin(), formed_.end());
  formed_.erase(std::unique(formed_.begin(), formed_.end()), formed_.end());
  options_.estimate_noise.resize(objective_.runs(), false);
  for (int r = 0; r < objective_.runs(); ++r) {
    if (options_.estimate_noise[r]) noisy_.push_back(r);
  }
}

int BatchMinimizer::FittedFor(int r) const {
  const Eigen::MatrixXd T = objective_.MapOf(r);
  int k = 0;
  for (int j : free_) k += T.col(j).cwiseAbs().maxCoeff() > 0.0 ? 1 : 0;
  return k;
}

void BatchMinimizer::Say(const std::string& line) const {
  if (options_.progress) options_.progress(line);
}

double BatchMinimizer::NoiseFloor(int r, int i) const {
  const RunProblem& p = *objective_.run(r).problem;
  return kNoiseFloorOfScale * std::abs(p.prior.mean[kKx + i]);
}

double BatchMinimizer::Objective(const BatchObjective::Point& pt) const {
  double f = pt.cost;
  for (std::size_t k = 0; k < noisy_.size(); ++k) f += rho_[k] * pt.reductions[noisy_[k]].log_det;
  return f;
}

void BatchMinimizer::Model(const BatchObjective::Point& pt, Eigen::VectorXd* g,
                           Eigen::MatrixXd* H) const {
  const int nf = static_cast<int>(free_.size());
  g->resize(nf);
  H->resize(nf, nf);
  for (int a = 0; a < nf; ++a) {
    (*g)[a] = pt.gradient[free_[a]];
    for (int b = 0; b < nf; ++b) (*H)(a, b) = pt.information(free_[a], free_[b]);
  }
}

BatchObjective::Point BatchMinimizer::Minimize(const Eigen::VectorXd& phi0,
                                               const std::vector<Eigen::Vector3d>& noise0,
                                               MinimizerSummary* summary) {
  summary_ = MinimizerSummary{};
  mu_ = 1e-8;
  nu_ = 2.0;
  secant_.resize(0, 0);
  noise_ = noise0;
  rho_.clear();
  IterationZero(phi0);
  while (ComputeStep()) {
    if (summary_.iterations >= options_.max_iterations) {
      char why[200];
      std::snprintf(why, sizeof(why),
                    "not converged after %d steps: a Newton step would still lower -log L by "
                    "%.3g (a step of about %.2g sigma)",
                    summary_.iterations, summary_.newton_decrement,
                    std::sqrt(2.0 * summary_.newton_decrement));
      summary_.termination = why;
      break;
    }
    TryStep();
    if (mu_ > kMaxDamping) {
      summary_.termination = kNoDescent;
      break;
    }
    if (options_.fraction) options_.fraction(1.0 - std::pow(0.7, summary_.iterations));
  }
  summary_.final_cost = current_.cost;
  // The steps formed the theta part by formed_ alone (a reduction by every
  // column has no block_columns: then it is whole already).
  bool whole = true;
  for (const RunReduction& red : current_.reductions) {
    whole = whole && !red.measurement_blocks.empty() && red.block_columns.empty();
  }
  if (options_.full_information && !whole && current_.finite() && !current_.passes.empty()) {
    objective_.Reweight(&current_, noise_);
  }
  *summary = summary_;
  return std::move(current_);  // not a copy: its reductions are 18 MB on the 40-min run
}

ThetaPart BatchMinimizer::FullUnlessNoisy() const {
  return noisy_.empty() ? ThetaPart::kGradientAndInformation : ThetaPart::kNone;
}

void BatchMinimizer::IterationZero(const Eigen::VectorXd& phi0) {
  // With a noise to estimate, the full reduction is formed at its maximum
  // (MaximiseNoise), not at the start noise.
  current_ = objective_.Evaluate(phi0, noise_, true, FullUnlessNoisy(), &formed_);
  summary_.passes += 1;
  summary_.initial_cost = current_.cost;
  for (int r : noisy_) {
    rho_.push_back(NoiseDofShare(current_.reductions[r], FittedFor(r)));
  }
  if (current_.finite()) {
    MaximiseNoise(&current_, &noise_, ThetaPart::kGradientAndInformation);
  } else {
    objective_.Reweight(&current_, noise_, ThetaPart::kGradientAndInformation, &formed_);
  }
}

void BatchMinimizer::MaximiseNoise(BatchObjective::Point* pt, std::vector<Eigen::Vector3d>* noise,
                                   ThetaPart theta_part) const {
  // Newton's method in s = log sigma at pt's theta (each run's noise apart:
  // at fixed theta they do not interact), with halving where -log L would
  // rise; reductions without the theta part, then one with theta_part at the
  // result.
  if (noisy_.empty()) return;
  double f = Objective(*pt);
  for (int step = 0; step < kNoiseSteps; ++step) {
    std::vector<Eigen::Vector3d> trial_noise = *noise;
    double largest = 0.0;
    for (std::size_t k = 0; k < noisy_.size(); ++k) {
      const int r = noisy_[k];
      const RunReduction& red = pt->reductions[r];
      const Eigen::Vector3d g = rho_[k] * red.channel_trace - red.channel_quadratic;
      Eigen::Matrix3d H = NoiseHessian(red, rho_[k]);
      Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.vectorD().minCoeff() > 0)) {
        H = (2.0 * red.channel_quadratic.cwiseMax(1e-300)).asDiagonal();
        ldlt.compute(H);
      }
      Eigen::Vector3d ds = -ldlt.solve(g);
      const double big = ds.cwiseAbs().maxCoeff();
      if (big > kMaxNoiseStep) ds *= kMaxNoiseStep / big;  // e^2: the exponential bends fast
      largest = std::max(largest, ds.cwiseAbs().maxCoeff());
      for (int i = 0; i < 3; ++i) {
        trial_noise[r][i] = std::max((*noise)[r][i] * std::exp(ds[i]), NoiseFloor(r, i));
      }
    }
    if (largest < kNoiseTolerance) break;
    if (largest < kLastNoiseStep) {
      *noise = trial_noise;
      break;
    }
    bool lowered = false;
    for (int halving = 0; halving < 20 && !lowered; ++halving) {
      BatchObjective::Point trial = objective_.AtNoise(*pt, trial_noise, ThetaPart::kNone);
      const double ft = Objective(trial);
      if (std::isfinite(ft) && ft <= f) {
        *pt = std::move(trial);
        *noise = trial_noise;
        f = ft;
        lowered = true;
        continue;
      }
      for (std::size_t k = 0; k < noisy_.size(); ++k) {
        const int r = noisy_[k];
        trial_noise[r] = ((*noise)[r].array() * trial_noise[r].array()).sqrt().matrix();
      }
    }
    if (!lowered) break;  // at the maximum to rounding
  }
  // Without a theta part, pt stays reduced at the noise before the last
  // step (within kLastNoiseStep of *noise).
  if (theta_part != ThetaPart::kNone) objective_.Reweight(pt, *noise, theta_part, &formed_);
}

bool BatchMinimizer::ComputeStep() {
  if (!current_.finite()) {
    if (summary_.termination.empty()) summary_.termination = "the cost is not finite";
    return false;
  }
  if (free_.empty()) {
    // The noise alone is at its maximum already (IterationZero).
    summary_.converged = true;
    summary_.termination = noisy_.empty() ? "nothing to estimate"
                                          : "no parameter to estimate: the reading noise alone";
    return false;
  }
  Eigen::VectorXd g;
  Eigen::MatrixXd H;
  Model(current_, &g, &H);
  FormCoupling(current_);
  // The decrement of -log L profiled over the noise (Gauss-Newton's
  // Hessian less the noise's coupling), or Gauss-Newton's where that is not
  // positive definite (far from the minimum).
  const Eigen::LDLT<Eigen::MatrixXd> gauss_newton(H);
  const double gauss_newton_decrement = 0.5 * g.dot(gauss_newton.solve(g));
  summary_.newton_decrement = gauss_newton_decrement;
  if (coupling_.size() > 0) {
    const Eigen::LDLT<Eigen::MatrixXd> profiled(H - coupling_);
    if (profiled.info() == Eigen::Success && profiled.isPositive() &&
        profiled.vectorD().minCoeff() > 0.0) {
      summary_.newton_decrement = 0.5 * g.dot(profiled.solve(g));
    }
  }
  if (!std::isfinite(summary_.newton_decrement)) {
    summary_.termination = "the information matrix is singular";
    return false;
  }
  if (std::abs(summary_.newton_decrement) < options_.tolerance) {
    summary_.converged = true;
    char why[160];
    std::snprintf(why, sizeof(why),
                  "converged in %d steps (%d passes over the samples): the next step would be "
                  "%.2g sigma",
                  summary_.iterations, summary_.passes,
                  std::sqrt(2.0 * std::abs(summary_.newton_decrement)));
    summary_.termination = why;
    return false;
  }
  // The model of -log L profiled over the noise: the Hessian above plus the
  // curvature the last step measured (MeasureCurvature), less the noise's
  // coupling, damped until positive definite; beyond CoupledModelReach (far
  // from the minimum) the model at fixed noise.
  const double mu = mu_, nu = nu_;
  couple_ = coupling_.size() > 0 && gauss_newton_decrement <= CoupledModelReach();
  if (couple_ && DampedModelStep(g, H)) return true;
  couple_ = false;
  mu_ = mu;
  nu_ = nu;
  summary_.termination.clear();
  summary_.newton_decrement = gauss_newton_decrement;
  return DampedModelStep(g, H);
}

double BatchMinimizer::CoupledModelReach() const {
  // The noise's quadratic model in the coupled one errs at third order: a
  // step with Newton decrement D moves each channel's noise by about D / N
  // (N its effective number of residuals, the channel traces), bending the
  // model's curvature along the step by about 4 D / 3 N, which leaves about
  // (16/9) D^3 / N^2 of decrement after the step. Within the tolerance that
  // is D <= (9/16 tolerance N^2)^(1/3); beyond it the model at fixed noise,
  // exact for the noise's common scale, is the better one (simulated 40-min
  // run from the RTS start: D 400, N 2.9e4, one step at fixed noise, two
  // coupled).
  double N = 0.0;
  for (int r : noisy_) N += current_.reductions[r].channel_trace.sum();
  return std::cbrt(9.0 / 16.0 * options_.tolerance * N * N);
}

bool BatchMinimizer::DampedModelStep(const Eigen::VectorXd& g, const Eigen::MatrixXd& H) {
  Eigen::MatrixXd B;
  Eigen::VectorXd scale;
  DampingModel(H, &B, &scale);
  for (;;) {
    bool ok = false;
    step_ = DampedStep(B, g, scale, mu_, &ok);
    if (ok) {
      predicted_ = -(g.dot(step_) + 0.5 * step_.dot(B * step_));
      if (predicted_ > 0.0) return true;
    }
    mu_ = std::max(mu_ * nu_, 1e-4);
    nu_ *= 2.0;
    if (mu_ > kMaxDamping) {
      summary_.termination = kNoDescent;
      return false;
    }
  }
}

void BatchMinimizer::DampingModel(const Eigen::MatrixXd& H, Eigen::MatrixXd* B,
                                  Eigen::VectorXd* scale) const {
  *B = H;
  if (secant_.rows() == H.rows()) *B += secant_;
  if (couple_) *B -= coupling_;
  *scale = H.diagonal().cwiseAbs().cwiseMax(1e-300);
}

void BatchMinimizer::FormCoupling(const BatchObjective::Point& pt) {
  const int nf = static_cast<int>(free_.size());
  coupling_.resize(0, 0);
  for (std::size_t k = 0; k < noisy_.size(); ++k) {
    const int r = noisy_[k];
    if (r >= static_cast<int>(pt.reductions.size())) continue;
    const RunReduction& red = pt.reductions[r];
    if (red.gradient_by_log_noise.rows() != objective_.run(r).problem->n) continue;
    // At the noise's maximum H_ss is positive definite; elsewhere (a noise
    // held at its floor) the coupling is left out.
    const Eigen::LDLT<Eigen::Matrix3d> H_ss(NoiseHessian(red, rho_[k]));
    if (H_ss.info() != Eigen::Success || !H_ss.isPositive() ||
        !(H_ss.vectorD().minCoeff() > 0.0)) {
      continue;
    }
    const Eigen::MatrixXd G_phi = objective_.MapOf(r).transpose() * red.gradient_by_log_noise;
    Eigen::MatrixXd G(nf, 3);
    for (int a = 0; a < nf; ++a) G.row(a) = G_phi.row(free_[a]);
    if (coupling_.size() == 0) coupling_ = Eigen::MatrixXd::Zero(nf, nf);
    coupling_.noalias() += G * H_ss.solve(G.transpose());
  }
}

Eigen::VectorXd BatchMinimizer::DampedStep(const Eigen::MatrixXd& B, const Eigen::VectorXd& g,
                                           const Eigen::VectorXd& scale, double mu,
                                           bool* ok) const {
  Eigen::MatrixXd D = B;
  D.diagonal() += mu * scale;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(D);
  *ok = ldlt.info() == Eigen::Success && ldlt.isPositive() && ldlt.vectorD().minCoeff() > 0.0;
  return *ok ? Eigen::VectorXd(-ldlt.solve(g)) : Eigen::VectorXd();
}

void BatchMinimizer::RaiseDamping(double rise) {
  // At least Nielsen's doubling. Beyond it, the damping whose step is as
  // long (in diag H's metric) as the minimum of the parabola through -log L
  // at the current point, its slope there along the refused step d and its
  // value at d: alpha = -g.d / (2 (rise - g.d)), within 0.1 .. 0.5 of d.
  // Nielsen's rule alone starts at 1e-4 of diag H, where the step is still
  // the refused one: the real fast roll run with the gyro refused three
  // such steps in a row (a pass each).
  const double grown = std::max(mu_ * nu_, 1e-4);
  nu_ *= 2.0;
  Eigen::VectorXd g;
  Eigen::MatrixXd H, B;
  Eigen::VectorXd scale;
  Model(current_, &g, &H);
  DampingModel(H, &B, &scale);
  const double slope = g.dot(step_), bend = rise - slope;
  if (!(std::isfinite(rise) && slope < 0.0 && bend > 0.0) || !current_.finite()) {
    mu_ = grown;
    return;
  }
  const double alpha = std::clamp(-slope / (2.0 * bend), 0.1, 0.5);
  auto length = [&](double mu) {
    bool ok = false;
    const Eigen::VectorXd d = DampedStep(B, g, scale, mu, &ok);
    return ok ? std::sqrt(d.cwiseAbs2().dot(scale)) : std::numeric_limits<double>::infinity();
  };
  const double target = alpha * std::sqrt(step_.cwiseAbs2().dot(scale));
  // The step's length falls as the damping rises: bisection in log mu.
  double lo = std::log(std::max(mu_, 1e-12)), hi = std::log(kMaxDamping);
  for (int it = 0; it < 50 && hi - lo > 1e-3; ++it) {
    const double mid = 0.5 * (lo + hi);
    (length(std::exp(mid)) > target ? lo : hi) = mid;
  }
  mu_ = std::max(std::exp(hi), grown);
}

Eigen::VectorXd BatchMinimizer::GradientAtTrialNoise(
    const BatchObjective::Point& trial, const std::vector<Eigen::Vector3d>& trial_noise) const {
  // The noise has not moved (none estimated: the decision's scale-and-offset
  // fit) and no gyro's is profiled: the current gradient is the one asked for.
  bool moved = trial_noise != noise_;
  for (int r = 0; r < objective_.runs(); ++r) moved = moved || objective_.HasGyroPart(current_, r);
  if (!moved) {
    Eigen::VectorXd g0(free_.size());
    for (std::size_t a = 0; a < free_.size(); ++a) g0[a] = current_.gradient[free_[a]];
    return g0;
  }
  BatchObjective::Point at =
      objective_.AtNoise(current_, trial_noise, ThetaPart::kGradient, &free_);
  objective_.ReweightGyro(&at, trial);
  Eigen::VectorXd g0(free_.size());
  for (std::size_t a = 0; a < free_.size(); ++a) g0[a] = at.gradient[free_[a]];
  return g0;
}

void BatchMinimizer::MeasureCurvature(const BatchObjective::Point& trial,
                                      const Eigen::VectorXd& g0) {
  // What the step showed of -log L's curvature beyond Gauss-Newton's: the
  // change of the gradient along it, y = g(theta_trial) - g(theta), both at
  // the trial's noise (the current point reweighted: a reduction, no pass),
  // so that y is the cost's at fixed weights and not the noise's response.
  // The correction S accumulates it by BFGS on the model B = H + S
  // (a structured secant update: Dennis, Gay & Welsch's NL2SOL keeps
  // Gauss-Newton's part exact and learns the rest): B+ = B - B d d^T B /
  // d^T B d + y y^T / y^T d, S = B+ - H at the new point. A misfit's
  // residual curvature made Gauss-Newton converge linearly (real fast roll
  // run: 13 steps with the noise held, 5 with S).
  Eigen::VectorXd g1;
  Eigen::MatrixXd H1;
  Model(trial, &g1, &H1);
  const Eigen::VectorXd y = g1 - g0;
  Eigen::MatrixXd B = H1;
  if (secant_.rows() == H1.rows()) B += secant_;
  const Eigen::VectorXd Bd = B * step_;
  const double dBd = step_.dot(Bd), yd = y.dot(step_);
  auto positive = [](const Eigen::MatrixXd& M) {
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(M);
    return ldlt.info() == Eigen::Success && ldlt.isPositive() && ldlt.vectorD().minCoeff() > 0.0;
  };
  // Only a curvature the step confirms (y^T d > 0) keeps B positive definite:
  // in exact arithmetic. In rounding, not when the step's gradient change
  // dwarfs H's smallest curvature (a start far from the run: offsets of 1500
  // counts declared 0, y 1e13, B's smallest pivot then -3e13). And without
  // an update the last S is on a new H: the real medium roll run's refit of
  // gyro_nonlinearity in diagnose, after a step with y^T d < 0, had no
  // positive model below a damping of 1.6 diag H (12 steps; 10 without that
  // S). A model that is not positive definite keeps no S: Gauss-Newton's
  // alone.
  if (dBd > 0.0 && yd > 0.0 && std::isfinite(yd)) {
    const Eigen::MatrixXd updated = B + y * y.transpose() / yd - Bd * Bd.transpose() / dBd;
    if (positive(updated)) {
      secant_ = updated - H1;
      return;
    }
  }
  if (secant_.rows() == H1.rows() && !positive(B)) secant_.resize(0, 0);
}

bool BatchMinimizer::TryStep() {
  const int nf = static_cast<int>(free_.size());
  Eigen::VectorXd phi = current_.phi;
  for (int k = 0; k < nf; ++k) phi[free_[k]] += step_[k];
  // The trial's noise at its conditional maximum there (the step's own
  // change of log sigma is Newton's on an exponential, and overshoots where
  // a channel's residual changed much): -log L profiled over the noise.
  // One point's blocks are held at a time: the current point's reductions
  // are dropped meanwhile (formed again if the step is refused: a
  // reduction, no pass), the trial's theta part is formed once it is
  // accepted.
  const double before = Objective(current_);
  current_.reductions.clear();
  std::vector<Eigen::Vector3d> noise = noise_;
  BatchObjective::Point trial = objective_.Evaluate(phi, noise, true, ThetaPart::kNone);
  if (trial.finite()) MaximiseNoise(&trial, &noise, ThetaPart::kNone);
  summary_.iterations += 1;
  summary_.passes += 1;
  const double after = Objective(trial);
  const double actual = before - after;
  char line[200];
  std::snprintf(line, sizeof(line),
                "step %d: -log L %.10g -> %.10g (predicted decrease %.4g; Newton decrement %.3g)",
                summary_.iterations, before, after, predicted_, summary_.newton_decrement);
  Say(line);
  if (trial.finite() && actual > 0.0) {
    // The current point gives way (its passes too) before the trial's theta part is formed.
    const Eigen::VectorXd g0 = GradientAtTrialNoise(trial, noise);
    const Eigen::VectorXd phi_current = current_.phi;
    current_ = BatchObjective::Point{};
    objective_.Reweight(&trial, noise, ThetaPart::kGradientAndInformation, &formed_);
    if (trial.finite()) {
      MeasureCurvature(trial, g0);
      const double rho = actual / predicted_;
      mu_ = std::max(mu_ * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)), 1e-12);
      nu_ = 2.0;
      current_ = std::move(trial);
      noise_ = noise;
      summary_.accepted += 1;
      return true;
    }
    // A gradient not finite: refused after all, the current point evaluated again.
    current_ = objective_.Evaluate(phi_current, noise_, true, ThetaPart::kGradientAndInformation,
                                   &formed_);
    summary_.passes += 1;
    RaiseDamping(std::numeric_limits<double>::infinity());
    return false;
  }
  objective_.Reweight(&current_, noise_, ThetaPart::kGradientAndInformation, &formed_);
  RaiseDamping(trial.finite() ? -actual : std::numeric_limits<double>::infinity());
  return false;
}

}  // namespace triadcal
