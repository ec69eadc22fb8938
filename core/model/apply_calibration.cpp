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
    const Eigen::Vector3d z(data.readings_mV(k));
    W[k] = SpecificForceFromReadings_g(cfg, cal.theta.data(), z, ctx);
    // Newton must have found a real root: the model maps W back onto z. With a
    // strong nonlinearity (K_ij) some readings have no real W at all; Newton then
    // stops anywhere, so check instead of writing its last iterate.
    const Eigen::Vector3d back = Readings_mV(cfg, cal.theta.data(), W[k], ctx);
    const double tolerance_mV = 1e-6 * cal.theta.segment<3>(kKx).cwiseAbs().maxCoeff();
    if (!W[k].allFinite() || !((back - z).cwiseAbs().maxCoeff() <= tolerance_mV)) {
      throw InputError(cal.path + ": the calibration has no real inverse for sample " +
                       std::to_string(k + 1) + " of " + run.data_path + " (t = " +
                       FormatDouble(data.t_s[k]) +
                       " s): its nonlinearity K_ij folds the readings model there (is the "
                       "calibration from this sensor, in these units?)");
    }
  }
  return W;
}

}  // namespace triadcal
