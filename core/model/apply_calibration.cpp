// Calibration files in, calibrated specific force out (apply_calibration.h).
#include "core/model/apply_calibration.h"

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "core/model/bench_model.h"
#include "core/model/errors.h"
#include "core/io/file_util.h"

namespace triadcal {
std::vector<Eigen::Vector3d> ApplyCalibration(const Calibration& cal, const RunDescription& run,
                                              const RunData& data) {
  ModelConfig cfg = MakeModelConfig(run, cal.layout);
  if (data.has_temp()) cfg.temp_ref_C = data.temp_C.front();
  std::vector<Eigen::Vector3d> W(data.size());
  for (std::size_t k = 0; k < data.size(); ++k) {
    const SampleContext ctx{data.t_s[k], data.has_temp() ? data.temp_C[k] : 0.0};
    W[k] = SpecificForceFromReadings_g(cfg, cal.theta.data(), Eigen::Vector3d(data.readings_mV(k)),
                                       ctx);
  }
  return W;
}

}  // namespace triadcal
