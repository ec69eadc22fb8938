#include "solvers/multirun/joint_solver.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/model/errors.h"
#include "solvers/statistics/statistics.h"
#include "solvers/estimation/batch_minimizer.h"
#include "solvers/estimation/batch_objective.h"
#include "solvers/estimation/hac_covariance.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/schur_covariance.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {
namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The priors over phi and each run's constraints mapped onto phi, whitened:
// A phi - b (theta_r = offset_r + T_r phi).
void JointRows(const JointLayout& jl, const std::vector<RunProblem>& problems, Eigen::MatrixXd* A,
               Eigen::VectorXd* b) {
  const int m = jl.size();
  int k = 0;
  for (const RunProblem& p : problems) k += static_cast<int>(p.constraints.size());
  A->setZero(m + k, m);
  b->resize(m + k);
  for (int j = 0; j < m; ++j) {
    const JointParam& p = jl.param(j);
    (*A)(j, j) = 1.0 / p.prior_sigma;
    (*b)[j] = p.prior_mean / p.prior_sigma;
  }
  int row = m;
  for (int r = 0; r < jl.runs(); ++r) {
    for (const ConstraintRow& c : problems[r].constraints) {
      A->row(row) = (jl.map(r).transpose() * c.c).transpose() / c.sigma;
      (*b)[row] = (c.value - c.c.dot(jl.offset(r))) / c.sigma;
      ++row;
    }
  }
}

BatchObjective MakeJointObjective(const JointLayout& jl, const std::vector<RunProblem>& problems,
                                  int threads) {
  std::vector<LinkedRun> linked;
  for (int r = 0; r < jl.runs(); ++r) linked.push_back({&problems[r], jl.offset(r), jl.map(r)});
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  JointRows(jl, problems, &A, &b);
  return BatchObjective(std::move(linked), std::move(A), std::move(b), jl.Nominal(), threads);
}

// The information of the constraints alone over phi.
Eigen::MatrixXd ConstraintInformationOverPhi(const BatchObjective& obj, int m) {
  const Eigen::MatrixXd rows = obj.rows().bottomRows(obj.rows().rows() - m);
  return rows.transpose() * rows;
}

Eigen::MatrixXd MapFree(const JointLayout& jl, int r, const std::vector<int>& free) {
  Eigen::MatrixXd T(jl.layout().size(), free.size());
  for (std::size_t k = 0; k < free.size(); ++k) T.col(k) = jl.map(r).col(free[k]);
  return T;
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
                               const RunReduction& at_joint, const Eigen::MatrixXd& map_free,
                               const Eigen::MatrixXd& cov_free, double alpha) {
  RunConsistency out;
  const ParameterLayout& layout = jl.layout();
  const int n = layout.size();
  std::vector<bool> held(n, false);
  for (const std::string& name : alone.held) held[layout.IndexOf(name)] = true;
  for (const std::string& name : alone.consider) held[layout.IndexOf(name)] = true;
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
// combined information at the nominal values, with --hold/--free on top:
// 0 estimated, 1 consider (not determined: nominal, prior uncertainty
// carried), 2 held. *pt_out, when given, gets that evaluation (of the
// readings the model predicts at the nominal values).
std::vector<int> HeldByRule(const JointLayout& jl, const std::vector<RunProblem>& problems,
                            const JointOptions& opt, int threads, BatchObjective::Point* pt_out) {
  const int m = jl.size();
  // The information of the readings the model predicts (a single run's
  // decision reads the same: ChooseHeldParameters).
  std::vector<RunProblem> predicted = problems;
  for (RunProblem& p : predicted) p.series.readings = SampleSeries::Readings::kPredictedAtRest;
  const BatchObjective objective = MakeJointObjective(jl, predicted, threads);
  std::vector<Eigen::Vector3d> noise;
  for (const RunProblem& p : problems) noise.push_back(p.noise_mV);
  BatchObjective::Point pt =
      objective.Evaluate(jl.Nominal(), noise, true, ThetaPart::kGradientAndInformationAtFixedNoise);
  const Eigen::VectorXd sigma = jl.PriorSigma();
  // Data and constraint information in prior units.
  const Eigen::MatrixXd info =
      sigma.asDiagonal() *
      (pt.data_information + ConstraintInformationOverPhi(objective, m)) * sigma.asDiagonal();
  // Below the information's resolution a parameter has none.
  const Eigen::VectorXd resolution =
      InformationResolution(pt.data_information_scale).cwiseProduct(sigma.cwiseAbs2());
  Eigen::VectorXd min_info = resolution.cwiseMax(opt.batch.holding.min_information);
  Eigen::VectorXd priority(m);
  for (int j = 0; j < m; ++j) {
    const JointParam& p = jl.param(j);
    priority[j] = p.base >= 0 ? HoldPriority(p.base) : 2.0;
  }
  std::vector<int> kind(m, 0);
  std::vector<bool> user_hold(m, false), user_free(m, false);
  for (const std::string& name : opt.batch.holding.hold) {
    for (int j : JointIndicesOf(jl, name, "hold")) user_hold[j] = true;
  }
  for (const std::string& name : opt.batch.holding.free) {
    for (int j : JointIndicesOf(jl, name, "free")) user_free[j] = true;
  }
  if (opt.batch.holding.auto_hold) {
    for (int j = 0; j < m; ++j) {
      if (user_free[j]) min_info[j] = 0.0;
      if (user_hold[j]) min_info[j] = std::numeric_limits<double>::infinity();
    }
    Eigen::VectorXd left;
    const Eigen::MatrixXd constraint_prior_units =
        sigma.asDiagonal() * ConstraintInformationOverPhi(objective, m) * sigma.asDiagonal();
    const std::vector<int> kept =
        SupportedByInformation(info, min_info, priority, &left, &constraint_prior_units);
    kind.assign(m, 1);
    for (int j : kept) kind[j] = 0;
    for (int j = 0; j < m; ++j) {
      if (kind[j] == 1 && left[j] < std::max(opt.batch.holding.null_information, resolution[j])) {
        kind[j] = 2;
      }
    }
  }
  for (int j = 0; j < m; ++j) {
    if (user_hold[j]) kind[j] = 2;
    if (user_free[j]) kind[j] = 0;
  }
  if (pt_out) *pt_out = std::move(pt);
  return kind;
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


// What run r alone says about joint unknown j: the run-layout parameter that
// j alone carries (|map| > 0.5, no other unknown moving it),
// when the run estimated it absolutely (not relative to a held parameter), as
// a value of j with its sigma given what the run considered (the spread of
// its own data: what it leaves at nominal is estimated jointly). Runs that do
// not determine j alone give nothing.
struct RunValue {
  int run = 0;
  double value = 0.0, sigma = 0.0;
};
// With `as_start`, a run's own unknown (dpsi@RUN, W0y@RUN) also takes the
// run's value relative to its held ones: the joint start (a single run's
// shaft offset relative to its held tilt started at 0 otherwise, 52 mg off:
// the real roll runs' joint fit took 14 steps instead of 6).
std::vector<RunValue> AloneValuesOf(const JointLayout& jl, const std::vector<JointRunResult>& runs,
                                    int j, bool as_start = false) {
  std::vector<RunValue> out;
  const JointParam& pj = jl.param(j);
  if (pj.degree != 0 || pj.base < 0) return out;
  const ParameterLayout& layout = jl.layout();
  for (int r = 0; r < jl.runs(); ++r) {
    if (pj.run >= 0 && pj.run != r) continue;
    const BatchResult& a = runs[r].alone;
    for (int i = 0; i < layout.size(); ++i) {
      const double w = jl.map(r)(i, j);
      if (std::abs(w) <= 0.5) continue;
      const std::string& name = layout.info(i).name;
      const double var = a.cov_given_consider.rows() == layout.size() ? a.cov_given_consider(i, i)
                                                                       : a.estimate.cov(i, i);
      const bool relative = a.relative_to.count(name) > 0 && !(as_start && pj.run >= 0);
      if (!(var > 0.0) || !IsEstimated(a, name) || relative) continue;
      // theta_i moves with phi_j alone (not with a temperature coefficient
      // or another unknown too): the run's value of theta_i is one of phi_j.
      bool alone = true;
      for (int k = 0; k < jl.size() && alone; ++k) {
        alone = k == j || std::abs(jl.map(r)(i, k)) <= 1e-9 * std::abs(w);
      }
      if (alone) out.push_back({r, a.estimate.theta[i] / w, std::sqrt(var) / std::abs(w)});
    }
  }
  return out;
}

// The between-run component of shared unknown j (random effects, DerSimonian
// and Laird 1986): from the runs that determine it alone, Cochran's
// Q = sum_r (x_r - xbar)^2 / s_r^2 over k runs (xbar their precision-weighted
// mean) and tau^2 = max(0, (Q - (k - 1)) / (sum w - sum w^2 / sum w)),
// w = 1 / s^2. The joint value is a weighted sum of what the runs say, its
// weights the runs' shares of the information (share(r, j)); a spread tau^2
// between the runs adds tau^2 sum_r share_r^2 to its variance, where Q says
// the runs disagree (p < alpha).
BetweenRuns BetweenRunComponent(const std::vector<RunValue>& values, const Eigen::MatrixXd& share,
                                int j, double variance, double alpha) {
  BetweenRuns b;
  b.index = j;
  b.runs = static_cast<int>(values.size());
  if (b.runs < 2) return b;
  double sw = 0.0, sw2 = 0.0, swx = 0.0;
  for (const RunValue& v : values) {
    const double w = 1.0 / (v.sigma * v.sigma);
    sw += w;
    sw2 += w * w;
    swx += w * v.value;
  }
  const double mean = swx / sw;
  for (const RunValue& v : values) {
    const double z = (v.value - mean) / v.sigma;
    b.q += z * z;
    b.largest_z = std::max(b.largest_z, std::abs(z));
  }
  b.dof = b.runs - 1;
  b.p_value = ChiSquareSurvival(b.q, b.dof);
  b.disagree = b.p_value < alpha;
  const double tau2 = std::max(0.0, (b.q - b.dof) / (sw - sw2 / sw));
  b.tau = std::sqrt(tau2);
  double s2 = 0.0;
  for (int r = 0; r < share.rows(); ++r) s2 += share(r, j) * share(r, j);
  if (b.disagree && variance > 0.0) b.sigma_factor = std::sqrt(1.0 + tau2 * s2 / variance);
  return b;
}

// Each run's epoch scores (schur_covariance.h) over the free unknowns: the
// run's own scores over its layout, mapped (theta_r = offset_r + T_r phi).
std::vector<Eigen::VectorXd> ScoresOverFree(const RunReduction& red, const Eigen::MatrixXd& T) {
  std::vector<Eigen::VectorXd> scores =
      EpochScores(red.process_blocks, red.measurement_blocks);
  for (Eigen::VectorXd& v : scores) v = T.transpose() * v;
  return scores;
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
                                       opt.batch.derivatives, nullptr, threads));
  }
  JointInformation out;
  // What is held: the joint fit's rule (its information of the readings
  // predicted at rest). The Fisher information: that of the readings
  // predicted for each sample's recorded motion, as a single run's
  // observability (ReadPredictedReadingsInMotion; at rest it was up to 1.2 %
  // off the single run's CRB for a runs file of that one run).
  BatchObjective::Point at_rest;
  const std::vector<int> kind = HeldByRule(jl, problems, opt, threads, &at_rest);
  std::vector<RunProblem> in_motion = problems;
  std::vector<Eigen::Vector3d> noise;
  for (int r = 0; r < R; ++r) {
    ReadPredictedReadingsInMotion(&in_motion[r], runs[r].data, opt.batch.derivatives, threads);
    noise.push_back(problems[r].noise_mV);
  }
  const BatchObjective::Point pt =
      MakeJointObjective(jl, in_motion, threads)
          .Evaluate(jl.Nominal(), noise, true, ThetaPart::kGradientAndInformationAtFixedNoise);
  out.information = pt.information;
  std::vector<int> free;
  for (int j = 0; j < m; ++j) (kind[j] != 0 ? out.held : free).push_back(j);
  const int nf = static_cast<int>(free.size());
  Eigen::MatrixXd H(nf, nf);
  for (int a = 0; a < nf; ++a)
    for (int b = 0; b < nf; ++b) H(a, b) = pt.information(free[a], free[b]);
  out.cov = ExpandFree(H.ldlt().solve(Eigen::MatrixXd::Identity(nf, nf)), free, m);
  std::vector<Eigen::MatrixXd> data_free;
  for (int r = 0; r < R; ++r) {
    const Eigen::MatrixXd T = MapFree(jl, r, free);
    data_free.push_back(T.transpose() * pt.reductions[r].information * T);
  }
  out.share = InformationShare(data_free, free, m);
  // Each run alone by the same rule, over its own layout at its nominal values.
  for (int r = 0; r < R; ++r) {
    const RunProblem& p = problems[r];
    Eigen::MatrixXd info = at_rest.reductions[r].information;
    for (const ConstraintRow& c : p.constraints) info += c.c * c.c.transpose() / (c.sigma * c.sigma);
    info = p.prior.sigma.asDiagonal() * info * p.prior.sigma.asDiagonal();
    const Eigen::VectorXd min_info = Eigen::VectorXd::Constant(n, opt.batch.holding.min_information);
    Eigen::VectorXd priority(n);
    for (int i = 0; i < n; ++i) priority[i] = HoldPriority(i);
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

  // 1. Each run alone: its estimate, what it determines, its noise.
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
                                   opt.batch.derivatives, nullptr, threads);
    p.noise_mV = rr.alone.noise_used_mV;
    problems.push_back(std::move(p));
  }
  res.seconds_alone = Seconds(t_alone);
  const auto t_joint = std::chrono::steady_clock::now();

  // 2. The start: each run's own estimate, the shared unknowns as the
  // precision-weighted mean of what the runs say about them.
  Eigen::VectorXd phi = jl.Nominal();
  for (int j = 0; j < m; ++j) {
    double num = 0.0, den = 0.0;
    for (const RunValue& v : AloneValuesOf(jl, res.runs, j, /*as_start=*/true)) {
      num += v.value / (v.sigma * v.sigma);
      den += 1.0 / (v.sigma * v.sigma);
    }
    if (den > 0.0) phi[j] = num / den;
  }

  // 3. What the runs together determine, decided at the nominal values, as a
  // single fit's and observability's decisions are (the information of the
  // readings predicted there does not depend on the zero offsets). Not at
  // the start: there the runs' own misalignments gave a scale factor that
  // neither determines information through their product (two real roll
  // runs: the shaft's, "determined only by the runs together" at its prior's
  // +-100 mg/g, and an angle both determine held instead; 14 steps, 5 now).
  // What is not estimated starts at its nominal value.
  say("joint: choosing the parameters the runs determine together");
  const std::vector<int> kind = HeldByRule(jl, problems, opt, threads, nullptr);
  std::vector<int> free;
  for (int j = 0; j < m; ++j) {
    if (kind[j] == 0) free.push_back(j);
    if (kind[j] == 1) res.consider.push_back(j);
    if (kind[j] == 2) res.held.push_back(j);
    if (kind[j] != 0) phi[j] = jl.Nominal()[j];
  }

  // 4. The minimum: the one minimiser of the batch problem over the runs
  // together, each run's noise estimated with the parameters.
  const BatchObjective objective = MakeJointObjective(jl, problems, threads);
  MinimizerOptions mo;
  mo.max_iterations = opt.max_iterations;
  mo.tolerance = opt.tolerance;
  mo.estimate_noise.assign(R, opt.batch.estimate_noise);
  mo.progress = [&](const std::string& s) { say("joint: " + s); };
  if (opt.batch.fraction) {
    mo.fraction = [&](double f) { opt.batch.fraction((R + f) / (R + 1.0)); };
  }
  BatchMinimizer minimizer(objective, free, mo);
  std::vector<Eigen::Vector3d> noise;
  for (const RunProblem& p : problems) noise.push_back(p.noise_mV);
  MinimizerSummary summary;
  const BatchObjective::Point pt = minimizer.Minimize(phi, noise, &summary);
  res.converged = summary.converged;
  res.termination = summary.termination;
  res.iterations = summary.iterations;
  phi = pt.phi;
  res.phi = phi;
  res.cost = pt.cost;
  const int nf = static_cast<int>(free.size());
  Eigen::MatrixXd H(nf, nf);
  for (int a = 0; a < nf; ++a)
    for (int b = 0; b < nf; ++b) H(a, b) = pt.information(free[a], free[b]);
  const Eigen::MatrixXd cov_free = H.ldlt().solve(Eigen::MatrixXd::Identity(nf, nf));

  // Degrees of freedom and each run's share.
  std::vector<Eigen::MatrixXd> data_free;
  for (int r = 0; r < R; ++r) {
    const Eigen::MatrixXd T = MapFree(jl, r, free);
    data_free.push_back(T.transpose() * pt.reductions[r].information * T);
  }
  res.share = InformationShare(data_free, free, m);

  // 5. The covariance, each run's data as its fit alone judged them: the
  // model's information where its residuals are white, its own HAC estimate
  // (over its own epochs) where they are not; the sum floored at the model's
  // covariance, as in a single fit. Then the prior uncertainty of the
  // considered unknowns, and the spread between the runs.
  say("joint: covariance");
  {
    const Eigen::VectorXd prior_var = jl.PriorSigma().cwiseAbs2();
    Eigen::MatrixXd fixed = H;  // what is not estimated from scores: priors, constraints, white runs
    Eigen::MatrixXd hac_part = Eigen::MatrixXd::Zero(nf, nf);
    bool any_hac = false;
    for (int r = 0; r < R; ++r) {
      JointRunResult& rr = res.runs[r];
      rr.sigma_method = rr.alone.sigma_method;
      if (rr.sigma_method != "hac") continue;
      any_hac = true;
      fixed -= data_free[r];
      Eigen::VectorXd weight = Eigen::VectorXd::Zero(nf);
      for (int a = 0; a < nf; ++a) {
        if (data_free[r](a, a) * prior_var[free[a]] >= 1.0) weight[a] = 1.0;
      }
      const HacDataPart part =
          HacDataCovariance(ScoresOverFree(pt.reductions[r], MapFree(jl, r, free)), cov_free,
                            weight, opt.batch.hac_bandwidth_epochs, false,
                            opt.batch.hac_kernel_bias_correction);
      rr.hac_bandwidth_epochs = part.bandwidth;
      hac_part += part.cov;
    }
    Eigen::MatrixXd cov = cov_free;
    if (any_hac) {
      cov = hac_part + cov_free * fixed * cov_free;
      cov = FloorVariances(0.5 * (cov + cov.transpose()), cov_free);
    }
    res.cov_white = ExpandFree(cov_free, free, m);
    res.cov = ExpandFree(cov, free, m);
  }
  if (!res.consider.empty()) {
    const Eigen::MatrixXd info = pt.data_information + ConstraintInformationOverPhi(objective, m);
    Eigen::MatrixXd sensitivity, add;
    ConsiderTerm(info, jl.PriorSigma(), free, res.consider, &sensitivity, &add);
    const Eigen::MatrixXd given = res.cov;
    res.cov += add;
    res.cov_white += add;
    Eigen::VectorXd consider_variance(res.consider.size());
    for (std::size_t q = 0; q < res.consider.size(); ++q) {
      consider_variance[q] = std::pow(jl.PriorSigma()[res.consider[q]], 2);
    }
    for (const auto& [j, with] :
         DeterminedOnlyWithConsidered(res.cov, given, sensitivity, consider_variance,
                                      jl.PriorSigma(), opt.batch.holding.min_information, free)) {
      std::vector<int>& w = res.with_considered[j];
      for (int q : with) w.push_back(res.consider[q]);
    }
  }
  for (int j : free) {
    const JointParam& p = jl.param(j);
    if (p.run >= 0 || p.degree != 0 || p.base < 0) continue;
    BetweenRuns b = BetweenRunComponent(AloneValuesOf(jl, res.runs, j), res.share, j,
                                        res.cov(j, j), opt.between_alpha);
    if (b.runs < 2) continue;
    if (b.sigma_factor > 1.0) {
      res.cov.row(j) *= b.sigma_factor;
      res.cov.col(j) *= b.sigma_factor;
    }
    res.between.push_back(b);
  }
  for (int r = 0; r < R; ++r) {
    JointRunResult& rr = res.runs[r];
    rr.theta = jl.ThetaOfRun(r, phi);
    rr.noise_mV = pt.reductions[r].noise_mV;
    rr.degrees_of_freedom = pt.reductions[r].degrees_of_freedom;
    rr.chi2_per_dof = 2.0 * pt.reductions[r].cost / std::max(1, rr.degrees_of_freedom);
    res.degrees_of_freedom += rr.degrees_of_freedom + static_cast<int>(problems[r].constraints.size());
  }
  res.chi2_per_dof = 2.0 * res.cost / std::max(1, res.degrees_of_freedom);

  // Determined together, by no run alone.
  {
    std::vector<std::vector<std::string>> held_alone;
    for (const JointRunResult& rr : res.runs) {
      std::vector<std::string> h = rr.alone.held;
      h.insert(h.end(), rr.alone.consider.begin(), rr.alone.consider.end());
      held_alone.push_back(h);
    }
    res.jointly_only = JointlyOnly(jl, free, held_alone);
  }

  // 6. Each run against the joint solution.
  for (int r = 0; r < R; ++r) {
    res.runs[r].consistency = TestConsistency(jl, r, res.runs[r].alone, pt.reductions[r],
                                              MapFree(jl, r, free), cov_free,
                                              opt.consistency_alpha);
  }
  res.seconds_joint = Seconds(t_joint);
  return res;
}

}  // namespace triadcal
