// Calibration files in, calibrated specific force out (apply_calibration.h).
#include "core/model/apply_calibration.h"

#include "core/model/mounting.h"

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "core/model/bench_model.h"
#include "core/model/errors.h"
#include "core/model/gyro_model.h"
#include "core/io/file_util.h"

namespace triadcal {
namespace {

// The calibration's parameters in the run's axes (mounted when it is in the
// IMU's own axes) and, with a temperature model, at each sample's temperature.
class SampleTheta {
 public:
  SampleTheta(const Calibration& cal, const RunDescription& run, const RunData& data)
      : data_(data), run_(run), ref_C_(cal.temperature_ref_C) {
    const Eigen::MatrixXd mount =
        cal.imu_axes ? MountingMap(run, cal.layout)
                     : Eigen::MatrixXd::Identity(cal.layout.size(), cal.layout.size());
    theta0_ = mount * cal.theta;
    for (const Calibration::TemperatureTerm& term : cal.temperature_terms) {
      for (std::size_t d = 0; d < term.coefficients.size(); ++d) {
        if (per_degree_.size() <= d) {
          per_degree_.push_back(Eigen::VectorXd::Zero(cal.layout.size()));
        }
        per_degree_[d][term.index] = term.coefficients[d];
      }
    }
    for (Eigen::VectorXd& v : per_degree_) v = mount * v;
    if (!per_degree_.empty() && !data.has_temp() && !run.temperature_C) {
      throw InputError(cal.path + ": the calibration has a temperature model and " + run.yaml_path +
                       " gives no temperature (a temp_C column, or temperature_C in run.yaml)");
    }
    theta_ = theta0_;
  }

  // theta_i(T) = theta_i + sum_k c_ik (T - reference)^k at sample k's temperature.
  const Eigen::VectorXd& At(std::size_t k) {
    if (per_degree_.empty()) return theta_;
    const double dT = (data_.has_temp() ? data_.temp_C[k] : *run_.temperature_C) - ref_C_;
    theta_ = theta0_;
    double power = 1.0;
    for (const Eigen::VectorXd& v : per_degree_) {
      power *= dT;
      theta_ += power * v;
    }
    return theta_;
  }

 private:
  const RunData& data_;
  const RunDescription& run_;
  double ref_C_;
  Eigen::VectorXd theta0_, theta_;
  std::vector<Eigen::VectorXd> per_degree_;
};

}  // namespace

std::vector<Eigen::Vector3d> ApplyCalibration(const Calibration& cal, const RunDescription& run,
                                              const RunData& data) {
  const ModelConfig cfg = MakeModelConfig(run, cal.layout, data);
  SampleTheta sample_theta(cal, run, data);
  std::vector<Eigen::Vector3d> W(data.size());
  for (std::size_t k = 0; k < data.size(); ++k) {
    const SampleContext ctx{data.t_s[k], data.has_temp() ? data.temp_C[k] : 0.0};
    const Eigen::VectorXd& theta = sample_theta.At(k);
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

std::vector<Eigen::Vector3d> ApplyGyroCalibration(const Calibration& cal, const RunDescription& run,
                                                  const RunData& data,
                                                  const std::vector<Eigen::Vector3d>& W_g) {
  if (!cal.layout.has_gyro()) {
    throw InputError(cal.path + ": the calibration has no gyro parameters (gyro.Kx..gyro.Gzz)");
  }
  if (!data.has_gyro()) {
    throw InputError((run.yaml_path.empty() ? std::string("run") : run.yaml_path) +
                     ": no gyro readings (gx gy gz, read with a gyro block)");
  }
  if (W_g.size() != data.size()) {
    throw InputError("the specific force has " + std::to_string(W_g.size()) +
                     " samples, the gyro readings " + std::to_string(data.size()));
  }
  const ModelConfig cfg = MakeModelConfig(run, cal.layout, data);
  SampleTheta sample_theta(cal, run, data);
  std::vector<Eigen::Vector3d> rate(data.size());
  for (std::size_t k = 0; k < data.size(); ++k) {
    rate[k] = GyroRateFromReadings(cfg, sample_theta.At(k).data(), data.gyro(k), W_g[k]);
  }
  return rate;
}

}  // namespace triadcal
