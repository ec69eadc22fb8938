#include "core/model/sample_noise.h"

#include <algorithm>
#include <cmath>

namespace triadcal {

double SecondDifferenceNoise(const std::vector<double>& x) {
  if (x.size() < 10) return 0.0;
  std::vector<double> d2(x.size() - 2);
  for (std::size_t k = 1; k + 1 < x.size(); ++k) {
    const double d = x[k + 1] - 2.0 * x[k] + x[k - 1];
    d2[k - 1] = d * d;
  }
  // The 98 % smallest: for N(0, s^2) their mean square is 0.87348 s^2
  // (1 - 2 z phi(z) / 0.98 at z = 2.3263).
  const std::size_t keep = std::max<std::size_t>(1, d2.size() * 98 / 100);
  std::nth_element(d2.begin(), d2.begin() + (keep - 1), d2.end());
  double sum = 0.0;
  for (std::size_t k = 0; k < keep; ++k) sum += d2[k];
  return std::sqrt(sum / static_cast<double>(keep) / 0.87348 / 6.0);
}

Eigen::Vector3d RunReadingNoise_mV(const RunDescription& run, const RunData& data) {
  Eigen::Vector3d noise = run.ChannelNoise_mV();
  if (!run.noise_auto) return noise;
  for (int i = 0; i < 3; ++i) {
    const double sd = SecondDifferenceNoise(data.w_mV[i]);
    if (sd > 0.0) noise[i] = sd;
  }
  return noise;
}

RunDescription WithReadingNoise(RunDescription run, const RunData& data) {
  const Eigen::Vector3d noise = RunReadingNoise_mV(run, data);
  run.noise_auto = false;
  run.noise_channel_mV = noise;
  run.noise_mV = noise.maxCoeff();
  if (run.gyro && run.gyro->noise_auto && data.has_gyro()) {
    for (int i = 0; i < 3; ++i) {
      const double sd = SecondDifferenceNoise(data.gyro_rad_s[i]);
      if (sd > 0.0) run.gyro->noise_rad_s[i] = sd;
    }
    run.gyro->noise_auto = false;
  }
  return run;
}

}  // namespace triadcal
