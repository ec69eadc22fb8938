// `triadcal merge SHARD.json... -o OUT.json`: the outputs of the N shards of
// one `montecarlo --shard I/N` or `batch --shard I/N` job as the one output
// the whole job would have written (tools/report/monte_carlo_shard.h,
// app/batch_summary.h). A batch merge also writes OUT.csv beside
// OUT.json.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/batch_summary.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "tools/report/monte_carlo_shard.h"

namespace triadcal {
namespace {

struct MergeArgs {
  std::vector<std::string> shards;
  std::string out_json;
};

int RunMerge(const MergeArgs& a, Session& session) {
  CheckOutputPath(a.out_json, session);
  std::vector<nlohmann::json> shards;
  std::string command;
  for (const std::string& path : a.shards) {
    nlohmann::json j = nlohmann::json::parse(ReadFile(path), nullptr, false);
    if (j.is_discarded() || !j.is_object()) throw InputError(path + ": not valid JSON");
    if (!j.contains("shard") || !j["shard"].is_object()) {
      throw InputError(path +
                       ": shard: missing (not the output of montecarlo or batch with "
                       "--shard I/N)");
    }
    const std::string c = j.value("command", "");
    if (c != "montecarlo" && c != "batch") {
      throw InputError(path + ": command: expected montecarlo or batch, got '" + c + "'");
    }
    if (!command.empty() && c != command) {
      throw InputError(path + ": command: " + c + " shard among " + command + " shards");
    }
    command = c;
    shards.push_back(std::move(j));
    session.NoteInput(path);
  }
  try {
    if (command == "montecarlo") {
      const MergedMonteCarlo m = MergeMonteCarloShards(shards, a.shards);
      nlohmann::json out = MonteCarloJson(m.settings, m.result);
      out["ranks"] = 0;
      for (const nlohmann::json& s : shards)
        out["ranks"] = out["ranks"].get<int>() + s.value("ranks", 1);
      out["shards"] = shards.size();
      WriteJson(out, a.out_json, session);
      PrintMonteCarlo(m.settings, m.result, out);
    } else {
      const nlohmann::json out = MergeBatchShards(shards, a.shards);
      std::vector<UnitResult> units;
      for (const nlohmann::json& r : out["results"]) units.push_back(UnitResultFromJson(r));
      std::string csv = a.out_json;
      if (csv.size() > 5 && csv.compare(csv.size() - 5, 5, ".json") == 0)
        csv.resize(csv.size() - 5);
      csv += ".csv";
      WriteFileAtomically(csv, BatchSummaryCsv(units), session.write_options());
      WriteJson(out, a.out_json, session);
      std::printf("batch: %d pass, %d fail, %d error of %d runs\n", out["pass"].get<int>(),
                  out["fail"].get<int>(), out["error"].get<int>(), out["units"].get<int>());
      std::printf("wrote %s\n", csv.c_str());
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(a.shards[0] + ": shard: malformed (" + std::string(e.what()) + ")");
  }
  std::printf("merged %zu %s shards; wrote %s\n", shards.size(), command.c_str(),
              a.out_json.c_str());
  return 0;
}

}  // namespace

Command AddMergeCommand(CLI::App& app) {
  auto a = std::make_shared<MergeArgs>();
  Command c;
  c.app = app.add_subcommand(
      "merge", "Join the outputs of the shards of a montecarlo or batch job (--shard I/N)");
  c.app->add_option("shards", a->shards, "the N shard outputs (JSON)")->required();
  c.app->add_option("-o,--output", a->out_json, "output JSON (batch: and OUT.csv)")->required();
  c.run = [a](Session& session) { return RunMerge(*a, session); };
  return c;
}

}  // namespace triadcal
