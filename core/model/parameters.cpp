#include "core/model/parameters.h"

#include "core/model/units.h"

namespace triadcal {

const std::vector<ParameterInfo>& BaseParameterInfo() {
  static const std::vector<ParameterInfo> info = [] {
    std::vector<ParameterInfo> v;
    auto add = [&v](const char* name, const char* unit, double f) {
      v.push_back({name, unit, f, std::nullopt});
    };
    for (const char* n : {"Kx", "Ky", "Kz"}) add(n, "mV/g", 1.0);
    for (const char* n : {"W0x", "W0y", "W0z"}) add(n, "mV", 1.0);
    for (const char* n : {"alpha_x", "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z"}) {
      add(n, "arcmin", kArcminToRad);
    }
    for (const char* n : {"Kxx", "Kxy", "Kxz", "Kyx", "Kyy", "Kyz", "Kzx", "Kzy", "Kzz"}) {
      add(n, "1/g", 1.0);
    }
    for (const char* n : {"dpsi", "dtheta_c", "dlambda2"}) add(n, "arcmin", kArcminToRad);
    for (const char* n : {"dx2", "dy2", "dz2"}) add(n, "mm", kMmToM);
    return v;
  }();
  return info;
}

const std::vector<ParameterInfo>& GyroParameterInfo() {
  static const std::vector<ParameterInfo> info = [] {
    std::vector<ParameterInfo> v;
    auto add = [&v](const std::string& name, const char* unit, double f) {
      v.push_back({"gyro." + name, unit, f, std::nullopt});
    };
    for (const char* n : {"Kx", "Ky", "Kz"}) add(n, "1", 1.0);
    for (const char* n : {"W0x", "W0y", "W0z"}) add(n, "deg/s", kDegToRad);
    for (const char* n : {"alpha_x", "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z"}) {
      add(n, "arcmin", kArcminToRad);
    }
    for (const char* n : {"Gxx", "Gxy", "Gxz", "Gyx", "Gyy", "Gyz", "Gzx", "Gzy", "Gzz"}) {
      add(n, "(deg/s)/g", kDegToRad);
    }
    return v;
  }();
  return info;
}

ParameterLayout::ParameterLayout() : ParameterLayout(std::vector<Effect>{}) {}

std::string InReadingsUnit(const std::string& unit, const std::string& name) {
  const std::size_t at = unit.find("mV");
  if (at == std::string::npos || name == "mV") return unit;
  return unit.substr(0, at) + name + unit.substr(at + 2);
}

ParameterLayout::ParameterLayout(const std::vector<Effect>& effects, bool gyro,
                                 const std::string& readings_unit)
    : readings_unit_(readings_unit) {
  info_ = BaseParameterInfo();
  for (ParameterInfo& p : info_) p.unit = InReadingsUnit(p.unit, readings_unit_);
  for (int i = 0; i < kNumEffects; ++i) offset_[i] = -1;
  for (Effect e : effects) {
    if (offset_[static_cast<int>(e)] >= 0) continue;  // listed twice
    effects_.push_back(e);
    offset_[static_cast<int>(e)] = static_cast<int>(info_.size());
    const EffectSpec& spec = GetEffectSpec(e);
    has_stage_[static_cast<int>(spec.stage)] = true;
    if (spec.zero_offset_signal != ZeroOffsetSignal::kNone) {
      zero_offset_terms_.push_back({offset_[static_cast<int>(e)], spec.zero_offset_signal});
    }
    for (const ParamSpec& p : spec.params) {
      stage_params_[static_cast<int>(spec.stage)].push_back(static_cast<int>(info_.size()));
      info_.push_back(
          {spec.name + "." + p.name, InReadingsUnit(p.unit, readings_unit_), p.si_per_unit, e});
    }
  }
  if (gyro) {
    gyro_offset_ = size();
    for (const ParameterInfo& p : GyroParameterInfo()) info_.push_back(p);
  }
  for (int i = 0; i < size(); ++i) index_[info_[i].name] = i;
}

int ParameterLayout::IndexOf(const std::string& name) const {
  auto it = index_.find(name);
  return it == index_.end() ? -1 : it->second;
}

NamedValues ToFileUnits(const ParameterLayout& layout, const Eigen::VectorXd& theta) {
  NamedValues out;
  for (int i = 0; i < layout.size(); ++i) {
    out[layout.info(i).name] = theta[i] / layout.info(i).si_per_unit;
  }
  return out;
}

void SetFromFileUnits(const ParameterLayout& layout, const NamedValues& values,
                      Eigen::VectorXd* theta) {
  for (const auto& [name, value] : values) {
    const int i = layout.IndexOf(name);
    if (i >= 0) (*theta)[i] = value * layout.info(i).si_per_unit;
  }
}

}  // namespace triadcal
