#include "solvers/estimation/kalman_smoother.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/model/errors.h"
#include "solvers/estimation/inertial_increments.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// The process step of the interval that ends at an epoch.
struct Interval {
  double T = 0.0;
  Eigen::Vector3d dv = Eigen::Vector3d::Zero(), ds = Eigen::Vector3d::Zero();
  Eigen::MatrixXd Jv, Js;  // 3 x n
  double qa2 = 0.0, qab = 0.0, qb2 = 0.0;  // Q = accel variance * [qa2 qab; qab qb2] (x) I3
  Eigen::VectorXd theta_lin;  // where dv, ds were evaluated (empty: the filtered theta)
};

struct EpochStore {
  Eigen::VectorXd x;           // filtered state
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

using Context = RunProblem;

Eigen::MatrixXd TransitionMatrix(const Interval& in, int n) {
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(6 + n, 6 + n);
  F.block(0, 6, 3, n) = in.Jv;
  F.block(3, 0, 3, 3) = in.T * Eigen::Matrix3d::Identity();
  F.block(3, 6, 3, n) = in.Js;
  return F;
}

Mat6 ProcessNoise(const Interval& in, double accel_var) {
  Mat6 Q = Mat6::Zero();
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  Q.block<3, 3>(0, 0) = accel_var * in.qa2 * I;
  Q.block<3, 3>(0, 3) = accel_var * in.qab * I;
  Q.block<3, 3>(3, 0) = accel_var * in.qab * I;
  Q.block<3, 3>(3, 3) = accel_var * in.qb2 * I;
  return Q;
}

// x_b = f(x_a): the process model linearised at in.theta_lin (or x_a's theta).
Eigen::VectorXd Propagate(const Interval& in, const Eigen::VectorXd& x, int n) {
  Eigen::VectorXd y = x;
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(n);
  if (in.theta_lin.size() == n) delta = x.tail(n) - in.theta_lin;
  y.head<3>() = x.head<3>() + in.dv + in.Jv * delta;
  y.segment<3>(3) = x.segment<3>(3) + x.head<3>() * in.T + in.ds + in.Js * delta;
  return y;
}

Eigen::MatrixXd PropagateCov(const Interval& in, const Eigen::MatrixXd& P, double accel_var,
                             int n) {
  const Eigen::MatrixXd F = TransitionMatrix(in, n);
  Eigen::MatrixXd Pp = F * P * F.transpose();
  Pp.topLeftCorner<6, 6>() += ProcessNoise(in, accel_var);
  return 0.5 * (Pp + Pp.transpose());
}

struct PassResult {
  std::vector<EpochStore> store;
  std::vector<FilterSeriesRow> series;
  Vec6 innovation_ss = Vec6::Zero();
  double nis_sum = 0.0;
};

PassResult ForwardPass(const Context& c, const Eigen::VectorXd* theta_lin, bool keep_series,
                       const std::function<void(double)>& progress) {
  const int n = c.n, N = 6 + n;
  PassResult out;
  out.store.reserve(c.epochs.size());
  Eigen::VectorXd x(N);
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(N, N);
  x.tail(n) = c.prior.mean;
  P.bottomRightCorner(n, n) = c.prior.sigma.array().square().matrix().asDiagonal();
  {
    const ReferenceSample r0 = EvaluateReference(
        c.cfg, theta_lin ? *theta_lin : c.prior.mean, c.series.recorded[c.epochs[0]], false);
    x.head<3>() = r0.v_mps;
    x.segment<3>(3) = r0.p_m;
    P.topLeftCorner<3, 3>() = 0.01 * Eigen::Matrix3d::Identity();   // 0.1 m/s
    P.block<3, 3>(3, 3) = 0.01 * Eigen::Matrix3d::Identity();       // 0.1 m
  }
  const std::size_t E = c.epochs.size();
  std::size_t next_report = 0;
  for (std::size_t e = 0; e < E; ++e) {
    EpochStore st;
    if (e > 0) {
      const Eigen::VectorXd th_l = theta_lin ? *theta_lin : Eigen::VectorXd(x.tail(n));
      const IntervalIncrement inc =
          IntegrateInterval(c.cfg, th_l, c.series, c.epochs[e - 1], c.epochs[e], true);
      Interval& in = st.in;
      in.T = inc.T_s;
      in.dv = inc.dv_mps;
      in.ds = inc.ds_m;
      in.Jv = inc.ddv_dtheta;
      in.Js = inc.dds_dtheta;
      in.qa2 = inc.sum_alpha2;
      in.qab = inc.sum_alpha_beta;
      in.qb2 = inc.sum_beta2;
      if (theta_lin) in.theta_lin = *theta_lin;
      x = Propagate(in, x, n);
      P = PropagateCov(in, P, c.accel_var, n);
    }
    // Measurement update with z_V, z_S (block B2).
    const std::size_t k = c.epochs[e];
    const Eigen::VectorXd th_l = theta_lin ? *theta_lin : Eigen::VectorXd(x.tail(n));
    const ReferenceSample ref = EvaluateReference(c.cfg, th_l, c.series.recorded[k], true);
    const Eigen::VectorXd dth = x.tail(n) - th_l;
    Vec6 h;
    h.head<3>() = x.head<3>() - (ref.v_mps + ref.dref_dtheta.topRows(3) * dth);
    h.tail<3>() = x.segment<3>(3) - (ref.p_m + ref.dref_dtheta.bottomRows(3) * dth);
    Eigen::MatrixXd H(6, N);
    H.leftCols(6).setIdentity();
    H.rightCols(n) = -ref.dref_dtheta;
    const Mat6 R =
        ReferenceNoiseCovariance(c.cfg, th_l, c.series.recorded[k], c.sigma_angle, c.sigma_rate);
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
      for (const ConstraintRow& cr : c.constraints) {
        Eigen::VectorXd hrow = Eigen::VectorXd::Zero(N);
        hrow.tail(n) = cr.c;
        const Eigen::VectorXd Ph = P * hrow;
        const double s = hrow.dot(Ph) + cr.sigma * cr.sigma;
        const double innov = cr.value - cr.c.dot(x.tail(n));
        x += Ph * (innov / s);
        P -= Ph * Ph.transpose() / s;
        P = 0.5 * (P + P.transpose());
      }
    }
    if (keep_series) {
      FilterSeriesRow row;
      row.t_s = c.series.run->t_s[k];
      row.theta = x.tail(n);
      row.sigma = P.diagonal().tail(n).cwiseMax(0.0).cwiseSqrt();
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

// Fixed-interval RTS smoother; returns the smoothed state and covariance at
// the first epoch.
Estimate Smooth(const Context& c, const PassResult& pass) {
  const int n = c.n, N = 6 + n;
  const std::size_t E = pass.store.size();
  Eigen::VectorXd xs = pass.store[E - 1].x;
  Eigen::MatrixXd Ps = Unpack(pass.store[E - 1].P_upper, N);
  for (std::size_t e = E - 1; e-- > 0;) {
    const EpochStore& cur = pass.store[e];
    const Interval& in = pass.store[e + 1].in;
    const Eigen::MatrixXd Pf = Unpack(cur.P_upper, N);
    const Eigen::MatrixXd F = TransitionMatrix(in, n);
    const Eigen::VectorXd x_pred = Propagate(in, cur.x, n);
    const Eigen::MatrixXd P_pred = PropagateCov(in, Pf, c.accel_var, n);
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
  return Estimate{xs.tail(n), Ps.bottomRightCorner(n, n)};
}

}  // namespace

FilterResult RunFilterSmoother(const RunDescription& run, const RunData& data,
                               const ParameterLayout& layout, const FilterOptions& options) {
  RunProblem c = BuildRunProblem(run, data, layout, options.epoch_s, options.derivatives);
  // The covariance form of the filter spans the prior (degrees, tens of mV)
  // down to what the data pin (um/s): with almost noise-free data that range
  // exceeds double precision and P stops being positive definite. A floor of
  // 50 ug per sample on the process noise keeps it well conditioned; real
  // MEMS noise is far above it, and the batch solver has no such floor.
  const double floor_mps2 = 50e-6 * run.g_mps2;
  c.accel_var = std::max(c.accel_var, floor_mps2 * floor_mps2);
  FilterResult res;
  res.prior = c.prior;
  res.epochs = static_cast<int>(c.epochs.size());
  res.rate_noise_rad_s = c.sigma_rate;
  const int passes = std::max(1, options.smoother_iterations);
  Eigen::VectorXd theta_lin;
  for (int p = 0; p < passes; ++p) {
    auto prog = [&](double f) {
      if (options.progress) options.progress(p + 1, f);
    };
    PassResult pass = ForwardPass(c, p == 0 ? nullptr : &theta_lin,
                                  options.keep_series && p == 0, prog);
    if (p == 0) {
      const int N = 6 + c.n;
      const Eigen::MatrixXd P_end = Unpack(pass.store.back().P_upper, N);
      res.ekf = Estimate{pass.store.back().x.tail(c.n), P_end.bottomRightCorner(c.n, c.n)};
      res.series = std::move(pass.series);
    }
    res.rts = Smooth(c, pass);
    theta_lin = res.rts.theta;
    const double E = static_cast<double>(pass.store.size());
    res.innovation_rms = (pass.innovation_ss / E).cwiseSqrt();
    res.mean_nis = pass.nis_sum / E;
    res.passes = p + 1;
  }
  return res;
}

}  // namespace triadcal
