#include "solvers/estimation/kalman_smoother.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/model/errors.h"
#include "core/model/units.h"
#include "solvers/estimation/gyro_measurements.h"
#include "solvers/estimation/inertial_increments.h"
#include "solvers/estimation/parallel.h"
#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/state_space_model.h"

namespace triadcal {
namespace {


// The augmented process step of [x; theta_free] over one interval: x_b =
// F x_a + u + U dtheta, theta_b = theta_a. The covariance's propagation is
// the dense F P F^T: computing only the six rows it moves (O(6 N^2)) rounds
// the V, S - theta block differently, and on the paper's 1-kHz run, where V
// and S are known to micrometres, that was enough to make the filter
// diverge.
Eigen::MatrixXd PropagateCov(const ProcessStep& step, const Eigen::MatrixXd& P, int n) {
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(6 + n, 6 + n);
  F.topLeftCorner<6, 6>() = step.F();
  F.block(0, 6, 6, n) = step.U;
  Eigen::MatrixXd Pp = F * P * F.transpose();
  Pp.topLeftCorner<6, 6>() += step.noise->Q;
  return 0.5 * (Pp + Pp.transpose());
}

// Joseph form, P <- (I - K H) P (I - K H)^T + K R K^T: a congruence plus a
// positive term, so P stays positive definite when the measurement is far
// more precise than the prediction (the first epoch's diffuse start,
// noise-free or nearly noise-free runs), however K is rounded. The products
// stay dense: as rank-6 corrections, P - K (H P) - ..., the same sum would
// subtract numbers of P's size to leave R's (3-5 % of `filter`'s time).
void JosephUpdate(const Eigen::MatrixXd& K, const Eigen::MatrixXd& H, const Eigen::MatrixXd& R,
                  Eigen::MatrixXd* P) {
  Eigen::MatrixXd IKH = -K * H;
  IKH.diagonal().array() += 1.0;
  *P = IKH * *P * IKH.transpose() + K * R * K.transpose();
  *P = 0.5 * (*P + P->transpose());
}

struct PassResult {
  Eigen::VectorXd x;  // filtered state [V, S, theta_free] at the last epoch
  Eigen::MatrixXd P;  // and its covariance
  double diverged_at_s = -1.0;  // the first epoch whose covariance is not one
  std::vector<FilterSeriesRow> series;
  Vec6 innovation_ss = Vec6::Zero();
  double nis_sum = 0.0;
  double gyro_nis_sum = 0.0;
  int gyro_count = 0;
};

// The gyro's interval k as a measurement of the parameter states
// (gyro_measurements.h), linearised at th_l (free parameters): the
// innovation -(nu + Jnu (theta - th_l)) with covariance S, Joseph form.
// Returns its normalised innovation squared (negative when left out).
double GyroUpdate(const StateSpaceModel& model, GyroMeasurements* gyro, std::size_t k,
                  const Eigen::VectorXd& th_l, Eigen::VectorXd* x, Eigen::MatrixXd* P) {
  const RunProblem& c = model.problem();
  const int n = model.num_free(), N = 6 + n;
  GyroInnovation g;
  if (!gyro->Next(k, model.Expand(th_l), &g)) return -1.0;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, N);
  for (int j = 0; j < n; ++j) H.col(6 + j) = g.H.col(c.free[j]);
  const Eigen::Vector3d y = -(g.nu + H.rightCols(n) * (x->tail(n) - th_l));
  const Eigen::MatrixXd PHt = *P * H.transpose();
  const Eigen::Matrix3d S = H * PHt + g.S;
  const Eigen::LLT<Eigen::Matrix3d> llt(S);
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();
  *x += K * y;
  JosephUpdate(K, H, g.S, P);
  return y.dot(llt.solve(y));
}

PassResult ForwardPass(const StateSpaceModel& model, GyroMeasurements* gyro, int threads,
                       const Eigen::VectorXd* theta_lin_free, bool keep_series,
                       const std::function<void(double)>& progress) {
  const RunProblem& c = model.problem();
  const int n = model.num_free(), N = 6 + n;
  PassResult out;
  Eigen::VectorXd x(N);
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(N, N);
  x.tail(n) = model.Free(c.prior.mean);
  P.bottomRightCorner(n, n) =
      model.Free(c.prior.sigma).array().square().matrix().asDiagonal();
  {
    const Eigen::VectorXd th0 = model.Expand(theta_lin_free ? *theta_lin_free : x.tail(n));
    x.head<6>() = model.Measurement(0, th0, false, false).h;
    // The model has no prior on x_0 (the batch solves for it freely): the
    // filter starts diffuse, (100 m/s)^2 and (100 m)^2, which the first B2
    // update collapses to the measurement's precision (the Joseph form below
    // keeps that step well conditioned).
    P.topLeftCorner<6, 6>() = 1e4 * Mat6::Identity();
  }
  const std::size_t E = c.epochs.size();
  std::size_t next_report = 0;
  std::size_t next_gyro = 0;  // the gyro's next interval
  if (gyro) {
    if (theta_lin_free) {
      const Eigen::VectorXd th = model.Expand(*theta_lin_free);
      gyro->Start(&th, threads);
    } else {
      gyro->Start(nullptr);
    }
  }
  for (std::size_t e = 0; e < E; ++e) {
    if (e > 0) {
      // The process model linear about th_l (the iterated smoother's
      // Gauss-Newton model): x_b = F x_a + u + U (theta - th_l).
      const Eigen::VectorXd th_l = theta_lin_free ? *theta_lin_free : Eigen::VectorXd(x.tail(n));
      const ProcessStep step = model.Process(e - 1, model.Expand(th_l), true);
      const Eigen::VectorXd dtheta =
          theta_lin_free ? Eigen::VectorXd(x.tail(n) - th_l) : Eigen::VectorXd::Zero(n);
      x.head<6>() = StateSpaceModel::PredictLinear(step, x.head<6>(), dtheta);
      P = PropagateCov(step, P, n);
    }
    // Measurement update with z = x - h(theta) = 0 (block B2).
    const std::size_t k = c.epochs[e];
    const Eigen::VectorXd th_l = theta_lin_free ? *theta_lin_free : Eigen::VectorXd(x.tail(n));
    const MeasurementStep m = model.Measurement(e, model.Expand(th_l), true, true);
    const Eigen::VectorXd dth = x.tail(n) - th_l;
    const Vec6 h = StateSpaceModel::MeasurementResidual(m, x.head<6>()) - m.H * dth;
    Eigen::MatrixXd H(6, N);
    H.leftCols(6).setIdentity();
    H.rightCols(n) = -m.H;
    const Mat6 R = m.R;
    const Eigen::MatrixXd PHt = P * H.transpose();
    const Mat6 S = H * PHt + R;
    const Eigen::LLT<Mat6> llt(S);
    const Vec6 y = -h;
    const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();
    x += K * y;
    JosephUpdate(K, H, R, &P);
    // A covariance with a negative variance (or none at all) is no longer
    // a covariance: the filter has diverged (readings far from the nominal
    // model; the real runs and the paper's never come near).
    if (out.diverged_at_s < 0.0 && (!P.allFinite() || (P.diagonal().array() < 0.0).any())) {
      out.diverged_at_s = c.series.run->t_s[k];
    }
    out.nis_sum += y.dot(llt.solve(y));
    out.innovation_ss += y.cwiseAbs2();
    if (e == 0) {
      // Every constraint is one scalar pseudo-measurement (its rows over the
      // free parameters, state_space_model.h), applied once.
      Eigen::MatrixXd A;
      Eigen::VectorXd b;
      model.ThetaRows(true, &A, &b);
      for (int r = n; r < A.rows(); ++r) {
        Eigen::VectorXd hrow = Eigen::VectorXd::Zero(N);
        hrow.tail(n) = A.row(r).transpose();
        const Eigen::VectorXd Ph = P * hrow;
        const double s = hrow.dot(Ph) + 1.0;  // whitened rows: unit variance
        const double innov = b[r] - hrow.dot(x);
        x += Ph * (innov / s);
        P -= Ph * Ph.transpose() / s;
        P = 0.5 * (P + P.transpose());
      }
    }
    // The gyro's intervals that end by this epoch (at the last, all left):
    // measurements of theta alone, each linearised at the current estimate
    // (or the pass's point).
    while (gyro && next_gyro < gyro->size() &&
           (e + 1 == E || gyro->end_sample(next_gyro) <= k)) {
      const Eigen::VectorXd th_l = theta_lin_free ? *theta_lin_free : Eigen::VectorXd(x.tail(n));
      const double nis = GyroUpdate(model, gyro, next_gyro++, th_l, &x, &P);
      if (nis >= 0.0) {
        out.gyro_nis_sum += nis;
        ++out.gyro_count;
      }
    }
    if (keep_series) {
      FilterSeriesRow row;
      row.t_s = c.series.run->t_s[k];
      row.theta = model.Expand(x.tail(n));
      row.sigma = Eigen::VectorXd::Zero(c.n);
      const Eigen::VectorXd sd = P.diagonal().tail(n).cwiseMax(0.0).cwiseSqrt();
      for (int j = 0; j < n; ++j) row.sigma[c.free[j]] = sd[j];
      row.innovation = y;
      row.innovation_sigma = S.diagonal().cwiseSqrt();
      out.series.push_back(std::move(row));
    }
    if (progress && e >= next_report) {
      progress(static_cast<double>(e) / E);
      next_report = e + std::max<std::size_t>(1, E / 50);
    }
  }
  out.x = std::move(x);
  out.P = std::move(P);
  return out;
}

// theta and its covariance over all n parameters (held ones at their values,
// with zero covariance) from the free part.
Estimate FullEstimate(const StateSpaceModel& model, const Eigen::VectorXd& theta_free,
                      const Eigen::MatrixXd& cov_free) {
  return Estimate{model.Expand(theta_free), model.ExpandCovariance(cov_free)};
}

// The fixed-interval RTS smoother's estimate of the parameters at the first
// epoch. They are constants (theta_b = theta_a, no process noise): given all
// the epochs, theta at the first is theta at the last, whose smoothed
// estimate is the filtered one. So the backward recursion would return the
// last filtered theta and its covariance (theta to 4e-9 sigma, sigma to 1e-8
// of itself on the real roll runs and the paper's run, where it was run
// before it was replaced by this); it would only improve the trajectory,
// which nothing here reads.
Estimate SmoothedParameters(const StateSpaceModel& model, const PassResult& pass) {
  const int n = model.num_free();
  return FullEstimate(model, pass.x.tail(n), pass.P.bottomRightCorner(n, n));
}

}  // namespace

FilterResult RunFilterSmoother(const RunDescription& run, const RunData& data,
                               const ParameterLayout& layout, const FilterOptions& options) {
  RunProblem c = BuildRunProblem(run, data, layout, options.epoch_s, options.derivatives, nullptr,
                                 options.threads);
  std::vector<int> held;
  for (const std::string& name : options.held) {
    const int i = layout.IndexOf(name);
    if (i < 0) throw InputError("held parameter '" + name + "' is not in the layout");
    held.push_back(i);
  }
  c.Hold(held);
  // The covariance form of the filter spans the prior (degrees, tens of mV)
  // down to what the data pin (um/s): with almost noise-free data that range
  // exceeds double precision and P stops being positive definite. A floor of
  // 50 ug per sample on the process noise keeps it well conditioned; real
  // MEMS noise is far above it, and the batch solver has no such floor.
  const double floor_mps2 = 50e-6 * run.g_mps2;
  const StateSpaceModel model(c);
  const double min_var = c.isotropic_var + model.ChannelVariance(c.prior.mean).minCoeff();
  if (min_var < floor_mps2 * floor_mps2) c.isotropic_var += floor_mps2 * floor_mps2 - min_var;
  FilterResult res;
  res.prior = c.prior;
  res.epochs = static_cast<int>(c.epochs.size());
  res.rate_noise_rad_s = c.sigma_rate;
  const int passes = std::max(1, options.smoother_iterations);
  // The gyro's increments, at its declared noise (floored).
  std::unique_ptr<GyroMeasurements> gyro;
  Eigen::Vector3d gyro_noise = c.gyro_noise_rad_s.cwiseMax(kGyroNoiseFloor_dps * kDegToRad);
  const int threads = options.threads > 0 ? options.threads : DefaultThreads();
  if (options.gyro && RunHasGyro(c)) gyro = std::make_unique<GyroMeasurements>(c, gyro_noise);
  Eigen::VectorXd theta_lin_free;
  for (int p = 0; p < passes; ++p) {
    auto prog = [&](double f) {
      if (options.progress) options.progress(p + 1, f);
    };
    PassResult pass = ForwardPass(model, gyro.get(), threads, p == 0 ? nullptr : &theta_lin_free,
                                  options.keep_series && p == 0, prog);
    res.rts = SmoothedParameters(model, pass);
    if (res.diverged_at_s < 0.0) res.diverged_at_s = pass.diverged_at_s;
    if (p == 0) {
      res.ekf = res.rts;  // the first pass's last filtered estimate
      res.series = std::move(pass.series);
    }
    theta_lin_free = model.Free(res.rts.theta);
    const double E = static_cast<double>(c.epochs.size());
    res.innovation_rms = (pass.innovation_ss / E).cwiseSqrt();
    res.mean_nis = pass.nis_sum / E;
    res.gyro_measurements = pass.gyro_count;
    res.gyro_mean_nis = pass.gyro_count > 0 ? pass.gyro_nis_sum / pass.gyro_count : 0.0;
    res.passes = p + 1;
  }
  if (gyro) {
    // The gyro's residuals at the smoothed estimate, at the noise the filter
    // ran at, and the noise the fit would estimate there.
    const GyroPass at = EvaluateGyroPass(c, res.rts.theta, false, threads);
    res.gyro = SummariseGyro(c, at, ReduceGyro(at, gyro_noise, 1.0, false));
    res.gyro.noise_declared_rad_s = run.gyro ? run.gyro->noise_rad_s : c.gyro_noise_rad_s;
    res.gyro.noise_auto = run.gyro && run.gyro->noise_auto;
    res.gyro_noise_ml_rad_s =
        ReduceGyroAtBestNoise(at, gyro_noise, kNumGyroParams, false, threads).noise_rad_s;
  }
  return res;
}

}  // namespace triadcal
