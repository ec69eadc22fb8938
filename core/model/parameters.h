// The parameter vector theta: the 27 base parameters of docs/file-formats.md followed
// by the parameters of each effect switched on in the layout, and, when the run
// carries a gyro triad (SPEC section 10), the 21 gyro parameters last.
//
// Internally every entry is in SI/radians (see units.h); ParameterInfo gives the
// name and the unit used in every file the tool reads or writes, and the factor
// between the two.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/effects.h"

namespace triadcal {

// Base parameters, in the order they occupy at the start of theta.
enum BaseParam : int {
  kKx = 0, kKy, kKz,                    // scale factors            [mV/g]
  kW0x, kW0y, kW0z,                     // zero offsets             [mV]
  kAlphaX, kAlphaY, kBetaX, kBetaZ,     // non-orthogonality angles [rad]
  kGammaY, kGammaZ,
  kKxx, kKxy, kKxz,                     // nonlinearity and cross-  [1/g]
  kKyx, kKyy, kKyz,                     //   coupling K_ij, row-major
  kKzx, kKzy, kKzz,
  kDpsi, kDthetaC, kDlambda2,           // bench set-up errors      [rad]
  kDx2, kDy2, kDz2,                     // lever-arm error, frame 2 [m]
  kNumBaseParams
};

// The gyro block (SPEC section 10), in the order it occupies at gyro_offset():
// scale factors [1: readings per input rate], biases [rad/s], the six
// misalignment angles [rad] in the order of the accelerometer's, and the
// g-sensitivity G_ij [rad/s per g], row-major.
enum GyroParam : int {
  kGKx = 0, kGKy, kGKz,
  kGW0x, kGW0y, kGW0z,
  kGAlphaX, kGAlphaY, kGBetaX, kGBetaZ, kGGammaY, kGGammaZ,
  kGGxx, kGGxy, kGGxz, kGGyx, kGGyy, kGGyz, kGGzx, kGGzy, kGGzz,
  kNumGyroParams
};

struct ParameterInfo {
  std::string name;  // file name: "Kx", "alpha_y", "angle_latency.tau"
  std::string unit;  // unit in files: "mV/g", "arcmin", "ms"
  double si_per_unit;
  std::optional<Effect> effect;  // empty for base parameters
};

// Names and units of the 27 base parameters (docs/file-formats.md).
const std::vector<ParameterInfo>& BaseParameterInfo();
// Names (gyro.Kx, ...) and units of the 21 gyro parameters (SPEC section 10).
const std::vector<ParameterInfo>& GyroParameterInfo();

// The unit the readings are in when nothing else is said (run.yaml columns in mV).
inline constexpr const char* kDefaultReadingsUnit = "mV";
// `unit` with its "mV" replaced by `readings_unit` ("mV/g" -> "counts/g").
std::string InReadingsUnit(const std::string& unit, const std::string& readings_unit);

// Which effects are switched on and where their parameters sit in theta.
//
// The layout of a run names its units for the run's readings: `readings_unit`
// ("mV", "counts" or "mg": core/io/column_mapping.h ReadingsUnit(run)) turns
// "mV/g" into "counts/g" or "mg/g" in every ParameterInfo::unit, so that every
// table, OUT file and message that names a unit through the layout follows
// the readings (a value of the layout, not a process-wide setting).
class ParameterLayout {
 public:
  ParameterLayout();  // base parameters only, readings in mV
  // Effects of the gyro stage act only with the gyro block (without it their
  // parameters are in theta but no model reads them; the commands refuse them).
  explicit ParameterLayout(const std::vector<Effect>& effects, bool gyro = false,
                           const std::string& readings_unit = kDefaultReadingsUnit);
  // The same parameters with the gyro block on or off.
  ParameterLayout WithGyro(bool gyro) const {
    return ParameterLayout(effects_, gyro, readings_unit_);
  }
  // Other effects, the same gyro block and readings unit.
  ParameterLayout WithEffects(const std::vector<Effect>& effects) const {
    return ParameterLayout(effects, has_gyro(), readings_unit_);
  }
  // The unit the readings are in ("mV", "counts", "mg").
  const std::string& readings_unit() const { return readings_unit_; }

  int size() const { return static_cast<int>(info_.size()); }
  const ParameterInfo& info(int i) const { return info_[i]; }
  const std::vector<ParameterInfo>& infos() const { return info_; }
  const std::vector<Effect>& effects() const { return effects_; }

  bool has(Effect e) const { return offset_[static_cast<int>(e)] >= 0; }
  // The gyro block: on when the run carries a gyro triad; its first index.
  bool has_gyro() const { return gyro_offset_ >= 0; }
  int gyro_offset() const { return gyro_offset_; }
  // True for the gyro block's indices.
  bool is_gyro(int i) const { return gyro_offset_ >= 0 && i >= gyro_offset_; }
  // Index in theta of the first parameter of effect e, or -1 when it is off.
  int offset(Effect e) const { return offset_[static_cast<int>(e)]; }
  // Index of a parameter by its file name, or -1.
  int IndexOf(const std::string& name) const;

  // True when some effect of this stage is on (bench_model.h skips a stage
  // without effects).
  bool has_stage(EffectStage s) const { return has_stage_[static_cast<int>(s)]; }
  // The theta indices of the parameters of the effects of stage s, in layout order.
  const std::vector<int>& StageParams(EffectStage s) const {
    return stage_params_[static_cast<int>(s)];
  }
  // The zero-offset terms (EffectSpec::zero_offset_signal) of the effects on:
  // theta[offset + i] multiplies the signal in W0_i, i = 0..2.
  struct ZeroOffsetTerm {
    int offset;
    ZeroOffsetSignal signal;
  };
  const std::vector<ZeroOffsetTerm>& zero_offset_terms() const { return zero_offset_terms_; }

 private:
  std::vector<Effect> effects_;
  std::string readings_unit_ = kDefaultReadingsUnit;
  std::vector<ParameterInfo> info_;
  int offset_[kNumEffects];
  int gyro_offset_ = -1;
  bool has_stage_[kNumEffectStages] = {false, false, false, false};
  std::vector<int> stage_params_[kNumEffectStages];  // StageParams, made with the layout
  std::vector<ZeroOffsetTerm> zero_offset_terms_;
  std::map<std::string, int> index_;
};

// Parameter values in file units, keyed by name (what JSON and YAML files hold).
using NamedValues = std::map<std::string, double>;

// theta (SI) -> file units, and back. FromFileUnits fills only the names present.
NamedValues ToFileUnits(const ParameterLayout& layout, const Eigen::VectorXd& theta);
void SetFromFileUnits(const ParameterLayout& layout, const NamedValues& values,
                      Eigen::VectorXd* theta);

}  // namespace triadcal
