#include "solvers/estimation/gyro_term.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include <ceres/jet.h>

#include "core/model/b1_jacobian.h"
#include "core/model/gyro_model.h"
#include "solvers/estimation/parallel.h"

namespace triadcal {
namespace {

using Mat3d = Eigen::Matrix3d;
using Vec3d = Eigen::Vector3d;

// The columns the gyro residual depends on: the gyro block, then dlambda2.
constexpr int kLocal = kNumGyroParams + 1;
constexpr int kLocalDlambda2 = kNumGyroParams;

// Which entry of Mg each misalignment angle sits at, with its sign
// (gyro_model.h): alpha_x, alpha_y, beta_x, beta_z, gamma_y, gamma_z.
struct AngleEntry {
  int row, col;
  double sign;
};
constexpr AngleEntry kAngleEntries[6] = {{1, 0, 1.0},  {0, 1, -1.0}, {2, 0, -1.0},
                                         {0, 2, 1.0},  {2, 1, 1.0},  {1, 2, -1.0}};

// The angle stage's parameters (latency, encoder harmonic, angle scale: at
// most 1 + 4 + 2) as Jets.
constexpr int kAngleJet = 8;
using AngleJet = ceres::Jet<double, kAngleJet>;

// The readings model's parameters: the base sensor block and the sensor-stage effects'.
std::vector<int> SensorStageIndices(const ParameterLayout& layout) {
  std::vector<int> idx;
  for (int i = kKx; i <= kKzz; ++i) idx.push_back(i);
  for (int i : layout.StageParams(EffectStage::kSensor)) idx.push_back(i);
  return idx;
}

// The bench angles at sample k (angle stage undone) and their derivatives by
// the angle stage's parameters idx: angle[axis] and d angle[axis] / d theta_idx.
struct BenchAngleSample {
  double angle[2];
  Eigen::Matrix<double, 2, kAngleJet> d = Eigen::Matrix<double, 2, kAngleJet>::Zero();
};

BenchAngleSample BenchAnglesAt(const ModelConfig& cfg, const std::vector<AngleJet>& th,
                               const std::vector<int>& idx, const BenchAngles<double>& rec) {
  BenchAngleSample out;
  if (idx.empty()) {
    for (int a = 0; a < 2; ++a) out.angle[a] = rec.axis[a].angle;
    return out;
  }
  const BenchAngles<AngleJet> b = BenchAnglesFromRecorded<AngleJet>(cfg, th.data(), rec);
  for (int a = 0; a < 2; ++a) {
    out.angle[a] = b.axis[a].angle.a;
    out.d.row(a) = b.axis[a].angle.v.transpose();
  }
  return out;
}

// The trapezoid weight of sample k in the interval k0..k1 [s].
double TrapezoidWeight(const RunData& d, std::size_t k0, std::size_t k1, std::size_t k) {
  double w = 0.0;
  if (k > k0) w += 0.5 * (d.t_s[k] - d.t_s[k - 1]);
  if (k < k1) w += 0.5 * (d.t_s[k + 1] - d.t_s[k]);
  return w;
}

// Moments w^2 {1, c, s, c^2, s^2, cs} of the noise's rotation at sample k.
void AddMoments(const RunData& d, std::size_t k, double w2, std::array<double, 6>* m) {
  const double c = std::cos(d.lambda_rad[1][k]), s = std::sin(d.lambda_rad[1][k]);
  (*m)[0] += w2;
  (*m)[1] += w2 * c;
  (*m)[2] += w2 * s;
  (*m)[3] += w2 * c * c;
  (*m)[4] += w2 * s * s;
  (*m)[5] += w2 * c * s;
}

// sum w^2 (P u)(P u)^T, P = Rx(l2), from the moments.
Mat3d WeightOf(const std::array<double, 6>& m, const Vec3d& u) {
  const double x = u.x(), a = u.y(), b = u.z();
  Mat3d W;
  W(0, 0) = x * x * m[0];
  W(0, 1) = W(1, 0) = x * (a * m[1] - b * m[2]);
  W(0, 2) = W(2, 0) = x * (a * m[2] + b * m[1]);
  W(1, 1) = a * a * m[3] - 2.0 * a * b * m[5] + b * b * m[4];
  W(2, 2) = a * a * m[4] + 2.0 * a * b * m[5] + b * b * m[3];
  W(1, 2) = W(2, 1) = a * a * m[5] + a * b * (m[3] - m[4]) - b * b * m[5];
  return W;
}

// M(X) = sum w^2 P^T X P from the moments (P = Rx(l2)): tr(X W(u)) =
// u^T M(X) u, and x^T W(u) y = u^T M(x y^T) u.
Mat3d MomentForm(const std::array<double, 6>& m, const Mat3d& X) {
  Mat3d M;
  const double x12 = X(1, 2) + X(2, 1);
  M(0, 0) = m[0] * X(0, 0);
  M(0, 1) = m[1] * X(0, 1) + m[2] * X(0, 2);
  M(0, 2) = m[1] * X(0, 2) - m[2] * X(0, 1);
  M(1, 0) = m[1] * X(1, 0) + m[2] * X(2, 0);
  M(2, 0) = m[1] * X(2, 0) - m[2] * X(1, 0);
  M(1, 1) = m[3] * X(1, 1) + m[5] * x12 + m[4] * X(2, 2);
  M(2, 2) = m[4] * X(1, 1) - m[5] * x12 + m[3] * X(2, 2);
  M(1, 2) = -m[5] * X(1, 1) + m[3] * X(1, 2) - m[4] * X(2, 1) + m[5] * X(2, 2);
  M(2, 1) = -m[5] * X(1, 1) - m[4] * X(1, 2) + m[3] * X(2, 1) + m[5] * X(2, 2);
  return M;
}

// W(u_i) of each channel, u_i = Mg^-1 e_i (the columns of U).
std::array<Mat3d, 3> ChannelWeights(const std::array<double, 6>& m, const Mat3d& U) {
  return {WeightOf(m, U.col(0)), WeightOf(m, U.col(1)), WeightOf(m, U.col(2))};
}

// The channels' covariance sum_i v_i W(u_i).
Mat3d Combine(const std::array<Mat3d, 3>& w, const Vec3d& v) {
  Mat3d W = Mat3d::Zero();
  for (int i = 0; i < 3; ++i) W += v[i] * w[i];
  return W;
}

Mat3d ChannelCovariance(const std::array<double, 6>& m, const Vec3d& v, const Mat3d& U) {
  return Combine(ChannelWeights(m, U), v);
}

// chol(S)^-1 of a symmetric positive definite 3 x 3 S (lower triangular),
// and 0.5 log det S. Not positive definite: NaN (the cost then is not finite,
// and a fit refuses the step).
Mat3d InverseCholesky3(const Mat3d& S, double* half_log_det) {
  const double l00 = std::sqrt(S(0, 0));
  const double l10 = S(1, 0) / l00, l20 = S(2, 0) / l00;
  const double l11 = std::sqrt(S(1, 1) - l10 * l10);
  const double l21 = (S(2, 1) - l20 * l10) / l11;
  const double l22 = std::sqrt(S(2, 2) - l20 * l20 - l21 * l21);
  Mat3d X = Mat3d::Zero();
  X(0, 0) = 1.0 / l00;
  X(1, 1) = 1.0 / l11;
  X(2, 2) = 1.0 / l22;
  X(1, 0) = -l10 * X(0, 0) * X(1, 1);
  X(2, 1) = -l21 * X(1, 1) * X(2, 2);
  X(2, 0) = -(l20 * X(0, 0) + l21 * X(1, 0)) * X(2, 2);
  *half_log_det = std::log(l00 * l11 * l22);
  return X;
}

// The angle noise of the recorded angles in the residual (inner, outer).
Mat3d AngleCovariance(double angle_var) {
  Mat3d R3 = Mat3d::Zero();
  R3(0, 0) = R3(1, 1) = angle_var;
  return R3;
}

}  // namespace

bool RunHasGyro(const RunProblem& p) {
  return p.cfg.layout.has_gyro() && p.series.run && p.series.run->has_gyro() &&
         p.gyro_epochs.size() >= 3;
}

GyroPass EvaluateGyroPass(const RunProblem& p, const Eigen::VectorXd& theta, bool with_jacobian,
                          int threads, std::size_t first, std::size_t count) {
  if (!RunHasGyro(p)) throw std::logic_error("EvaluateGyroPass: the run has no gyro");
  const RunData& d = *p.series.run;
  const ModelConfig& cfg = p.cfg;
  const int go = cfg.layout.gyro_offset();
  const int n = static_cast<int>(theta.size());
  const double* th = theta.data();
  const double* g = th + go;
  const std::vector<std::size_t>& epochs = p.gyro_epochs;
  const std::size_t E = epochs.size();
  if (first >= E - 1) throw std::logic_error("EvaluateGyroPass: no such interval");
  const std::size_t count_in = std::min(count, E - 1 - first);

  const Mat3d Mg_inv = GyroMisalignmentMatrix(g).inverse();
  const Mat3d Gs = GyroGSensitivity(g);
  const bool earth = !cfg.earth_rate_L.isZero();
  // The gyro-stage effects (gyro_model.h): their first indices, or -1.
  const int o_a = cfg.layout.offset(Effect::kGyroScaleAsymmetry);
  const int o_q = cfg.layout.offset(Effect::kGyroNonlinearity);
  const bool gyro_fx = o_a >= 0 || o_q >= 0;

  GyroPass pass;
  pass.theta = theta;
  pass.with_jacobian = with_jacobian;
  pass.first_interval = first;
  pass.angle_var = p.sigma_angle * p.sigma_angle;
  for (int i = 0; i < 3; ++i) {
    pass.K[i] = g[kGKx + i];
    pass.K_ref[i] = p.prior.mean[go + kGKx + i];
  }
  if (with_jacobian) pass.J_info.resize(count_in);
  // The bench's angle rates for the information's K columns, by central
  // differences over about +-0.05 s.
  const double dt_mean = (d.t_s.back() - d.t_s.front()) / std::max<std::size_t>(1, d.size() - 1);
  const std::size_t half = std::max<std::size_t>(1, static_cast<std::size_t>(0.05 / dt_mean));
  auto angle_rate = [&](int axis, std::size_t k) {
    const std::size_t a = k >= half ? k - half : 0, b = std::min(d.size() - 1, k + half);
    return (d.lambda_rad[axis][b] - d.lambda_rad[axis][a]) / (d.t_s[b] - d.t_s[a]);
  };
  // The recorded angles' second derivative at sample k, by the three-point
  // formula over +-0.2 s (0 where the run's ends cut the window). Over
  // +-0.05 s the encoder's 0.088-deg steps and the time stamps' jitter of the
  // real roll runs made it move the shaft's scale by 3e-4 at both speeds;
  // over +-0.2 s by 4e-5 (slow) and 1.7e-4 (medium), as the swing's speed
  // says; a sine swinging at 3 rad/s loses 3 % of its amplitude.
  const std::size_t wide = std::max<std::size_t>(1, static_cast<std::size_t>(0.2 / dt_mean));
  auto angle_accel = [&](int axis, std::size_t k) {
    if (k < wide || k + wide >= d.size()) return 0.0;
    const std::size_t a = k - wide, b = k + wide;
    const std::vector<double>& l = d.lambda_rad[axis];
    return 2.0 *
           ((l[b] - l[k]) / (d.t_s[b] - d.t_s[k]) - (l[k] - l[a]) / (d.t_s[k] - d.t_s[a])) /
           (d.t_s[b] - d.t_s[a]);
  };
  const Mat3d Mg = GyroMisalignmentMatrix(g);
  pass.Mg_inv = Mg_inv;
  pass.Mg_inv_ref = GyroMisalignmentMatrix(p.prior.mean.data() + go).inverse();
  // The angle stage (shared with the accelerometer's residuals: a latency of
  // the angles is one time offset between the angles and both triads).
  const std::vector<int> angle_idx = cfg.layout.StageParams(EffectStage::kAngle);
  if (angle_idx.size() > kAngleJet) throw std::logic_error("EvaluateGyroPass: angle stage too large");
  const int na = static_cast<int>(angle_idx.size());
  std::vector<AngleJet> th_jet(n);
  for (int i = 0; i < n; ++i) th_jet[i] = AngleJet(th[i]);
  for (int q = 0; q < na; ++q) th_jet[angle_idx[q]].v[q] = 1.0;
  // W's derivatives by the accelerometer's sensor-stage parameters (the
  // readings model: W of the g-sensitivity depends on them).
  const std::vector<int> sensor_idx = SensorStageIndices(cfg.layout);
  const int ns = static_cast<int>(sensor_idx.size());
  auto bench_at = [&](std::size_t k) {
    return BenchAnglesAt(cfg, th_jet, angle_idx, p.series.Recorded(k));
  };
  pass.r.resize(count_in);
  pass.valid.assign(count_in, 1);
  pass.moments.assign(count_in, {0, 0, 0, 0, 0, 0});
  pass.cross_moments.assign(count_in, {0, 0, 0, 0, 0, 0});
  if (with_jacobian) pass.J.resize(count_in);

  ParallelFor(count_in, threads, [&](std::size_t i) {
    const std::size_t e = first + i;  // the run's interval
    const std::size_t k0 = epochs[e], k1 = epochs[e + 1];
    if (!d.gyro_clipped.empty()) {
      for (std::size_t k = k0; k <= k1; ++k) {
        if (d.gyro_clipped[k]) pass.valid[i] = 0;
      }
    }
    Vec3d r = Vec3d::Zero();
    Eigen::Matrix<double, 3, kLocal> Jl = Eigen::Matrix<double, 3, kLocal>::Zero();
    Eigen::Matrix<double, 3, 9> JI = Eigen::Matrix<double, 3, 9>::Zero();
    Eigen::Matrix<double, 3, kAngleJet> Ja = Eigen::Matrix<double, 3, kAngleJet>::Zero();
    Eigen::Matrix<double, 3, Eigen::Dynamic> Js = Eigen::MatrixXd::Zero(3, ns);
    Eigen::Matrix<double, 3, Eigen::Dynamic> dW_all(3, with_jacobian ? n : 0);
    Eigen::Matrix<double, 3, Eigen::Dynamic> dW(3, ns);
    Eigen::Matrix<double, 3, 6> Je = Eigen::Matrix<double, 3, 6>::Zero();  // dK, k2 columns
    std::array<double, 6> mom = {0, 0, 0, 0, 0, 0};
    SampleSeries::Walk recorded(p.series, k0);
    for (std::size_t k = k0; k <= k1; ++k) {
      const BenchAngles<double> rec = recorded.Next();
      const BenchAngleSample b = BenchAnglesAt(cfg, th_jet, angle_idx, rec);
      const double w = TrapezoidWeight(d, k0, k1, k);
      const SampleContext ctx{d.t_s[k], d.has_temp() ? d.temp_C[k] : 0.0};
      // The specific force at O from the accelerometers, at theta (the
      // readings the model predicts where the series says so).
      const Eigen::Vector3d z = p.series.Readings_mV(cfg, th, k, rec, ctx);
      Vec3d W;
      if (with_jacobian) {
        SpecificForceWithJacobian(cfg, th, z, ctx, &W, dW_all);
        for (int q = 0; q < ns; ++q) dW.col(q) = dW_all.col(sensor_idx[q]);
      } else {
        W = SpecificForceFromReadings_g<double>(cfg, th, z, ctx);
      }
      const Vec3d y = d.gyro(k) - Vec3d(g[kGW0x], g[kGW0y], g[kGW0z]) - Gs * W;
      // m = f^-1(y) per axis (gyro_model.h; m = y / K without gyro effects) and
      // f'(m), which takes K's place in the derivatives.
      Vec3d m_axes, slope = Vec3d(g[kGKx], g[kGKy], g[kGKz]);
      if (gyro_fx) {
        for (int i = 0; i < 3; ++i) {
          const GyroAxisResponse<double> ax = GyroAxis(cfg.layout, th, i);
          m_axes[i] = GyroAxisRate(ax, y[i]);
          slope[i] = ax.K * (1.0 + 3.0 * ax.k2 * m_axes[i] * m_axes[i]) +
                     (m_axes[i] < 0.0 ? -ax.dK : ax.dK);
        }
      } else {
        m_axes = y.cwiseQuotient(slope);
      }
      Vec3d rate = Mg_inv * m_axes;
      if (earth) {
        const double l1 = d.lambda_rad[0][k] + th[kDthetaC];
        const double l2 = d.lambda_rad[1][k] + th[kDlambda2];
        const Mat3d C_L2 = Rz<double>(th[kDpsi]) * Ry<double>(l1) * Rx<double>(l2);
        rate -= C_L2.transpose() * cfg.earth_rate_L;
      }
      const Mat3d P = Rx<double>(b.angle[1] + th[kDlambda2]);
      r += w * (P * rate);
      AddMoments(d, k, w * w, &mom);
      if (!with_jacobian) continue;
      const Mat3d PM = w * P * Mg_inv;
      const Mat3d PA = PM * slope.cwiseInverse().asDiagonal();  // w P Mg^-1 diag(f')^-1
      Js.noalias() -= (PA * Gs) * dW;
      for (int i = 0; i < 3; ++i) {
        // dm_i / d p = -(df_i / d p) / f'_i for p = K_i, dK_i, k2_i.
        const double mi = m_axes[i];
        Jl.col(kGW0x + i) -= PA.col(i);
        Jl.col(kGKx + i) -= PA.col(i) * (mi * (1.0 + (o_q >= 0 ? th[o_q + i] * mi * mi : 0.0)));
        if (o_a >= 0) Je.col(i) -= PA.col(i) * std::abs(mi);
        if (o_q >= 0) Je.col(3 + i) -= PA.col(i) * (g[kGKx + i] * mi * mi * mi);
        for (int j = 0; j < 3; ++j) Jl.col(kGGxx + 3 * i + j) -= PA.col(i) * W[j];
      }
      const Vec3d w_dps = Mg_inv * m_axes;  // the gyro's rate before Earth's is taken off
      for (int a = 0; a < 6; ++a) {
        const AngleEntry& en = kAngleEntries[a];
        Jl.col(kGAlphaX + a) -= PM.col(en.row) * (en.sign * w_dps[en.col]);
      }
      const Vec3d turn = w * P * Vec3d::UnitX().cross(rate);  // d / d(inner angle)
      Jl.col(kLocalDlambda2) += turn;
      if (na > 0) Ja += turn * b.d.row(1);
      const double l1_rate = angle_rate(0, k), l2_rate = angle_rate(1, k);
      Vec3d w_bench = P.transpose() * Vec3d(0.0, l1_rate, 0.0);
      w_bench.x() += l2_rate;
      const Vec3d m_bench = Mg * w_bench;
      for (int i = 0; i < 3; ++i) JI.col(i) -= PM.col(i) * (m_bench[i] / g[kGKx + i]);
      for (int a = 0; a < 6; ++a) {
        const AngleEntry& en = kAngleEntries[a];
        JI.col(3 + a) -= PM.col(en.row) * (en.sign * w_bench[en.col]);
      }
    }
    const BenchAngleSample b0 = bench_at(k0), b1 = bench_at(k1);
    r -= Vec3d(b1.angle[1] - b0.angle[1], b1.angle[0] - b0.angle[0], 0.0);
    // The trapezoid's own error (Euler-Maclaurin): the rule gives the
    // integral of f = P rate = (l2', l1', 0) plus (h^2 / 12) (f'(b) - f'(a)),
    // a relative (h w)^2 / 12 of a rate swinging at w that the fit took into
    // the scale (50 Hz, the paper's amplitudes doubled and periods halved:
    // gyro.Kx biased by 6-7 sigma). Taken off with the recorded angles'
    // accelerations at the interval's ends.
    const double h = (d.t_s[k1] - d.t_s[k0]) / static_cast<double>(std::max<std::size_t>(1, k1 - k0));
    r -= (h * h / 12.0) * Vec3d(angle_accel(1, k1) - angle_accel(1, k0),
                                angle_accel(0, k1) - angle_accel(0, k0), 0.0);
    if (with_jacobian && na > 0) {
      Ja.row(0) -= b1.d.row(1) - b0.d.row(1);
      Ja.row(1) -= b1.d.row(0) - b0.d.row(0);
    }
    pass.r[i] = r;
    pass.moments[i] = mom;
    // The sample at epoch e+1 ends this interval and starts the next.
    if (e + 2 < E) {
      const double w_last = TrapezoidWeight(d, k0, k1, k1);
      const double w_first = TrapezoidWeight(d, k1, epochs[e + 2], k1);
      AddMoments(d, k1, w_last * w_first, &pass.cross_moments[i]);
    }
    if (with_jacobian) {
      Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, n);
      J.middleCols(go, kNumGyroParams) = Jl.leftCols(kNumGyroParams);
      J.col(kDlambda2) = Jl.col(kLocalDlambda2);
      for (int q = 0; q < na; ++q) J.col(angle_idx[q]) = Ja.col(q);
      for (int q = 0; q < ns; ++q) J.col(sensor_idx[q]) += Js.col(q);
      for (int i = 0; i < 3; ++i) {
        if (o_a >= 0) J.col(o_a + i) = Je.col(i);
        if (o_q >= 0) J.col(o_q + i) = Je.col(3 + i);
      }
      pass.J[i] = std::move(J);
      pass.J_info[i] = JI;
    }
  });
  pass.weights.resize(count_in);
  pass.cross_weights.resize(count_in);
  pass.weights_ref.resize(count_in);
  pass.cross_weights_ref.resize(count_in);
  ParallelFor(count_in, threads, [&](std::size_t i) {
    pass.weights[i] = ChannelWeights(pass.moments[i], pass.Mg_inv);
    pass.cross_weights[i] = ChannelWeights(pass.cross_moments[i], pass.Mg_inv);
    pass.weights_ref[i] = ChannelWeights(pass.moments[i], pass.Mg_inv_ref);
    pass.cross_weights_ref[i] = ChannelWeights(pass.cross_moments[i], pass.Mg_inv_ref);
  });
  return pass;
}

void GyroIncrementCovariance(const GyroPass& pass, std::size_t i,
                             const Eigen::Vector3d& noise_rad_s, Eigen::Matrix3d* own,
                             Eigen::Matrix3d* with_next) {
  // As ReduceGyro: channel i's noise sigma_i / K_i along P Mg^-1 e_i, the
  // angle noise at both ends (shared, with the opposite sign, with the next).
  const Vec3d var = noise_rad_s.cwiseQuotient(pass.K).cwiseAbs2();
  const Mat3d R3 = AngleCovariance(pass.angle_var);
  *own = 2.0 * R3 + Combine(pass.weights[i], var);
  *with_next = -R3 + Combine(pass.cross_weights[i], var);
}

GyroSummary SummariseGyro(const RunProblem& p, const GyroPass& pass, const GyroReduction& red) {
  const RunData& d = *p.series.run;
  GyroSummary s;
  s.present = true;
  s.noise_rad_s = red.noise_rad_s;
  s.degrees_of_freedom = red.degrees_of_freedom;
  s.neg_log_likelihood = red.neg_log_l;
  Vec3d ss = Vec3d::Zero();
  std::size_t used = 0;
  for (std::size_t i = 0; i < pass.r.size(); ++i) {
    if (!pass.valid[i]) continue;
    const std::size_t k = pass.first_interval + i;
    ss += pass.r[i].cwiseAbs2();
    ++used;
    s.mid_samples.push_back((p.gyro_epochs[k] + p.gyro_epochs[k + 1]) / 2);
    s.residual_rad.push_back(pass.r[i]);
    s.whitened.push_back(red.whitened[i]);
  }
  s.residual_rms_rad = (ss / std::max<std::size_t>(1, used)).cwiseSqrt();
  s.intervals = static_cast<int>(pass.r.size());
  // The mean interval as the samples fall (at 25 Hz a 0.1-s target gives 0.12 s).
  const std::vector<std::size_t>& ge = p.gyro_epochs;
  s.interval_s = ge.size() > 1 ? (d.t_s[ge.back()] - d.t_s[ge.front()]) /
                                     static_cast<double>(ge.size() - 1)
                               : 0.0;
  s.intervals_clipped = static_cast<int>(pass.r.size() - used);
  s.whitened_rms = std::sqrt(2.0 * red.cost / std::max(1, red.degrees_of_freedom));
  return s;
}

namespace {

// The derivatives of -log L by the noise weights, in the forms of
// MomentForm: channel i's part of Sigma is v_i W(u_i) (v_i = (sigma_i /
// K_i)^2, u_i = Mg^-1 e_i), so with w = Sigma^-1 r the cost's derivative is
// d cost = -0.5 w^T dSigma w = -0.5 sum_i d(v_i u_i^T F u_i) (F = cost: the
// sum of M(w_e w_e^T) and 2 M(w_e w_e+1^T), the shared sample's moments for
// the second), and the log-determinant's 0.5 d log det Sigma = 0.5 tr(Sigma^-1
// dSigma) = 0.5 sum_i d(v_i) u_i^T G u_i (G = log_det: the same of Sigma^-1's
// blocks on its band; of the reference's Sigma, at the reference's u_i).
struct WeightForms {
  bool with_log_det = false;
  Mat3d cost = Mat3d::Zero(), log_det = Mat3d::Zero();
};

// ReduceGyro; without with_log_det the cost alone is wanted: the
// log-determinant at the reference scale factors, a second elimination, is
// not formed, and neg_log_l is left NaN. forms (with the pass's own
// weights): the 3 x 3 forms the derivatives by the weights come from
// (WeightForms).
GyroReduction ReduceGyroOrCost(const GyroPass& pass, const Eigen::Vector3d& noise_rad_s,
                               double rho, bool theta_part, bool with_scores,
                               const Eigen::Matrix3d* mg_inv, bool with_log_det,
                               WeightForms* forms = nullptr) {
  const Mat3d& Mi = mg_inv ? *mg_inv : pass.Mg_inv;
  const std::size_t K = pass.r.size();
  const int n = static_cast<int>(pass.theta.size());
  const bool jac = theta_part && pass.with_jacobian;
  // Channel i's noise in the residual's units: sigma_i / K_i (above).
  const Vec3d var = noise_rad_s.cwiseQuotient(pass.K).cwiseAbs2();
  const Vec3d var_ref = noise_rad_s.cwiseQuotient(pass.K_ref).cwiseAbs2();
  const bool same_ref = (pass.K - pass.K_ref).cwiseAbs().maxCoeff() == 0.0 &&
                        (Mi - pass.Mg_inv_ref).cwiseAbs().maxCoeff() == 0.0;
  // The channels' covariance of interval k (own, or with the next: cross),
  // by the pass's weights unless other Mg^-1 are asked for.
  const bool own_weights = mg_inv == nullptr && pass.weights.size() == K;
  auto channels = [&](std::size_t k, bool cross, const Vec3d& v) {
    if (own_weights) return Combine(cross ? pass.cross_weights[k] : pass.weights[k], v);
    return ChannelCovariance(cross ? pass.cross_moments[k] : pass.moments[k], v, Mi);
  };
  auto channels_ref = [&](std::size_t k, bool cross, const Vec3d& v) {
    if (pass.weights_ref.size() == K) {
      return Combine(cross ? pass.cross_weights_ref[k] : pass.weights_ref[k], v);
    }
    return ChannelCovariance(cross ? pass.cross_moments[k] : pass.moments[k], v,
                             pass.Mg_inv_ref);
  };
  const Mat3d R3 = AngleCovariance(pass.angle_var);
  GyroReduction out;
  out.noise_rad_s = noise_rad_s;
  out.rho = rho;
  out.whitened.resize(K);
  // The columns with a derivative in some interval (the others are zero
  // throughout: the reduction works on these alone).
  std::vector<int> cols;
  if (jac) {
    for (int c = 0; c < n; ++c) {
      for (std::size_t k = 0; k < K; ++k) {
        if (pass.J[k].col(c).squaredNorm() > 0.0) {
          cols.push_back(c);
          break;
        }
      }
    }
    out.gradient = Eigen::VectorXd::Zero(n);
    out.information = Eigen::MatrixXd::Zero(n, n);
  }
  const int m = static_cast<int>(cols.size());
  const int go = pass.theta.size() - kNumGyroParams;  // the gyro block is last
  // Where K_x..K_z and the six angles sit among cols.
  std::vector<int> k_slot(9, -1);
  for (int q = 0; q < m; ++q) {
    const int j = cols[q] - go;
    if (j >= kGKx && j <= kGKz) k_slot[j - kGKx] = q;
    if (j >= kGAlphaX && j <= kGGammaZ) k_slot[3 + j - kGAlphaX] = q;
  }
  // The innovations whitened as they are formed: with T_e = Li_{e-1}
  // C_{e-1,e} (Li = chol(S)^-1), G_e C_{e-1,e} = T_e^T T_e and G_e x_{e-1} =
  // T_e^T (Li_{e-1} x_{e-1}), so each interval needs its own factor and the
  // previous one's whitened innovation, Jacobian and information form
  // (3 x 3 products written out: Eigen's general kernels cost more than the
  // arithmetic at this size; the real medium roll run with its gyro took
  // 1.5 s of its fit's 2.4 s in these reductions).
  using Cols3 = Eigen::Matrix<double, 3, Eigen::Dynamic>;
  Cols3 Jk(3, m), Ik(3, m), Jnu(3, m), Inu(3, m);
  Cols3 Jz(3, m), Iz(3, m), Jz_prev(3, m), Iz_prev(3, m);  // whitened
  Eigen::VectorXd sc(m);
  double log_det_ref = 0.0;
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(m);
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(m, m);
  Mat3d C_prev = Mat3d::Zero(), Li_prev = Mat3d::Zero();
  Mat3d Cref_prev = Mat3d::Zero(), Liref_prev = Mat3d::Zero();
  Vec3d z_prev = Vec3d::Zero();
  bool chained = false;  // the previous interval is used and shares this one's first epoch
  int used = 0;
  // For forms: each interval's factor, coupling to the one before and
  // whitened innovation (Sigma^-1 r by the back substitution below), and the
  // factors of the log-determinant's Sigma when it is another (the
  // reference's).
  const bool ref_chain = forms && forms->with_log_det && !same_ref;
  std::vector<Mat3d> Li_all, T_all, Liref_all, Tref_all;
  std::vector<Vec3d> z_all;
  std::vector<char> chained_all;
  if (forms) {
    Li_all.resize(K);
    T_all.resize(K);
    z_all.resize(K);
    chained_all.assign(K, 0);
  }
  if (ref_chain) {
    Liref_all.resize(K);
    Tref_all.resize(K);
  }
  for (std::size_t k = 0; k < K; ++k) {
    if (!pass.valid[k]) {
      chained = false;
      out.whitened[k].setZero();
      if (jac && with_scores) out.scores.push_back(Eigen::VectorXd::Zero(n));
      continue;
    }
    ++used;
    Mat3d S = 2.0 * R3 + channels(k, false, var);
    Vec3d nu = pass.r[k];
    Mat3d T;
    if (chained) {
      T.noalias() = Li_prev.lazyProduct(C_prev);
      S.noalias() -= T.transpose().lazyProduct(T);
      nu.noalias() -= T.transpose() * z_prev;
    }
    if (jac) {
      for (int q = 0; q < m; ++q) Jk.col(q) = pass.J[k].col(cols[q]);
      Ik = Jk;
      for (int i = 0; i < 9; ++i) {
        if (k_slot[i] >= 0) Ik.col(k_slot[i]) = pass.J_info[k].col(i);
      }
      if (chained) {
        Jnu.noalias() = Jk - T.transpose().lazyProduct(Jz_prev);
        Inu.noalias() = Ik - T.transpose().lazyProduct(Iz_prev);
      } else {
        Jnu = Jk;
        Inu = Ik;
      }
    }
    if (!same_ref && with_log_det) {
      // The log-determinant at the reference scale factors.
      Mat3d Sr = 2.0 * R3 + channels_ref(k, false, var_ref);
      if (chained) {
        const Mat3d Tr = Liref_prev.lazyProduct(Cref_prev);
        Sr.noalias() -= Tr.transpose().lazyProduct(Tr);
        if (ref_chain) Tref_all[k] = Tr;
      }
      double half_log_det_ref = 0.0;
      Liref_prev = InverseCholesky3(Sr, &half_log_det_ref);
      if (ref_chain) Liref_all[k] = Liref_prev;
      log_det_ref += half_log_det_ref;
      Cref_prev = -R3 + channels_ref(k, true, var_ref);
    }
    double half_log_det = 0.0;
    const Mat3d Li = InverseCholesky3(S, &half_log_det);
    out.log_det += half_log_det;  // 0.5 log det S
    const Vec3d z = Li * nu;
    out.whitened[k] = z;
    out.cost += 0.5 * z.squaredNorm();
    if (forms) {
      Li_all[k] = Li;
      z_all[k] = z;
      chained_all[k] = chained;
      if (chained) T_all[k] = T;
    }
    if (jac) {
      Jz.noalias() = Li.lazyProduct(Jnu);
      sc.noalias() = Jz.transpose() * z;
      if (with_scores) {
        Eigen::VectorXd full = Eigen::VectorXd::Zero(n);
        for (int q = 0; q < m; ++q) full[cols[q]] = sc[q];
        out.scores.push_back(std::move(full));
      }
      grad += sc;
      Iz.noalias() = Li.lazyProduct(Inu);
      // The rank-3 update of the information, its lower triangle (mirrored below).
      for (int r = 0; r < 3; ++r) {
        for (int b = 0; b < m; ++b) {
          const double v = Iz(r, b);
          for (int a = b; a < m; ++a) info(a, b) += Iz(r, a) * v;
        }
      }
      Jz_prev.swap(Jz);
      Iz_prev.swap(Iz);
    }
    // The covariance of this residual with the next one.
    C_prev = -R3 + channels(k, true, var);
    Li_prev = Li;
    z_prev = z;
    chained = true;
  }
  if (forms) {
    auto linked = [&](std::size_t k) {  // interval k + 1 is chained to k
      return k + 1 < K && pass.valid[k + 1] && chained_all[k + 1];
    };
    // w_e = Li_e^T (z_e - T_e+1 w_e+1): the factorisation's back
    // substitution (G_e+1^T = S_e^-1 C_e,e+1 = Li_e^T T_e+1).
    std::vector<Vec3d> w(K, Vec3d::Zero());
    for (std::size_t k = K; k-- > 0;) {
      if (!pass.valid[k]) continue;
      Vec3d x = z_all[k];
      if (linked(k)) x.noalias() -= T_all[k + 1] * w[k + 1];
      w[k] = Li_all[k].transpose() * x;
    }
    forms->cost.setZero();
    for (std::size_t k = 0; k < K; ++k) {
      if (!pass.valid[k]) continue;
      forms->cost += MomentForm(pass.moments[k], w[k] * w[k].transpose());
      if (linked(k)) forms->cost += 2.0 * MomentForm(pass.cross_moments[k], w[k] * w[k + 1].transpose());
    }
    if (forms->with_log_det) {
      // Sigma^-1's blocks on the band, backwards (selected inversion):
      // X_ee = S_e^-1 + G_e+1^T X_e+1,e+1 G_e+1, X_e,e+1 = -G_e+1^T X_e+1,e+1.
      const std::vector<Mat3d>& Lf = ref_chain ? Liref_all : Li_all;
      const std::vector<Mat3d>& Tf = ref_chain ? Tref_all : T_all;
      forms->log_det.setZero();
      Mat3d X_next = Mat3d::Zero();
      for (std::size_t k = K; k-- > 0;) {
        if (!pass.valid[k]) continue;
        Mat3d X = Lf[k].transpose() * Lf[k];
        if (linked(k)) {
          const Mat3d Gt = Lf[k].transpose() * Tf[k + 1];  // G_e+1^T
          const Mat3d X_cross = -Gt * X_next;
          X.noalias() -= X_cross * Gt.transpose();
          forms->log_det += 2.0 * MomentForm(pass.cross_moments[k], X_cross);
        }
        forms->log_det += MomentForm(pass.moments[k], X);
        X_next = X;
      }
    }
  }
  out.degrees_of_freedom = 3 * used;
  info.triangularView<Eigen::StrictlyUpper>() = info.transpose();
  if (!same_ref) out.log_det = with_log_det ? log_det_ref : std::numeric_limits<double>::quiet_NaN();
  out.neg_log_l = out.cost + rho * out.log_det;
  if (jac) {
    for (int a = 0; a < m; ++a) {
      out.gradient[cols[a]] = grad[a];
      for (int b = 0; b < m; ++b) out.information(cols[a], cols[b]) = info(a, b);
    }
  }
  return out;
}

}  // namespace

GyroReduction ReduceGyro(const GyroPass& pass, const Eigen::Vector3d& noise_rad_s, double rho,
                         bool theta_part, bool with_scores, const Eigen::Matrix3d* mg_inv) {
  return ReduceGyroOrCost(pass, noise_rad_s, rho, theta_part, with_scores, mg_inv, true);
}

double GyroNoiseDofShare(const GyroPass& pass, int fitted_parameters) {
  double dof = 0.0;
  for (char v : pass.valid) dof += v ? 3.0 : 0.0;
  dof = std::max(dof, 1.0);
  return std::max(0.1, 1.0 - fitted_parameters / dof);
}

GyroReduction ReduceGyroWithNoiseGradient(const GyroPass& pass, const Eigen::Vector3d& sigma,
                                          double rho, Eigen::Vector3d* g) {
  // Exact (WeightForms): d/ds_i = -v_i u_i^T F u_i + rho v_ref_i u_ref_i^T G
  // u_ref_i (dv_i / ds_i = 2 v_i).
  WeightForms forms;
  forms.with_log_det = true;
  GyroReduction r = ReduceGyroOrCost(pass, sigma, rho, false, false, nullptr, true, &forms);
  const Vec3d var = sigma.cwiseQuotient(pass.K).cwiseAbs2();
  const Vec3d var_ref = sigma.cwiseQuotient(pass.K_ref).cwiseAbs2();
  for (int i = 0; i < 3; ++i) {
    const Vec3d u = pass.Mg_inv.col(i), u_ref = pass.Mg_inv_ref.col(i);
    (*g)[i] = -var[i] * u.dot(forms.cost * u) + rho * var_ref[i] * u_ref.dot(forms.log_det * u_ref);
  }
  return r;
}

GyroReduction ReduceGyroAtBestNoise(const GyroPass& pass, const Eigen::Vector3d& start,
                                    int fitted_parameters, bool theta_part, int threads) {
  const double rho = GyroNoiseDofShare(pass, fitted_parameters);
  // -log L in s = log sigma, by Newton's method on its exact gradient
  // (ReduceGyroWithNoiseGradient, a reduction with its back substitutions, O(E)), the
  // Hessian its forward differences (3 more, independent: on `threads`)
  // where the last step left the region where -log L is quadratic
  // (kChordReach; within it the Hessian moves by about the step, and chord
  // steps with the last one converge about as fast). The steps go on to
  // 1e-12 in -log L, so the profile is a smooth function of theta to
  // rounding.
  Eigen::Vector3d s = start.array().max(1e-12).log();
  const double h = 1e-4;
  constexpr double kChordReach = 0.1;  // in log sigma
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  bool have_hessian = false;
  double last_big = std::numeric_limits<double>::infinity();
  for (int it = 0; it < 30; ++it) {
    const bool hessian = !have_hessian || last_big > kChordReach;
    // Point 0: s; points 1..3: s + h e_i (the Hessian's).
    std::array<Vec3d, 4> grads;
    GyroReduction center;
    ParallelFor(hessian ? 4 : 1, threads, [&](std::size_t q) {
      Vec3d at = s;
      if (q > 0) at[q - 1] += h;
      GyroReduction r = ReduceGyroWithNoiseGradient(pass, at.array().exp(), rho, &grads[q]);
      if (q == 0) center = std::move(r);
    });
    const double f0 = center.neg_log_l;
    // Far out (a start several times off the residual's noise: the declared
    // figure or the readings' own against a misfit) a Newton step in log
    // sigma moves about 0.5 (the cost's exp(-2 s) dominates): 16 steps on
    // the real slow gyro run's first point. The whitened residual's mean
    // square per degree of freedom says where a common scale of the three
    // goes; one jump there, kept when -log L falls.
    if (it == 0 && center.degrees_of_freedom > 0) {
      const double c = 2.0 * center.cost / (rho * center.degrees_of_freedom);
      if (std::isfinite(c) && c > 0.0 && std::abs(std::log(c)) > 1.0) {
        const Eigen::Vector3d jump = s.array() + 0.5 * std::log(c);
        if (ReduceGyro(pass, jump.array().exp(), rho, false).neg_log_l < f0) {
          s = jump;
          continue;
        }
      }
    }
    const Vec3d g = grads[0];
    if (hessian) {
      for (int j = 0; j < 3; ++j) H.col(j) = (grads[1 + j] - g) / h;
      H = (0.5 * (H + H.transpose())).eval();
    }
    have_hessian = true;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
    Eigen::Vector3d step;
    if (ldlt.info() == Eigen::Success && ldlt.isPositive() && (ldlt.vectorD().array() > 0.0).all()) {
      step = -ldlt.solve(g);
    } else {
      step = -g.cwiseQuotient(H.diagonal().cwiseAbs().cwiseMax(1.0));  // far out: gradient
    }
    // At most a factor e per step (the cost is far from quadratic far out).
    const double big = step.cwiseAbs().maxCoeff();
    if (big > 1.0) step /= big;
    s += step;
    last_big = big;
    // Converged: the next step would be below 1e-10 (the forward
    // differences' Hessian is exact to ~h = 1e-4 relative).
    if (-g.dot(step) < 1e-12 || big < 1e-5) break;
  }
  if (!theta_part) return ReduceGyro(pass, s.array().exp(), rho, false);
  return ReduceGyroAtNoise(pass, s.array().exp(), rho);
}

GyroReduction ReduceGyroAtNoise(const GyroPass& pass, const Eigen::Vector3d& noise_rad_s,
                                double rho) {
  WeightForms forms;
  GyroReduction out = ReduceGyroOrCost(pass, noise_rad_s, rho, true, true, nullptr, true, &forms);
  if (out.gradient.size() == 0) return out;
  // The weights' derivatives at the residual held (WeightForms; the
  // log-determinant is the reference's, not theta's): by K_i, dv_i / dK_i =
  // -2 v_i / K_i; by an angle a of Mg (entry (r, c), sign s_a), du_i = -s_a
  // Mg^-1 e_r (Mg^-1)_ci, and d(u^T F u) = du^T (F + F^T) u.
  const Mat3d& F = forms.cost;
  const int go = static_cast<int>(pass.theta.size()) - kNumGyroParams;
  const Mat3d& Mi = pass.Mg_inv;
  const Vec3d var = noise_rad_s.cwiseQuotient(pass.K).cwiseAbs2();
  const Mat3d Fs = F + F.transpose();
  for (int i = 0; i < 3; ++i) {
    const Vec3d u = Mi.col(i);
    out.gradient[go + kGKx + i] += var[i] * u.dot(F * u) / pass.K[i];
  }
  for (int a = 0; a < 6; ++a) {
    const AngleEntry& e = kAngleEntries[a];
    double d = 0.0;
    for (int i = 0; i < 3; ++i) {
      const Vec3d du = -e.sign * Mi.col(e.row) * Mi(e.col, i);
      d += var[i] * du.dot(Fs * Mi.col(i));
    }
    out.gradient[go + kGAlphaX + a] += -0.5 * d;
  }
  return out;
}

}  // namespace triadcal
