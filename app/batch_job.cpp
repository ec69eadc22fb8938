#include "app/batch_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

#include "app/acceptance.h"
#include "app/calibration_store.h"
#include "app/diagnose_job.h"
#include "app/output_guard.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "solvers/estimation/parallel.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

// What a rank hands to rank 0 for one manifest run: the fit job and, when the
// manifest asks, the diagnose job with its defaults, each run in a session of
// its own (the runs are fitted in parallel; each names its units for its own
// readings, through its layout) that notes what it loads into the command's
// guard.
nlohmann::json FitUnit(const FitSettings& settings, const ManifestEntry& e, int item,
                       const std::shared_ptr<OutputGuard>& guard) {
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json j = {{"item", item},
                      {"status", "fitted"},
                      {"reason", ""},
                      {"warnings", nlohmann::json::array()},
                      {"diagnose", nullptr}};
  try {
    Session session;
    session.output_guard = guard;
    const LoadedRun run = LoadRun(e.run_path, &session, 1);  // one thread a run, as its fit
    j["warnings"] = run.warnings;
    FitSettings fs = settings;
    fs.threads = 1;  // the result must not depend on the split (see above)
    FitOutcome fit = FitRun(fs, e.run_path, run, session);
    j["calibration"] = std::move(fit.json);
    for (const std::string& w : fit.warnings) j["warnings"].push_back(w);
    if (e.diagnose) {
      DiagnoseSettings ds;  // `triadcal diagnose` with its defaults
      ds.threads = 1;
      DiagnoseOutcome d = DiagnoseRun(ds, e.run_path, run, nullptr, session);
      j["diagnose"] = std::move(d.json);
      for (const std::string& w : d.warnings) j["warnings"].push_back(w);
    }
  } catch (const InputError& err) {
    j["status"] = "error";
    j["reason"] = err.what();
  } catch (const std::exception& err) {
    j["status"] = "error";
    j["reason"] = std::string("internal error: ") + err.what();
  }
  j["time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return j;
}

// The calibration's verdict: inside every limit (pass) or not (fail), each
// limit judged in the unit the fit gives its parameter (the readings' unit,
// from its layout); not converged (error).
void Judge(const ManifestEntry& e, const nlohmann::json& cal, UnitResult* u) {
  if (!cal.value("converged", false)) {
    u->status = "error";
    const nlohmann::json& verdict = cal.contains("verdict") ? cal["verdict"] : nlohmann::json();
    const nlohmann::json& sentence =
        verdict.is_object() && verdict.contains("sentence") ? verdict["sentence"] : verdict;
    u->reason = "no convergence (" +
                (sentence.is_string() ? sentence.get<std::string>() : std::string("no verdict")) +
                ")";
    return;
  }
  u->violations = CheckLimits(e.limits, cal["parameters"]);
  u->status = u->violations.empty() ? "pass" : "fail";
  for (const LimitViolation& v : u->violations) {
    u->reason += (u->reason.empty() ? "outside limits: " : "; ") + v.Text();
  }
}

// The change since the unit's previous calibration, in sigma.
void CompareWithPrevious(const std::string& out_dir, const nlohmann::json& cal,
                         const Session& session, UnitResult* u) {
  if (u->previous.empty()) return;
  const std::string previous = (fs::path(out_dir) / u->previous / "calibration.json").string();
  const nlohmann::json before = nlohmann::json::parse(ReadFile(previous));
  session.NoteInput(previous);
  u->change_sigma = ChangeInSigma(cal["parameters"], before["parameters"]);
  for (auto it = u->change_sigma.begin(); it != u->change_sigma.end(); ++it) {
    if (std::abs(it.value().get<double>()) > std::abs(u->largest_change_sigma) ||
        u->largest_change_parameter.empty()) {
      u->largest_change_sigma = it.value().get<double>();
      u->largest_change_parameter = it.key();
    }
  }
}

// Rank 0: files one fitted run (calibration.json, diagnose.json, unit.json)
// and judges it.
UnitResult FileUnit(const std::string& manifest, const std::string& out_dir,
                    const std::string& date, const ManifestEntry& e, const nlohmann::json& job,
                    const Session& session) {
  UnitResult u;
  u.item = job["item"].get<int>();
  u.serial = e.serial;
  u.run = e.run;
  u.warnings = job["warnings"].get<std::vector<std::string>>();
  u.seconds = job["time_s"].get<double>();
  if (job["status"] == "error") {
    u.status = "error";
    u.reason = job["reason"].get<std::string>();
    return u;
  }
  const nlohmann::json& cal = job["calibration"];
  u.folder = ClaimCalibrationFolder(out_dir, e.serial, date);
  u.previous = PreviousCalibration(out_dir, e.serial, u.folder);
  const fs::path folder = fs::path(out_dir) / u.folder;
  WriteJsonFile(cal, (folder / "calibration.json").string(), session);
  if (!job["diagnose"].is_null()) {
    WriteJsonFile(job["diagnose"], (folder / "diagnose.json").string(), session);
    u.diagnosed = true;
    u.diagnose_selected = job["diagnose"]["selected"].get<std::vector<std::string>>();
  }
  Judge(e, cal, &u);
  CompareWithPrevious(out_dir, cal, session, &u);
  nlohmann::json unit = UnitResultJson(u);
  unit["limits"] = LimitsJson(e.limits);
  unit["manifest"] = manifest;
  WriteJsonFile(unit, (folder / "unit.json").string(), session);
  return u;
}

// DIR/summary_<stamp>[_k][_shard-I-of-N] without an existing .csv or .json.
std::string SummaryBase(const std::string& dir, const std::string& stamp, const Shard& shard) {
  const std::string tail = shard.whole() ? ""
                                         : "_shard-" + std::to_string(shard.index) + "-of-" +
                                               std::to_string(shard.count);
  for (int k = 1;; ++k) {
    const std::string base =
        (fs::path(dir) / ("summary_" + stamp + (k > 1 ? "_" + std::to_string(k) : "") + tail))
            .string();
    if (!fs::exists(base + ".csv") && !fs::exists(base + ".json")) return base;
  }
}

}  // namespace

void BatchSettings::Validate() const {
  if (shard.count < 1 || shard.index < 1 || shard.index > shard.count) {
    throw InputError("--shard: expected I/N with 1 <= I <= N, got '" +
                     std::to_string(shard.index) + "/" + std::to_string(shard.count) + "'");
  }
  if (!date.empty()) CheckDate(date);
  if (threads < 0 || threads > 1024) {
    throw InputError("--threads: Value " + std::to_string(threads) + " not in range 0 to 1024");
  }
  fit.Validate();
}

BatchOutcome BatchRun(const BatchSettings& s, const std::string& manifest,
                      const std::vector<ManifestEntry>& entries, const std::string& out_dir,
                      const BatchRanks& ranks, const Session& session) {
  s.Validate();
  const auto t0 = std::chrono::steady_clock::now();
  const std::string started = UtcStampNow();
  const std::string date = s.date.empty() ? UtcDateToday() : s.date;
  BatchOutcome o;
  o.threads = s.threads > 0 ? s.threads : std::max(1, DefaultThreads() / ranks.local);
  const ItemRange range = ShardRange(static_cast<int>(entries.size()), s.shard);
  const std::vector<int> mine = RankItems(range, ranks.rank, ranks.ranks);

  std::vector<nlohmann::json> jobs(mine.size());
  std::mutex mutex;
  int done = 0;
  ParallelFor(mine.size(), o.threads, [&](std::size_t k) {
    jobs[k] = FitUnit(s.fit, entries[mine[k]], mine[k], session.output_guard);
    std::lock_guard<std::mutex> lock(mutex);
    ++done;
    if (ranks.rank != 0) return;
    if (session.stage) {
      session.stage(std::to_string(done) + "/" + std::to_string(mine.size()) + " runs");
    }
    if (session.fraction) session.fraction(static_cast<double>(done) / mine.size());
  });
  const std::vector<nlohmann::json> parts = ranks.gather(nlohmann::json(jobs));
  if (ranks.rank != 0) return o;
  std::map<int, nlohmann::json> by_item;
  for (const nlohmann::json& p : parts) {
    for (const nlohmann::json& j : p) by_item[j["item"].get<int>()] = j;
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);  // a library caller's; the command checked it
  for (const auto& [item, job] : by_item) {
    o.units.push_back(FileUnit(manifest, out_dir, date, entries[item], job, session));
  }

  const nlohmann::json execution = {
      {"ranks", ranks.ranks},
      {"threads_per_rank", o.threads},
      {"started_utc", started},
      {"time_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}};
  o.json = BatchSummaryJson(manifest, out_dir, date, o.units, execution);
  if (!s.shard.whole()) {
    o.json["shard"] = {{"index", s.shard.index},
                       {"count", s.shard.count},
                       {"items", {range.begin, range.end}},
                       {"manifest_units", entries.size()}};
  }
  o.summary_base = SummaryBase(out_dir, started, s.shard);
  WriteFileAtomically(o.summary_base + ".csv", BatchSummaryCsv(o.units), session.write_options());
  WriteJsonFile(o.json, o.summary_base + ".json", session);
  o.filed = true;
  return o;
}

}  // namespace triadcal
