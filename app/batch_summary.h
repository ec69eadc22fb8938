// The summary of `triadcal batch`: one row per manifest run with its verdict,
//   pass   fitted, converged, inside every limit
//   fail   fitted, converged, outside a limit (the violations name each one)
//   error  not calibrated: the run's one-line input error, or "no convergence"
// its folder, the previous calibration of the unit and the change since then
// in sigma (calibration_store.h). Written as summary_<stamp>.csv for people and
// summary_<stamp>.json for programs; shards write theirs with a "shard"
// object and `triadcal merge` joins them (MergeBatchShards).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/acceptance.h"

namespace triadcal {

struct UnitResult {
  int item = 0;  // index in the manifest (0-based)
  std::string serial, run;
  std::string status;  // "pass", "fail", "error"
  std::string reason;  // "" for pass; the violations or the error otherwise
  std::vector<LimitViolation> violations;
  std::string folder;    // "serial/date[_k]" under DIR; "" when nothing was filed
  std::string previous;  // the previous calibration's folder; "" for a first
  nlohmann::json change_sigma = nlohmann::json::object();  // parameter -> change in sigma
  std::string largest_change_parameter;
  double largest_change_sigma = 0.0;  // signed; 0 without a previous calibration
  bool diagnosed = false;
  std::vector<std::string> diagnose_selected;  // effects the closed loop added
  std::vector<std::string> warnings;           // the run's: loading, and its jobs'
  double seconds = 0.0;                        // execution time (not a result)
};

nlohmann::json UnitResultJson(const UnitResult& u);
UnitResult UnitResultFromJson(const nlohmann::json& j);

// Counts of pass / fail / error.
struct BatchCounts {
  int pass = 0, fail = 0, error = 0;
};
BatchCounts CountUnits(const std::vector<UnitResult>& units);

// CSV: serial,status,reason,folder,previous,largest_change_sigma,
// largest_change_parameter,run (fields with a comma or quote are quoted).
std::string BatchSummaryCsv(const std::vector<UnitResult>& units);

// {"command": "batch", "manifest", "output_dir", "date", "units", "pass",
//  "fail", "error", "results": [...], "execution": {...}} (+ "shard").
nlohmann::json BatchSummaryJson(const std::string& manifest, const std::string& output_dir,
                                const std::string& date, const std::vector<UnitResult>& units,
                                const nlohmann::json& execution);

// Joins the summaries of shards 1..N of one batch into the whole's
// (results in manifest order). Throws InputError naming the file when one is
// missing, repeated, or from another batch.
nlohmann::json MergeBatchShards(const std::vector<nlohmann::json>& shards,
                                const std::vector<std::string>& paths);

}  // namespace triadcal
