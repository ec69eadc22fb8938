// `triadcal batch MANIFEST -o DIR`: a production line's runs (tools/batch/
// manifest.h), each fitted exactly as `triadcal fit` fits it (app/fit_job.h),
// diagnosed when the manifest asks, judged against its limits and filed as
// DIR/<serial>/<UTC date>[_k]/ (tools/batch/calibration_store.h), with one
// summary table (tools/batch/batch_summary.h). A run that fails is a row of the
// summary, never the end of the batch.
//
// The runs are shared among threads, MPI ranks (`mpirun -n R`) and Slurm
// shards (`--shard I/N`, joined by `triadcal merge`); each fit is
// single-threaded so that its result does not depend on how the work was
// split. The ranks send their fits to rank 0, which alone files them and
// writes the summary, in manifest order.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "solvers/estimation/parallel.h"
#include "tools/batch/acceptance.h"
#include "tools/batch/batch_summary.h"
#include "tools/batch/calibration_store.h"
#include "tools/batch/manifest.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "app/diagnose_job.h"
#include "tools/distribution/mpi_context.h"
#include "tools/distribution/work_split.h"
#include "app/fit_job.h"
#include "tools/fit_options.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

struct BatchArgs {
  std::string manifest, out_dir, shard, date;
  int threads = 0;
  FitOptions fit;
};

// What a rank hands to rank 0 for one manifest run: the fit job and, when the
// manifest asks, the diagnose job with its defaults, each run in a session of
// its own (the runs are fitted in parallel; each names its units for its own
// readings, through its layout).
nlohmann::json FitUnit(const FitSettings& settings, const ManifestEntry& e, int item,
                       OutputGuard* guard) {
  const ScopedOutputGuard on(guard);  // this thread's reads are the command's inputs
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json j = {{"item", item},
                      {"status", "fitted"},
                      {"reason", ""},
                      {"warnings", nlohmann::json::array()},
                      {"diagnose", nullptr}};
  try {
    Session session;
    const LoadedRun run = LoadRun(e.run_path, &session);
    j["warnings"] = run.warnings;
    FitSettings fs = settings;
    fs.threads = 1;  // the result must not depend on the split (see above)
    j["calibration"] = FitRun(fs, e.run_path, run, session).json;
    if (e.diagnose) {
      DiagnoseSettings ds;  // `triadcal diagnose` with its defaults
      ds.threads = 1;
      j["diagnose"] = DiagnoseRun(ds, e.run_path, run, nullptr, session).json;
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

// Rank 0: files one fitted run and judges it.
UnitResult FileUnit(const BatchArgs& a, const std::string& date, const ManifestEntry& e,
                    const nlohmann::json& job, const Session& session) {
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
  u.folder = ClaimCalibrationFolder(a.out_dir, e.serial, date);
  u.previous = PreviousCalibration(a.out_dir, e.serial, u.folder);
  const fs::path folder = fs::path(a.out_dir) / u.folder;
  WriteJson(cal, (folder / "calibration.json").string(), session);
  if (!job["diagnose"].is_null()) {
    WriteJson(job["diagnose"], (folder / "diagnose.json").string(), session);
    u.diagnosed = true;
    u.diagnose_selected = job["diagnose"]["selected"].get<std::vector<std::string>>();
  }
  if (!cal.value("converged", false)) {
    u.status = "error";
    // The fit's verdict is an object; its sentence says why (reading it as a
    // string threw: an internal error, exit 3, for any unit not converged).
    const nlohmann::json& verdict = cal.contains("verdict") ? cal["verdict"] : nlohmann::json();
    const nlohmann::json& sentence =
        verdict.is_object() && verdict.contains("sentence") ? verdict["sentence"] : verdict;
    u.reason = "no convergence (" +
               (sentence.is_string() ? sentence.get<std::string>() : std::string("no verdict")) +
               ")";
  } else {
    u.violations = CheckLimits(e.limits, cal["parameters"]);
    u.status = u.violations.empty() ? "pass" : "fail";
    for (const LimitViolation& v : u.violations) {
      u.reason += (u.reason.empty() ? "outside limits: " : "; ") + v.Text();
    }
  }
  if (!u.previous.empty()) {
    const nlohmann::json before = nlohmann::json::parse(
        ReadFile((fs::path(a.out_dir) / u.previous / "calibration.json").string()));
    u.change_sigma = ChangeInSigma(cal["parameters"], before["parameters"]);
    for (auto it = u.change_sigma.begin(); it != u.change_sigma.end(); ++it) {
      if (std::abs(it.value().get<double>()) > std::abs(u.largest_change_sigma) ||
          u.largest_change_parameter.empty()) {
        u.largest_change_sigma = it.value().get<double>();
        u.largest_change_parameter = it.key();
      }
    }
  }
  nlohmann::json unit = UnitResultJson(u);
  unit["limits"] = nlohmann::json::array();
  for (const ParameterLimit& l : e.limits) {
    nlohmann::json jl = {{"parameter", l.parameter}};
    if (l.min) jl["min"] = *l.min;
    if (l.max) jl["max"] = *l.max;
    if (l.sigma_max) jl["sigma_max"] = *l.sigma_max;
    unit["limits"].push_back(jl);
  }
  unit["manifest"] = a.manifest;
  WriteJson(unit, (folder / "unit.json").string(), session);
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

int RunBatch(const BatchArgs& a, Session& session) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string started = UtcStampNow();
  const Shard shard = ParseShard(a.shard);
  const std::string date = a.date.empty() ? UtcDateToday() : a.date;
  CheckDate(date);
  const FitSettings settings = a.fit.Settings();
  const std::vector<ManifestEntry> entries = LoadManifest(a.manifest);
  // On every rank (the same answer on a shared file system), so that a bad
  // DIR stops them all before the gather.
  std::error_code ec;
  fs::create_directories(a.out_dir, ec);
  CheckOutputPath((fs::path(a.out_dir) / "summary.json").string());
  const int threads = a.threads > 0 ? a.threads : std::max(1, DefaultThreads() / MpiLocalSize());
  const ItemRange range = ShardRange(static_cast<int>(entries.size()), shard);
  const std::vector<int> mine = RankItems(range, MpiRank(), MpiSize());

  std::vector<nlohmann::json> jobs(mine.size());
  std::mutex mutex;
  int done = 0;
  ParallelFor(mine.size(), threads, [&](std::size_t k) {
    jobs[k] = FitUnit(settings, entries[mine[k]], mine[k], session.output_guard.get());
    std::lock_guard<std::mutex> lock(mutex);
    ++done;
    if (MpiRoot()) {
      ShowProgress("batch: " + std::to_string(done) + "/" + std::to_string(mine.size()) + " runs",
                   static_cast<double>(done) / mine.size());
    }
  });
  const std::vector<nlohmann::json> parts = GatherJsonOnRoot(nlohmann::json(jobs));
  if (!MpiRoot()) return 0;
  EndProgress();
  std::map<int, nlohmann::json> by_item;
  for (const nlohmann::json& p : parts) {
    for (const nlohmann::json& j : p) {
      const int item = j["item"].get<int>();
      by_item[item] = j;
    }
  }
  std::vector<UnitResult> units;
  for (const auto& [item, job] : by_item) {
    units.push_back(FileUnit(a, date, entries[item], job, session));
  }

  nlohmann::json execution = {
      {"ranks", MpiSize()},
      {"threads_per_rank", threads},
      {"started_utc", started},
      {"time_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}};
  nlohmann::json summary = BatchSummaryJson(a.manifest, a.out_dir, date, units, execution);
  if (!shard.whole()) {
    summary["shard"] = {{"index", shard.index},
                        {"count", shard.count},
                        {"items", {range.begin, range.end}},
                        {"manifest_units", entries.size()}};
  }
  const std::string base = SummaryBase(a.out_dir, started, shard);
  WriteFileAtomically(base + ".csv", BatchSummaryCsv(units));
  WriteJson(summary, base + ".json", session);

  for (const UnitResult& u : units) {
    std::printf("%-16s %-5s %-24s", u.serial.c_str(), u.status.c_str(),
                u.folder.empty() ? "-" : u.folder.c_str());
    if (!u.previous.empty()) {
      std::printf(" change %+.2f sigma (%s)", u.largest_change_sigma,
                  u.largest_change_parameter.c_str());
    }
    if (!u.reason.empty()) std::printf(" %s", u.reason.c_str());
    std::printf("\n");
  }
  const BatchCounts c = CountUnits(units);
  std::printf("batch: %d pass, %d fail, %d error of %zu runs", c.pass, c.fail, c.error,
              units.size());
  if (!shard.whole()) {
    std::printf(" (shard %d/%d of %zu runs)", shard.index, shard.count, entries.size());
  }
  std::printf("; %d rank(s) x %d thread(s), %.1f s\n", MpiSize(), threads,
              execution["time_s"].get<double>());
  std::printf("wrote %s.csv and %s.json\n", base.c_str(), base.c_str());
  return 0;
}

}  // namespace

Command AddBatchCommand(CLI::App& app) {
  auto a = std::make_shared<BatchArgs>();
  Command c;
  c.app = app.add_subcommand(
      "batch", "Fit every run of a manifest, judge it against its limits, file it by serial/date");
  c.app->add_option("manifest", a->manifest, "MANIFEST.csv or MANIFEST.yaml")->required();
  c.app->add_option("-o,--output", a->out_dir, "folder of the calibrations and summaries")
      ->required();
  c.app->add_option("--date", a->date, "file under this UTC date (YYYY-MM-DD) instead of today");
  c.app
      ->add_option("--threads", a->threads,
                   "runs fitted at once per process (0: the cores, shared among the MPI ranks "
                   "on a machine)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.app->add_option("--shard", a->shard,
                    "do shard I of N (1 <= I <= N) of the runs, e.g. $SLURM_ARRAY_TASK_ID/N; "
                    "join the N summaries with `triadcal merge`");
  AddFitOptions(c.app, &a->fit);
  c.run = [a](Session& session) { return RunBatch(*a, session); };
  return c;
}

}  // namespace triadcal
