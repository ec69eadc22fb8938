#include "solvers/estimation/noise_estimation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "solvers/statistics/statistics.h"

namespace triadcal {

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
