#include "solvers/estimation/batch_solver.h"

#include <ceres/ceres.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include "core/model/errors.h"
#include "solvers/estimation/batch_costs.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/batch_linearization.h"
#include "solvers/estimation/observability.h"

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
                    const RunProblem& p, const BatchOptions& opt) {
  const int n = p.n;
  Estimate e{p.prior.mean, Eigen::MatrixXd(p.prior.sigma.array().square().matrix().asDiagonal())};
  if (opt.init == BatchInit::kGiven) {
    if (opt.init_theta.size() != n) throw std::invalid_argument("init_theta has the wrong size");
    e.theta = opt.init_theta;
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
  const FilterResult fr = RunFilterSmoother(run, thin, layout, fo);
  return fr.rts;
}

std::unique_ptr<ceres::LossFunction> MakeLoss(const BatchOptions& opt) {
  if (opt.robust_loss.empty()) return nullptr;
  if (opt.robust_loss == "huber") return std::make_unique<ceres::HuberLoss>(opt.robust_scale);
  if (opt.robust_loss == "cauchy") return std::make_unique<ceres::CauchyLoss>(opt.robust_scale);
  throw InputError("--robust: unknown loss '" + opt.robust_loss + "' (huber, cauchy)");
}

ceres::LinearSolverType SolverType(const std::string& name) {
  if (name == "sparse_normal_cholesky") return ceres::SPARSE_NORMAL_CHOLESKY;
  if (name == "sparse_schur") return ceres::SPARSE_SCHUR;
  if (name == "dense_qr") return ceres::DENSE_QR;
  throw InputError("--linear-solver: unknown '" + name +
                   "' (sparse_normal_cholesky, sparse_schur, dense_qr)");
}

// The parameters the data determine: pivoted Cholesky of the data information
// in prior units (cov is the posterior with priors; the prior contributes the
// identity there). Most informative first, primary parameters preferred among
// near-equals; stops when what is left is below min_info.
std::vector<int> SupportedParameters(const Eigen::MatrixXd& cov, const Eigen::VectorXd& prior_sigma,
                                     const Eigen::VectorXd& min_info) {
  const int n = static_cast<int>(cov.rows());
  const Eigen::MatrixXd Pn =
      prior_sigma.cwiseInverse().asDiagonal() * cov * prior_sigma.cwiseInverse().asDiagonal();
  Eigen::MatrixXd S = Pn.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  S.diagonal().array() -= 1.0;
  auto priority = [](int i) {
    if (i <= kW0z) return 4.0;      // scale factors, zero offsets
    if (i <= kGammaZ) return 2.0;   // misalignments
    if (i >= kDx2 && i <= kDz2) return 2.0;
    return 1.0;                     // K_ij, bench zeros, effects
  };
  std::vector<int> kept;
  std::vector<bool> used(n, false);
  for (;;) {
    int best = -1;
    double best_score = 0.0;
    for (int j = 0; j < n; ++j) {
      if (used[j] || S(j, j) < min_info[j]) continue;
      const double score = S(j, j) * priority(j);
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

}  // namespace

HoldDecision ChooseHeldParameters(const RunDescription& run, const RunData& data,
                                  const ParameterLayout& layout, const HoldPolicy& o,
                                  double epoch_s, const AngleDerivativeOptions& derivatives,
                                  int decimation_hz, int threads) {
  const int n = layout.size();
  if (threads <= 0) threads = DefaultThreads();
  HoldDecision d;
  std::vector<bool> held(n, false);
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
  }
  auto index_of = [&](const std::string& name) {
    const int i = layout.IndexOf(name);
    if (i < 0) throw InputError("--hold/--free: unknown parameter '" + name + "'");
    return i;
  };
  for (const std::string& h : o.hold) held[index_of(h)] = true;
  for (const std::string& f : o.free) held[index_of(f)] = false;
  for (int i = 0; i < n; ++i) {
    if (held[i]) d.held.push_back(layout.info(i).name);
  }
  return d;
}

BatchResult SolveBatch(const RunDescription& run, const RunData& data,
                       const ParameterLayout& layout, const BatchOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  const int threads = opt.threads > 0 ? opt.threads : DefaultThreads();
  const ceres::LinearSolverType solver_type = SolverType(opt.linear_solver);
  RunProblem p = BuildRunProblem(run, data, layout, opt.epoch_s, opt.derivatives);
  const int n = p.n;
  const std::size_t E = p.epochs.size();
  auto say = [&](const std::string& s) {
    if (opt.progress) opt.progress(s);
  };

  BatchResult res;
  res.prior = p.prior;
  res.epochs = static_cast<int>(E);
  res.linear_solver = opt.linear_solver;
  RunDescription run_held = run;
  if (opt.holding.auto_hold || !opt.holding.hold.empty()) {
    say("choosing the parameters this run supports");
    const HoldDecision hd = ChooseHeldParameters(run, data, layout, opt.holding, opt.epoch_s,
                                                 opt.derivatives, opt.init_decimation_hz, threads);
    res.unsupported_at_start = hd.unsupported;
    res.held = hd.held;
    for (const std::string& name : hd.held) {
      const int i = layout.IndexOf(name);
      // Pinned with a prior a million times tighter, here and in the start.
      p.prior.sigma[i] *= 1e-6;
      run_held.prior_sigma[name] = p.prior.sigma[i] / layout.info(i).si_per_unit;
    }
  }

  say("initialising (" + std::string(opt.init == BatchInit::kRts ? "RTS smoother" : "nominal") +
      ")");
  res.initial = Initialise(run_held, data, layout, p, opt);
  for (int i = 0; i < n; ++i) {
    if (p.prior.sigma[i] < res.prior.sigma[i]) res.initial.theta[i] = p.prior.mean[i];
  }
  res.init_seconds = Seconds(t_start);

  // Unknowns: theta and the trajectory, started on the B2 reference motion.
  Eigen::VectorXd theta = res.initial.theta;
  std::vector<double> x(6 * E);
  for (std::size_t e = 0; e < E; ++e) {
    const ReferenceSample r = EvaluateReference(p.cfg, theta, p.series.recorded[p.epochs[e]], false);
    Eigen::Map<Vec6>(&x[6 * e]) << r.v_mps, r.p_m;
  }

  // Priors and constraints: fixed linear rows over theta.
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  ThetaRows(p, true, &A, &b);
  const int nc = static_cast<int>(p.constraints.size());

  const auto t_solve = std::chrono::steady_clock::now();
  BatchLinearization lin;
  std::unique_ptr<ceres::Problem> problem;
  std::vector<ProcessCost*> process_costs(E - 1);
  std::vector<MeasurementCost*> measurement_costs(E);
  double last_step = 0.0;
  // Backtracking: the cost at a new linearisation point is the true cost
  // there; if a step made it worse than at the previous point, go half way back.
  Eigen::VectorXd theta_prev;
  std::vector<double> x_prev;
  double cost_prev = std::numeric_limits<double>::infinity();
  int halvings = 0;
  for (int outer = 0; outer < opt.max_outer_iterations + halvings; ++outer) {
    say("relinearising pass " + std::to_string(outer + 1));
    lin = Linearize(p, theta, !opt.exact_increments, threads);
    const std::vector<IntervalIncrement>& inc = lin.increments;
    const std::vector<Mat6>& LQ = lin.LQ;
    const std::vector<Mat6>& LR = lin.LR;

    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
    problem = std::make_unique<ceres::Problem>(po);
    for (std::size_t e = 0; e < E; ++e) problem->AddParameterBlock(&x[6 * e], 6);
    problem->AddParameterBlock(theta.data(), n);
    for (std::size_t e = 0; e + 1 < E; ++e) {
      ceres::LossFunction* loss = MakeLoss(opt).release();  // may throw: before the cost
      process_costs[e] = new ProcessCost(&inc[e], &lin.theta_lin, LQ[e],
                                         opt.exact_increments ? &p : nullptr, p.epochs[e],
                                         p.epochs[e + 1]);
      problem->AddResidualBlock(process_costs[e], loss, &x[6 * e], &x[6 * (e + 1)],
                                theta.data());
    }
    for (std::size_t e = 0; e < E; ++e) {
      ceres::LossFunction* loss = MakeLoss(opt).release();
      measurement_costs[e] = new MeasurementCost(&p, p.epochs[e], LR[e]);
      problem->AddResidualBlock(measurement_costs[e], loss, &x[6 * e], theta.data());
    }
    problem->AddResidualBlock(new LinearThetaCost(A, b), nullptr, theta.data());

    ceres::Solver::Options so;
    so.linear_solver_type = solver_type;
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
    if (solver_type == ceres::SPARSE_SCHUR) {
      // Eliminate every other epoch's state: an independent set, since the
      // process residuals couple only neighbours.
      auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
      for (std::size_t e = 0; e < E; ++e) ordering->AddElementToGroup(&x[6 * e], e % 2 == 0 ? 0 : 1);
      ordering->AddElementToGroup(theta.data(), 1);
      so.linear_solver_ordering = ordering;
    }
    // The true cost at this point (before solving), to judge the last step.
    double cost_here = 0.0;
    problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost_here, nullptr, nullptr, nullptr);
    if (cost_here > cost_prev * (1.0 + 1e-9) && halvings < 20 && !opt.exact_increments) {
      ++halvings;
      theta = 0.5 * (theta + theta_prev);
      for (std::size_t i = 0; i < x.size(); ++i) x[i] = 0.5 * (x[i] + x_prev[i]);
      continue;
    }
    theta_prev = theta;
    x_prev = x;
    cost_prev = cost_here;
    ceres::Solver::Summary summary;
    ceres::Solve(so, problem.get(), &summary);
    if (summary.termination_type == ceres::FAILURE) {
      throw std::runtime_error(
          "Ceres failed: " + summary.message +
          " (most likely cause in the input: a reading, angle or time far outside the "
          "rest of the run, or a prior or constraint sigma that fixes a parameter)");
    }
    res.outer_iterations = outer + 1;
    res.ceres_iterations += static_cast<int>(summary.iterations.size()) - 1;
    res.final_cost = summary.final_cost;
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
    last_step = step;
    if (opt.exact_increments || small || predicted_small) {
      res.converged = summary.termination_type == ceres::CONVERGENCE || small || predicted_small;
      break;
    }
  }
  res.solve_seconds = Seconds(t_solve);

  // Residuals at the solution.
  res.estimate.theta = theta;
  res.epoch_t.resize(E);
  res.epoch_samples = p.epochs;
  res.measurement_residual.assign(E, Vec6::Zero());
  res.process_residual.assign(E, Vec6::Zero());
  res.measurement_whitened.assign(E, Vec6::Zero());
  res.process_whitened.assign(E, Vec6::Zero());
  Vec6 mss = Vec6::Zero(), pss = Vec6::Zero();
  double mw = 0.0, pw = 0.0;
  for (std::size_t e = 0; e < E; ++e) {
    res.epoch_t[e] = data.t_s[p.epochs[e]];
    const Vec6 rm = measurement_costs[e]->Raw(&x[6 * e], theta.data());
    res.measurement_residual[e] = rm;
    mss += rm.cwiseAbs2();
    res.measurement_whitened[e] = lin.LR[e] * rm;
    mw += res.measurement_whitened[e].squaredNorm();
    if (e > 0) {
      const Vec6 rp = process_costs[e - 1]->Raw(&x[6 * (e - 1)], &x[6 * e], theta.data());
      res.process_residual[e] = rp;
      pss += rp.cwiseAbs2();
      res.process_whitened[e] = lin.LQ[e - 1] * rp;
      pw += res.process_whitened[e].squaredNorm();
    }
  }
  res.residuals.measurement_rms = (mss / E).cwiseSqrt();
  res.residuals.process_rms = (pss / (E - 1)).cwiseSqrt();
  res.residuals.measurement_whitened_rms = std::sqrt(mw / (6.0 * E));
  res.residuals.process_whitened_rms = std::sqrt(pw / (6.0 * (E - 1)));
  res.residual_count = static_cast<int>(12 * E - 6 + n + nc);
  res.degrees_of_freedom = res.residual_count - static_cast<int>(6 * E) - n;
  res.chi2_per_dof = 2.0 * res.final_cost / std::max(1, res.degrees_of_freedom);

  res.estimate.cov = Eigen::MatrixXd::Zero(n, n);
  if (opt.compute_covariance) {
    say("covariance");
    const auto t_cov = std::chrono::steady_clock::now();
    const bool use_ceres = opt.covariance_method == "ceres" || !opt.robust_loss.empty();
    if (!use_ceres && opt.covariance_method != "schur") {
      throw InputError("--covariance: unknown method '" + opt.covariance_method +
                       "' (schur, ceres)");
    }
    if (use_ceres) {
      // Ceres's sparse QR on the whole Jacobian (applies the robust loss's
      // weights). The priors keep the Jacobian full rank.
      ceres::Covariance::Options co;
      co.algorithm_type = ceres::SPARSE_QR;
      co.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
      co.num_threads = threads;
      ceres::Covariance cov(co);
      std::vector<std::pair<const double*, const double*>> blocks = {
          {theta.data(), theta.data()}};
      if (!cov.Compute(blocks, problem.get())) {
        throw std::runtime_error("covariance of theta: Ceres could not factor the Jacobian");
      }
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> C(n, n);
      cov.GetCovarianceBlock(theta.data(), theta.data(), C.data());
      res.estimate.cov = C;
    } else {
      res.estimate.cov = ThetaCovariance(p, lin, theta, A, threads);
    }
    res.covariance_seconds = Seconds(t_cov);
  }
  return res;
}

}  // namespace triadcal
