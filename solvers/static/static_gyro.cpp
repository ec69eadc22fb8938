#include "solvers/static/static_gyro.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/model/bench_model.h"
#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

// The accelerometer's specific force [g] at readings z (its exact inverse).
Eigen::Vector3d SpecificForce(const ModelConfig& cfg, const StaticResult& accel,
                              const RunData& data, std::size_t k) {
  const SampleContext ctx{data.t_s[k], data.has_temp() ? data.temp_C[k] : 0.0};
  return SpecificForceFromReadings_g(cfg, accel.theta.data(), data.readings_mV(k), ctx);
}

// Step 1: each position's mean gyro reading over the accelerometer's still
// intervals, and its specific force from the accelerometer's calibration.
std::vector<StaticGyroPosition> AveragePositions(const RunData& data, const StaticResult& accel) {
  std::vector<StaticGyroPosition> out;
  for (const StaticPosition& p : accel.positions) {
    StaticGyroPosition g;
    g.name = p.name;
    for (const StillInterval& iv : p.intervals) {
      for (std::size_t k = iv.begin; k < iv.end; ++k) g.mean_rad_s += data.gyro(k);
      g.samples += iv.samples();
    }
    if (g.samples == 0) continue;
    g.mean_rad_s /= static_cast<double>(g.samples);
    g.W_g = p.W_g;
    out.push_back(g);
  }
  return out;
}

// Step 1: per axis i, weighted least squares g_p,i = W0_i + G_W,i. W_p.
// Fills theta's W0 and G_W, their declared covariance per axis (4 x 4), the
// residuals and chi2.
void FitBiasAndGSensitivity(const RunDescription& run, StaticGyroResult* r,
                            Eigen::Matrix4d cov_axis[3]) {
  const std::size_t n = r->positions.size();
  r->chi2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double sigma = run.gyro->noise_rad_s[i];
    Eigen::Matrix4d N = Eigen::Matrix4d::Zero();
    Eigen::Vector4d b = Eigen::Vector4d::Zero();
    for (const StaticGyroPosition& p : r->positions) {
      const Eigen::Vector4d x(1.0, p.W_g[0], p.W_g[1], p.W_g[2]);
      const double w = static_cast<double>(p.samples) / (sigma * sigma);
      N += w * x * x.transpose();
      b += w * x * p.mean_rad_s[i];
    }
    const Eigen::FullPivLU<Eigen::Matrix4d> lu(N);
    if (lu.rank() < 4) {
      throw InputError(
          "gyro: the static positions do not separate the gyro bias from its g-sensitivity "
          "(need four positions with independent specific forces)");
    }
    const Eigen::Vector4d c = lu.solve(b);
    cov_axis[i] = lu.inverse();
    r->theta[kGW0x + i] = c[0];
    for (int j = 0; j < 3; ++j) r->theta[kGGxx + 3 * i + j] = c[1 + j];
    for (StaticGyroPosition& p : r->positions) {
      const Eigen::Vector4d x(1.0, p.W_g[0], p.W_g[1], p.W_g[2]);
      p.residual_rad_s[i] = p.mean_rad_s[i] - x.dot(c);
      r->chi2 += p.residual_rad_s[i] * p.residual_rad_s[i] * p.samples / (sigma * sigma);
    }
  }
  r->dof = 3.0 * (static_cast<double>(n) - 4.0);
  const double ratio = r->dof >= 1.0 ? r->chi2 / r->dof : 0.0;
  r->sigma_scale = std::max(1.0, std::sqrt(ratio));
  r->sigma_source = ratio > 1.0 ? "residual scatter" : "declared noise";
  for (int i = 0; i < 3; ++i) {
    r->sigma[kGW0x + i] = std::sqrt(cov_axis[i](0, 0)) * r->sigma_scale;
    for (int j = 0; j < 3; ++j) {
      r->sigma[kGGxx + 3 * i + j] = std::sqrt(cov_axis[i](1 + j, 1 + j)) * r->sigma_scale;
    }
  }
}

// Step 2: one turn's corrected readings integrated, and what the noise and
// the uncertainty of W0, G_W propagate into it (variance per axis).
StaticGyroTurnResult IntegrateTurn(const ModelConfig& cfg, const RunDescription& run,
                                   const RunData& data, const StaticResult& accel,
                                   const StaticGyroResult& r, const Eigen::Matrix4d cov_axis[3],
                                   const GyroTurn& turn, Eigen::Vector3d* var_integral) {
  std::vector<std::size_t> idx;
  for (std::size_t k = 0; k < data.size(); ++k) {
    if (data.label[k] == turn.label) idx.push_back(k);
  }
  if (idx.size() < 2) {
    throw InputError("gyro: no samples labelled '" + turn.label +
                     "' (the turn the gyro's scale factors come from)");
  }
  // The sample interval: the median step inside the turn (Ferraris: the sum / rate).
  std::vector<double> steps;
  for (std::size_t m = 1; m < idx.size(); ++m)
    steps.push_back(data.t_s[idx[m]] - data.t_s[idx[m - 1]]);
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  const double dt = steps[steps.size() / 2];

  const Eigen::Vector3d W0 = r.theta.segment<3>(kGW0x);
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> G(r.theta.data() + kGGxx);
  StaticGyroTurnResult t;
  t.label = turn.label;
  t.samples = idx.size();
  t.duration_s = dt * static_cast<double>(idx.size());
  Eigen::Vector3d sum_W = Eigen::Vector3d::Zero();
  for (std::size_t k : idx) {
    const Eigen::Vector3d W = SpecificForce(cfg, accel, data, k);
    t.integral_rad += (data.gyro(k) - W0 - G * W) * dt;
    sum_W += W;
  }
  t.mean_W_g = sum_W / static_cast<double>(idx.size());
  // dI_i / d(W0_i, G_W,i.) = -(T, sum W dt); white noise adds N sigma_i^2 dt^2.
  const Eigen::Vector4d d(t.duration_s, sum_W[0] * dt, sum_W[1] * dt, sum_W[2] * dt);
  for (int i = 0; i < 3; ++i) {
    const double s = run.gyro->noise_rad_s[i];
    (*var_integral)[i] = d.dot(cov_axis[i] * d) * r.sigma_scale * r.sigma_scale +
                         static_cast<double>(idx.size()) * s * s * dt * dt;
  }
  return t;
}

// K_i = A_ii and the six angles of Mg = diag(K)^-1 A (the form of M, gyro_model.h).
void ScaleAndAngles(const Eigen::Matrix3d& A, const Eigen::Matrix3d& sigma_A, StaticGyroResult* r) {
  const int angle_of[3][3] = {
      {-1, kGAlphaY, kGBetaZ}, {kGAlphaX, -1, kGGammaZ}, {kGBetaX, kGGammaY, -1}};
  const double sign_of[3][3] = {{0, -1, 1}, {1, 0, -1}, {-1, 1, 0}};
  for (int i = 0; i < 3; ++i) {
    r->theta[kGKx + i] = A(i, i);
    r->sigma_noise[kGKx + i] = sigma_A(i, i);
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      r->theta[angle_of[i][j]] = sign_of[i][j] * A(i, j) / A(i, i);
      r->sigma_noise[angle_of[i][j]] = sigma_A(i, j) / std::abs(A(i, i));
    }
  }
}

}  // namespace

StaticGyroResult SolveStaticGyro(const RunDescription& run, const RunData& data,
                                 const StaticResult& accel, const StaticGyroOptions& options) {
  if (!run.gyro || !data.has_gyro()) throw InputError("gyro: the run has no gyro triad");
  if (!data.has_label()) throw InputError("gyro: the turns need a label column (columns.label)");
  if (!(options.turn_deg > 0.0)) throw OptionError("turn_deg", "must be > 0");
  if (options.turns.size() != 3) throw OptionError("turns", "three turns are needed");
  StaticGyroResult r;
  r.theta.setZero();
  r.sigma.setConstant(std::numeric_limits<double>::quiet_NaN());
  r.sigma_noise.setZero();
  const ModelConfig cfg = MakeModelConfig(run, accel.layout, data);

  r.positions = AveragePositions(data, accel);
  if (r.positions.size() < 4) {
    throw InputError("gyro: " + std::to_string(r.positions.size()) +
                     " still positions; the bias and g-sensitivity need at least four");
  }
  Eigen::Matrix4d cov_axis[3];
  FitBiasAndGSensitivity(run, &r, cov_axis);

  const double angle_rad = options.turn_deg * kDegToRad;
  Eigen::Matrix3d I, U, var_I;
  for (int j = 0; j < 3; ++j) {
    const GyroTurn& turn = options.turns[j];
    Eigen::Vector3d var;
    StaticGyroTurnResult t = IntegrateTurn(cfg, run, data, accel, r, cov_axis, turn, &var);
    const Eigen::Vector3d u = turn.axis_platform.normalized();
    // The sense: the nominal scale reads the turn with its own sign.
    const Eigen::Vector3d nominal_read = run.gyro->scale.cwiseProduct(u);
    t.sense = t.integral_rad.dot(nominal_read) >= 0.0 ? 1 : -1;
    I.col(j) = t.integral_rad;
    U.col(j) = t.sense * angle_rad * u;
    var_I.col(j) = var;
    r.turns.push_back(t);
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(U);
  if (lu.rank() < 3) throw OptionError("turns", "the three turn axes must be independent");
  r.A = I * lu.inverse();
  // Noise-only sigma of A: exact for axes along e_j (A's column j = I_j / (s_j angle)).
  const Eigen::Matrix3d sigma_A = var_I.cwiseSqrt() / angle_rad;
  ScaleAndAngles(r.A, sigma_A, &r);
  return r;
}

}  // namespace triadcal
