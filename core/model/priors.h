// Weak priors on theta (docs/method.md, batch block 4): mean = the run's nominal
// values, sigma = datasheet-like spreads, overridable per parameter with the
// `priors:` key of run.yaml (file units). The estimators start from them and the
// observability analysis measures what the data add to them.
//
// Defaults (file units):
//   Kx Ky Kz          10 % of the nominal scale          mV/g
//   W0x W0y W0z       0.2 g worth of nominal scale        mV
//   six angles        180 (3 deg)                         arcmin
//   K_ij              0.02                                1/g
//   dpsi dtheta_c dlambda2   180 (3 deg)                  arcmin
//   dx2 dy2 dz2       50                                  mm
//   gyro.K*           10 % of the gyro's nominal scale        1
//   gyro.W0*          10                                      deg/s
//   gyro angles       180 (3 deg)                             arcmin
//   gyro.G*           1                                       (deg/s)/g
//   effects           ParamSpec::prior_sigma of the catalogue (effects.cpp):
//                     angle_latency.tau 20 ms, encoder_harmonic 10 arcmin,
//                     axis_nonintersection.d 10 mm, axis_nonperpendicularity.eps
//                     30 arcmin, size_effect 20 mm, thermal_drift 10 mV/min,
//                     thermal_drift_temp 10 mV/degC, scale_asymmetry 5 % of the
//                     nominal scale (largest |K_i|).
#pragma once

#include <Eigen/Core>

#include "core/model/parameters.h"
#include "core/model/run_description.h"

namespace triadcal {

struct Prior {
  Eigen::VectorXd mean;   // SI
  Eigen::VectorXd sigma;  // SI
};

// Throws InputError when run.prior_sigma names an unknown parameter or a
// sigma <= 0.
Prior MakePrior(const RunDescription& run, const ParameterLayout& layout);

}  // namespace triadcal
