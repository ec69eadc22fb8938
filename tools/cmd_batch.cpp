// `triadcal batch MANIFEST -o DIR`: the batch job (app/batch_job.h) on this
// process's share of the runs (MPI ranks, `mpirun -n R`; Slurm shards,
// `--shard I/N`, joined by `triadcal merge`), and its summary table.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/batch_job.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/distribution/mpi_context.h"
#include "tools/fit_options.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

struct BatchArgs {
  std::string manifest, out_dir, shard;
  FitOptions fit;
  BatchSettings settings;  // date and threads, filled by CLI11 directly
};

void PrintBatch(const BatchOutcome& o) {
  for (const UnitResult& u : o.units) {
    std::printf("%-16s %-5s %-24s", u.serial.c_str(), u.status.c_str(),
                u.folder.empty() ? "-" : u.folder.c_str());
    if (!u.previous.empty()) {
      std::printf(" change %+.2f sigma (%s)", u.largest_change_sigma,
                  u.largest_change_parameter.c_str());
    }
    if (!u.reason.empty()) std::printf(" %s", u.reason.c_str());
    std::printf("\n");
  }
  const BatchCounts c = CountUnits(o.units);
  std::printf("batch: %d pass, %d fail, %d error of %zu runs", c.pass, c.fail, c.error,
              o.units.size());
  if (o.json.contains("shard")) {
    const nlohmann::json& sh = o.json["shard"];
    std::printf(" (shard %d/%d of %d runs)", sh["index"].get<int>(), sh["count"].get<int>(),
                sh["manifest_units"].get<int>());
  }
  const nlohmann::json& x = o.json["execution"];
  std::printf("; %d rank(s) x %d thread(s), %.1f s\n", x["ranks"].get<int>(), o.threads,
              x["time_s"].get<double>());
  std::printf("wrote %s.csv and %s.json\n", o.summary_base.c_str(), o.summary_base.c_str());
}

int RunBatch(BatchArgs a, Session& session) {
  BatchSettings& s = a.settings;
  s.shard = ParseShard(a.shard);
  s.fit = a.fit.Settings();
  s.Validate();
  const std::vector<ManifestEntry> entries = LoadManifest(a.manifest);
  session.NoteInput(a.manifest);
  // On every rank (the same answer on a shared file system), so that a bad
  // DIR stops them all before the gather.
  std::error_code ec;
  fs::create_directories(a.out_dir, ec);
  CheckOutputPath((fs::path(a.out_dir) / "summary.json").string(), session);
  BatchRanks ranks;
  ranks.rank = MpiRank();
  ranks.ranks = MpiSize();
  ranks.local = MpiLocalSize();
  ranks.gather = GatherJsonOnRoot;
  std::string done;
  Session batching = session;
  batching.stage = [&](const std::string& x) { done = x; };
  batching.fraction = [&](double x) { ShowProgress("batch: " + done, x); };
  const BatchOutcome o = BatchRun(s, a.manifest, entries, a.out_dir, ranks, batching);
  if (!o.filed) return 0;
  EndProgress();
  PrintBatch(o);
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
  c.app->add_option("--date", a->settings.date,
                    "file under this UTC date (YYYY-MM-DD) instead of today");
  c.app
      ->add_option("--threads", a->settings.threads,
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
