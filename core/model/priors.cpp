#include "core/model/priors.h"

#include <cmath>

#include "core/model/errors.h"

namespace triadcal {
namespace {

// Gyro defaults (file units): scale 10 % of nominal, bias 10 deg/s, angles
// 3 deg, g-sensitivity 1 (deg/s)/g (MEMS datasheets: about 0.1).
double GyroPriorSigma(const RunDescription& run, int j) {
  if (j <= kGKz) return 0.1 * std::abs(run.gyro.value_or(GyroDescription{}).scale[j - kGKx]);
  if (j <= kGW0z) return 10.0;
  if (j <= kGGammaZ) return 180.0;
  return 1.0;
}

}  // namespace

Prior MakePrior(const RunDescription& run, const ParameterLayout& layout) {
  Prior p;
  p.mean = NominalTheta(run, layout);
  p.sigma.resize(layout.size());
  const double k_nom = run.scale_mV_per_g.cwiseAbs().maxCoeff();
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& info = layout.info(i);
    double s = 0.0;  // file units
    if (layout.is_gyro(i)) {
      s = GyroPriorSigma(run, i - layout.gyro_offset());
    } else if (i <= kKz) {
      s = 0.1 * std::abs(run.scale_mV_per_g[i - kKx]);
    } else if (i <= kW0z) {
      s = 0.2 * std::abs(run.scale_mV_per_g[i - kW0x]);
    } else if (i <= kGammaZ) {
      s = 180.0;
    } else if (i <= kKzz) {
      s = 0.02;
    } else if (i <= kDlambda2) {
      s = 180.0;
    } else if (i <= kDz2) {
      s = 50.0;
    } else {
      const EffectSpec& e = GetEffectSpec(*info.effect);
      s = DefaultPriorSigma(e, e.params[i - layout.offset(e.id)], k_nom);
    }
    p.sigma[i] = s * info.si_per_unit;
  }
  for (const auto& [name, sigma] : run.prior_sigma) {
    const int i = layout.IndexOf(name);
    if (i < 0) {
      // Effect parameters of effects not in this layout are fine to list.
      if (name.find('.') != std::string::npos) continue;
      throw InputError(run.yaml_path + ": priors." + name + ": unknown parameter");
    }
    if (!(sigma > 0.0)) {
      throw InputError(run.yaml_path + ": priors." + name + ": sigma must be > 0");
    }
    p.sigma[i] = sigma * layout.info(i).si_per_unit;
  }
  return p;
}

}  // namespace triadcal
