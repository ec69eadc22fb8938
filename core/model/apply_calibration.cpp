// Calibration files in, calibrated specific force out (apply_calibration.h).
#include "core/model/apply_calibration.h"

#include "core/model/mounting.h"

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "core/model/bench_model.h"
#include "core/model/errors.h"
#include "core/io/file_util.h"

namespace triadcal {
std::vector<Eigen::Vector3d> ApplyCalibration(const Calibration& cal, const RunDescription& run,
                                              const RunData& data) {
  const ModelConfig cfg = MakeModelConfig(run, cal.layout, data);
  // The calibration in this run's axes, and its temperature terms.
  const Eigen::MatrixXd mount =
      cal.imu_axes ? MountingMap(run, cal.layout)
                   : Eigen::MatrixXd::Identity(cal.layout.size(), cal.layout.size());
  const Eigen::VectorXd theta0 = mount * cal.theta;
  std::vector<Eigen::VectorXd> per_degree;
  for (const Calibration::TemperatureTerm& term : cal.temperature_terms) {
    for (std::size_t d = 0; d < term.coefficients.size(); ++d) {
      if (per_degree.size() <= d) per_degree.push_back(Eigen::VectorXd::Zero(cal.layout.size()));
      per_degree[d][term.index] = term.coefficients[d];
    }
  }
  for (Eigen::VectorXd& v : per_degree) v = mount * v;
  if (!per_degree.empty() && !data.has_temp() && !run.temperature_C) {
    throw InputError(cal.path + ": the calibration has a temperature model and " + run.yaml_path +
                     " gives no temperature (a temp_C column, or temperature_C in run.yaml)");
  }
  std::vector<Eigen::Vector3d> W(data.size());
  Eigen::VectorXd theta = theta0;
  for (std::size_t k = 0; k < data.size(); ++k) {
    const SampleContext ctx{data.t_s[k], data.has_temp() ? data.temp_C[k] : 0.0};
    if (!per_degree.empty()) {
      const double dT = (data.has_temp() ? data.temp_C[k] : *run.temperature_C) -
                        cal.temperature_ref_C;
      theta = theta0;
      double power = 1.0;
      for (const Eigen::VectorXd& v : per_degree) {
        power *= dT;
        theta += power * v;
      }
    }
    const Eigen::Vector3d z(data.readings_mV(k));
    W[k] = SpecificForceFromReadings_g(cfg, theta.data(), z, ctx);
    // Newton must have found a real root: the model maps W back onto z. With a
    // strong nonlinearity (K_ij) some readings have no real W at all; Newton then
    // stops anywhere, so check instead of writing its last iterate.
    const Eigen::Vector3d back = Readings_mV(cfg, theta.data(), W[k], ctx);
    const double tolerance_mV = 1e-6 * theta.segment<3>(kKx).cwiseAbs().maxCoeff();
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
