#include "core/model/angle_derivatives.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace triadcal {
namespace {

// Least-squares cubic through (s_j, y_j); returns the coefficient vector c.
// Columns are scaled by h so the normal matrix stays well conditioned.
Eigen::Vector4d LocalCubic(const double* t, const double* y, int n, double t0, double h,
                           int degree) {
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
  for (int j = 0; j < n; ++j) {
    const double s = (t[j] - t0) / h;
    const double p[4] = {1.0, s, s * s, s * s * s};
    for (int r = 0; r <= degree; ++r) {
      b[r] += p[r] * y[j];
      for (int c = 0; c <= degree; ++c) A(r, c) += p[r] * p[c];
    }
  }
  const int m = degree + 1;
  Eigen::Vector4d c = Eigen::Vector4d::Zero();
  c.head(m) = A.topLeftCorner(m, m).ldlt().solve(b.head(m));
  for (int r = 1; r < 4; ++r) c[r] /= std::pow(h, r);
  return c;
}

}  // namespace

namespace {

// Rate and acceleration of both axes at sample k from the samples in the
// window [lo, hi) (widened to at least 5 points).
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
  const int degree = std::min(3, m - 1);
  for (int i = 0; i < 2; ++i) {
    if (run.has_rates()) {
      o->axis[i].rate = run.rate_rad_s[i][k];
      const Eigen::Vector4d c =
          LocalCubic(&run.t_s[a], &run.rate_rad_s[i][a], m, t0, h, std::min(degree, 2));
      o->axis[i].accel = c[1];
    } else {
      const Eigen::Vector4d c = LocalCubic(&run.t_s[a], &run.lambda_rad[i][a], m, t0, h, degree);
      o->axis[i].rate = c[1];
      o->axis[i].accel = 2.0 * c[2];
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

std::vector<BenchAngles<double>> EstimateAngleDerivatives(const RunData& run,
                                                          const AngleDerivativeOptions& opt,
                                                          const std::vector<std::size_t>* only) {
  const std::size_t n = run.size();
  std::vector<BenchAngles<double>> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    for (int i = 0; i < 2; ++i) out[k].axis[i].angle = run.lambda_rad[i][k];
  }
  const double h = opt.half_window_s;
  auto window = [&](std::size_t k, std::size_t* lo, std::size_t* hi) {
    const double t0 = run.t_s[k];
    *lo = std::lower_bound(run.t_s.begin(), run.t_s.begin() + k, t0 - h) - run.t_s.begin();
    *hi = std::upper_bound(run.t_s.begin() + k, run.t_s.end(), t0 + h) - run.t_s.begin();
  };
  if (only) {
    for (std::size_t k : *only) {
      std::size_t lo, hi;
      window(k, &lo, &hi);
      FitAt(run, k, lo, hi, h, &out[k]);
    }
    return out;
  }
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t lo, hi;
    window(k, &lo, &hi);
    FitAt(run, k, lo, hi, h, &out[k]);
  }
  return out;
}

double RateNoiseGain(double dt_s, const AngleDerivativeOptions& opt) {
  // The fitted slope is a linear combination sum_j w_j y_j; its noise gain is |w|.
  const int half = std::max(2, static_cast<int>(std::floor(opt.half_window_s / dt_s + 1e-9)));
  const int n = 2 * half + 1;
  std::vector<double> t(n);
  for (int j = 0; j < n; ++j) t[j] = (j - half) * dt_s;
  double sum2 = 0.0;
  for (int j = 0; j < n; ++j) {
    std::vector<double> e(n, 0.0);
    e[j] = 1.0;
    const double w = LocalCubic(t.data(), e.data(), n, 0.0, opt.half_window_s, 3)[1];
    sum2 += w * w;
  }
  return std::sqrt(sum2);
}

}  // namespace triadcal
