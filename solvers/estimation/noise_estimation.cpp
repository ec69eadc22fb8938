#include "solvers/estimation/noise_estimation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "solvers/estimation/parallel.h"
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

std::array<std::vector<double>, 6> ExpectedProcessAutocorrelation(
    const std::vector<Eigen::MatrixXd>& C, const Eigen::MatrixXd& cov_free, int lags,
    int threads) {
  std::array<std::vector<double>, 6> rho;
  const std::size_t T = C.size();
  if (T == 0 || cov_free.rows() == 0) return rho;
  ParallelFor(6, threads, [&](std::size_t c) {
    std::vector<Eigen::VectorXd> a(T);  // cov j_t
    double trace_rest = 0.0;
    for (std::size_t t = 0; t < T; ++t) {
      a[t] = cov_free * C[t].row(c).transpose();
      trace_rest += 1.0 - C[t].row(c).dot(a[t]);
    }
    rho[c].assign(lags, 0.0);
    // When the fit takes most of a channel's residual (few epochs for the
    // parameters: a 10-s run has 20), its share is not a small correction
    // and the ratio below is unstable (it reached -200): nothing is
    // subtracted then.
    if (trace_rest < 0.5 * static_cast<double>(T)) return;
    for (int k = 1; k <= lags && static_cast<std::size_t>(k) < T; ++k) {
      double h = 0.0;
      for (std::size_t t = 0; t + k < T; ++t) h += C[t + k].row(c).dot(a[t]);
      rho[c][k - 1] = std::clamp(-h / trace_rest, -1.0, 1.0);
    }
  });
  return rho;
}

}  // namespace triadcal
