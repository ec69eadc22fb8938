#include "solvers/estimation/noise_estimation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "solvers/statistics/statistics.h"

namespace triadcal {

NoiseEstimate EstimateChannelNoise(const StateSpaceModel& model, const BatchLinearization& lin,
                                   const std::vector<Vec6>& process_residual, int dof,
                                   const std::vector<Vec6>& process_whitened) {
  const std::size_t E = model.num_epochs();
  Eigen::Vector3d num = Eigen::Vector3d::Zero(), tr = Eigen::Vector3d::Zero(),
                  tr2 = Eigen::Vector3d::Zero();
  for (std::size_t e = 0; e + 1 < E; ++e) {
    const ProcessStep& s = lin.process[e];
    const Eigen::LDLT<Mat6> Q(s.Q);
    const Vec6 w = Q.solve(process_residual[e + 1]);  // Q^-1 r
    for (int i = 0; i < 3; ++i) {
      const Mat6 A = Q.solve(s.channel_Q[i]);
      num[i] += w.dot(s.channel_Q[i] * w);
      tr[i] += A.trace();
      tr2[i] += (A * A).trace();
    }
  }
  const double rho = std::max(0.1, std::min(1.0, dof / (6.0 * (E - 1))));
  NoiseEstimate out;
  out.assumed_mV = model.problem().noise_mV;
  bool consistent = true;
  for (int i = 0; i < 3; ++i) {
    const double f = tr[i] > 0 ? num[i] / (rho * tr[i]) : 1.0;
    out.dof[i] = tr2[i] > 0 ? rho * tr[i] * tr[i] / tr2[i] : 0.0;
    out.estimated_mV[i] = out.assumed_mV[i] * std::sqrt(std::max(f, 0.0));
    out.sd_mV[i] = out.dof[i] > 0 ? out.estimated_mV[i] * std::sqrt(0.5 / out.dof[i]) : 0.0;
    const double diff = std::abs(out.estimated_mV[i] - out.assumed_mV[i]);
    if (diff > 3.0 * out.sd_mV[i] && diff > 0.02 * out.assumed_mV[i]) consistent = false;
  }
  out.consistent = consistent;

  // Whiteness: lag-1 of each whitened component over the intervals (index 0
  // is the first epoch, which ends no interval).
  const std::size_t n = process_whitened.size() > 1 ? process_whitened.size() - 1 : 0;
  out.white_bound = n > 0 ? std::max(kWhiteLag1, 4.0 / std::sqrt(static_cast<double>(n)))
                          : kWhiteLag1;
  if (n > 2) {
    for (int c = 0; c < 6; ++c) {
      std::vector<double> x(n);
      for (std::size_t e = 1; e <= n; ++e) x[e - 1] = process_whitened[e][c];
      out.lag1[c] = Autocorrelation(x, 1);
      if (std::abs(out.lag1[c]) > out.white_bound) out.white = false;
    }
  }
  out.channels_alike =
      out.estimated_mV.maxCoeff() <= kMaxChannelRatio * out.estimated_mV.minCoeff();
  return out;
}

WhitenessSummary ProcessWhiteness(const std::vector<Vec6>& process_whitened,
                                  const std::array<std::vector<double>, 6>& expected_acf) {
  WhitenessSummary out;
  const std::size_t E = process_whitened.size();
  if (E <= 20) return out;
  double p_min = 1.0;
  const int lags = static_cast<int>(std::min<std::size_t>(20, E / 5));
  for (int c = 0; c < 6; ++c) {
    std::vector<double> x;
    x.reserve(E - 1);
    for (std::size_t e = 1; e < E; ++e) x.push_back(process_whitened[e][c]);
    const std::vector<double>& expected = expected_acf[c];
    p_min = std::min(p_min, LjungBox(x, lags, expected.empty() ? nullptr : &expected).p_value);
  }
  out.p_value = std::min(1.0, 6.0 * p_min);
  out.white = out.p_value >= 0.01;
  return out;
}

}  // namespace triadcal
