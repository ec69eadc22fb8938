#include "solvers/multirun/joint_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/model/errors.h"
#include "solvers/statistics/statistics.h"
#include "solvers/estimation/levenberg_marquardt.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/reduced_run.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {
namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The joint cost at phi over the free unknowns F: sum of the runs' reduced
// costs, the priors and the constraints, with gradient and Gauss-Newton
// information.
struct JointEvaluation {
  Eigen::VectorXd phi;           // where
  double cost = 0.0;
  Eigen::VectorXd gradient;      // over F
  Eigen::MatrixXd information;   // over F, with priors and constraints
  std::vector<ReducedRun> runs;  // information over each run's whole layout
  std::vector<Eigen::MatrixXd> data_information;  // T_rF^T I_r T_rF
};

class JointProblem {
 public:
  JointProblem(const JointLayout& jl, const std::vector<RunProblem>& problems,
               const std::vector<int>& free, int threads)
      : jl_(jl), problems_(problems), free_(free), threads_(threads) {
    for (int r = 0; r < jl.runs(); ++r) {
      Eigen::MatrixXd T(jl.layout().size(), free.size());
      for (std::size_t k = 0; k < free.size(); ++k) T.col(k) = jl.map(r).col(free[k]);
      map_free_.push_back(T);
    }
  }

  const Eigen::MatrixXd& map_free(int r) const { return map_free_[r]; }

  JointEvaluation Evaluate(const Eigen::VectorXd& phi) const {
    const int nf = static_cast<int>(free_.size());
    JointEvaluation ev;
    ev.phi = phi;
    ev.gradient = Eigen::VectorXd::Zero(nf);
    ev.information = Eigen::MatrixXd::Zero(nf, nf);
    for (int r = 0; r < jl_.runs(); ++r) {
      const Eigen::VectorXd theta = jl_.ThetaOfRun(r, phi);
      ReducedRun red = ReduceRun(problems_[r], theta, threads_);
      const Eigen::MatrixXd& T = map_free_[r];
      ev.cost += red.cost;
      ev.gradient.noalias() += T.transpose() * red.gradient;
      Eigen::MatrixXd D = T.transpose() * red.information * T;
      ev.information += D;
      ev.data_information.push_back(std::move(D));
      // Each run's pseudo-measurements, over its parameters.
      for (const ConstraintRow& c : problems_[r].constraints) {
        const double res = (c.c.dot(theta) - c.value) / c.sigma;
        const Eigen::VectorXd row = T.transpose() * c.c / c.sigma;
        ev.cost += 0.5 * res * res;
        ev.gradient += res * row;
        ev.information += row * row.transpose();
      }
      ev.runs.push_back(std::move(red));
    }
    for (int k = 0; k < nf; ++k) {
      const JointParam& p = jl_.param(free_[k]);
      const double res = (phi[free_[k]] - p.prior_mean) / p.prior_sigma;
      ev.cost += 0.5 * res * res;
      ev.gradient[k] += res / p.prior_sigma;
      ev.information(k, k) += 1.0 / (p.prior_sigma * p.prior_sigma);
    }
    return ev;
  }

 private:
  const JointLayout& jl_;
  const std::vector<RunProblem>& problems_;
  std::vector<int> free_;
  int threads_;
  std::vector<Eigen::MatrixXd> map_free_;
};

// Scale factors stay within [1/5, 5] of their nominal values (as in the batch
// solver's bounds).
void KeepScalesInBounds(const JointLayout& jl, Eigen::VectorXd* phi) {
  for (int j = 0; j < jl.size(); ++j) {
    const JointParam& p = jl.param(j);
    if (p.base < kKx || p.base > kKz || p.degree != 0) continue;
    const double k0 = std::abs(p.prior_mean);
    const double lo = p.prior_mean < 0 ? -5.0 * k0 : 0.2 * k0;
    const double hi = p.prior_mean < 0 ? -0.2 * k0 : 5.0 * k0;
    (*phi)[j] = std::clamp((*phi)[j], lo, hi);
  }
}

// The phi index whose column moves run-layout parameter i the most among the
// shared unknowns of degree 0 (-1 when none): names a platform-axis parameter
// in the IMU's axes.
int SharedSourceOf(const JointLayout& jl, int r, int i) {
  int best = -1;
  double best_w = 0.0;
  for (int j = 0; j < jl.size(); ++j) {
    const JointParam& p = jl.param(j);
    if (p.run >= 0 || p.degree != 0) continue;
    const double w = std::abs(jl.map(r)(i, j));
    if (w > best_w + 1e-12) {
      best_w = w;
      best = j;
    }
  }
  return best;
}

// Score form of the Hausman test: run r's gradient at the joint solution
// over the parameters it determines alone, against its variance under "the
// runs agree", I_r - I_r T Sigma_J T^T I_r (the part of run r's information
// the joint solution did not use up).
RunConsistency TestConsistency(const JointLayout& jl, int r, const BatchResult& alone,
                               const ReducedRun& at_joint, const Eigen::MatrixXd& map_free,
                               const Eigen::MatrixXd& cov_free, double alpha) {
  RunConsistency out;
  const ParameterLayout& layout = jl.layout();
  const int n = layout.size();
  std::vector<bool> held(n, false);
  for (const std::string& name : alone.held) held[layout.IndexOf(name)] = true;
  std::vector<int> f;
  for (int i = 0; i < n; ++i) {
    if (!held[i]) f.push_back(i);
  }
  const Eigen::MatrixXd& I = at_joint.information;
  const Eigen::MatrixXd IT = I * map_free;
  const Eigen::MatrixXd Vg_all = I - IT * cov_free * IT.transpose();
  const int m = static_cast<int>(f.size());
  Eigen::VectorXd g(m), s(m);
  Eigen::MatrixXd Vg(m, m);
  for (int a = 0; a < m; ++a) {
    g[a] = at_joint.gradient[f[a]];
    s[a] = std::sqrt(std::max(I(f[a], f[a]), 1e-300));
    for (int b = 0; b < m; ++b) Vg(a, b) = Vg_all(f[a], f[b]);
  }
  // In units of the run's own information; directions with less than 1e-3 of
  // it left (what the joint fit takes from this run alone: its own set-up)
  // carry no test.
  const Eigen::MatrixXd Vn = s.cwiseInverse().asDiagonal() * Vg * s.cwiseInverse().asDiagonal();
  const Eigen::VectorXd gn = g.cwiseQuotient(s);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (Vn + Vn.transpose()));
  for (int k = 0; k < m; ++k) {
    const double lambda = eig.eigenvalues()[k];
    if (!(lambda > 1e-3)) continue;
    const double u = eig.eigenvectors().col(k).dot(gn);
    out.chi2 += u * u / lambda;
    out.dof += 1;
  }
  out.tested = out.dof > 0;
  out.p_value = out.tested ? ChiSquareSurvival(out.chi2, out.dof) : 1.0;
  out.consistent = out.p_value >= alpha;
  for (int a = 0; a < m; ++a) {
    if (!(Vn(a, a) > 1e-3)) continue;
    const int i = f[a];
    // Positive z: the run alone would put the parameter below the joint value.
    const double z = gn[a] / std::sqrt(Vn(a, a));
    out.z.emplace_back(layout.info(i).name, z);
    const int source = SharedSourceOf(jl, r, i);
    if (std::abs(z) >= 3.0) {
      out.pulls.emplace_back(source >= 0 ? jl.param(source).name : layout.info(i).name, z);
    }
  }
  std::sort(out.pulls.begin(), out.pulls.end(),
            [](const auto& a, const auto& b) { return std::abs(a.second) > std::abs(b.second); });
  return out;
}

// The covariance over the free unknowns placed in an m x m matrix (zero for
// the held ones).
Eigen::MatrixXd ExpandFree(const Eigen::MatrixXd& cov_free, const std::vector<int>& free, int m) {
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(m, m);
  for (std::size_t a = 0; a < free.size(); ++a)
    for (std::size_t b = 0; b < free.size(); ++b) cov(free[a], free[b]) = cov_free(a, b);
  return cov;
}

// share(r, j): run r's part of the diagonal of the data information on
// unknown free[k] (data_information over the free unknowns, in their order).
Eigen::MatrixXd InformationShare(const std::vector<Eigen::MatrixXd>& data_information,
                                 const std::vector<int>& free, int m) {
  const int R = static_cast<int>(data_information.size());
  Eigen::MatrixXd share = Eigen::MatrixXd::Zero(R, m);
  Eigen::VectorXd total = Eigen::VectorXd::Zero(free.size());
  for (const Eigen::MatrixXd& D : data_information) total += D.diagonal();
  for (int r = 0; r < R; ++r) {
    for (std::size_t k = 0; k < free.size(); ++k) {
      if (total[k] > 0.0) share(r, free[k]) = data_information[r](k, k) / total[k];
    }
  }
  return share;
}

// The joint unknowns a --hold or --free name means: a joint parameter ("Kx",
// "dpsi@roll_slow"), or a per-run parameter's name without "@RUN" ("dpsi"),
// which means it in every run. Checked before any run is fitted.
std::vector<int> JointIndicesOf(const JointLayout& jl, const std::string& name,
                                const char* option) {
  const int j = jl.IndexOf(name);
  if (j >= 0) return {j};
  std::vector<int> every_run;
  for (int k = 0; k < jl.size(); ++k) {
    const std::string& n = jl.param(k).name;
    if (jl.param(k).run >= 0 && n.size() > name.size() && n.compare(0, name.size(), name) == 0 &&
        n[name.size()] == '@') {
      every_run.push_back(k);
    }
  }
  if (every_run.empty()) {
    throw OptionError(option, "unknown parameter '" + name +
                                  "' in this joint fit (a shared parameter such as Kx, a "
                                  "per-run one such as dpsi@RUN, or dpsi for every run)");
  }
  return every_run;
}

// The hold rule (SupportedByInformation, as a single run's fit) on the
// combined information at the nominal values, with --hold/--free on top.
// *ev_out, when given, gets that evaluation (over every unknown).
std::vector<bool> HeldByRule(const JointLayout& jl, const std::vector<RunProblem>& problems,
                             const JointOptions& opt, int threads, JointEvaluation* ev_out) {
  const int m = jl.size();
  std::vector<int> all(m);
  for (int j = 0; j < m; ++j) all[j] = j;
  const JointProblem full(jl, problems, all, threads);
  JointEvaluation ev = full.Evaluate(jl.Nominal());
  const Eigen::VectorXd sigma = jl.PriorSigma();
  // Data and constraint information in prior units (the priors' identity removed).
  Eigen::MatrixXd info = sigma.asDiagonal() * ev.information * sigma.asDiagonal();
  info.diagonal().array() -= 1.0;
  Eigen::VectorXd min_info(m), priority(m);
  for (int j = 0; j < m; ++j) {
    const JointParam& p = jl.param(j);
    const bool base = p.base >= 0 && p.base < kNumBaseParams;
    min_info[j] = base || p.base < 0 ? opt.batch.holding.min_information
                                     : opt.batch.holding.min_information_effects;
    priority[j] = p.base >= 0 ? HoldPriority(p.base) : 2.0;
  }
  std::vector<bool> held(m, false);
  if (opt.batch.holding.auto_hold) {
    held.assign(m, true);
    for (int j : SupportedByInformation(info, min_info, priority)) held[j] = false;
  }
  for (const std::string& name : opt.batch.holding.hold) {
    for (int j : JointIndicesOf(jl, name, "hold")) held[j] = true;
  }
  for (const std::string& name : opt.batch.holding.free) {
    for (int j : JointIndicesOf(jl, name, "free")) held[j] = false;
  }
  if (ev_out) *ev_out = std::move(ev);
  return held;
}

// The free unknowns that no run determines alone: for each, the run-layout
// parameter it moves most is held in every run alone (a per-run unknown
// counts as its own run's).
std::vector<std::string> JointlyOnly(const JointLayout& jl, const std::vector<int>& free,
                                     const std::vector<std::vector<std::string>>& held_alone) {
  const ParameterLayout& layout = jl.layout();
  std::vector<std::string> out;
  for (int j : free) {
    const JointParam& p = jl.param(j);
    if (p.degree != 0 || p.base < 0) continue;
    bool alone = false;
    for (int r = 0; r < jl.runs() && !alone; ++r) {
      if (p.run >= 0 && p.run != r) continue;
      int i = -1;
      double best = 0.0;
      for (int q = 0; q < layout.size(); ++q) {
        if (std::abs(jl.map(r)(q, j)) > best) {
          best = std::abs(jl.map(r)(q, j));
          i = q;
        }
      }
      const auto& h = held_alone[r];
      alone = i >= 0 && std::find(h.begin(), h.end(), layout.info(i).name) == h.end();
    }
    if (!alone) out.push_back(p.name);
  }
  return out;
}

}  // namespace

JointInformation JointInformationAtNominal(const std::vector<JointRun>& runs,
                                           const JointLayout& jl, const JointOptions& opt) {
  const int threads = opt.batch.threads > 0 ? opt.batch.threads : DefaultThreads();
  const ParameterLayout& layout = jl.layout();
  const int m = jl.size(), R = jl.runs(), n = layout.size();
  std::vector<RunProblem> problems;
  for (const JointRun& r : runs) {
    problems.push_back(BuildRunProblem(r.run, r.data, layout, opt.batch.epoch_s,
                                       opt.batch.derivatives));
  }
  JointInformation out;
  JointEvaluation ev;
  const std::vector<bool> held = HeldByRule(jl, problems, opt, threads, &ev);
  out.information = ev.information;
  std::vector<int> free;
  for (int j = 0; j < m; ++j) (held[j] ? out.held : free).push_back(j);
  const int nf = static_cast<int>(free.size());
  Eigen::MatrixXd H(nf, nf);
  for (int a = 0; a < nf; ++a)
    for (int b = 0; b < nf; ++b) H(a, b) = ev.information(free[a], free[b]);
  out.cov = ExpandFree(H.ldlt().solve(Eigen::MatrixXd::Identity(nf, nf)), free, m);
  // The evaluation is over every unknown: its data information restricted to the free ones.
  std::vector<Eigen::MatrixXd> data_free;
  for (const Eigen::MatrixXd& D : ev.data_information) {
    Eigen::MatrixXd F(nf, nf);
    for (int a = 0; a < nf; ++a)
      for (int b = 0; b < nf; ++b) F(a, b) = D(free[a], free[b]);
    data_free.push_back(F);
  }
  out.share = InformationShare(data_free, free, m);
  // Each run alone by the same rule, over its own layout at its nominal values.
  for (int r = 0; r < R; ++r) {
    const RunProblem& p = problems[r];
    Eigen::MatrixXd info = ev.runs[r].information;
    for (const ConstraintRow& c : p.constraints) info += c.c * c.c.transpose() / (c.sigma * c.sigma);
    info = p.prior.sigma.asDiagonal() * info * p.prior.sigma.asDiagonal();
    Eigen::VectorXd min_info(n), priority(n);
    for (int i = 0; i < n; ++i) {
      min_info[i] = i < kNumBaseParams ? opt.batch.holding.min_information
                                       : opt.batch.holding.min_information_effects;
      priority[i] = HoldPriority(i);
    }
    std::vector<bool> kept(n, false);
    for (int i : SupportedByInformation(info, min_info, priority)) kept[i] = true;
    std::vector<std::string> h;
    for (int i = 0; i < n; ++i) {
      if (!kept[i]) h.push_back(layout.info(i).name);
    }
    out.held_alone.push_back(h);
  }
  out.jointly_only = JointlyOnly(jl, free, out.held_alone);
  return out;
}


JointResult SolveJoint(const std::vector<JointRun>& runs, const JointLayout& jl,
                       const JointOptions& opt) {
  const int threads = opt.batch.threads > 0 ? opt.batch.threads : DefaultThreads();
  const ParameterLayout& layout = jl.layout();
  const int m = jl.size();
  const int R = jl.runs();
  auto say = [&](const std::string& s) {
    if (opt.batch.progress) opt.batch.progress(s);
  };
  JointResult res;
  res.runs.resize(R);

  // --hold/--free: checked now, not after the runs alone. A run's own
  // parameters among them (dpsi@RUN, or dpsi for every run) are held or
  // freed in its fit alone too; shared ones (IMU axes) only jointly.
  std::vector<std::vector<std::string>> hold_alone(R), free_alone(R);
  auto per_run_names = [&](const std::vector<std::string>& names, const char* option,
                           std::vector<std::vector<std::string>>* out) {
    for (const std::string& name : names) {
      for (int j : JointIndicesOf(jl, name, option)) {
        const JointParam& p = jl.param(j);
        if (p.run >= 0 && p.base >= 0 && p.degree == 0) {
          (*out)[p.run].push_back(layout.info(p.base).name);
        }
      }
    }
  };
  per_run_names(opt.batch.holding.hold, "hold", &hold_alone);
  per_run_names(opt.batch.holding.free, "free", &free_alone);

  // 1. Each run alone: its estimate, held set and noise.
  const auto t_alone = std::chrono::steady_clock::now();
  std::vector<RunProblem> problems;
  for (int r = 0; r < R; ++r) {
    JointRunResult& rr = res.runs[r];
    rr.name = jl.run_name(r);
    BatchOptions bo = opt.batch;
    bo.holding.hold = hold_alone[r];
    bo.holding.free = free_alone[r];
    const auto progress = opt.batch.progress;
    bo.progress = [&, progress](const std::string& s) {
      if (progress) progress("run " + rr.name + " alone: " + s);
    };
    // Each run alone a share of the work, the joint solve the last share.
    const auto fraction = opt.batch.fraction;
    bo.fraction = nullptr;
    if (fraction) bo.fraction = [fraction, r, R](double x) { fraction((r + x) / (R + 1.0)); };
    rr.alone = SolveBatch(runs[r].run, runs[r].data, layout, bo);
    RunProblem p = BuildRunProblem(runs[r].run, runs[r].data, layout, opt.batch.epoch_s,
                                   opt.batch.derivatives);
    p.noise_mV = rr.alone.noise_used_mV;
    // A run whose residual split is misfit enters with its variance factor
    // on every noise (its information divided by it), as its own sigma.
    p.ScaleNoise(rr.alone.variance_factor);
    rr.noise_mV = p.noise_mV;
    problems.push_back(std::move(p));
  }
  res.seconds_alone = Seconds(t_alone);
  const auto t_joint = std::chrono::steady_clock::now();

  // 2. What the runs together determine, at the nominal values.
  Eigen::VectorXd phi = jl.Nominal();
  say("joint: choosing the parameters the runs determine together");
  const std::vector<bool> held = HeldByRule(jl, problems, opt, threads, nullptr);
  std::vector<int> free;
  for (int j = 0; j < m; ++j) (held[j] ? res.held : free).push_back(j);

  // 3. The start: each run's own estimate, the shared unknowns as the
  // precision-weighted mean of what the runs say about them.
  {
    Eigen::VectorXd num = Eigen::VectorXd::Zero(m), den = Eigen::VectorXd::Zero(m);
    for (int r = 0; r < R; ++r) {
      const BatchResult& a = res.runs[r].alone;
      for (int i = 0; i < layout.size(); ++i) {
        const double var = a.estimate.cov(i, i);
        if (!(var > 0.0)) continue;
        // The unknown that carries parameter i in this run, if one does alone.
        int source = -1;
        double weight = 0.0;
        for (int j = 0; j < m; ++j) {
          const double w = jl.map(r)(i, j);
          if (std::abs(w) > 0.5 && jl.param(j).degree == 0 && jl.param(j).base >= 0) {
            if (source >= 0) {
              source = -2;
              break;
            }
            source = j;
            weight = w;
          }
        }
        if (source < 0 || held[source]) continue;
        num[source] += a.estimate.theta[i] / weight / var;
        den[source] += 1.0 / var;
      }
    }
    for (int j = 0; j < m; ++j) {
      if (den[j] > 0.0) phi[j] = num[j] / den[j];
    }
    KeepScalesInBounds(jl, &phi);
  }

  // 4. Levenberg-Marquardt on the free unknowns.
  const JointProblem problem(jl, problems, free, threads);
  const int nf = static_cast<int>(free.size());
  JointEvaluation ev = problem.Evaluate(phi);
  const LmOutcome lm = MinimiseLevenbergMarquardt(
      &ev, [&](const Eigen::VectorXd& trial) { return problem.Evaluate(trial); },
      [&](const JointEvaluation& from, const Eigen::VectorXd& step) {
        Eigen::VectorXd trial = from.phi;
        for (int k = 0; k < nf; ++k) trial[free[k]] += step[k];
        KeepScalesInBounds(jl, &trial);
        return trial;
      },
      [&](int it, const JointEvaluation& at, double predicted) {
        char line[160];
        std::snprintf(line, sizeof(line),
                      "joint: iteration %d, chi2 %.6g, predicted decrease %.3g", it + 1,
                      2.0 * at.cost, predicted);
        say(line);
        if (opt.batch.fraction) {
          opt.batch.fraction((R + 1.0 - std::pow(0.7, it + 1)) / (R + 1.0));
        }
      },
      opt.max_iterations, opt.tolerance);
  res.converged = lm.converged;
  res.iterations = lm.iterations;
  phi = ev.phi;
  res.phi = phi;
  res.cost = ev.cost;
  const Eigen::MatrixXd cov_free =
      ev.information.ldlt().solve(Eigen::MatrixXd::Identity(nf, nf));
  res.cov = ExpandFree(cov_free, free, m);

  // Degrees of freedom and each run's share.
  res.share = InformationShare(ev.data_information, free, m);
  for (int r = 0; r < R; ++r) {
    JointRunResult& rr = res.runs[r];
    rr.theta = jl.ThetaOfRun(r, phi);
    rr.degrees_of_freedom = ev.runs[r].degrees_of_freedom;
    rr.chi2_per_dof = 2.0 * ev.runs[r].cost / std::max(1, rr.degrees_of_freedom);
    res.degrees_of_freedom += rr.degrees_of_freedom + static_cast<int>(problems[r].constraints.size());
  }
  res.chi2_per_dof = 2.0 * res.cost / std::max(1, res.degrees_of_freedom);

  // Determined together, by no run alone.
  {
    std::vector<std::vector<std::string>> held_alone;
    for (const JointRunResult& rr : res.runs) held_alone.push_back(rr.alone.held);
    res.jointly_only = JointlyOnly(jl, free, held_alone);
  }

  // 5. Each run against the joint solution.
  for (int r = 0; r < R; ++r) {
    res.runs[r].consistency = TestConsistency(jl, r, res.runs[r].alone, ev.runs[r],
                                              problem.map_free(r), cov_free, opt.consistency_alpha);
  }
  res.seconds_joint = Seconds(t_joint);
  return res;
}

}  // namespace triadcal
