#include "solvers/estimation/batch_solver.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include "core/model/errors.h"
#include "core/model/sample_noise.h"
#include "solvers/estimation/batch_minimizer.h"
#include "solvers/estimation/batch_objective.h"
#include "solvers/estimation/hac_covariance.h"
#include "solvers/estimation/observability.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/run_evaluation.h"

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

std::vector<int> Indices(const ParameterLayout& layout, const std::vector<std::string>& names) {
  std::vector<int> out;
  for (const std::string& n : names) out.push_back(layout.IndexOf(n));
  std::sort(out.begin(), out.end());
  return out;
}

Eigen::MatrixXd Sub(const Eigen::MatrixXd& M, const std::vector<int>& rows,
                    const std::vector<int>& cols) {
  Eigen::MatrixXd out(rows.size(), cols.size());
  for (std::size_t a = 0; a < rows.size(); ++a)
    for (std::size_t b = 0; b < cols.size(); ++b) out(a, b) = M(rows[a], cols[b]);
  return out;
}

Eigen::MatrixXd Expand(const Eigen::MatrixXd& M, const std::vector<int>& idx, int n) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t a = 0; a < idx.size(); ++a)
    for (std::size_t b = 0; b < idx.size(); ++b) out(idx[a], idx[b]) = M(a, b);
  return out;
}

// The information of the constraints alone (n x n, SI).
Eigen::MatrixXd ConstraintInformation(const RunProblem& p) {
  Eigen::MatrixXd I = Eigen::MatrixXd::Zero(p.n, p.n);
  for (const ConstraintRow& c : p.constraints) I += c.c * c.c.transpose() / (c.sigma * c.sigma);
  return I;
}

// The reading noise the fit starts from: the declared figures, or with
// noise_mV: auto each channel's own white noise from its second differences
// (sample_noise.h; no model needed).
Eigen::Vector3d StartNoise(const RunDescription& run, const RunData& data,
                           const BatchOptions& opt) {
  if ((opt.noise_override.array() > 0.0).all()) return opt.noise_override;
  return RunReadingNoise_mV(run, data);
}

// The start of the minimiser. With the RTS start, *diverged_at_s gets the
// time at which the filter diverged (the nominal values are returned then).
Estimate Initialise(const RunDescription& run, const RunData& data, const ParameterLayout& layout,
                    const RunProblem& p, const BatchOptions& opt,
                    const std::vector<std::string>& not_estimated, const Eigen::Vector3d& noise,
                    double* diverged_at_s) {
  Estimate e{p.prior.mean, Eigen::MatrixXd(p.prior.sigma.array().square().matrix().asDiagonal())};
  if (opt.init == BatchInit::kGiven) {
    if (opt.init_theta.size() != p.n) throw std::invalid_argument("init_theta has the wrong size");
    e.theta = opt.init_theta;
    for (const std::string& name : not_estimated) {
      const int i = layout.IndexOf(name);
      e.theta[i] = p.prior.mean[i];
    }
    return e;
  }
  if (opt.init == BatchInit::kNominal) return e;
  // The EKF + RTS smoother on samples thinned to about init_decimation_hz and
  // 1-s epochs: a start within a few sigma at a fraction of a pass.
  const RunData thin = Decimate(data, ThinningFactor(data, opt.init_decimation_hz));
  RunDescription start = run;
  start.noise_auto = false;
  start.noise_channel_mV = noise;
  start.noise_mV = noise.maxCoeff();
  FilterOptions fo;
  fo.epoch_s = std::max(opt.epoch_s, 1.0);
  fo.derivatives = opt.derivatives;
  fo.smoother_iterations = 1;
  fo.held = not_estimated;
  fo.threads = opt.threads;
  // The gyro starts at its nominal values: with the gyro's measurements the
  // thinned filter took the real slow run's fit from 3 steps to 7 (same
  // estimates), and cost 0.8 s more.
  fo.gyro = false;
  const FilterResult fr = RunFilterSmoother(start, thin, layout, fo);
  // A diverged filter's estimate is no estimate (`filter` refuses to print
  // it): the caller starts from the nominal values instead.
  if (fr.diverged_at_s >= 0.0 || !fr.rts.theta.allFinite()) {
    if (diverged_at_s) *diverged_at_s = std::max(fr.diverged_at_s, 0.0);
    return e;
  }
  return fr.rts;
}

// Residuals at the solution, raw and whitened, and their summaries.
// weights: the reference pass whose noise weights whiten the residuals in the
// cost (run_evaluation.h), so that the whitened residuals are the cost's.
void CollectResiduals(const RunProblem& p, const RunData& data, const RunPass& weights,
                      const Eigen::VectorXd& theta, const RunReduction& red, int fitted,
                      BatchResult* res) {
  const std::size_t E = p.epochs.size();
  res->epoch_t.resize(E);
  res->epoch_samples = p.epochs;
  res->measurement_residual = red.measurement_residual;
  res->process_residual = red.process_residual;
  res->measurement_whitened.assign(E, Vec6::Zero());
  res->process_whitened.assign(E, Vec6::Zero());
  Vec6 mss = Vec6::Zero(), pss = Vec6::Zero();
  double mw = 0.0, pw = 0.0;
  for (std::size_t e = 0; e < E; ++e) {
    res->epoch_t[e] = data.t_s[p.epochs[e]];
    mss += red.measurement_residual[e].cwiseAbs2();
    res->measurement_whitened[e] = weights.LR[e] * red.measurement_residual[e];
    mw += res->measurement_whitened[e].squaredNorm();
    if (e > 0) pss += red.process_residual[e].cwiseAbs2();
  }
  // Whitened as a sequence: neighbouring intervals share their epoch's sample.
  const StateSpaceModel model(p, red.noise_mV);
  const std::vector<Vec6> raw(red.process_residual.begin() + 1, red.process_residual.end());
  const std::vector<Vec6> white = model.WhitenProcessSequence(weights.process, raw, theta);
  for (std::size_t e = 1; e < E; ++e) {
    res->process_whitened[e] = white[e - 1];
    pw += white[e - 1].squaredNorm();
  }
  res->residuals.measurement_rms = (mss / E).cwiseSqrt();
  res->residuals.process_rms = (pss / (E - 1)).cwiseSqrt();
  res->residuals.measurement_whitened_rms = std::sqrt(mw / (6.0 * E));
  res->residuals.process_whitened_rms = std::sqrt(pw / (6.0 * (E - 1)));
  const int nc = static_cast<int>(p.constraints.size());
  res->residual_count = static_cast<int>(12 * E - 6) + fitted + nc;
  res->degrees_of_freedom = res->residual_count - static_cast<int>(6 * E) - fitted;
  res->chi2_per_dof = 2.0 * res->final_cost / std::max(1, res->degrees_of_freedom);
}

// The noise estimate against the declaration: the estimate at the solution,
// its sampling error and degrees of freedom, consistent when every channel is
// within 3 sd (or 2 %) of the declared figure; lag-1 of the whitened residual.
NoiseEstimate CheckNoise(const RunReduction& red, const Eigen::Vector3d& declared, int fitted,
                         const std::vector<Vec6>& process_whitened) {
  NoiseEstimate out;
  out.assumed_mV = declared;
  out.estimated_mV = red.noise_mV;
  out.dof = NoiseDegreesOfFreedom(red, fitted);
  bool consistent = true;
  for (int i = 0; i < 3; ++i) {
    out.sd_mV[i] = out.dof[i] > 0 ? out.estimated_mV[i] * std::sqrt(0.5 / out.dof[i]) : 0.0;
    const double diff = std::abs(out.estimated_mV[i] - declared[i]);
    if (diff > 3.0 * out.sd_mV[i] && diff > 0.02 * declared[i]) consistent = false;
  }
  out.consistent = consistent;
  const std::size_t n = process_whitened.size() > 1 ? process_whitened.size() - 1 : 0;
  out.white_bound =
      n > 0 ? std::max(kWhiteLag1, 4.0 / std::sqrt(static_cast<double>(n))) : kWhiteLag1;
  if (n > 2) {
    for (int c = 0; c < 6; ++c) {
      Eigen::VectorXd x(n);
      for (std::size_t e = 1; e <= n; ++e) x[e - 1] = process_whitened[e][c];
      out.lag1[c] = Lag1(x);
      if (std::abs(out.lag1[c]) > out.white_bound) out.white = false;
    }
  }
  return out;
}

}  // namespace

double HoldPriority(const ParameterLayout& layout, int index) {
  if (layout.is_gyro(index)) {
    // As the accelerometer's: a common rotation of both triads about a bench
    // axis is resolved by the bench zero (held), the sensors' angles relative to it.
    const int j = index - layout.gyro_offset();
    if (j >= kGW0x && j <= kGW0z) return 5.0;
    if (j <= kGKz) return 4.0;
    if (j <= kGGammaZ) return 3.0;
    return 2.0;  // g-sensitivity
  }
  return HoldPriority(index);
}

double HoldPriority(int index) {
  if (index >= kW0x && index <= kW0z) return 5.0;  // zero offsets
  if (index <= kKz) return 4.0;                     // scale factors
  if (index <= kGammaZ) return 3.0;                 // misalignments
  if (index >= kDx2 && index <= kDz2) return 3.0;   // lever arm
  if (index >= kKxx && index <= kKzz) return 2.0;   // nonlinearity, cross-coupling
  return 1.0;                                       // bench zeros, effects
}

Eigen::VectorXd InformationResolution(const Eigen::VectorXd& scale) {
  return kInformationResolution * std::numeric_limits<double>::epsilon() * scale.cwiseAbs();
}

std::vector<int> SupportedByInformation(const Eigen::MatrixXd& information,
                                        const Eigen::VectorXd& min_info,
                                        const Eigen::VectorXd& priority, Eigen::VectorXd* left,
                                        const Eigen::MatrixXd* constraint_information) {
  const int n = static_cast<int>(information.rows());
  // The whole information and the data's alone, eliminated along the same
  // pivots: what a parameter keeps of each once the kept ones are known.
  Eigen::MatrixXd S = information;
  Eigen::MatrixXd D = constraint_information ? Eigen::MatrixXd(information - *constraint_information)
                                             : information;
  const Eigen::VectorXd own_data = D.diagonal();
  std::vector<int> kept;
  std::vector<bool> used(n, false);
  Eigen::VectorXd at_pick = Eigen::VectorXd::Zero(n);
  auto eligible = [&](int j) {
    if (used[j] || S(j, j) < min_info[j]) return false;
    // Separable by the data from the kept ones (|rho| < 0.99), or determined
    // by a constraint beyond what the data give (dpsi - dlambda2 pins one
    // member of a direction the data leave flat).
    return D(j, j) >= kMinSeparableShare * own_data[j] || S(j, j) - D(j, j) >= min_info[j];
  };
  for (;;) {
    int best = -1;
    for (int j = 0; j < n; ++j) {
      if (!eligible(j)) continue;
      if (best < 0 || priority[j] > priority[best] ||
          (priority[j] == priority[best] && S(j, j) > S(best, best))) {
        best = j;
      }
    }
    if (best < 0) break;
    used[best] = true;
    kept.push_back(best);
    at_pick[best] = S(best, best);
    const Eigen::VectorXd col = S.col(best) / std::sqrt(S(best, best));
    S -= col * col.transpose();
    if (D(best, best) > 1e-12 * std::max(1.0, own_data[best])) {
      const Eigen::VectorXd dcol = D.col(best) / std::sqrt(D(best, best));
      D -= dcol * dcol.transpose();
    }
  }
  if (left) {
    // Kept: what it had beyond those kept before it; the rest: what is left.
    *left = S.diagonal().cwiseMax(0.0);
    for (int j : kept) (*left)[j] = at_pick[j];
  }
  return kept;
}

// The decision's point: the nominal values with the zero offsets fitted (the
// accelerometer's and the gyro's), three Levenberg-Marquardt steps on the
// samples thinned by m. Not the scale factors: the residual's weights follow
// them, and with the noise held no log-determinant balances that, so a
// misfit moved the ones the run does not determine (the real pitch run's Ky
// to 22 500 mg/g, a simulated vertical shaft's Ky and Kz to 1861 and 760
// mV/g against 996 and 1010, CliReliability.TheDecisionsPointKeepsThe...;
// every real gyro run's gyro.K 280 to 5e4 sigma short of its minimum), and the
// decision's information was formed there; at their nominal values, the
// prior's mean, it is the information the prior expects (the predicted
// readings' information scales with them). The thinned run is gone when it
// returns (the decision's full pass comes after it: the 40-min 1-kHz run's
// peak memory).
Eigen::VectorXd ZeroOffsetPoint(const RunDescription& run, const RunData& data,
                                const ParameterLayout& layout, double epoch_s,
                                const AngleDerivativeOptions& derivatives, std::size_t m,
                                int threads) {
  const RunData thin = Decimate(data, m);
  const RunProblem pt = BuildRunProblem(run, thin, layout, epoch_s, derivatives, nullptr, threads);
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  PriorAndConstraintRows(pt, &A, &b);
  BatchObjective objective({LinkedRun{&pt, {}, {}}}, A, b, pt.prior.mean, threads);
  objective.HoldGyroNoise();
  MinimizerOptions mo;
  mo.max_iterations = 3;  // a point to linearise at, not an estimate
  mo.tolerance = 5e-3;
  mo.full_information = false;  // the information is the decision's pass's
  // A sensor's offsets are tens to hundreds of mg (a gyro's degrees per second).
  std::vector<int> offsets = {kW0x, kW0y, kW0z};
  if (objective.has_gyro(0)) {
    for (int i = kGW0x; i <= kGW0z; ++i) offsets.push_back(layout.gyro_offset() + i);
  }
  BatchMinimizer offsets_only(objective, offsets, mo);
  MinimizerSummary summary;
  return offsets_only.Minimize(pt.prior.mean, {pt.noise_mV}, &summary).phi;
}

std::map<int, std::vector<int>> DeterminedOnlyWithConsidered(
    const Eigen::MatrixXd& cov, const Eigen::MatrixXd& cov_given, const Eigen::MatrixXd& sensitivity,
    const Eigen::VectorXd& consider_variance, const Eigen::VectorXd& prior_sigma,
    double min_information, const std::vector<int>& estimated) {
  std::map<int, std::vector<int>> out;
  const int c = static_cast<int>(consider_variance.size());
  if (c == 0 || sensitivity.cols() != c) return out;
  for (int i : estimated) {
    const double total = cov(i, i), given = cov_given(i, i);
    if (!(total > 2.0 * given) || total * min_information <= prior_sigma[i] * prior_sigma[i]) {
      continue;
    }
    std::vector<std::pair<double, int>> share;
    for (int q = 0; q < c; ++q) {
      const double s = sensitivity(i, q);
      share.push_back({s * s * consider_variance[q], q});
    }
    std::sort(share.rbegin(), share.rend());
    std::vector<int>& with = out[i];
    for (const auto& [v, q] : share) {
      if (with.empty() || v >= 0.25 * (total - given)) with.push_back(q);
    }
  }
  return out;
}

std::vector<int> ZerosOfStillAxes(const RunData& data) {
  const std::vector<double>& l = data.lambda_rad[1];
  const auto [lo, hi] = std::minmax_element(l.begin(), l.end());
  if (lo != l.end() && *lo == *hi) return {kDlambda2};
  return {};
}

HoldDecision ChooseHeldParameters(const RunDescription& run, const RunData& data,
                                  const ParameterLayout& layout, const HoldPolicy& o,
                                  double epoch_s, const AngleDerivativeOptions& derivatives,
                                  int decimation_hz, int threads, SharedRunWork* shared) {
  const int n = layout.size();
  if (threads <= 0) threads = DefaultThreads();
  auto index_of = [&](const std::string& name) {
    const int i = layout.IndexOf(name);
    if (i < 0) throw OptionError("hold_free", "unknown parameter '" + name + "'");
    return i;
  };
  std::set<int> user_hold, user_free;
  for (const std::string& h : o.hold) user_hold.insert(index_of(h));
  for (const std::string& f : o.free) user_free.insert(index_of(f));
  for (int i : user_hold) {
    if (user_free.count(i)) {
      throw OptionError("hold_free", "'" + layout.info(i).name + "' is both held and freed");
    }
  }
  HoldDecision d;
  d.conditional_information = Eigen::VectorXd::Zero(n);
  // 0 estimated, 1 consider, 2 held
  std::vector<int> kind(n, 0);
  if (o.auto_hold) {
    // At the nominal values with the zero offsets fitted (ZeroOffsetPoint; a
    // degenerate direction has no information there). That point is found on
    // the samples thinned to decimation_hz; the information there is all the
    // samples' (one pass): thinned, the increments' quadrature is coarser
    // than the motion and the information of a weak direction is not the
    // fit's (real pitch run at 31 Hz: Ky's 0.079 prior units left, 0.0039
    // at 100 Hz; alpha_x's 6.2e8, 8.1e8 at 100 Hz).
    // It is the information of the readings the model predicts there for
    // the recorded attitude (SampleSeries::readings), not of the
    // recorded readings: a parameter that multiplies a small component of
    // the specific force would take that component's reading noise for
    // information (a simulated vertical shaft, 6 mg of tilt under 12 mg of
    // noise across the shaft: gamma_y and gamma_z were estimated, and the
    // fit turned them to 13 400'; HoldDecision.ReadingNoiseIsNoInformation).
    const std::size_t m = ThinningFactor(data, decimation_hz);
    d.theta = ZeroOffsetPoint(run, data, layout, epoch_s, derivatives, m, threads);
    RunProblem pt = BuildRunProblem(run, data, layout, epoch_s, derivatives, shared, threads);
    pt.series.readings = SampleSeries::Readings::kPredictedAtRest;
    Eigen::MatrixXd A;
    Eigen::VectorXd b;
    PriorAndConstraintRows(pt, &A, &b);
    std::vector<std::shared_ptr<const RunPass>> weights;
    if (shared) weights.push_back(shared->Weights(pt, threads));
    BatchObjective all({LinkedRun{&pt, {}, {}}}, A, b, pt.prior.mean, threads, weights);
    all.HoldGyroNoise();
    const BatchObjective::Point at = all.Evaluate(d.theta, {pt.noise_mV}, true,
                                                  ThetaPart::kGradientAndInformationAtFixedNoise);
    const Eigen::MatrixXd info_si = at.data_information + ConstraintInformation(pt);
    const Eigen::VectorXd& s = pt.prior.sigma;
    d.information = s.asDiagonal() * info_si * s.asDiagonal();
    d.information = 0.5 * (d.information + d.information.transpose());
    // The structural nulls, named (what a held parameter stands for).
    ObservabilityThresholds null_directions;
    null_directions.unobservable = o.null_information;
    std::vector<Direction> nulls;
    ClassifyDirections(layout, info_si, s, null_directions, &nulls, nullptr);
    for (const Direction& dir : nulls) d.unsupported.push_back(dir.named);
    // Below the information's resolution a parameter has none.
    const Eigen::VectorXd resolution =
        InformationResolution(at.data_information_scale).cwiseProduct(s.cwiseAbs2());
    Eigen::VectorXd min_info = resolution.cwiseMax(o.min_information);
    Eigen::VectorXd priority(n);
    for (int i = 0; i < n; ++i) priority[i] = HoldPriority(layout, i);
    for (int i : user_free) min_info[i] = 0.0;  // kept first whatever their information
    for (int i : user_hold) min_info[i] = std::numeric_limits<double>::infinity();
    Eigen::VectorXd left;
    const Eigen::MatrixXd constraint_prior_units =
        s.asDiagonal() * ConstraintInformation(pt) * s.asDiagonal();
    const std::vector<int> kept =
        SupportedByInformation(d.information, min_info, priority, &left, &constraint_prior_units);
    d.conditional_information = left;
    kind.assign(n, 1);
    for (int i : kept) kind[i] = 0;
    for (int i = 0; i < n; ++i) {
      if (kind[i] == 1 && left[i] < std::max(o.null_information, resolution[i])) kind[i] = 2;
    }
    // An inner axis that does not turn: its zero is where the frame is put.
    for (int zero : ZerosOfStillAxes(data)) {
      if (kind[zero] == 2) continue;
      kind[zero] = 2;
      WeakDirection still;
      still.weights = {{layout.info(zero).name, 1.0}};
      still.description = "the inner bench axis does not turn (its angle is a constant): its zero " +
                          layout.info(zero).name + " is where the frame is put";
      d.unsupported.push_back(still);
    }
  }
  for (int i : user_hold) kind[i] = 2;
  for (int i : user_free) kind[i] = 0;
  for (int i = 0; i < n; ++i) {
    if (kind[i] == 1) d.consider.push_back(layout.info(i).name);
    if (kind[i] == 2) d.held.push_back(layout.info(i).name);
  }
  // What the held parameters stand for: the other members of their
  // undetermined directions are estimated relative to them (a consider
  // parameter stands for nothing: its uncertainty is in the others' sigma).
  const std::set<std::string> held_set(d.held.begin(), d.held.end());
  const std::set<std::string> consider_set(d.consider.begin(), d.consider.end());
  for (const WeakDirection& w : d.unsupported) {
    std::vector<std::string> anchors;
    for (const auto& [name, weight] : w.weights) {
      if (held_set.count(name) && std::abs(weight) >= 0.1) anchors.push_back(name);
    }
    if (anchors.empty()) continue;
    for (const auto& [name, weight] : w.weights) {
      if (held_set.count(name) || consider_set.count(name) || std::abs(weight) < 0.1) continue;
      std::vector<std::string>& r = d.relative_to[name];
      for (const std::string& a : anchors) {
        if (std::find(r.begin(), r.end(), a) == r.end()) r.push_back(a);
      }
    }
  }
  return d;
}

void ConsiderTerm(const Eigen::MatrixXd& info, const Eigen::VectorXd& prior_sigma,
                  const std::vector<int>& est, const std::vector<int>& consider,
                  Eigen::MatrixXd* sensitivity, Eigen::MatrixXd* term) {
  const int n = static_cast<int>(info.rows());
  const int c = static_cast<int>(consider.size());
  *sensitivity = Eigen::MatrixXd::Zero(n, c);
  *term = Eigen::MatrixXd::Zero(n, n);
  if (c == 0 || est.empty()) return;
  Eigen::MatrixXd Iaa = Sub(info, est, est);
  for (std::size_t a = 0; a < est.size(); ++a) {
    Iaa(a, a) += 1.0 / (prior_sigma[est[a]] * prior_sigma[est[a]]);
  }
  const Eigen::MatrixXd S = -Iaa.ldlt().solve(Sub(info, est, consider));
  Eigen::VectorXd pc(c);
  for (int q = 0; q < c; ++q) pc[q] = prior_sigma[consider[q]] * prior_sigma[consider[q]];
  const Eigen::MatrixXd add = S * pc.asDiagonal() * S.transpose();
  for (std::size_t a = 0; a < est.size(); ++a) {
    sensitivity->row(est[a]) = S.row(a);
    for (std::size_t b = 0; b < est.size(); ++b) (*term)(est[a], est[b]) = add(a, b);
  }
}

HoldDecision DecisionOf(const BatchResult& r) {
  HoldDecision d;
  d.held = r.held;
  d.consider = r.consider;
  d.unsupported = r.unsupported_at_start;
  d.relative_to = r.relative_to;
  d.information = r.information_at_start;
  d.conditional_information = r.conditional_information;
  return d;
}

bool IsEstimated(const BatchResult& r, const std::string& name) {
  return std::find(r.held.begin(), r.held.end(), name) == r.held.end() &&
         std::find(r.consider.begin(), r.consider.end(), name) == r.consider.end();
}

HoldDecision DecideHeldParameters(const RunDescription& run, const RunData& data,
                                  const ParameterLayout& layout, const BatchOptions& opt) {
  // The declared noise, or with auto the readings' own (the gyro's too).
  RunDescription at_start = WithReadingNoise(run, data);
  at_start.noise_channel_mV = StartNoise(run, data, opt);
  at_start.noise_mV = (*at_start.noise_channel_mV).maxCoeff();
  return ChooseHeldParameters(at_start, data, layout, opt.holding, opt.epoch_s, opt.derivatives,
                              opt.init_decimation_hz, opt.threads, opt.shared);
}

namespace {

// One fit, step by step (SolveBatch): the state in members, each step named.
class BatchSolve {
 public:
  BatchSolve(const RunDescription& run, const RunData& data, const ParameterLayout& layout,
             const BatchOptions& opt)
      : run_(run), data_(data), layout_(layout), opt_(opt),
        shared_(opt.shared ? opt.shared : &own_shared_) {}

  BatchResult Run() {
    SetUp();
    Decide();
    Start();
    if (!Minimise()) return RefitAtTheDeclaredNoise();
    RecordGyro();
    Residuals();
    res_.estimate.cov = Eigen::MatrixXd::Zero(p_.n, p_.n);
    if (opt_.compute_covariance && !est_.empty()) {
      Covariance();
    } else {
      const WhitenessSummary w = ProcessWhiteness(res_.process_whitened, {});
      res_.whiteness_p_value = w.p_value;
      res_.residual_white = w.white;
    }
    Fraction(1.0);
    return std::move(res_);
  }

 private:
  void Say(const std::string& s) const {
    if (opt_.progress) opt_.progress(s);
  }
  void Fraction(double f) const {
    if (opt_.fraction) opt_.fraction(f);
  }

  // The run problem and the noise to start from.
  void SetUp() {
    t_start_ = std::chrono::steady_clock::now();
    threads_ = opt_.threads > 0 ? opt_.threads : DefaultThreads();
    if (opt_.sigma != "auto" && opt_.sigma != "white" && opt_.sigma != "hac") {
      throw OptionError("sigma", "unknown '" + opt_.sigma + "' (auto, white, hac)");
    }
    p_ = BuildRunProblem(run_, data_, layout_, opt_.epoch_s, opt_.derivatives, shared_, threads_);
    res_.prior = p_.prior;
    res_.epochs = static_cast<int>(p_.epochs.size());
    res_.noise_declared_mV = run_.ChannelNoise_mV();
    res_.noise_auto = run_.noise_auto;
    noise0_ = StartNoise(run_, data_, opt_);
    res_.noise_start_mV = noise0_;
    p_.noise_mV = noise0_;
    if (run_.noise_auto) {
      char line[160];
      std::snprintf(line, sizeof(line),
                    "noise_mV auto: starting from the readings' own white noise %.3g %.3g %.3g "
                    "(second differences)",
                    noise0_[0], noise0_[1], noise0_[2]);
      Say(line);
    }
  }

  // 1. What the run determines, at the nominal values (scale factors and
  // offsets fitted) and the declared noise (or the readings' own with
  // noise_mV: auto): decided before the fit, so that no misfit can move
  // what the run does not determine.
  void Decide() {
    const auto t_decide = std::chrono::steady_clock::now();
    if (opt_.decision) {
      decision_ = *opt_.decision;
    } else {
      Say("choosing the parameters this run determines");
      Fraction(0.0);
      BatchOptions o = opt_;
      o.shared = shared_;  // the decision's full pass shares the fit's weights
      decision_ = DecideHeldParameters(run_, data_, layout_, o);
    }
    res_.decide_seconds = Seconds(t_decide);
    res_.held = decision_.held;
    res_.consider = decision_.consider;
    res_.relative_to = decision_.relative_to;
    res_.min_information = opt_.holding.min_information;
    res_.unsupported_at_start = decision_.unsupported;
    res_.information_at_start = decision_.information;
    res_.conditional_information = decision_.conditional_information;
    held_ = Indices(layout_, decision_.held);
    consider_ = Indices(layout_, decision_.consider);
    for (int i = 0; i < p_.n; ++i) {
      if (!std::binary_search(held_.begin(), held_.end(), i) &&
          !std::binary_search(consider_.begin(), consider_.end(), i)) {
        est_.push_back(i);
      }
    }
  }

  // 2. The start; what is not estimated at its nominal value.
  void Start() {
    Say("initialising (" +
        std::string(opt_.init == BatchInit::kRts       ? "RTS smoother"
                    : opt_.init == BatchInit::kNominal ? "nominal values, zero offsets fitted"
                                                       : "given") +
        ")");
    Fraction(0.1);
    std::vector<std::string> not_estimated = decision_.held;
    not_estimated.insert(not_estimated.end(), decision_.consider.begin(),
                         decision_.consider.end());
    double diverged_at_s = -1.0;
    res_.initial = Initialise(run_, data_, layout_, p_, opt_, not_estimated, noise0_,
                              &diverged_at_s);
    if (diverged_at_s >= 0.0) {
      char why[200];
      std::snprintf(why, sizeof(why),
                    "the RTS smoother diverged (its covariance lost its positive definiteness "
                    "at t = %.3g s): started from the nominal values, zero offsets fitted",
                    diverged_at_s);
      res_.start_note = why;
      Say(why);
    }
    if ((opt_.init == BatchInit::kNominal || diverged_at_s >= 0.0) &&
        decision_.theta.size() == p_.n) {
      res_.initial.theta = decision_.theta;  // the nominal values, zero offsets fitted
    }
    res_.init_seconds = Seconds(t_start_);
    theta0_ = res_.initial.theta;
    for (int i : held_) theta0_[i] = p_.prior.mean[i];
    for (int i : consider_) theta0_[i] = p_.prior.mean[i];
  }

  // 3. The minimum. False when the noise was to be estimated and the run
  // has too few degrees of freedom for it (a declared noise to fall back on).
  bool Minimise() {
    t_solve_ = std::chrono::steady_clock::now();
    PriorAndConstraintRows(p_, &A_, &b_);
    std::vector<std::shared_ptr<const RunPass>> weights;
    weights.push_back(shared_->Weights(p_, threads_));
    objective_.emplace(std::vector<LinkedRun>{LinkedRun{&p_, {}, {}}}, A_, b_, p_.prior.mean,
                       threads_, std::move(weights));
    MinimizerOptions mo;
    mo.max_iterations = opt_.max_iterations;
    mo.tolerance = opt_.tolerance;
    mo.estimate_noise = {opt_.estimate_noise};
    mo.progress = [this](const std::string& s) { Say(s); };
    if (opt_.fraction) mo.fraction = [this](double f) { opt_.fraction(0.15 + 0.75 * f); };
    // The steps form the considered parameters' columns too: the consider
    // term reads them at the minimum (no reduction by every column after).
    mo.also_formed = consider_;
    mo.full_information = false;
    BatchMinimizer minimizer(*objective_, est_, mo);
    MinimizerSummary summary;
    pt_ = minimizer.Minimize(theta0_, {noise0_}, &summary);
    res_.converged = summary.converged;
    res_.termination = summary.termination;
    res_.iterations = summary.iterations;
    res_.passes = summary.passes;
    Say(summary.termination);
    res_.final_cost = pt_.cost - pt_.gyro_cost;
    if (opt_.cost_at_noise.minCoeff() > 0.0) {
      const BatchObjective::Point at =
          objective_->AtNoise(pt_, {opt_.cost_at_noise}, ThetaPart::kNone);
      res_.cost_at_noise = at.cost - at.gyro_cost;
    }
    res_.estimate.theta = pt_.phi;
    res_.noise_used_mV = pt_.reductions[0].noise_mV;
    res_.noise_source = opt_.estimate_noise ? "estimated" : "declared";
    // A noise estimate needs degrees of freedom; with noise_mV: auto there is
    // no declared figure to fall back on.
    const Eigen::Vector3d noise_dof =
        NoiseDegreesOfFreedom(pt_.reductions[0], static_cast<int>(est_.size()));
    if (opt_.estimate_noise && noise_dof.minCoeff() < kMinNoiseDof) {
      if (run_.noise_auto) {
        throw InputError(run_.yaml_path + ": triad.noise_mV: auto needs a longer run: " +
                         std::to_string(static_cast<int>(noise_dof.minCoeff())) +
                         " degrees of freedom in the weakest channel, at least " +
                         std::to_string(static_cast<int>(kMinNoiseDof)) +
                         " (declare the noise instead)");
      }
      return false;
    }
    res_.solve_seconds = Seconds(t_solve_);
    const BatchObjective::Work& work = objective_->work();
    res_.solve_pass_seconds = work.pass_seconds;
    res_.solve_reduction_seconds = work.reduction_seconds;
    res_.reductions = work.reductions;
    return true;
  }

  // Too short to estimate the noise: the declared noise, refitted at it.
  BatchResult RefitAtTheDeclaredNoise() const {
    Say("too few degrees of freedom to estimate the noise: the declared noise is used");
    BatchOptions o = opt_;
    o.estimate_noise = false;
    o.decision = &decision_;
    o.fraction = nullptr;
    return SolveBatch(run_, data_, layout_, o);
  }

  // The gyro triad's part at the minimum, when the run has one.
  void RecordGyro() {
    if (!objective_->HasGyroPart(pt_, 0)) return;
    res_.gyro = SummariseGyro(p_, *pt_.gyro_passes[0], pt_.gyro[0]);
    res_.gyro.noise_declared_rad_s = run_.gyro ? run_.gyro->noise_rad_s : p_.gyro_noise_rad_s;
    res_.gyro.noise_auto = run_.gyro && run_.gyro->noise_auto;
  }

  // The residuals at the minimum and what they say of the noise.
  void Residuals() {
    const RunReduction& red = pt_.reductions[0];
    const int fitted = static_cast<int>(est_.size());
    CollectResiduals(p_, data_, objective_->weights(0), pt_.passes[0]->theta, red, fitted, &res_);
    res_.noise_check = CheckNoise(red, res_.noise_declared_mV, fitted, res_.process_whitened);
  }

  // 4. The covariance at the minimum: the model's, with the consider term,
  // and the HAC sandwich over the epoch scores; the residual's whiteness
  // (the autocorrelation the fit itself leaves subtracted) chooses.
  void Covariance() {
    Say("covariance");
    Fraction(0.95);
    const auto t_cov = std::chrono::steady_clock::now();
    const int n = p_.n;
    const std::size_t E = p_.epochs.size();
    RunReduction& red = pt_.reductions[0];
    const Eigen::MatrixXd Iaa = Sub(pt_.information, est_, est_);
    const Eigen::MatrixXd cov_a = Eigen::LDLT<Eigen::MatrixXd>(Iaa).solve(
        Eigen::MatrixXd::Identity(est_.size(), est_.size()));
    // The whitened process Jacobians over the estimated parameters: the
    // autocorrelation the fit itself leaves in the residuals.
    std::vector<Eigen::MatrixXd> C(E - 1);
    // The minimum's blocks, narrowed in place: the covariance is their last use.
    std::vector<ProcessBlock> pb = std::move(red.process_blocks);
    std::vector<MeasurementBlock> mb = std::move(red.measurement_blocks);
    // Each estimated parameter's column in the blocks (formed by the
    // estimated and considered ones: Reduce's block_columns).
    std::vector<int> at(est_.size());
    for (std::size_t k = 0; k < est_.size(); ++k) {
      const std::vector<int>& cols = red.block_columns;
      at[k] = cols.empty() ? est_[k]
                           : static_cast<int>(std::lower_bound(cols.begin(), cols.end(), est_[k]) -
                                              cols.begin());
    }
    for (std::size_t e = 0; e < E; ++e) {
      Eigen::MatrixXd N(6, est_.size());
      for (std::size_t k = 0; k < est_.size(); ++k) N.col(k) = mb[e].N.col(at[k]);
      mb[e].N = N;
      if (e + 1 < E) {
        Eigen::MatrixXd Ce(6, est_.size());
        for (std::size_t k = 0; k < est_.size(); ++k) Ce.col(k) = pb[e].C.col(at[k]);
        pb[e].C = Ce;
        C[e] = Ce;
      }
    }
    res_.process_whitened_expected_acf = ExpectedProcessAutocorrelation(C, cov_a, 20, threads_);
    const WhitenessSummary w =
        ProcessWhiteness(res_.process_whitened, res_.process_whitened_expected_acf);
    res_.whiteness_p_value = w.p_value;
    res_.residual_white = w.white;
    // The consider term, from the information at the solution.
    res_.information = pt_.data_information + ConstraintInformation(p_);
    Eigen::MatrixXd add = Eigen::MatrixXd::Zero(n, n);
    if (!consider_.empty()) {
      ConsiderTerm(res_.information, p_.prior.sigma, est_, consider_, &res_.consider_sensitivity,
                   &add);
      res_.consider_cov = Eigen::MatrixXd::Zero(consider_.size(), consider_.size());
      for (std::size_t q = 0; q < consider_.size(); ++q) {
        res_.consider_cov(q, q) = p_.prior.sigma[consider_[q]] * p_.prior.sigma[consider_[q]];
      }
    }
    res_.cov_white = Expand(cov_a, est_, n) + add;
    res_.estimate.cov = res_.cov_white;
    Eigen::MatrixXd Aa(A_.rows(), est_.size());
    for (std::size_t k = 0; k < est_.size(); ++k) Aa.col(k) = A_.col(est_[k]);
    const Eigen::MatrixXd rows_info = Aa.transpose() * Aa;
    const HacCovariance hac =
        HacThetaCovariance(Scores(pb, mb), Iaa, rows_info, opt_.hac_bandwidth_epochs, false,
                           opt_.hac_kernel_bias_correction);
    res_.hac_bandwidth_epochs = hac.bandwidth;
    res_.hac_kernel_bias_corrected = opt_.hac_kernel_bias_correction;
    res_.hac_kernel_bias_factor_max =
        hac.kernel_bias_factor.size() > 0 ? hac.kernel_bias_factor.maxCoeff() : 1.0;
    res_.cov_hac = Expand(hac.cov, est_, n) + add;
    if (opt_.sigma == "hac" || (opt_.sigma == "auto" && !res_.residual_white)) {
      res_.sigma_method = "hac";
      res_.estimate.cov = FloorVariances(Expand(hac.cov, est_, n), Expand(cov_a, est_, n)) + add;
      if (opt_.sigma == "auto") {
        char figures[200];
        std::snprintf(figures, sizeof(figures),
                      "sigma from the HAC covariance: the residual is correlated in time "
                      "(whiteness p %.2g; Bartlett bandwidth %.1f epochs)",
                      w.p_value, hac.bandwidth);
        Say(figures);
      }
    }
    if (!consider_.empty()) res_.cov_given_consider = res_.estimate.cov - add;
    res_.covariance_seconds = Seconds(t_cov);
  }

  // Each epoch's score over the estimated parameters; with the gyro, each
  // gyro interval's score at the first epoch at or after its end.
  std::vector<Eigen::VectorXd> Scores(const std::vector<ProcessBlock>& pb,
                                      const std::vector<MeasurementBlock>& mb) const {
    std::vector<Eigen::VectorXd> scores = EpochScores(pb, mb);
    if (!objective_->HasGyroPart(pt_, 0)) return scores;
    const std::size_t E = p_.epochs.size();
    const std::vector<Eigen::VectorXd>& gs = pt_.gyro[0].scores;
    std::size_t e = 0;
    for (std::size_t k = 0; k < gs.size(); ++k) {
      const std::size_t end = p_.gyro_epochs[k + 1];
      while (e + 1 < E && p_.epochs[e] < end) ++e;
      for (std::size_t q = 0; q < est_.size(); ++q) scores[e][q] += gs[k][est_[q]];
    }
    return scores;
  }

  const RunDescription& run_;
  const RunData& data_;
  const ParameterLayout& layout_;
  const BatchOptions& opt_;
  // The work the decision and the fit share (their weights' reference pass,
  // the angles' derivatives): opt_.shared, or this fit's own.
  SharedRunWork own_shared_;
  SharedRunWork* shared_;
  std::chrono::steady_clock::time_point t_start_, t_solve_;
  int threads_ = 1;
  RunProblem p_;
  Eigen::Vector3d noise0_ = Eigen::Vector3d::Zero();
  HoldDecision decision_;
  std::vector<int> held_, consider_, est_;  // indices into the layout
  Eigen::VectorXd theta0_;
  Eigen::MatrixXd A_;  // prior and constraint rows
  Eigen::VectorXd b_;
  std::optional<BatchObjective> objective_;  // over p_ (built once p_ is final)
  BatchObjective::Point pt_;                 // the minimum
  BatchResult res_;
};

}  // namespace

BatchResult SolveBatch(const RunDescription& run, const RunData& data,
                       const ParameterLayout& layout, const BatchOptions& opt) {
  return BatchSolve(run, data, layout, opt).Run();
}

}  // namespace triadcal
