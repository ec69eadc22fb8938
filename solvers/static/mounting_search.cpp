// Search of the IMU mounting and the angle-sensor zeros (mounting_search.h).
#include "solvers/static/mounting_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "core/model/bench_model.h"
#include "core/model/units.h"

namespace triadcal {

namespace {

// The 24 proper signed permutations of the axes.
std::vector<std::pair<std::array<int, 3>, std::array<double, 3>>> ProperMountings() {
  std::vector<std::pair<std::array<int, 3>, std::array<double, 3>>> out;
  std::array<int, 3> p = {0, 1, 2};
  do {
    for (int s = 0; s < 8; ++s) {
      const std::array<double, 3> sign = {s & 1 ? -1.0 : 1.0, s & 2 ? -1.0 : 1.0,
                                          s & 4 ? -1.0 : 1.0};
      int inversions = 0;
      for (int i = 0; i < 3; ++i) {
        for (int j = i + 1; j < 3; ++j) inversions += p[i] > p[j];
      }
      const double det = (inversions % 2 ? -1.0 : 1.0) * sign[0] * sign[1] * sign[2];
      if (det > 0) out.push_back({p, sign});
    }
  } while (std::next_permutation(p.begin(), p.end()));
  return out;
}

std::vector<std::size_t> Subsample(std::size_t n, std::size_t max_samples) {
  std::vector<std::size_t> idx;
  const std::size_t step = std::max<std::size_t>(1, n / std::max<std::size_t>(1, max_samples));
  for (std::size_t k = 0; k < n; k += step) idx.push_back(k);
  return idx;
}

// Gravity projection W (platform frame, in g) at each chosen sample.
std::vector<Eigen::Vector3d> GravityProjection(const RunDescription& run, const RunData& data,
                                               const std::vector<std::size_t>& idx, double z1,
                                               double z2) {
  ModelConfig cfg;
  cfg.g_mps2 = run.g_mps2;
  std::vector<double> theta(cfg.layout.size(), 0.0);
  theta[kDthetaC] = z1;
  theta[kDlambda2] = z2;
  std::vector<Eigen::Vector3d> W;
  W.reserve(idx.size());
  for (std::size_t k : idx) {
    BenchAngles<double> b;
    b.axis[0].angle = data.lambda_rad[0][k];
    b.axis[1].angle = data.lambda_rad[1][k];
    const BenchMotion<double> m = ComputeBenchMotion(cfg, theta.data(), b);
    W.push_back(SpecificForce_g(cfg, m.C_L2, Eigen::Vector3d::Zero().eval()));
  }
  return W;
}

// Variance of gravity's share on platform axis i over the samples [g^2].
double ShareVariance(const std::vector<Eigen::Vector3d>& W, int i) {
  double s = 0.0, ss = 0.0;
  for (const Eigen::Vector3d& v : W) {
    s += v[i];
    ss += v[i] * v[i];
  }
  const double n = static_cast<double>(std::max<std::size_t>(1, W.size()));
  return ss / n - (s / n) * (s / n);
}

// Per-axis fit w = b + K W_i; returns the misfit sum of squares in g^2, or a
// large number when K <= 0 (a flipped axis). With `at_nominal` K and b are
// the triad's nominal ones (nominal_scale, nominal_bias): where gravity turns
// on no platform axis (a vertical shaft) no axis gives them, and the axis
// reading 1 g must be the one put up (with K and b free every mounting fitted
// such a run exactly, and the search ranked them by chance). Otherwise an
// axis that never sees gravity change (a horizontal shaft's own) cannot
// tell: misfit 0.
double FitAxis(const std::vector<double>& w, const std::vector<Eigen::Vector3d>& W, int i,
               bool at_nominal, double nominal_scale, double nominal_bias, double* scale,
               double* bias) {
  const double n = static_cast<double>(w.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    const double x = W[k][i];
    sx += x;
    sy += w[k];
    sxx += x * x;
    sxy += x * w[k];
  }
  const double var = sxx - sx * sx / n;
  if (!at_nominal && !(var > 1e-6 * n)) {  // this axis never sees gravity change: cannot tell
    *scale = 0.0;
    *bias = sy / n;
    return 0.0;
  }
  const double K = at_nominal ? nominal_scale : (sxy - sx * sy / n) / var;
  const double b = at_nominal ? nominal_bias : (sy - K * sx) / n;
  *scale = K;
  *bias = b;
  if (!(K > 0.0)) return 1e30;
  double ss = 0.0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    const double e = (w[k] - b - K * W[k][i]) / K;
    ss += e * e;
  }
  return ss;
}

// imu: the IMU's readings at the samples idx (ImuReadings).
MountingFit Fit(const std::vector<std::vector<double>>& imu, const std::vector<std::size_t>& idx,
                const ImuAxesNominal& nominal, const std::vector<Eigen::Vector3d>& W,
                const int (&source)[3], const double (&sign)[3], double z1, double z2) {
  MountingFit f;
  double ss = 0.0;
  std::vector<double> w(idx.size());
  // Gravity turns on no platform axis (by 0.1 g RMS or more): judged at the
  // nominal scales and offsets.
  bool at_nominal = true;
  for (int i = 0; i < 3; ++i) at_nominal = at_nominal && ShareVariance(W, i) < 0.01;
  for (int i = 0; i < 3; ++i) {
    f.axis_source[i] = source[i];
    f.axis_sign[i] = sign[i];
    for (std::size_t j = 0; j < idx.size(); ++j) w[j] = sign[i] * imu[source[i]][j];
    ss += FitAxis(w, W, i, at_nominal, nominal.scale[source[i]],
                  sign[i] * nominal.bias[source[i]], &f.scale[i], &f.bias[i]);
  }
  f.zero_rad[0] = z1;
  f.zero_rad[1] = z2;
  f.rms_g = std::sqrt(ss / (3.0 * static_cast<double>(std::max<std::size_t>(1, idx.size()))));
  return f;
}

}  // namespace

std::string MountingFit::AxesText() const {
  std::string s = "[";
  for (int i = 0; i < 3; ++i) {
    s += std::string(i ? ", " : "") + "\"" + (axis_sign[i] < 0 ? "-" : "+") +
         "xyz"[axis_source[i]] + "\"";
  }
  return s + "]";
}

std::vector<std::vector<double>> ImuReadings(const RunDescription& run, const RunData& data,
                                             const std::vector<std::size_t>& idx) {
  std::vector<std::vector<double>> imu(3);
  for (int i = 0; i < 3; ++i) {
    std::vector<double>& col = imu[run.axis_source[i]];
    col.resize(idx.size());
    for (std::size_t j = 0; j < idx.size(); ++j) col[j] = run.axis_sign[i] * data.w_mV[i][idx[j]];
  }
  return imu;
}

namespace {

// The samples a search uses and the IMU's own readings at them.
struct SearchData {
  std::vector<std::size_t> idx;
  std::vector<std::vector<double>> imu;
  ImuAxesNominal nominal;
};

// Every proper mounting at its best zeros on the grid.
std::vector<MountingFit> GridFits(const RunDescription& run, const RunData& data,
                                  const SearchData& s, double zero_range_rad,
                                  double zero_step_rad) {
  const auto mountings = ProperMountings();
  std::vector<MountingFit> best(mountings.size());
  for (auto& b : best) b.rms_g = 1e300;
  auto try_zeros = [&](double z1, double z2) {
    const std::vector<Eigen::Vector3d> W = GravityProjection(run, data, s.idx, z1, z2);
    for (std::size_t m = 0; m < mountings.size(); ++m) {
      const int src[3] = {mountings[m].first[0], mountings[m].first[1], mountings[m].first[2]};
      const double sg[3] = {mountings[m].second[0], mountings[m].second[1], mountings[m].second[2]};
      const MountingFit f = Fit(s.imu, s.idx, s.nominal, W, src, sg, z1, z2);
      // Prefer the smaller zeros among fits equal to 0.1 %.
      const bool better =
          f.rms_g < best[m].rms_g * 0.999 ||
          (f.rms_g <= best[m].rms_g * 1.001 &&
           std::hypot(z1, z2) < std::hypot(best[m].zero_rad[0], best[m].zero_rad[1]));
      if (better) best[m] = f;
    }
  };
  const int steps = static_cast<int>(std::floor(zero_range_rad / zero_step_rad + 1e-9));
  for (int a = -steps; a <= steps; ++a) {
    for (int b = -steps; b <= steps; ++b) try_zeros(a * zero_step_rad, b * zero_step_rad);
  }
  return best;
}

// One mounting's zeros refined around its grid optimum: a finer grid,
// halving four times.
void Refine(const RunDescription& run, const RunData& data, const SearchData& s,
            double zero_range_rad, double zero_step_rad, MountingFit* best) {
  double step = zero_step_rad / 2.0;
  for (int round = 0; round < 4; ++round, step /= 2.0) {
    const double c1 = best->zero_rad[0], c2 = best->zero_rad[1];
    for (int a = -1; a <= 1; ++a) {
      for (int b = -1; b <= 1; ++b) {
        if (a == 0 && b == 0) continue;
        const double z1 = c1 + a * step, z2 = c2 + b * step;
        if (std::abs(z1) > zero_range_rad || std::abs(z2) > zero_range_rad) continue;
        const MountingFit f =
            Fit(s.imu, s.idx, s.nominal, GravityProjection(run, data, s.idx, z1, z2),
                {best->axis_source[0], best->axis_source[1], best->axis_source[2]},
                {best->axis_sign[0], best->axis_sign[1], best->axis_sign[2]}, z1, z2);
        if (f.rms_g < best->rms_g) *best = f;
      }
    }
  }
}

void SortByMisfit(std::vector<MountingFit>* fits) {
  std::sort(fits->begin(), fits->end(),
            [](const MountingFit& a, const MountingFit& b) { return a.rms_g < b.rms_g; });
}

}  // namespace

std::vector<MountingFit> SearchMountings(const RunDescription& run, const RunData& data,
                                         double zero_range_rad, double zero_step_rad,
                                         std::size_t max_samples) {
  SearchData s{Subsample(data.size(), max_samples), {}, NominalOfImuAxes(run)};
  s.imu = ImuReadings(run, data, s.idx);
  std::vector<MountingFit> best = GridFits(run, data, s, zero_range_rad, zero_step_rad);
  for (MountingFit& f : best) Refine(run, data, s, zero_range_rad, zero_step_rad, &f);
  SortByMisfit(&best);
  return best;
}

std::string StillGravityNote(const RunDescription& run, const RunData& data) {
  if (data.size() < 10) return "";
  const std::vector<std::size_t> idx = Subsample(data.size(), 2000);
  const std::vector<Eigen::Vector3d> W = GravityProjection(run, data, idx, 0.0, 0.0);
  double turned = 0.0;  // the largest range of gravity's share on a platform axis [g]
  for (int i = 0; i < 3; ++i) {
    const auto [lo, hi] = std::minmax_element(
        W.begin(), W.end(), [i](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
          return a[i] < b[i];
        });
    turned = std::max(turned, (*hi)[i] - (*lo)[i]);
  }
  // What the readings moved by [g]: each channel's 1st to 99th percentile
  // (the noise's tails and a few outliers left out), at its nominal scale.
  const ImuAxesNominal nominal = NominalOfImuAxes(run);
  const std::vector<std::vector<double>> imu = ImuReadings(run, data, idx);
  double moved = 0.0;
  for (int j = 0; j < 3; ++j) {
    std::vector<double> v = imu[j];
    std::sort(v.begin(), v.end());
    const double lo = v[v.size() / 100], hi = v[v.size() - 1 - v.size() / 100];
    moved = std::max(moved, (hi - lo) / std::abs(nominal.scale[j]));
  }
  if (!(turned > 0.5 && moved < 0.15)) return "";
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "the readings do not follow the angles: these angles turn gravity's share on "
                "a platform axis through %.2g g, the readings move by %.2g g at most (gravity "
                "lies along the axis that turns, a vertical shaft, or the readings do not "
                "respond). For a vertical shaft record its angle as lambda2, the inner axis, "
                "which is vertical at lambda1 = 0, with lambda1: {value: 0}, and the IMU's "
                "upward axis as platform x (mounting.axes)",
                turned, moved);
  return buf;
}

std::string MountingWarning(const RunDescription& run, const RunData& data) {
  if (data.size() < 10) return "";
  const std::string still = StillGravityNote(run, data);
  if (!still.empty()) return still;
  // Only when both angles together sweep gravity through a wide range.
  for (int i = 0; i < 2; ++i) {
    const auto [lo, hi] = std::minmax_element(data.lambda_rad[i].begin(), data.lambda_rad[i].end());
    if (*hi - *lo > 60.0 * kDegToRad) break;
    if (i == 1) return "";
  }
  // The grid's best and the declared mounting refined (the others do not
  // matter here).
  const double range = 5.0 * kDegToRad;
  SearchData s{Subsample(data.size(), 500), {}, NominalOfImuAxes(run)};
  s.imu = ImuReadings(run, data, s.idx);
  std::vector<MountingFit> fits = GridFits(run, data, s, range, range / 2.0);
  SortByMisfit(&fits);
  MountingFit best = fits.front(), declared;
  bool found = false;
  for (const MountingFit& f : fits) {
    bool same = true;
    for (int i = 0; i < 3; ++i) {
      same = same && f.axis_source[i] == run.axis_source[i] && f.axis_sign[i] == run.axis_sign[i];
    }
    if (same) {
      declared = f;
      found = true;
    }
  }
  if (!found) return "";
  Refine(run, data, s, range, range / 2.0, &best);
  Refine(run, data, s, range, range / 2.0, &declared);
  if (declared.rms_g < best.rms_g) best = declared;
  if (!(declared.rms_g > 3.0 * best.rms_g && declared.rms_g > best.rms_g + 0.05)) return "";
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "mounting.axes %s fits the data worse (gravity misfit %.3g g) than %s "
                "(%.3g g): check the mounting (`triadcal mounting RUN.yaml` lists the fits)",
                declared.AxesText().c_str(), declared.rms_g, best.AxesText().c_str(), best.rms_g);
  return buf;
}

}  // namespace triadcal
