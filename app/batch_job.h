// A production line's runs as `triadcal batch` does them: each manifest run
// (app/manifest.h) fitted exactly as `triadcal fit` fits it (app/fit_job.h),
// diagnosed when the manifest asks (app/diagnose_job.h), judged against its
// limits in the units of its own fit (app/acceptance.h), filed as
// DIR/<serial>/<UTC date>[_k]/ (app/calibration_store.h), and one summary
// (app/batch_summary.h). A run that fails is a row of the summary, never the
// end of the batch.
//
// The runs are shared among threads, processes (BatchRanks: MPI ranks, which
// the command line supplies) and shards (BatchSettings::shard, joined by
// MergeBatchShards); each fit is single-threaded so that its result does not
// depend on how the work was split. Rank 0 alone files the runs and writes
// the summary, in manifest order.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/batch_summary.h"
#include "app/fit_job.h"
#include "app/manifest.h"
#include "app/session.h"
#include "app/work_split.h"

namespace triadcal {

// The settings of a batch, each default declared here once.
struct BatchSettings {
  FitSettings fit;   // every run's fit (run single-threaded, see above)
  std::string date;  // the UTC date the runs are filed under, YYYY-MM-DD; "": today
  int threads = 0;   // runs fitted at once by a process (0: its share of the cores)
  Shard shard;       // the part of the manifest this job does (1/1: all)

  // Throws InputError naming the option (as the command line's flag) for a
  // bad setting (--shard, --date, --threads, then the fit's), before any work.
  void Validate() const;
};

// The processes sharing the runs: this one is rank `rank` of `ranks`, `local`
// of them on this machine (they share its cores); `gather` gives rank 0 every
// rank's fitted runs in rank order, the other ranks nothing. The default: a
// job of one process.
struct BatchRanks {
  int rank = 0, ranks = 1, local = 1;
  std::function<std::vector<nlohmann::json>(const nlohmann::json&)> gather =
      [](const nlohmann::json& mine) { return std::vector<nlohmann::json>{mine}; };
};

struct BatchOutcome {
  bool filed = false;             // on rank 0: the runs filed and the summary written
  std::vector<UnitResult> units;  // this shard's runs, in manifest order
  int threads = 0;                // runs fitted at once by each process
  std::string summary_base;       // DIR/summary_<stamp>[_k][_shard-I-of-N]: .csv and .json
  nlohmann::json json;  // the summary as written (without the provenance its writer adds)
};

// Validates the settings, fits the shard's runs of `entries` (read from
// `manifest`) and, on rank 0, files them under out_dir (created) and writes
// the summary. Progress ("3/20 runs" and the fraction done) goes to the
// session's callbacks on rank 0.
BatchOutcome BatchRun(const BatchSettings& s, const std::string& manifest,
                      const std::vector<ManifestEntry>& entries, const std::string& out_dir,
                      const BatchRanks& ranks, const Session& session);

}  // namespace triadcal
