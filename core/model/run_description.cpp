#include "core/model/run_description.h"

#include "core/model/gyro_model.h"

namespace triadcal {

Eigen::VectorXd NominalTheta(const RunDescription& run, const ParameterLayout& layout) {
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(layout.size());
  for (int i = 0; i < 3; ++i) {
    theta[kKx + i] = run.scale_mV_per_g[i];
    theta[kW0x + i] = run.bias_mV[i];
  }
  if (layout.has_gyro()) {
    const GyroDescription g = run.gyro.value_or(GyroDescription{});
    for (int i = 0; i < 3; ++i) {
      theta[layout.gyro_offset() + kGKx + i] = g.scale[i];
      theta[layout.gyro_offset() + kGW0x + i] = g.bias_rad_s[i];
    }
  }
  return theta;
}

ModelConfig MakeModelConfig(const RunDescription& run, const ParameterLayout& layout) {
  ModelConfig cfg;
  cfg.lever_arm0_m = run.lever_arm0_m;
  cfg.g_mps2 = run.g_mps2;
  if (run.latitude_rad && run.heading_rad) {
    cfg.earth_rate_L = EarthRateInL(*run.latitude_rad, *run.heading_rad);
  }
  cfg.layout = layout;
  return cfg;
}

ModelConfig MakeModelConfig(const RunDescription& run, const ParameterLayout& layout,
                            const RunData& data) {
  ModelConfig cfg = MakeModelConfig(run, layout);
  if (data.has_temp()) cfg.temp_ref_C = data.temp_C.front();
  if (!data.t_s.empty()) {
    cfg.time_start_s = data.t_s.front();
    cfg.time_span_s = data.t_s.back() - data.t_s.front();
  }
  return cfg;
}

ImuAxesNominal NominalOfImuAxes(const RunDescription& run) {
  ImuAxesNominal n;
  for (int i = 0; i < 3; ++i) {
    n.scale[run.axis_source[i]] = run.scale_mV_per_g[i];
    n.bias[run.axis_source[i]] = run.axis_sign[i] * run.bias_mV[i];
  }
  return n;
}

}  // namespace triadcal
