#include "solvers/estimation/batch_solver.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "core/model/errors.h"
#include "core/model/sample_noise.h"
#include "solvers/estimation/batch_costs.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/batch_linearization.h"
#include "solvers/estimation/hac_covariance.h"
#include "solvers/estimation/noise_estimation.h"
#include "solvers/estimation/state_space_model.h"
#include "solvers/estimation/observability.h"
#include "solvers/estimation/reduced_run.h"

namespace triadcal {
namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The thinning that brings a run to about rate_hz.
std::size_t ThinningFactor(const RunData& data, int rate_hz) {
  const double span = data.t_s.back() - data.t_s.front();
  const double rate = (data.size() - 1) / std::max(span, 1e-9);
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::floor(rate / std::max(1, rate_hz))));
}

// Starting point of theta (and its sigma when an estimator gave one).
Estimate Initialise(const RunDescription& run, const RunData& data, const ParameterLayout& layout,
                    const RunProblem& p, const BatchOptions& opt,
                    const std::vector<std::string>& held) {
  const int n = p.n;
  Estimate e{p.prior.mean, Eigen::MatrixXd(p.prior.sigma.array().square().matrix().asDiagonal())};
  for (int i : p.held) {
    e.cov.row(i).setZero();
    e.cov.col(i).setZero();
  }
  if (opt.init == BatchInit::kGiven) {
    if (opt.init_theta.size() != n) throw std::invalid_argument("init_theta has the wrong size");
    e.theta = opt.init_theta;
    for (int i : p.held) e.theta[i] = p.theta_held[i];
    return e;
  }
  if (opt.init == BatchInit::kNominal) return e;
  // RTS on samples thinned to about init_decimation_hz: a start within a few
  // sigma of the optimum at a fraction of a full pass.
  const RunData thin = Decimate(data, ThinningFactor(data, opt.init_decimation_hz));
  FilterOptions fo;
  fo.epoch_s = std::max(opt.epoch_s, 1.0);  // coarse epochs: the start needs no more
  fo.derivatives = opt.derivatives;
  fo.smoother_iterations = 1;
  fo.held = held;
  const FilterResult fr = RunFilterSmoother(run, thin, layout, fo);
  return fr.rts;
}

std::unique_ptr<ceres::LossFunction> MakeLoss(const BatchOptions& opt) {
  if (opt.robust_loss.empty()) return nullptr;
  if (opt.robust_loss == "huber") return std::make_unique<ceres::HuberLoss>(opt.robust_scale);
  if (opt.robust_loss == "cauchy") return std::make_unique<ceres::CauchyLoss>(opt.robust_scale);
  throw OptionError("robust_loss", "unknown loss '" + opt.robust_loss + "' (huber, cauchy)");
}

ceres::LinearSolverType SolverType(const std::string& name) {
  if (name == "sparse_normal_cholesky") return ceres::SPARSE_NORMAL_CHOLESKY;
  if (name == "sparse_schur") return ceres::SPARSE_SCHUR;
  if (name == "dense_qr") return ceres::DENSE_QR;
  throw OptionError("linear_solver", "unknown '" + name +
                   "' (sparse_normal_cholesky, sparse_schur, dense_qr)");
}

// The posterior covariance in prior units of the parameters `idx` under the
// data information `info` (prior units) and unit priors, the others held.
Eigen::MatrixXd PosteriorOver(const Eigen::MatrixXd& info, const std::vector<int>& idx) {
  const int k = static_cast<int>(idx.size());
  Eigen::MatrixXd F(k, k);
  for (int a = 0; a < k; ++a) {
    for (int b = 0; b < k; ++b) F(a, b) = info(idx[a], idx[b]) + (a == b ? 1.0 : 0.0);
  }
  return F.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
}

// cov is the posterior with priors; the prior contributes the identity to
// its inverse in prior units.
std::vector<int> SupportedParameters(const Eigen::MatrixXd& cov, const Eigen::VectorXd& prior_sigma,
                                     const Eigen::VectorXd& min_info) {
  const int n = static_cast<int>(cov.rows());
  const Eigen::MatrixXd Pn =
      prior_sigma.cwiseInverse().asDiagonal() * cov * prior_sigma.cwiseInverse().asDiagonal();
  Eigen::MatrixXd S = Pn.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  S.diagonal().array() -= 1.0;
  Eigen::VectorXd priority(n);
  for (int i = 0; i < n; ++i) priority[i] = HoldPriority(i);
  return SupportedByInformation(S, min_info, priority);
}

}  // namespace

double HoldPriority(int index) {
  if (index <= kW0z) return 4.0;      // scale factors, zero offsets
  if (index <= kGammaZ) return 2.0;   // misalignments
  if (index >= kDx2 && index <= kDz2) return 2.0;
  return 1.0;                         // K_ij, bench zeros, effects
}

std::vector<int> SupportedByInformation(const Eigen::MatrixXd& information,
                                        const Eigen::VectorXd& min_info,
                                        const Eigen::VectorXd& priority) {
  const int n = static_cast<int>(information.rows());
  Eigen::MatrixXd S = information;
  std::vector<int> kept;
  std::vector<bool> used(n, false);
  for (;;) {
    int best = -1;
    double best_score = 0.0;
    for (int j = 0; j < n; ++j) {
      if (used[j] || S(j, j) < min_info[j]) continue;
      const double score = S(j, j) * priority[j];
      if (score > best_score) {
        best_score = score;
        best = j;
      }
    }
    if (best < 0) break;
    used[best] = true;
    kept.push_back(best);
    const Eigen::VectorXd col = S.col(best) / std::sqrt(S(best, best));
    S -= col * col.transpose();
  }
  return kept;
}

HoldDecision ChooseHeldParameters(const RunDescription& run, const RunData& data,
                                  const ParameterLayout& layout, const HoldPolicy& o,
                                  double epoch_s, const AngleDerivativeOptions& derivatives,
                                  int decimation_hz, int threads) {
  const int n = layout.size();
  if (threads <= 0) threads = DefaultThreads();
  HoldDecision d;
  std::vector<bool> held(n, false);
  // The data information at the full rate in prior units (n x n), when the
  // auto hold computed it.
  Eigen::MatrixXd info_full;
  if (o.auto_hold) {
    // Decided at the nominal values (where a degenerate direction has no
    // information at all) on the samples thinned to decimation_hz: the
    // information scales with the samples, so the thresholds are scaled too.
    const std::size_t m = ThinningFactor(data, decimation_hz);
    const RunData thin = Decimate(data, m);
    const RunProblem pt = BuildRunProblem(run, thin, layout, epoch_s, derivatives);
    const BatchLinearization lt = Linearize(pt, pt.prior.mean, true, threads);
    Eigen::MatrixXd At;
    Eigen::VectorXd bt;
    ThetaRows(pt, true, &At, &bt);
    const Eigen::MatrixXd cov0 = ThetaCovariance(pt, lt, pt.prior.mean, At, threads);
    ObservabilityThresholds th;
    th.unobservable /= static_cast<double>(m);
    th.weak /= static_cast<double>(m);
    d.unsupported = UnsupportedDirections(layout, cov0, pt.prior.sigma, th);
    held.assign(n, true);
    Eigen::VectorXd min_info(n);
    for (int i = 0; i < n; ++i) {
      min_info[i] = (i < kNumBaseParams ? o.min_information : o.min_information_effects) /
                    static_cast<double>(m);
    }
    for (int i : SupportedParameters(cov0, pt.prior.sigma, min_info)) held[i] = false;
    const Eigen::VectorXd inv_sigma = pt.prior.sigma.cwiseInverse();
    const Eigen::MatrixXd Pn = inv_sigma.asDiagonal() * cov0 * inv_sigma.asDiagonal();
    info_full = Pn.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
    info_full.diagonal().array() -= 1.0;
    info_full *= static_cast<double>(m);
  }
  auto index_of = [&](const std::string& name) {
    const int i = layout.IndexOf(name);
    if (i < 0) throw OptionError("hold_free", "unknown parameter '" + name + "'");
    return i;
  };
  for (const std::string& h : o.hold) held[index_of(h)] = true;
  for (const std::string& h : o.pinned) held[index_of(h)] = true;
  for (const std::string& f : o.free) held[index_of(f)] = false;
  for (int i = 0; i < n; ++i) {
    if (held[i]) d.held.push_back(layout.info(i).name);
  }
  // What the held parameters stand for: the other members of their
  // undetermined directions are estimated relative to them. A pinned one
  // stands for nothing: its uncertainty goes into the others' sigma.
  const std::set<std::string> held_set(d.held.begin(), d.held.end());
  const std::set<std::string> pinned_set(o.pinned.begin(), o.pinned.end());
  for (const WeakDirection& w : d.unsupported) {
    std::vector<std::string> anchors;
    for (const auto& [name, weight] : w.weights) {
      if (held_set.count(name) && !pinned_set.count(name) && std::abs(weight) >= 0.1) {
        anchors.push_back(name);
      }
    }
    if (anchors.empty()) continue;
    for (const auto& [name, weight] : w.weights) {
      if (held_set.count(name) || std::abs(weight) < 0.1) continue;
      std::vector<std::string>& r = d.relative_to[name];
      for (const std::string& a : anchors) {
        if (std::find(r.begin(), r.end(), a) == r.end()) r.push_back(a);
      }
    }
  }
  d.information = info_full;
  return d;
}

namespace {

// Reports BatchOptions::fraction from inside a Ceres solve.
class IterationFraction : public ceres::IterationCallback {
 public:
  IterationFraction(double begin, double end, const std::function<void(double)>& report)
      : at_(begin), end_(end), report_(report) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    at_ += (end_ - at_) / 3.0;
    if (report_) report_(at_);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  double at_, end_;
  const std::function<void(double)>& report_;
};

// The Ceres problem of one linearisation: the trajectory blocks, theta_free,
// one process cost per interval, one measurement cost per epoch, the prior
// and constraint rows.
struct LinearisedProblem {
  std::unique_ptr<ceres::Problem> problem;
  std::vector<ProcessCost*> process;
  std::vector<MeasurementCost*> measurement;
};

LinearisedProblem BuildCeresProblem(const StateSpaceModel& model, const BatchLinearization& lin,
                                    const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                    const BatchOptions& opt, std::vector<double>* x,
                                    Eigen::VectorXd* theta_free) {
  const std::size_t E = model.num_epochs();
  LinearisedProblem lp;
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  lp.problem = std::make_unique<ceres::Problem>(po);
  lp.process.resize(E - 1);
  lp.measurement.resize(E);
  for (std::size_t e = 0; e < E; ++e) lp.problem->AddParameterBlock(&(*x)[6 * e], 6);
  lp.problem->AddParameterBlock(theta_free->data(), model.num_free());
  for (std::size_t e = 0; e + 1 < E; ++e) {
    ceres::LossFunction* loss = MakeLoss(opt).release();  // may throw: before the cost
    lp.process[e] =
        new ProcessCost(&lin.process[e], &lin.theta_lin_free, &model, opt.exact_increments, e);
    lp.problem->AddResidualBlock(lp.process[e], loss, &(*x)[6 * e], &(*x)[6 * (e + 1)],
                                 theta_free->data());
  }
  for (std::size_t e = 0; e < E; ++e) {
    ceres::LossFunction* loss = MakeLoss(opt).release();
    lp.measurement[e] = new MeasurementCost(&model, e, lin.LR[e]);
    lp.problem->AddResidualBlock(lp.measurement[e], loss, &(*x)[6 * e], theta_free->data());
  }
  lp.problem->AddResidualBlock(new LinearThetaCost(A, b), nullptr, theta_free->data());
  // Scale factors stay within [1/5, 5] of their nominal values: beyond that the
  // run.yaml's nominal is wrong, and on motion that hardly excites an axis the
  // flat cost would otherwise let a trust-region step reach K = 0, where the
  // noise weight g sigma / K (state_space_model.h) is undefined.
  const RunProblem& p = model.problem();
  for (std::size_t j = 0; j < p.free.size(); ++j) {
    const int i = p.free[j];
    if (i < kKx || i > kKz) continue;
    const double k0 = std::abs(p.prior.mean[i]);
    const bool negative = p.prior.mean[i] < 0.0;
    lp.problem->SetParameterLowerBound(theta_free->data(), static_cast<int>(j),
                                       negative ? -5.0 * k0 : 0.2 * k0);
    lp.problem->SetParameterUpperBound(theta_free->data(), static_cast<int>(j),
                                       negative ? -0.2 * k0 : 5.0 * k0);
  }
  return lp;
}

ceres::Solver::Options SolverOptions(const BatchOptions& opt, int threads, std::size_t E,
                                     std::vector<double>* x, Eigen::VectorXd* theta_free) {
  ceres::Solver::Options so;
  so.linear_solver_type = SolverType(opt.linear_solver);
  so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  so.max_num_iterations = opt.max_ceres_iterations;
  so.num_threads = threads;
  so.function_tolerance = 1e-12;
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-12;
  so.logging_type = ceres::SILENT;
  // The problem is close to linear (B1 enters linearised, B2 is smooth in
  // theta): start with a Gauss-Newton-sized step instead of Ceres's cautious
  // default radius, which costs a dozen iterations on a 72k-unknown problem.
  so.initial_trust_region_radius = 1e12;
  if (so.linear_solver_type == ceres::SPARSE_SCHUR) {
    // Eliminate every other epoch's state: an independent set, since the
    // process residuals couple only neighbours.
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (std::size_t e = 0; e < E; ++e) ordering->AddElementToGroup(&(*x)[6 * e], e % 2 == 0 ? 0 : 1);
    ordering->AddElementToGroup(theta_free->data(), 1);
    so.linear_solver_ordering = ordering;
  }
  return so;
}

// What the relinearisation loop carries from one pass to the next.
struct SolveState {
  Eigen::VectorXd theta_free;
  std::vector<double> x;  // 6 per epoch
  BatchLinearization lin;
  LinearisedProblem lp;
  // Set once relinearising has been seen to converge only linearly (steps
  // shrinking by less than kSlowRatio a pass): the rest of the solve then
  // recomputes the increments in every evaluation.
  bool exact = false;
};

// A pass whose step is more than this fraction of the previous one, from the
// fourth pass on, means the linearised increments are the bottleneck: on a
// weakly excited run the parameters slide along a flat direction by degrees
// and the cross terms of the linearisation (state_space_model.h) make each
// pass cover only part of the way.
constexpr double kSlowRatio = 0.3;
constexpr int kPassesBeforeExact = 3;
// The linearised increments are judged off when the true cost at a new
// linearisation point differs from the cost the last pass predicted there by
// more than this fraction of the decrease it predicted (on the vertical-shaft
// run: 63-85 %; on the real slow roll run, slow for other reasons, less).
constexpr double kMissRatio = 0.5;
// Steps of the Gauss-Newton finish on the exact increments. Its information
// leaves out the weights' dependence on theta, so on a run the model misfits
// it converges linearly: on the real slow roll run with angle_latency and
// thermal_drift (dpsi held) the predicted decrease shrank by about 0.7 a
// step (61 at step 5, 0.3 at step 19; in the refit with the noise estimated,
// 0.37 still at step 34), so the old limit of 30 sent it to the fallback. Past this the solve falls
// back to Ceres with exact increments, which is far slower (hours there).
constexpr int kExactGaussNewtonSteps = 100;
// Halvings of one step back towards the last point before the linearised
// increments are judged to mislead there: after this many the solve takes
// Gauss-Newton on the exact increments from the step's end, as it did before
// after halving on (each halving costs a linearisation) until the point came
// back to where the pass started and the identical pass ran again (real slow
// roll run: 17 halvings and a second 100-iteration pass, 11 s of a 27-s fit).
constexpr int kHalvingsBeforeExact = 3;

// Relinearise and solve until the linearisation point stops moving.
void Relinearise(const RunProblem& p, const StateSpaceModel& model, const Eigen::MatrixXd& A,
                 const Eigen::VectorXd& b, const BatchOptions& opt, int threads,
                 const std::function<void(const std::string&)>& say, SolveState* st,
                 BatchResult* res) {
  const std::size_t E = model.num_epochs();
  Eigen::VectorXd& theta_free = st->theta_free;
  std::vector<double>& x = st->x;
  double last_step = 0.0;
  // Backtracking: the cost at a new linearisation point is the true cost
  // there; if a step made it worse than at the previous point, go half way back.
  Eigen::VectorXd theta_prev;
  std::vector<double> x_prev;
  double cost_prev = std::numeric_limits<double>::infinity();
  // What the last pass's linearised problem predicted for the cost at its
  // solution, and the decrease it predicted: at the next linearisation point
  // the true cost shows how far the linearised increments were off.
  double predicted_cost = std::numeric_limits<double>::quiet_NaN();
  double predicted_change = 0.0;
  bool linearisation_off = false;
  int halvings = 0, halvings_in_row = 0;
  Eigen::VectorXd theta_end;  // where the step being halved ended
  std::vector<double> x_end;
  // Set when Gauss-Newton on the exact increments has converged: that is the
  // minimum of the exact problem, so the next pass only solves the trajectory
  // at it (the linearised increments, whose gradient differs from the exact
  // one by the weights' dependence on theta, would step a fraction of a sigma
  // away and back without end: the real roll runs, 0.4-0.9 sigma a pass).
  bool at_exact_minimum = false;
  res->converged = false;
  BatchOptions o = opt;
  // Gauss-Newton on the reduced cost (the trajectory solved for at every
  // step, reduced_run.h): one linearisation per step and quadratic
  // convergence on the exact problem; the next pass then relinearises at its
  // solution, where Ceres has next to nothing left to do.
  auto exact_gauss_newton = [&]() {
    say("Gauss-Newton on the exact increments");
    bool gn_converged = false;
    int gn_iterations = 0;
    theta_free = MinimiseReducedCost(p, theta_free, threads, kExactGaussNewtonSteps,
                                     opt.outer_tolerance, &gn_converged, &gn_iterations, say);
    res->ceres_iterations += gn_iterations;
    for (std::size_t e = 0; e < E; ++e) {
      Eigen::Map<Vec6> x_e(&x[6 * e]);
      x_e = model.Measurement(e, model.Expand(theta_free), false, false).h;
    }
    // The next pass's cost is the true one at a better point: no backtracking.
    cost_prev = std::numeric_limits<double>::infinity();
    predicted_cost = std::numeric_limits<double>::quiet_NaN();
    last_step = 0.0;
    halvings_in_row = 0;
    if (gn_converged) {
      at_exact_minimum = true;
    } else {
      st->exact = true;  // the slow but sure way for the rest
    }
  };
  for (int outer = 0; outer < opt.max_outer_iterations + halvings || at_exact_minimum; ++outer) {
    o.exact_increments = opt.exact_increments || st->exact;
    say(o.exact_increments && !opt.exact_increments
            ? "solving with exact increments (pass " + std::to_string(outer + 1) + ")"
            : "relinearising pass " + std::to_string(outer + 1));
    const double pass_begin = 0.3 + 0.65 * (1.0 - std::pow(0.5, outer));
    const double pass_end = 0.3 + 0.65 * (1.0 - std::pow(0.5, outer + 1));
    if (opt.fraction) opt.fraction(pass_begin);
    st->lin = Linearize(p, model.Expand(theta_free), !o.exact_increments, threads);
    st->lp = BuildCeresProblem(model, st->lin, A, b, o, &x, &theta_free);
    ceres::Solver::Options so = SolverOptions(opt, threads, E, &x, &theta_free);
    // The true cost at this point (before solving), to judge the last step.
    double cost_here = 0.0;
    st->lp.problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost_here, nullptr, nullptr,
                             nullptr);
    if (std::isfinite(predicted_cost) && predicted_change > 0.0) {
      linearisation_off = std::abs(cost_here - predicted_cost) > kMissRatio * predicted_change;
    }
    if (at_exact_minimum) {
      // The trajectory for this theta (a linear problem), then stop.
      st->lp.problem->SetParameterBlockConstant(theta_free.data());
      ceres::Solver::Summary summary;
      ceres::Solve(so, st->lp.problem.get(), &summary);
      st->lp.problem->SetParameterBlockVariable(theta_free.data());
      res->outer_iterations += 1;
      res->ceres_iterations += static_cast<int>(summary.iterations.size()) - 1;
      res->final_cost = summary.final_cost;
      res->converged = summary.termination_type != ceres::FAILURE;
      say("  converged: the minimum of the exact problem (Gauss-Newton), trajectory solved "
          "at it");
      break;
    }
    if (cost_here > cost_prev * (1.0 + 1e-9) && halvings < 20 && !o.exact_increments) {
      if (halvings_in_row < kHalvingsBeforeExact) {
        if (halvings_in_row == 0) {
          theta_end = theta_free;
          x_end = x;
        }
        ++halvings;
        ++halvings_in_row;
        theta_free = 0.5 * (theta_free + theta_prev);
        for (std::size_t i = 0; i < x.size(); ++i) x[i] = 0.5 * (x[i] + x_prev[i]);
        continue;
      }
      say("  the linearised step made the cost worse even at 1/" +
          std::to_string(1 << kHalvingsBeforeExact) + " of its length");
      theta_free = theta_end;
      x = x_end;
      exact_gauss_newton();
      continue;
    }
    halvings_in_row = 0;
    theta_prev = theta_free;
    x_prev = x;
    cost_prev = cost_here;
    // Each Ceres iteration moves the fraction a third of the way to the pass's end.
    IterationFraction iteration_fraction(pass_begin, pass_end, opt.fraction);
    if (opt.fraction) so.callbacks.push_back(&iteration_fraction);
    ceres::Solver::Summary summary;
    ceres::Solve(so, st->lp.problem.get(), &summary);
    if (summary.termination_type == ceres::FAILURE) {
      throw std::runtime_error(
          "Ceres failed: " + summary.message +
          " (most likely cause in the input: a reading, angle or time far outside the "
          "rest of the run, or a prior or constraint sigma that fixes a parameter)");
    }
    res->outer_iterations += 1;
    res->ceres_iterations += static_cast<int>(summary.iterations.size()) - 1;
    res->final_cost = summary.final_cost;
    predicted_cost = summary.final_cost;
    predicted_change = std::max(0.0, summary.initial_cost - summary.final_cost);
    // Convergence of the relinearisation. The cost change of an inner solve is
    // 0.5 |step|^2 in the metric of the information matrix, so s = sqrt(2
    // change) is the step in sigma units. Relinearising converges
    // quadratically, s_k ~ c s_{k-1}^2: the next step is predicted as
    // (s_k / s_{k-1}^2) s_k^2, and once that is below 0.01 sigma another pass
    // over the samples would not move the answer.
    const double change = std::max(0.0, summary.initial_cost - summary.final_cost);
    const double step = std::sqrt(2.0 * change);
    const bool small = change < opt.outer_tolerance;
    const bool predicted_small = last_step > 0.0 && step < 1.0 &&
                                 (step / (last_step * last_step)) * step * step < 0.01;
    const bool slow = outer >= kPassesBeforeExact && last_step > 0.0 &&
                      step > kSlowRatio * last_step;
    last_step = step;
    {
      char line[200];
      std::snprintf(line, sizeof(line),
                    "  pass %d: cost %.6g -> %.6g, step %.3g sigma, %d Ceres iterations", outer + 1,
                    summary.initial_cost, summary.final_cost, step,
                    static_cast<int>(summary.iterations.size()) - 1);
      say(line);
    }
    if (o.exact_increments || small || predicted_small) {
      res->converged = summary.termination_type == ceres::CONVERGENCE || small || predicted_small;
      break;
    }
    // Exact increments only help when the linearised increments are what
    // holds the passes back: their prediction of the cost at the last point
    // missed by more than kMissRatio of the decrease it promised.
    if (slow && linearisation_off) exact_gauss_newton();
  }
}

// Residuals at the solution, raw and whitened, and their summaries.
void CollectResiduals(const RunProblem& p, const RunData& data, const BatchLinearization& lin,
                      const LinearisedProblem& lp, const std::vector<double>& x,
                      const Eigen::VectorXd& theta_free, BatchResult* res) {
  const std::size_t E = p.epochs.size();
  const int nf = static_cast<int>(theta_free.size());
  res->epoch_t.resize(E);
  res->epoch_samples = p.epochs;
  res->measurement_residual.assign(E, Vec6::Zero());
  res->process_residual.assign(E, Vec6::Zero());
  res->measurement_whitened.assign(E, Vec6::Zero());
  res->process_whitened.assign(E, Vec6::Zero());
  Vec6 mss = Vec6::Zero(), pss = Vec6::Zero();
  double mw = 0.0, pw = 0.0;
  for (std::size_t e = 0; e < E; ++e) {
    res->epoch_t[e] = data.t_s[p.epochs[e]];
    const Vec6 rm = lp.measurement[e]->Raw(&x[6 * e], theta_free.data());
    res->measurement_residual[e] = rm;
    mss += rm.cwiseAbs2();
    res->measurement_whitened[e] = lin.LR[e] * rm;
    mw += res->measurement_whitened[e].squaredNorm();
    if (e > 0) {
      const Vec6 rp = lp.process[e - 1]->Raw(&x[6 * (e - 1)], &x[6 * e], theta_free.data());
      res->process_residual[e] = rp;
      pss += rp.cwiseAbs2();
    }
  }
  // Whitened as a sequence: neighbouring intervals share their epoch's sample.
  {
    const StateSpaceModel model(p);
    const std::vector<Vec6> raw(res->process_residual.begin() + 1, res->process_residual.end());
    const std::vector<Vec6> white =
        model.WhitenProcessSequence(lin.process, raw, model.Expand(lin.theta_lin_free));
    for (std::size_t e = 1; e < E; ++e) {
      res->process_whitened[e] = white[e - 1];
      pw += white[e - 1].squaredNorm();
    }
  }
  res->residuals.measurement_rms = (mss / E).cwiseSqrt();
  res->residuals.process_rms = (pss / (E - 1)).cwiseSqrt();
  res->residuals.measurement_whitened_rms = std::sqrt(mw / (6.0 * E));
  res->residuals.process_whitened_rms = std::sqrt(pw / (6.0 * (E - 1)));
  const int nc = static_cast<int>(p.constraints.size());
  res->residual_count = static_cast<int>(12 * E - 6 + nf + nc);
  res->degrees_of_freedom = res->residual_count - static_cast<int>(6 * E) - nf;
  res->chi2_per_dof = 2.0 * res->final_cost / std::max(1, res->degrees_of_freedom);
}

// Covariance of the free parameters at the solution, and with the Schur
// method its HAC sandwich (hac_covariance.h) when `hac` is given.
Eigen::MatrixXd FreeCovariance(const RunProblem& p, const BatchLinearization& lin,
                               const LinearisedProblem& lp, const Eigen::VectorXd& theta,
                               Eigen::VectorXd* theta_free, const std::vector<double>* x,
                               const Eigen::MatrixXd& A, const BatchOptions& opt, int threads,
                               std::vector<Eigen::MatrixXd>* process_jacobians,
                               HacCovariance* hac) {
  const int nf = static_cast<int>(theta_free->size());
  const bool use_ceres = opt.covariance_method == "ceres" || !opt.robust_loss.empty();
  if (!use_ceres && opt.covariance_method != "schur") {
    throw OptionError("covariance_method",
                      "unknown method '" + opt.covariance_method + "' (schur, ceres)");
  }
  if (!use_ceres) {
    // The process costs' own Jacobians by theta (with the derivative of
    // their whitening), so that both paths factor the same Jacobian, and
    // every whitened residual at the solution for the epoch scores.
    const std::size_t E = p.epochs.size();
    std::vector<Eigen::MatrixXd> C(E - 1);
    std::vector<Vec6> rp(E - 1), rm(E);
    ParallelFor(E, threads, [&](std::size_t e) {
      if (e + 1 < E) {
        const ProcessCost* cost = lp.process[e];
        Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor> J(6, nf);
        const double* params[3] = {&(*x)[6 * e], &(*x)[6 * (e + 1)], theta_free->data()};
        double* jac[3] = {nullptr, nullptr, J.data()};
        cost->Evaluate(params, rp[e].data(), jac);
        C[e] = J;
      }
      const double* params[2] = {&(*x)[6 * e], theta_free->data()};
      lp.measurement[e]->Evaluate(params, rm[e].data(), nullptr);
    });
    std::vector<ProcessBlock> pb;
    std::vector<MeasurementBlock> mb;
    SchurBlocks(p, lin, theta, threads, &C, &pb, &mb);
    for (std::size_t e = 0; e < E; ++e) {
      if (e + 1 < E) pb[e].r0 = rp[e];
      mb[e].r0 = rm[e];
    }
    const Eigen::MatrixXd info = ThetaInformationBySchur(pb, mb, A);
    const Eigen::MatrixXd cov =
        Eigen::LDLT<Eigen::MatrixXd>(info).solve(Eigen::MatrixXd::Identity(nf, nf));
    if (hac) {
      *hac = HacThetaCovariance(EpochScores(pb, mb), info, A.transpose() * A,
                                opt.hac_bandwidth_epochs, false,
                                opt.hac_kernel_bias_correction);
    }
    if (process_jacobians) *process_jacobians = std::move(C);
    return cov;
  }
  // Ceres's sparse QR on the whole Jacobian (applies the robust loss's
  // weights). The priors keep the Jacobian full rank.
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::SPARSE_QR;
  co.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  co.num_threads = threads;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> blocks = {
      {theta_free->data(), theta_free->data()}};
  if (!cov.Compute(blocks, lp.problem.get())) {
    throw std::runtime_error("covariance of theta: Ceres could not factor the Jacobian");
  }
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> C(nf, nf);
  cov.GetCovarianceBlock(theta_free->data(), theta_free->data(), C.data());
  return C;
}

// One fit with the hold decision of opt.holding (SolveBatch adds the pins).
BatchResult SolveBatchOnce(const RunDescription& run, const RunData& data,
                           const ParameterLayout& layout, const BatchOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  const int threads = opt.threads > 0 ? opt.threads : DefaultThreads();
  SolverType(opt.linear_solver);  // checks the name before the work
  if (opt.sigma != "auto" && opt.sigma != "white" && opt.sigma != "hac") {
    throw OptionError("sigma", "unknown '" + opt.sigma + "' (auto, white, hac)");
  }
  if (opt.sigma == "hac" && (opt.covariance_method != "schur" || !opt.robust_loss.empty())) {
    throw OptionError("sigma", "hac needs the Schur covariance (not with a robust loss)");
  }
  RunProblem p = BuildRunProblem(run, data, layout, opt.epoch_s, opt.derivatives);
  const std::size_t E = p.epochs.size();
  auto say = [&](const std::string& s) {
    if (opt.progress) opt.progress(s);
  };

  BatchResult res;
  res.prior = p.prior;
  res.epochs = static_cast<int>(E);
  res.linear_solver = opt.linear_solver;

  RunDescription run_start = run;  // the noise the start (RTS) assumes
  if (run.noise_auto) {
    // noise_mV: auto starts from the readings' own white noise (second
    // differences, sample_noise.h), one level for the three channels (their
    // split is the residuals' to tell, below): the largest channel's. A
    // start below the residual's level lets a weakly determined scale factor
    // run (real medium roll run: at 46 mV Ky ran to its 1/5 bound, at 55 and
    // 69 mV it stays): the cost lacks the log-det term of the noise, which
    // follows the scale factors, so lowering a scale factor buys chi2.
    Eigen::Vector3d sd;
    for (int i = 0; i < 3; ++i) sd[i] = SecondDifferenceNoise(data.w_mV[i]);
    const double level = sd.maxCoeff();
    res.noise_auto = true;
    if (level > 0.0) {
      res.noise_start_mV = level;
      p.noise_mV = Eigen::Vector3d::Constant(level);
      run_start.noise_mV = level;
      run_start.noise_channel_mV.reset();
    }
    char figures[160];
    std::snprintf(figures, sizeof(figures),
                  "noise_mV auto: starting from the readings' own noise, %.3g mV (second "
                  "differences %.3g %.3g %.3g mV)",
                  p.noise_mV[0], sd[0], sd[1], sd[2]);
    say(figures);
  }

  // 1. Which parameters are estimated: the held ones leave the problem.
  if (opt.holding.auto_hold || !opt.holding.hold.empty() || !opt.holding.pinned.empty()) {
    say("choosing the parameters this run supports");
    if (opt.fraction) opt.fraction(0.0);
    const HoldDecision hd = ChooseHeldParameters(run_start, data, layout, opt.holding, opt.epoch_s,
                                                 opt.derivatives, opt.init_decimation_hz, threads);
    res.unsupported_at_start = hd.unsupported;
    res.information_at_start = hd.information;
    res.held = hd.held;
    res.relative_to = hd.relative_to;
    std::vector<int> held;
    for (const std::string& name : hd.held) held.push_back(layout.IndexOf(name));
    p.Hold(held);
  }
  const StateSpaceModel model(p);

  // 2. The start.
  say("initialising (" + std::string(opt.init == BatchInit::kRts ? "RTS smoother" : "nominal") +
      ")");
  if (opt.fraction) opt.fraction(0.1);
  res.initial = Initialise(run_start, data, layout, p, opt, res.held);
  res.init_seconds = Seconds(t_start);
  Eigen::VectorXd theta_free = model.Free(res.initial.theta);
  // The trajectory starts on the B2 reference motion.
  std::vector<double> x(6 * E);
  for (std::size_t e = 0; e < E; ++e) {
    Eigen::Map<Vec6> x_e(&x[6 * e]);
    x_e = model.Measurement(e, res.initial.theta, false, false).h;
  }
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  model.ThetaRows(true, &A, &b);

  // 3. Relinearise and solve until the linearisation point stops moving.
  const auto t_solve = std::chrono::steady_clock::now();
  SolveState st{theta_free, std::move(x), {}, {}};
  Relinearise(p, model, A, b, opt, threads, say, &st, &res);
  CollectResiduals(p, data, st.lin, st.lp, st.x, st.theta_free, &res);

  // 4. The noise from the residuals: refit with it when the run asks for it
  // (noise_mV: auto) or when the declared noise is not what the residuals
  // hold, so that sigma rests on the noise the run has.
  res.noise_declared_mV = run.ChannelNoise_mV();
  res.noise_source = "declared";
  res.noise_check = EstimateChannelNoise(model, st.lin, res.process_residual,
                                         res.degrees_of_freedom, res.process_whitened);
  if (opt.estimate_noise) {
    // Per channel when the residual is noise: refit with it. When it is not
    // (not white, or channels unalike: noise_estimation.h), its split between
    // channels, and between readings and angles, is misfit; then the weights
    // stay and one a-posteriori variance factor, chi2/dof, scales the
    // covariance (no refit: the estimate is the declared weights' one).
    for (int pass = 0; pass < 4; ++pass) {
      const NoiseEstimate ne = EstimateChannelNoise(model, st.lin, res.process_residual,
                                                    res.degrees_of_freedom, res.process_whitened);
      if (pass == 0) {
        res.noise_check = ne;
        if (run.noise_auto && ne.dof.minCoeff() < kMinNoiseDof) {
          throw InputError(run.yaml_path + ": triad.noise_mV: auto needs a longer run: " +
                           std::to_string(static_cast<int>(ne.dof.minCoeff())) +
                           " degrees of freedom in the weakest channel, at least " +
                           std::to_string(static_cast<int>(kMinNoiseDof)) +
                           " (declare the noise instead)");
        }
        if (!ne.PerChannel()) {
          if (run.noise_auto) {
            // No figure declared to keep: the readings at the residual's
            // common level first (the start is arbitrary), then the factor.
            p.noise_mV = Eigen::Vector3d::Constant(std::sqrt(ne.estimated_mV.squaredNorm() / 3));
            say("refitting with the readings' noise at the residual's common level");
            Relinearise(p, model, A, b, opt, threads, say, &st, &res);
            CollectResiduals(p, data, st.lin, st.lp, st.x, st.theta_free, &res);
            // The per-channel figures of the refit's residual (the decision,
            // white and alike, stays the one taken above).
            const NoiseEstimate again = EstimateChannelNoise(
                model, st.lin, res.process_residual, res.degrees_of_freedom, res.process_whitened);
            res.noise_check.estimated_mV = again.estimated_mV;
            res.noise_check.sd_mV = again.sd_mV;
            res.noise_check.dof = again.dof;
          }
          const double f = res.chi2_per_dof;
          const double sd = std::sqrt(2.0 / std::max(1, res.degrees_of_freedom));
          res.noise_check.consistent = std::abs(f - 1.0) <= 3.0 * sd;
          if (run.noise_auto || !res.noise_check.consistent) {
            res.variance_factor = f;
            res.noise_source = "estimated_common";
            char figures[120];
            std::snprintf(figures, sizeof(figures), " (chi2/dof %.3g; worst lag-1 %.2f)", f,
                          ne.lag1.cwiseAbs().maxCoeff());
            say(std::string(ne.white ? "one weight for the three channels: their residuals "
                                       "differ beyond 3x, more than one triad's noise does"
                                     : "one variance factor for the whole run: the residual is "
                                       "not white, so its split between channels is misfit, "
                                       "not noise") +
                figures);
          }
          break;
        }
        if (!run.noise_auto && ne.consistent) break;
      }
      res.noise_estimate = ne;
      const Eigen::Vector3d next = ne.estimated_mV;
      const double change = (next - p.noise_mV).cwiseQuotient(p.noise_mV).cwiseAbs().maxCoeff();
      if (pass > 0 && change < 0.01) break;
      p.noise_mV = next;
      res.noise_source = "estimated";
      char figures[120];
      std::snprintf(figures, sizeof(figures), " (%.3g %.3g %.3g mV; worst lag-1 %.2f)", next[0],
                    next[1], next[2], ne.lag1.cwiseAbs().maxCoeff());
      say(std::string("refitting with the noise estimated from the residuals") + figures);
      Relinearise(p, model, A, b, opt, threads, say, &st, &res);
      CollectResiduals(p, data, st.lin, st.lp, st.x, st.theta_free, &res);
    }
  }
  res.noise_used_mV = p.noise_mV;
  res.solve_seconds = Seconds(t_solve);
  const Eigen::VectorXd theta = model.Expand(st.theta_free);
  res.estimate.theta = theta;

  // 5. Covariance at the solution: the model's (white) and the HAC sandwich;
  // sigma is the HAC one when the residual is not white.
  res.estimate.cov = Eigen::MatrixXd::Zero(p.n, p.n);
  if (opt.compute_covariance) {
    say("covariance");
    if (opt.fraction) opt.fraction(0.95);
    const auto t_cov = std::chrono::steady_clock::now();
    std::vector<Eigen::MatrixXd> C;
    HacCovariance hac;
    const bool with_hac = opt.covariance_method == "schur" && opt.robust_loss.empty();
    const Eigen::MatrixXd cov_free = FreeCovariance(p, st.lin, st.lp, theta, &st.theta_free,
                                                    &st.x, A, opt, threads, &C,
                                                    with_hac ? &hac : nullptr);
    res.process_whitened_expected_acf = ExpectedProcessAutocorrelation(C, cov_free, 20);
    const WhitenessSummary w =
        ProcessWhiteness(res.process_whitened, res.process_whitened_expected_acf);
    res.whiteness_p_value = w.p_value;
    res.residual_white = w.white;
    // The a-posteriori variance factor (1 unless the noise was judged misfit).
    res.cov_white = ExpandCovariance(p, cov_free) * res.variance_factor;
    res.estimate.cov = res.cov_white;
    // One weight for channels whose residuals differ beyond kMaxChannelRatio
    // (the split was not used): the model's covariance gives every channel's
    // parameters the common level, too small for the loud channel's and too
    // large for the quiet one's (real medium roll run: 20.5 / 3.1 / 16.7 mV
    // weighted alike at 15.4). The sandwich measures what each channel's
    // residual holds, so it is the reported sigma then, white or not.
    const bool misweighted =
        res.noise_source == "estimated_common" && !res.noise_check.channels_alike;
    if (with_hac) {
      res.hac_bandwidth_epochs = hac.bandwidth;
      res.hac_kernel_bias_corrected = opt.hac_kernel_bias_correction;
      res.hac_kernel_bias_factor_max = hac.kernel_bias_factor.size() > 0
                                           ? hac.kernel_bias_factor.maxCoeff()
                                           : 1.0;
      res.cov_hac = ExpandCovariance(p, hac.cov);
      if (opt.sigma == "hac" || (opt.sigma == "auto" && (!res.residual_white || misweighted))) {
        res.sigma_method = "hac";
        // The floor: the model's covariance, or with misweighted channels the
        // Cramer-Rao bound with each channel at the noise its residual holds
        // (no estimator of these data does better; the angles as declared).
        Eigen::MatrixXd floor = res.cov_white;
        res.hac_floor = "white";
        if (misweighted) {
          RunProblem q = p;
          q.noise_mV = res.noise_check.estimated_mV;
          const BatchLinearization lq = Linearize(q, theta, true, threads);
          floor = ExpandCovariance(p, ThetaCovariance(q, lq, theta, A, threads));
          res.hac_floor = "per_channel_bound";
        }
        res.estimate.cov = FloorVariances(res.cov_hac, floor);
        if (opt.sigma == "auto") {
          char figures[200];
          std::snprintf(figures, sizeof(figures),
                        " (whiteness p %.2g; Bartlett bandwidth %.1f epochs)", w.p_value,
                        hac.bandwidth);
          say(std::string(res.residual_white
                              ? "sigma from the HAC covariance: one weight serves channels "
                                "whose residuals differ beyond 3x"
                              : "sigma from the HAC covariance: the residual is correlated in "
                                "time") +
              figures);
        }
      }
    }
    res.covariance_seconds = Seconds(t_cov);
  } else {
    // Whiteness without the fit's own autocorrelation (it needs the covariance).
    const WhitenessSummary w = ProcessWhiteness(res.process_whitened, {});
    res.whiteness_p_value = w.p_value;
    res.residual_white = w.white;
  }
  if (opt.fraction) opt.fraction(1.0);
  return res;
}

}  // namespace

void AddPinnedUncertainty(const ParameterLayout& layout, BatchResult* r) {
  const int n = layout.size();
  if (r->information_at_start.rows() != n) return;
  std::vector<int> kept, pins;
  for (int i = 0; i < n; ++i) {
    if (std::find(r->held.begin(), r->held.end(), layout.info(i).name) == r->held.end()) {
      kept.push_back(i);
    }
  }
  for (const PinnedExcursion& p : r->pinned) {
    if (layout.IndexOf(p.name) < 0) {
      throw std::logic_error("AddPinnedUncertainty: pinned '" + p.name + "' is not in the layout");
    }
    pins.push_back(layout.IndexOf(p.name));
  }
  std::vector<int> both = kept;
  both.insert(both.end(), pins.begin(), pins.end());
  const int k = static_cast<int>(kept.size()), m = static_cast<int>(pins.size());
  const Eigen::MatrixXd& info = r->information_at_start;
  const Eigen::MatrixXd marginal = PosteriorOver(info, both);
  const Eigen::MatrixXd conditional = PosteriorOver(info, kept);
  // In prior units: S = -conditional Lambda_kp (the prior adds nothing off
  // the diagonal), and marginal_kk - conditional = S P S^T with P the pins'
  // block of the marginal posterior.
  Eigen::MatrixXd info_kp(k, m);
  for (int a = 0; a < k; ++a)
    for (int q = 0; q < m; ++q) info_kp(a, q) = info(kept[a], pins[q]);
  const Eigen::MatrixXd S = -conditional * info_kp;
  r->pinned_sensitivity = Eigen::MatrixXd::Zero(n, m);
  r->pinned_cov = Eigen::MatrixXd::Zero(m, m);
  for (int q = 0; q < m; ++q) {
    const double sq = r->prior.sigma[pins[q]];
    for (int a = 0; a < k; ++a) {
      r->pinned_sensitivity(kept[a], q) = S(a, q) * r->prior.sigma[kept[a]] / sq;
    }
    for (int c = 0; c < m; ++c) {
      r->pinned_cov(q, c) = marginal(k + q, k + c) * sq * r->prior.sigma[pins[c]];
    }
  }
  Eigen::MatrixXd add = Eigen::MatrixXd::Zero(n, n);
  for (int a = 0; a < k; ++a) {
    for (int b = 0; b < k; ++b) {
      add(kept[a], kept[b]) = (marginal(a, b) - conditional(a, b)) * r->prior.sigma[kept[a]] *
                              r->prior.sigma[kept[b]];
    }
  }
  r->cov_given_pinned = r->estimate.cov;
  for (Eigen::MatrixXd* c : {&r->estimate.cov, &r->cov_white, &r->cov_hac}) {
    if (c->rows() == n) *c += add;
  }
}

std::string DescribePins(const std::vector<PinnedExcursion>& pinned) {
  std::string out;
  for (const PinnedExcursion& p : pinned) {
    char one[96];
    std::snprintf(one, sizeof(one), "%s%s (%+.1f, %.2g)", out.empty() ? "" : " ", p.name.c_str(),
                  p.z, p.data_information);
    out += one;
  }
  return out;
}

bool IsPinned(const BatchResult& r, const std::string& name) {
  return std::any_of(r.pinned.begin(), r.pinned.end(),
                     [&](const PinnedExcursion& p) { return p.name == name; });
}

Eigen::VectorXd MarginalInformationAtStart(const ParameterLayout& layout, const BatchResult& r) {
  const int n = layout.size();
  if (r.information_at_start.rows() != n) return {};
  std::vector<int> kept;
  for (int i = 0; i < n; ++i) {
    if (std::find(r.held.begin(), r.held.end(), layout.info(i).name) == r.held.end()) {
      kept.push_back(i);
    }
  }
  Eigen::VectorXd info = Eigen::VectorXd::Zero(n);
  const Eigen::MatrixXd C = PosteriorOver(r.information_at_start, kept);
  for (std::size_t a = 0; a < kept.size(); ++a) {
    info[kept[a]] = 1.0 / std::max(C(a, a), 1e-300) - 1.0;
  }
  return info;
}

std::vector<PinnedExcursion> WeakExcursions(const ParameterLayout& layout, const BatchResult& r,
                                            const HoldPolicy& policy) {
  std::vector<PinnedExcursion> out;
  const Eigen::VectorXd info = MarginalInformationAtStart(layout, r);
  if (info.size() != layout.size()) return out;
  for (const PriorExcursion& e :
       BeyondPrior(layout, r.estimate.theta, r.prior.mean, r.prior.sigma,
                   policy.pin_excursion_sigma)) {
    const int i = layout.IndexOf(e.name);
    if (std::find(r.held.begin(), r.held.end(), e.name) != r.held.end()) continue;
    if (std::find(policy.free.begin(), policy.free.end(), e.name) != policy.free.end()) continue;
    if (info[i] > policy.pin_max_information) continue;
    out.push_back({e.name, e.z, info[i]});
  }
  return out;
}

BatchResult SolveBatch(const RunDescription& run, const RunData& data,
                       const ParameterLayout& layout, const BatchOptions& opt) {
  const bool may_pin = opt.holding.auto_hold && opt.holding.pin_weak_excursions;
  // With pins possible the first fit reports 0..0.7 and each refit the next
  // part (0.7..0.9, 0.9..0.97, 0.97..0.99), so the fraction only climbs.
  auto within = [&opt](double lo, double hi) {
    BatchOptions o = opt;
    if (opt.fraction) {
      o.fraction = [f = opt.fraction, lo, hi](double x) { f(lo + (hi - lo) * x); };
    }
    return o;
  };
  BatchResult res = SolveBatchOnce(run, data, layout, may_pin ? within(0.0, 0.7) : opt);
  if (!may_pin) return res;
  // Each pin moves the fit: what it then moves is checked again (at most
  // three refits; a parameter once pinned stays pinned).
  std::vector<PinnedExcursion> pinned;
  constexpr double kRefitEnds[4] = {0.7, 0.9, 0.97, 0.99};
  for (int round = 0; round < 3; ++round) {
    const std::vector<PinnedExcursion> more = WeakExcursions(layout, res, opt.holding);
    if (more.empty()) break;
    BatchOptions o = within(kRefitEnds[round], kRefitEnds[round + 1]);
    for (const PinnedExcursion& p : pinned) o.holding.pinned.push_back(p.name);
    std::string names;
    for (const PinnedExcursion& p : more) {
      o.holding.pinned.push_back(p.name);
      pinned.push_back(p);
      char one[96];
      std::snprintf(one, sizeof(one), " %s (%+.1f prior sigma, data information %.2g)",
                    p.name.c_str(), p.z, p.data_information);
      names += one;
    }
    if (opt.progress) {
      char head[160];
      std::snprintf(head, sizeof(head),
                    "refitting with weakly determined parameters that the fit moved beyond %g "
                    "prior sigma pinned at nominal:",
                    opt.holding.pin_excursion_sigma);
      opt.progress(head + names);
    }
    res = SolveBatchOnce(run, data, layout, o);
    res.pinned = pinned;
  }
  if (!pinned.empty()) AddPinnedUncertainty(layout, &res);
  if (opt.fraction) opt.fraction(1.0);
  return res;
}

}  // namespace triadcal
