// `triadcal static RUN.yaml`: the standard static method
// (solvers/static/static_method.h) -- still intervals, averaged positions,
// the readings model fitted to them with the angles, the position labels or
// the gravity norm as the reference -- and, with a gyro block, the gyro's
// calibration from the same positions and three turns (static_gyro.h). The
// settings, the job and the OUT.json; the command prints it.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/run_loading.h"
#include "app/session.h"
#include "solvers/static/static_gyro.h"
#include "solvers/static/static_method.h"

namespace triadcal {

// --reference: "auto" (nullopt: angles when recorded, else labels, else
// none) or one of ReferenceName's; throws InputError("--reference: expected
// auto, angles, labels or none, got 'X'").
std::optional<StaticReference> ParseStaticReference(const std::string& text);
const char* StaticReferenceName(const std::optional<StaticReference>& reference);

// The settings of `static`, each default declared here once (the still
// detection's in StillOptions).
struct StaticSettings {
  std::optional<StaticReference> reference;  // nullopt: auto
  std::vector<std::string> fix;              // held at nominal; "K_ij" stands for all nine
  // 1 sigma orientation error of each position that does not average out
  // (hand placement, table tilt, bench positioning) [deg], 0 to 45.
  double placement_sigma_deg = 0.0;
  StillOptions still;

  // Throws InputError naming the option (as the command line's flag).
  void Validate() const;
};

struct StaticOutcome {
  StaticResult result;
  std::optional<StaticGyroResult> gyro;  // with a gyro block and gyro columns
  std::vector<std::string> warnings;     // also said through the session
  nlohmann::json json;                   // OUT.json of `static` (without the provenance)
};

// Validates the settings and solves `run` (read from run_yaml). A run that
// lacks what the reference needs is an InputError after "--reference NAME: ";
// a gyro that cannot be calibrated is a warning (the accelerometer's result
// stands).
StaticOutcome StaticRun(const StaticSettings& s, const std::string& run_yaml, const LoadedRun& run,
                        const Session& session);

}  // namespace triadcal
