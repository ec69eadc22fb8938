// Where `triadcal batch` files calibrations: DIR/<serial>/<UTC date>/ for the
// first of a day, DIR/<serial>/<date>_2/, _3/ ... for later ones, so that no
// calibration is ever overwritten. A folder is claimed by creating it (an
// atomic mkdir), so ranks, shards and reruns never share one.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace triadcal {

// "2026-11-23" (UTC, now) and "20261123T074512Z".
std::string UtcDateToday();
std::string UtcStampNow();
// Throws InputError("--date: ...") unless `date` is YYYY-MM-DD.
void CheckDate(const std::string& date);

// Creates DIR/serial/date (or the first free date_k) and returns
// "serial/<folder>" relative to DIR. Throws InputError when DIR cannot be written.
std::string ClaimCalibrationFolder(const std::string& dir, const std::string& serial,
                                   const std::string& date);

// The latest folder of `serial` filed before `folder` ("serial/<folder>", in
// date then _k order) whose calibration.json converged; "" if none.
std::string PreviousCalibration(const std::string& dir, const std::string& serial,
                                const std::string& folder);

// Per parameter estimated in both calibrations ("parameters" objects, file
// units): the change now - before in units of its sigma,
//   (v_now - v_before) / sqrt(sigma_now^2 + sigma_before^2),
// the two being independent runs (a unit that did not change gives N(0, 1)).
nlohmann::json ChangeInSigma(const nlohmann::json& now, const nlohmann::json& before);

}  // namespace triadcal
