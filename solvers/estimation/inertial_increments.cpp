#include "solvers/estimation/inertial_increments.h"

#include <ceres/jet.h>

#include "core/model/b1_jacobian.h"
#include "core/model/sparse_jets.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace triadcal {

namespace {

BenchAngles<double> WithoutDerivatives(const RunData& run, std::size_t k) {
  BenchAngles<double> b;
  for (int i = 0; i < 2; ++i) b.axis[i] = AxisState<double>{run.lambda_rad[i][k], 0.0, 0.0};
  return b;
}

}  // namespace

Eigen::Vector3d SampleSeries::PredictedReadings_mV(const ModelConfig& cfg, const double* theta,
                                                  const BenchAngles<double>& recorded,
                                                  const SampleContext& ctx, bool at_rest) {
  BenchAngles<double> b = recorded;
  if (at_rest) {
    for (AxisState<double>& a : b.axis) a.rate = a.accel = 0.0;
  }
  return PredictReadings_mV<double>(cfg, theta, BenchAnglesFromRecorded<double>(cfg, theta, b),
                                    ctx);
}

BenchAngles<double> SampleSeries::Recorded(std::size_t k) const {
  if (at.empty()) return (*derivatives)[k];
  const auto it = std::lower_bound(at.begin(), at.end(), k);
  if (it != at.end() && *it == k) return (*derivatives)[it - at.begin()];
  return WithoutDerivatives(*run, k);
}

SampleSeries::Walk::Walk(const SampleSeries& s, std::size_t k0)
    : s_(s), k_(k0), j_(std::lower_bound(s.at.begin(), s.at.end(), k0) - s.at.begin()) {}

BenchAngles<double> SampleSeries::Walk::Next() {
  const std::size_t k = k_++;
  if (s_.at.empty()) return (*s_.derivatives)[k];
  if (j_ < s_.at.size() && s_.at[j_] == k) return (*s_.derivatives)[j_++];
  return WithoutDerivatives(*s_.run, k);
}

namespace {

template <int N>
void AccumulateWithJacobian(const ModelConfig& cfg, const Eigen::VectorXd& theta,
                            const SampleSeries& s, std::size_t k0, std::size_t k1,
                            const std::vector<double>& alpha, const std::vector<double>& beta,
                            IntervalIncrement* inc) {
  using J = ceres::Jet<double, N>;
  const int n = static_cast<int>(theta.size());
  std::vector<J> th(N);
  for (int i = 0; i < N; ++i) th[i] = J(i < n ? theta[i] : 0.0, i);
  Eigen::Matrix<double, 3, N> dv = Eigen::Matrix<double, 3, N>::Zero();
  Eigen::Matrix<double, 3, N> ds = Eigen::Matrix<double, 3, N>::Zero();
  const RunData& run = *s.run;
  SampleSeries::Walk recorded(s, k0);
  for (std::size_t k = k0; k <= k1; ++k) {
    const SampleContext ctx{run.t_s[k], run.has_temp() ? run.temp_C[k] : 0.0};
    const BenchAngles<double> rec = recorded.Next();
    const Vec3<J> a = AccelerationFromReadings_L<J>(
        cfg, th.data(), rec, s.Readings_mV(cfg, theta.data(), k, rec, ctx), ctx);
    const double wa = alpha[k - k0], wb = beta[k - k0];
    for (int r = 0; r < 3; ++r) {
      inc->dv_mps[r] += wa * a[r].a;
      inc->ds_m[r] += wb * a[r].a;
      dv.row(r) += wa * a[r].v.transpose();
      ds.row(r) += wb * a[r].v.transpose();
    }
  }
  inc->ddv_dtheta = dv.leftCols(n);
  inc->dds_dtheta = ds.leftCols(n);
}

}  // namespace

IntervalIncrement IntegrateInterval(const ModelConfig& cfg, const Eigen::VectorXd& theta,
                                    const SampleSeries& s, std::size_t k0, std::size_t k1,
                                    bool with_jacobian, bool with_noise, bool with_values) {
  if (!with_values && with_jacobian) {
    throw std::logic_error("IntegrateInterval: a Jacobian needs the values");
  }
  const RunData& run = *s.run;
  IntervalIncrement inc;
  const std::size_t m = k1 - k0;
  const double t_b = run.t_s[k1];
  inc.T_s = t_b - run.t_s[k0];
  std::vector<double> alpha(m + 1, 0.0), beta(m + 1, 0.0);
  for (std::size_t j = 0; j < m; ++j) {  // step from sample k0+j to k0+j+1
    const double dt = run.t_s[k0 + j + 1] - run.t_s[k0 + j];
    const double remain = t_b - run.t_s[k0 + j + 1];
    alpha[j] += 0.5 * dt;
    alpha[j + 1] += 0.5 * dt;
    beta[j] += 0.5 * dt * remain + dt * dt / 3.0;
    beta[j + 1] += 0.5 * dt * remain + dt * dt / 6.0;
  }
  for (Eigen::Matrix<double, 6, 6>& w : inc.channel_weight) w.setZero();
  SampleSeries::Walk recorded_for_noise(s, k0);
  for (std::size_t j = 0; j <= m && with_noise; ++j) {
    const double a2 = alpha[j] * alpha[j], ab = alpha[j] * beta[j], b2 = beta[j] * beta[j];
    inc.sum_alpha2 += a2;
    inc.sum_alpha_beta += ab;
    inc.sum_beta2 += b2;
    const BenchAngles<double> b =
        BenchAnglesFromRecorded<double>(cfg, theta.data(), recorded_for_noise.Next());
    const Eigen::Matrix3d C_L2 = ComputeBenchMotion<double>(cfg, theta.data(), b).C_L2;
    if (j == 0 || j == m) {
      (j == 0 ? inc.first_weight : inc.last_weight) << alpha[j], beta[j];
      for (int i = 0; i < 3; ++i) {
        Eigen::Matrix<double, 6, 1>& w = (j == 0 ? inc.first_channel : inc.last_channel)[i];
        w << alpha[j] * C_L2.col(i), beta[j] * C_L2.col(i);
      }
    }
    for (int i = 0; i < 3; ++i) {
      const Eigen::Matrix3d cc = C_L2.col(i) * C_L2.col(i).transpose();
      Eigen::Matrix<double, 6, 6>& w = inc.channel_weight[i];
      w.topLeftCorner<3, 3>() += a2 * cc;
      w.topRightCorner<3, 3>() += ab * cc;
      w.bottomRightCorner<3, 3>() += b2 * cc;
    }
  }
  for (Eigen::Matrix<double, 6, 6>& w : inc.channel_weight) {
    w.bottomLeftCorner<3, 3>() = w.topRightCorner<3, 3>().transpose();
  }
  if (!with_values) return inc;
  const int n = static_cast<int>(theta.size());
  SampleSeries::Walk recorded(s, k0);
  if (!with_jacobian) {
    for (std::size_t k = k0; k <= k1; ++k) {
      const SampleContext ctx{run.t_s[k], run.has_temp() ? run.temp_C[k] : 0.0};
      const BenchAngles<double> rec = recorded.Next();
      const Vec3<double> a = AccelerationFromReadings_L<double>(
          cfg, theta.data(), rec, s.Readings_mV(cfg, theta.data(), k, rec, ctx), ctx);
      inc.dv_mps += alpha[k - k0] * a;
      inc.ds_m += beta[k - k0] * a;
    }
    return inc;
  }
  if (B1HasAnalyticJacobian(cfg.layout)) {
    inc.ddv_dtheta = Eigen::MatrixXd::Zero(3, n);
    inc.dds_dtheta = Eigen::MatrixXd::Zero(3, n);
    Eigen::MatrixXd Jk(3, n);
    Eigen::Vector3d a;
    for (std::size_t k = k0; k <= k1; ++k) {
      const SampleContext ctx{run.t_s[k], run.has_temp() ? run.temp_C[k] : 0.0};
      const BenchAngles<double> rec = recorded.Next();
      AccelerationWithJacobian(cfg, theta.data(), rec, s.Readings_mV(cfg, theta.data(), k, rec, ctx),
                               ctx, &a, Jk);
      inc.dv_mps += alpha[k - k0] * a;
      inc.ds_m += beta[k - k0] * a;
      inc.ddv_dtheta += alpha[k - k0] * Jk;
      inc.dds_dtheta += beta[k - k0] * Jk;
    }
    return inc;
  }
  if (n <= 32) {
    AccumulateWithJacobian<32>(cfg, theta, s, k0, k1, alpha, beta, &inc);
  } else if (n <= 48) {
    AccumulateWithJacobian<48>(cfg, theta, s, k0, k1, alpha, beta, &inc);
  } else if (n <= 64) {
    AccumulateWithJacobian<64>(cfg, theta, s, k0, k1, alpha, beta, &inc);
  } else {
    throw std::invalid_argument("more than 64 parameters are not supported");
  }
  return inc;
}

double IsotropicSampleVariance(double angle_noise_rad, double g_mps2) {
  const double s_angle = g_mps2 * angle_noise_rad;
  const double floor = 1e-6;  // m/s^2: keeps noise-free runs well posed
  return s_angle * s_angle + floor * floor;
}

namespace {

// The reference motion reads dpsi, dtheta_c, dlambda2, the lever arm, d,
// eps and the angle stage's parameters (ReferenceMotion): Jets over those
// alone, where its Jacobian is not written out (ReferenceMotionWithJacobian).
constexpr int kReferenceJet = 6 + 2 + 7;

ReferenceSample ReferenceWithJacobian(const ModelConfig& cfg, const Eigen::VectorXd& theta,
                                      const BenchAngles<double>& rec) {
  using J = ceres::Jet<double, kReferenceJet>;
  const ParameterLayout& layout = cfg.layout;
  const int n = static_cast<int>(theta.size());
  if (n > 64) throw std::invalid_argument("more than 64 parameters are not supported");
  std::vector<int> idx = {kDpsi, kDthetaC, kDlambda2, kDx2, kDy2, kDz2};
  for (Effect e : {Effect::kAxisNonintersection, Effect::kAxisNonperpendicularity}) {
    if (layout.offset(e) >= 0) idx.push_back(layout.offset(e));
  }
  for (int i : layout.StageParams(EffectStage::kAngle)) idx.push_back(i);
  if (static_cast<int>(idx.size()) > kReferenceJet) {
    throw std::logic_error(
        "EvaluateReference: more parameters reach the reference motion than its Jets hold");
  }
  const int count = static_cast<int>(idx.size());
  const SparseJets<J> th(theta.data(), idx.data(), count, count);
  const PointMotion<J> pm = ReferenceMotion<J>(cfg, th.data(), rec);
  ReferenceSample out;
  out.dref_dtheta = Eigen::MatrixXd::Zero(6, n);
  for (int r = 0; r < 3; ++r) {
    out.v_mps[r] = pm.v_L[r].a;
    out.p_m[r] = pm.p_L[r].a;
    for (int q = 0; q < count; ++q) {
      out.dref_dtheta(r, idx[q]) = pm.v_L[r].v[q];
      out.dref_dtheta(3 + r, idx[q]) = pm.p_L[r].v[q];
    }
  }
  return out;
}

}  // namespace

ReferenceSample EvaluateReference(const ModelConfig& cfg, const Eigen::VectorXd& theta,
                                  const BenchAngles<double>& rec, bool with_jacobian) {
  if (!with_jacobian) {
    const PointMotion<double> pm = ReferenceMotion<double>(cfg, theta.data(), rec);
    return ReferenceSample{pm.v_L, pm.p_L, Eigen::MatrixXd()};
  }
  if (B1HasAnalyticJacobian(cfg.layout)) {
    ReferenceSample out;
    out.dref_dtheta.resize(6, theta.size());
    ReferenceMotionWithJacobian(cfg, theta.data(), rec, &out.v_mps, &out.p_m, out.dref_dtheta);
    return out;
  }
  return ReferenceWithJacobian(cfg, theta, rec);
}

Eigen::Matrix<double, 6, 6> ReferenceNoiseCovariance(const ModelConfig& cfg,
                                                     const Eigen::VectorXd& theta,
                                                     const BenchAngles<double>& rec,
                                                     double sigma_angle_rad,
                                                     double sigma_rate_rad_s) {
  Eigen::Matrix<double, 6, 4> J;
  auto eval = [&](const BenchAngles<double>& b) {
    const PointMotion<double> pm = ReferenceMotion<double>(cfg, theta.data(), b);
    Eigen::Matrix<double, 6, 1> y;
    y << pm.v_L, pm.p_L;
    return y;
  };
  for (int c = 0; c < 4; ++c) {
    const int axis = c % 2;
    const bool rate = c >= 2;
    const double h = 1e-6;
    BenchAngles<double> bp = rec, bm = rec;
    (rate ? bp.axis[axis].rate : bp.axis[axis].angle) += h;
    (rate ? bm.axis[axis].rate : bm.axis[axis].angle) -= h;
    J.col(c) = (eval(bp) - eval(bm)) / (2 * h);
  }
  Eigen::Vector4d var;
  var << sigma_angle_rad * sigma_angle_rad, sigma_angle_rad * sigma_angle_rad,
      sigma_rate_rad_s * sigma_rate_rad_s, sigma_rate_rad_s * sigma_rate_rad_s;
  Eigen::Matrix<double, 6, 6> R = J * var.asDiagonal() * J.transpose();
  // Floor: 1 um and 1 um/s keep a noise-free run's update well posed.
  R.diagonal().array() += 1e-12;
  return R;
}

}  // namespace triadcal
