// `triadcal montecarlo SCENARIO.yaml -n N -o OUT.json`: N simulated runs of a
// scenario through the EKF, the RTS smoother and the batch solver, their error
// scatter against their own sigma and against the Cramer-Rao bound
// (solvers/analysis/monte_carlo.h), in parallel over the cores, over the ranks
// of `mpirun -n R` and over Slurm shards (`--shard I/N`, merged by `triadcal
// merge`); see app/work_split.h for who does which seed.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/model/errors.h"
#include "core/simulation/simulator.h"
#include "solvers/analysis/monte_carlo.h"
#include "solvers/analysis/experiment_design.h"
#include "solvers/analysis/monte_carlo_records.h"
#include "solvers/estimation/parallel.h"
#include "tools/command_util.h"
#include "solvers/estimation/run_problem.h"
#include "tools/commands.h"
#include "app/output_guard.h"
#include "app/work_split.h"
#include "tools/distribution/mpi_context.h"
#include "tools/report/monte_carlo_json.h"
#include "tools/report/monte_carlo_shard.h"

namespace triadcal {
namespace {

// At most this many runs in one job (a million fits; shard a bigger study).
constexpr int kMaxRuns = 1000000;

struct MonteCarloArgs {
  std::string scenario, out_json, report_html, effects, shard;
  std::string estimators = "ekf,rts,batch";
  int runs = 100;
  std::string first_seed_text = "1";
  std::uint64_t first_seed = 1;
  int threads = 0;
  double epoch_s = kDefaultEpoch_s;
  double tolerance = 0.1;
  bool per_seed = false;
};

int RunMonteCarloCommand(MonteCarloArgs a, Session& session) {
  const auto t0 = std::chrono::steady_clock::now();
  a.first_seed = ParseSeed(a.first_seed_text, "--first-seed");
  if (a.runs > 0 && a.first_seed > UINT64_MAX - static_cast<std::uint64_t>(a.runs - 1)) {
    throw InputError("--first-seed: " + std::to_string(a.runs) + " runs from seed " +
                     a.first_seed_text +
                     " pass the largest seed 18446744073709551615 (2^64 - 1): at most " +
                     std::to_string(UINT64_MAX - a.first_seed + 1) + " from there");
  }
  if (!a.report_html.empty()) CheckOutputPath(a.report_html, session, "--report");
  if (a.runs < 1) throw InputError("-n: at least 1 run, got " + std::to_string(a.runs));
  if (a.runs > kMaxRuns) {
    throw InputError("-n: at most " + std::to_string(kMaxRuns) + " runs, got " +
                     std::to_string(a.runs));
  }
  if (!(a.tolerance > 0)) throw InputError("--tolerance: must be > 0");
  if (!(a.tolerance <= 1000.0)) throw InputError("--tolerance: must be at most 1000");
  const Shard shard = ParseShard(a.shard);
  CheckOutputPath(a.out_json, session);
  const Scenario s = LoadScenario(a.scenario);
  session.RecordInput("scenario", a.scenario);
  CheckOverwrite(a.out_json, session);  // before the long work
  MonteCarloOptions opt;
  opt.runs = a.runs;
  opt.first_seed = a.first_seed;
  // A rank's share of the machine: its cores divided among the ranks on it.
  opt.threads = a.threads > 0 ? a.threads : std::max(1, DefaultThreads() / MpiLocalSize());
  opt.estimators = SplitList(a.estimators);
  WithFlags({{"estimators", "--estimators"}}, [&] { CheckEstimators(opt.estimators); return 0; });
  // The gyro's parameters with a gyro block, as `fit` estimates them (the
  // filter leaves them out).
  opt.layout = ParameterLayout(ParseEffectList(a.effects), s.run.gyro.has_value());
  opt.filter.epoch_s = a.epoch_s;
  opt.batch.epoch_s = a.epoch_s;
  opt.keep_runs = a.per_seed;
  const ItemRange range = ShardRange(a.runs, shard);
  const std::vector<int> mine = RankItems(range, MpiRank(), MpiSize());
  if (MpiRoot()) {
    opt.progress = [](int done, int total) {
      ShowProgress("montecarlo: " + std::to_string(done) + "/" + std::to_string(total) + " runs",
                   static_cast<double>(done) / total);
    };
  }

  MonteCarloResult r;
  r.layout = opt.layout;
  r.threads = opt.threads;
  // Every rank computes the CRB (0.1 s), though only rank 0 needs it: a
  // scenario the CRB rejects then fails on every rank alike, and no rank is
  // left waiting for another in the gather below.
  r.truth = TruthInLayout(s, opt.layout);
  r.crb = MonteCarloCrb(s, opt);
  r.crb_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::vector<MonteCarloRun> my_runs = RunMonteCarloSeeds(s, opt, mine);
  // Rank 0 puts every rank's runs back in seed order and sums them as one
  // process would.
  const std::vector<nlohmann::json> parts = GatherJsonOnRoot(MonteCarloRunsJson(my_runs));
  if (!MpiRoot()) return 0;
  EndProgress();
  std::map<std::uint64_t, MonteCarloRun> by_seed;
  for (const nlohmann::json& p : parts) {
    for (MonteCarloRun& run : MonteCarloRunsFromJson(p,
                                                     opt.estimators.size(), r.layout.size(),
                                                     "rank")) {
      by_seed[run.seed] = std::move(run);
    }
  }
  std::vector<MonteCarloRun> runs;
  for (auto& [seed, run] : by_seed) runs.push_back(std::move(run));
  SummariseMonteCarlo(opt.estimators, runs, &r);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  MonteCarloSettings whole;
  whole.scenario = a.scenario;
  whole.effects = a.effects;
  whole.estimators = opt.estimators;
  whole.runs = a.runs;
  whole.first_seed = a.first_seed;
  whole.epoch_s = a.epoch_s;
  whole.tolerance = a.tolerance;
  whole.rate_hz = s.profile.rate_hz;
  whole.duration_s = s.profile.duration_s;
  whole.per_seed = a.per_seed;
  whole.gyro = opt.layout.has_gyro();
  // A shard's own statistics describe its seeds only.
  MonteCarloSettings mine_settings = whole;
  mine_settings.runs = range.end - range.begin;
  mine_settings.first_seed = a.first_seed + range.begin;
  if (a.per_seed || !shard.whole()) r.runs = runs;
  nlohmann::json out = MonteCarloJson(mine_settings, r);
  out["ranks"] = MpiSize();
  if (!shard.whole()) {
    out["shard"] = MonteCarloShardJson(shard.index, shard.count, range.begin, range.end, whole, r,
                                       runs);
  }
  WriteJson(out, a.out_json, session);
  WriteReportIfAsked(a.report_html, out, a.out_json, session);
  PrintMonteCarlo(mine_settings, r, out);
  if (MpiSize() > 1) std::printf("%d MPI ranks of %d threads each\n", MpiSize(), opt.threads);
  if (!shard.whole()) {
    std::printf("shard %d/%d: seeds %llu..%llu of the job's %d; merge the %d shards with "
                "`triadcal merge`\n",
                shard.index, shard.count,
                static_cast<unsigned long long>(a.first_seed + range.begin),
                static_cast<unsigned long long>(a.first_seed + range.end - 1), a.runs,
                shard.count);
  }
  std::printf("wrote %s\n", a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddMonteCarloCommand(CLI::App& app) {
  auto a = std::make_shared<MonteCarloArgs>();
  Command c;
  c.app = app.add_subcommand(
      "montecarlo", "N simulated runs through EKF, RTS and batch: error scatter against sigma and CRB");
  c.app->add_option("scenario", a->scenario, "SCENARIO.yaml")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON")->required();
  c.app->add_option("--report", a->report_html,
                    "also write the HTML report of OUT (one self-contained file)");
  c.app
      ->add_option("-n,--runs", a->runs,
                   "number of runs, 1 to 1000000 (seeds first-seed .. first-seed + n - 1)")
      ->capture_default_str();
  c.app->add_option("--first-seed", a->first_seed_text, "first seed, 0 to 2^64 - 1")
      ->capture_default_str();
  c.app->add_option("--estimators", a->estimators, "comma-separated: ekf, rts, batch")
      ->capture_default_str();
  c.app
      ->add_option("--threads", a->threads,
                   "parallel runs per process (0: the cores, shared among the MPI ranks on a "
                   "machine)")
      ->capture_default_str()
      ->check(kThreadsRange);
  c.app->add_option("--effects", a->effects, "catalogue effects to estimate too, e.g. a,b");
  c.app->add_option("--epoch-s", a->epoch_s, "interval between epochs [s]")->capture_default_str()
      ->check(kEpochRange);
  c.app
      ->add_option("--tolerance", a->tolerance,
                   "relative tolerance of scatter / CRB reported as within or outside, > 0 and at "
                   "most 1000")
      ->capture_default_str();
  c.app->add_flag("--per-seed", a->per_seed, "add every run's errors and sigmas to OUT");
  c.app->add_option("--shard", a->shard,
                    "do shard I of N (1 <= I <= N) of the seeds, e.g. $SLURM_ARRAY_TASK_ID/N; "
                    "merge the N outputs with `triadcal merge`");
  c.run = [a](Session& session) { return RunMonteCarloCommand(*a, session); };
  return c;
}

}  // namespace triadcal
