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


// The process step of the interval that ends at an epoch, with where it was
// linearised (theta_lin_free empty: at the filtered theta of the epoch before).
struct Interval {
  ProcessStep step;
  Eigen::VectorXd theta_lin_free;
};

struct EpochStore {
  Eigen::VectorXd x;           // filtered state [V, S, theta_free]
  std::vector<double> P_upper;  // packed upper triangle of the filtered covariance
  Interval in;                  // interval from the previous epoch (empty at 0)
};

std::vector<double> Pack(const Eigen::MatrixXd& P) {
  const int N = static_cast<int>(P.rows());
  std::vector<double> out;
  out.reserve(N * (N + 1) / 2);
  for (int r = 0; r < N; ++r)
    for (int c = r; c < N; ++c) out.push_back(P(r, c));
  return out;
}

Eigen::MatrixXd Unpack(const std::vector<double>& v, int N) {
  Eigen::MatrixXd P(N, N);
  std::size_t i = 0;
  for (int r = 0; r < N; ++r)
    for (int c = r; c < N; ++c) P(r, c) = P(c, r) = v[i++];
  return P;
}

// The augmented transition of [x; theta_free]: x_b = F x_a + u + U dtheta.
Eigen::MatrixXd TransitionMatrix(const Interval& in, int n) {
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(6 + n, 6 + n);
  F.topLeftCorner<6, 6>() = in.step.F();
  F.block(0, 6, 6, n) = in.step.U;
  return F;
}

// x_b = f(x_a): the process model of state_space_model.h, linear about the
// pass's linearisation point (the iterated smoother's Gauss-Newton model).
Eigen::VectorXd Propagate(const Interval& in, const Eigen::VectorXd& x, int n) {
  Eigen::VectorXd y = x;
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(n);
  if (in.theta_lin_free.size() == n) delta = x.tail(n) - in.theta_lin_free;
  y.head<6>() = StateSpaceModel::PredictLinear(in.step, x.head<6>(), delta);
  return y;
}

Eigen::MatrixXd PropagateCov(const Interval& in, const Eigen::MatrixXd& P, int n) {
  const Eigen::MatrixXd F = TransitionMatrix(in, n);
  Eigen::MatrixXd Pp = F * P * F.transpose();
  Pp.topLeftCorner<6, 6>() += in.step.noise->Q;
  return 0.5 * (Pp + Pp.transpose());
}

struct PassResult {
  std::vector<EpochStore> store;
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
  Eigen::MatrixXd IKH = -K * H;
  IKH.diagonal().array() += 1.0;
  *P = IKH * *P * IKH.transpose() + K * g.S * K.transpose();
  *P = 0.5 * (*P + P->transpose());
  return y.dot(llt.solve(y));
}

PassResult ForwardPass(const StateSpaceModel& model, GyroMeasurements* gyro, int threads,
                       const Eigen::VectorXd* theta_lin_free, bool keep_series,
                       const std::function<void(double)>& progress) {
  const RunProblem& c = model.problem();
  const int n = model.num_free(), N = 6 + n;
  PassResult out;
  out.store.reserve(c.epochs.size());
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
    EpochStore st;
    if (e > 0) {
      const Eigen::VectorXd th_l = theta_lin_free ? *theta_lin_free : Eigen::VectorXd(x.tail(n));
      st.in.step = model.Process(e - 1, model.Expand(th_l), true);
      if (theta_lin_free) st.in.theta_lin_free = *theta_lin_free;
      x = Propagate(st.in, x, n);
      P = PropagateCov(st.in, P, n);
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
    // Joseph form: keeps P positive definite when the measurement is far more
    // precise than the prediction (noise-free or nearly noise-free runs).
    Eigen::MatrixXd IKH = -K * H;
    IKH.diagonal().array() += 1.0;
    P = IKH * P * IKH.transpose() + K * R * K.transpose();
    P = 0.5 * (P + P.transpose());
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
    st.x = x;
    st.P_upper = Pack(P);
    out.store.push_back(std::move(st));
    if (progress && e >= next_report) {
      progress(static_cast<double>(e) / E);
      next_report = e + std::max<std::size_t>(1, E / 50);
    }
  }
  return out;
}

// theta and its covariance over all n parameters (held ones at their values,
// with zero covariance) from the free part.
Estimate FullEstimate(const StateSpaceModel& model, const Eigen::VectorXd& theta_free,
                      const Eigen::MatrixXd& cov_free) {
  return Estimate{model.Expand(theta_free), model.ExpandCovariance(cov_free)};
}

// Fixed-interval RTS smoother; returns the smoothed state and covariance at
// the first epoch.
Estimate Smooth(const StateSpaceModel& model, const PassResult& pass) {
  const int n = model.num_free(), N = 6 + n;
  const std::size_t E = pass.store.size();
  Eigen::VectorXd xs = pass.store[E - 1].x;
  Eigen::MatrixXd Ps = Unpack(pass.store[E - 1].P_upper, N);
  for (std::size_t e = E - 1; e-- > 0;) {
    const EpochStore& cur = pass.store[e];
    const Interval& in = pass.store[e + 1].in;
    const Eigen::MatrixXd Pf = Unpack(cur.P_upper, N);
    const Eigen::MatrixXd F = TransitionMatrix(in, n);
    const Eigen::VectorXd x_pred = Propagate(in, cur.x, n);
    const Eigen::MatrixXd P_pred = PropagateCov(in, Pf, n);
    // G = Pf F^T P_pred^-1, solved in the scaled coordinates of P_pred.
    const Eigen::VectorXd d = P_pred.diagonal().cwiseMax(1e-300).cwiseSqrt();
    const Eigen::MatrixXd Pn = d.cwiseInverse().asDiagonal() * P_pred * d.cwiseInverse().asDiagonal();
    const Eigen::MatrixXd FPf = F * Pf;  // = (Pf F^T)^T
    const Eigen::MatrixXd Gt =
        d.cwiseInverse().asDiagonal() * Pn.ldlt().solve(d.cwiseInverse().asDiagonal() * FPf);
    const Eigen::MatrixXd G = Gt.transpose();
    xs = cur.x + G * (xs - x_pred);
    Ps = Pf + G * (Ps - P_pred) * G.transpose();
    Ps = 0.5 * (Ps + Ps.transpose());
  }
  return FullEstimate(model, xs.tail(n), Ps.bottomRightCorner(n, n));
}

}  // namespace

FilterResult RunFilterSmoother(const RunDescription& run, const RunData& data,
                               const ParameterLayout& layout, const FilterOptions& options) {
  RunProblem c = BuildRunProblem(run, data, layout, options.epoch_s, options.derivatives);
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
  const int n = model.num_free();
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
    if (p == 0) {
      const Eigen::MatrixXd P_end = Unpack(pass.store.back().P_upper, 6 + n);
      res.ekf = FullEstimate(model, pass.store.back().x.tail(n), P_end.bottomRightCorner(n, n));
      res.series = std::move(pass.series);
    }
    res.rts = Smooth(model, pass);
    theta_lin_free = model.Free(res.rts.theta);
    const double E = static_cast<double>(pass.store.size());
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
