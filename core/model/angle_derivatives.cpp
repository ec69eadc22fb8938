#include "core/model/angle_derivatives.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/model/errors.h"

namespace triadcal {

void AngleDerivativeOptions::Check() const {
  if (std::isfinite(half_window_s) && half_window_s >= kMinHalfWindow_s &&
      half_window_s <= kMaxHalfWindow_s) {
    return;
  }
  char text[160];
  std::snprintf(text, sizeof(text), "%g s is outside [%g, %g] s", half_window_s, kMinHalfWindow_s,
                kMaxHalfWindow_s);
  throw OptionError("half_window_s", text);
}

namespace {

// Rate and acceleration of both axes at sample k from the samples in the
// window [lo, hi) (widened to at least 5 points). The two axes share the time
// stamps, so one pass over the window gives the power sums of the normal
// matrix (A(r, c) = sum s^(r+c), s = (t - t_k) / h) for both.
void FitAt(const RunData& run, std::size_t k, std::size_t lo, std::size_t hi, double h,
           BenchAngles<double>* o) {
  const std::size_t n = run.size();
  const double t0 = run.t_s[k];
  std::size_t a = lo, b = hi;
  while (b - a < 5 && (a > 0 || b < n)) {
    if (a > 0) --a;
    if (b - a < 5 && b < n) ++b;
  }
  const int m = static_cast<int>(b - a);
  const bool rates = run.has_rates();
  // Angles: a cubic (rate c1, acceleration 2 c2); rates: a quadratic (acceleration c1).
  const int degree = std::min(rates ? 2 : 3, m - 1);
  const std::vector<double>& y0 = rates ? run.rate_rad_s[0] : run.lambda_rad[0];
  const std::vector<double>& y1 = rates ? run.rate_rad_s[1] : run.lambda_rad[1];
  double S[7] = {0, 0, 0, 0, 0, 0, 0};
  Eigen::Vector4d T0 = Eigen::Vector4d::Zero(), T1 = Eigen::Vector4d::Zero();
  for (std::size_t j = a; j < b; ++j) {
    const double s1 = (run.t_s[j] - t0) / h, s2 = s1 * s1, s3 = s2 * s1;
    S[0] += 1.0;
    S[1] += s1;
    S[2] += s2;
    S[3] += s3;
    S[4] += s2 * s2;
    S[5] += s2 * s3;
    S[6] += s3 * s3;
    const Eigen::Vector4d p(1.0, s1, s2, s3);
    T0 += p * y0[j];
    T1 += p * y1[j];
  }
  // Coefficients above the degree: identity rows and zero sums, so they solve to 0.
  const int q = degree + 1;
  Eigen::Matrix4d A = Eigen::Matrix4d::Identity();
  for (int r = 0; r < q; ++r)
    for (int c = 0; c < q; ++c) A(r, c) = S[r + c];
  T0.tail(4 - q).setZero();
  T1.tail(4 - q).setZero();
  const Eigen::LDLT<Eigen::Matrix4d> ldlt(A);
  const Eigen::Vector4d c[2] = {ldlt.solve(T0), ldlt.solve(T1)};
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector4d& ci = c[i];
    if (rates) {
      o->axis[i].rate = run.rate_rad_s[i][k];
      o->axis[i].accel = q > 1 ? ci[1] / h : 0.0;
    } else {
      o->axis[i].rate = q > 1 ? ci[1] / h : 0.0;
      o->axis[i].accel = q > 2 ? 2.0 * ci[2] / (h * h) : 0.0;
    }
  }
}

}  // namespace

bool NeedsRatesAtEverySample(const ParameterLayout& layout) {
  for (Effect e : layout.effects()) {
    if (GetEffectSpec(e).needs.rates_at_every_sample) return true;
  }
  return false;
}

std::vector<BenchAngles<double>> EstimateAngleDerivativesAt(const RunData& run,
                                                            const AngleDerivativeOptions& opt,
                                                            const std::vector<std::size_t>& at) {
  opt.Check();
  const double h = opt.half_window_s;
  std::vector<BenchAngles<double>> out(at.size());
  for (std::size_t j = 0; j < at.size(); ++j) {
    const std::size_t k = at[j];
    const double t0 = run.t_s[k];
    const std::size_t lo =
        std::lower_bound(run.t_s.begin(), run.t_s.begin() + k, t0 - h) - run.t_s.begin();
    const std::size_t hi =
        std::upper_bound(run.t_s.begin() + k, run.t_s.end(), t0 + h) - run.t_s.begin();
    for (int i = 0; i < 2; ++i) out[j].axis[i].angle = run.lambda_rad[i][k];
    FitAt(run, k, lo, hi, h, &out[j]);
  }
  return out;
}

std::vector<BenchAngles<double>> EstimateAngleDerivatives(const RunData& run,
                                                          const AngleDerivativeOptions& opt) {
  std::vector<std::size_t> every(run.size());
  for (std::size_t k = 0; k < every.size(); ++k) every[k] = k;
  return EstimateAngleDerivativesAt(run, opt, every);
}

double RateNoiseGain(double dt_s, const AngleDerivativeOptions& opt) {
  opt.Check();
  // The fitted slope is a linear combination sum_j w_j y_j; its noise gain is
  // |w|. With P the n x 4 matrix of rows p_j = (1, s_j, s_j^2, s_j^3),
  // s_j = t_j / h, the coefficients are (P^T P)^-1 P^T y, so w_j = e_1^T
  // (P^T P)^-1 p_j / h: one normal matrix for all j (linear in n; a fit per
  // unit vector made it quadratic, minutes for a wide window on a fast run).
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return 0.0;
  const double half_d = std::floor(opt.half_window_s / dt_s + 1e-9);
  const long half = std::max(2L, static_cast<long>(std::min(half_d, 1e7)));
  const long n = 2 * half + 1;
  const double h = opt.half_window_s;
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  for (long j = 0; j < n; ++j) {
    const double s = (j - half) * dt_s / h;
    const Eigen::Vector4d p(1.0, s, s * s, s * s * s);
    A += p * p.transpose();
  }
  const Eigen::Vector4d row = A.ldlt().solve(Eigen::Vector4d::UnitY());  // (P^T P)^-1 e_1
  double sum2 = 0.0;
  for (long j = 0; j < n; ++j) {
    const double s = (j - half) * dt_s / h;
    const double w = (row[0] + s * (row[1] + s * (row[2] + s * row[3]))) / h;
    sum2 += w * w;
  }
  return std::sqrt(sum2);
}

}  // namespace triadcal
