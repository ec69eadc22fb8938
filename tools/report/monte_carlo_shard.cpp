#include "tools/report/monte_carlo_shard.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "core/model/errors.h"
#include "solvers/analysis/monte_carlo_records.h"

namespace triadcal {
namespace {

std::vector<Effect> EffectsFromNames(const std::string& list, const std::string& where) {
  std::vector<Effect> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    try {
      out.push_back(EffectFromName(item));
    } catch (const std::invalid_argument& e) {
      throw InputError(where + ": " + e.what());
    }
  }
  return out;
}

}  // namespace

nlohmann::json MonteCarloShardJson(int index, int count, int begin, int end,
                                   const MonteCarloSettings& whole, const MonteCarloResult& part,
                                   const std::vector<MonteCarloRun>& runs) {
  return {{"index", index},
          {"count", count},
          {"items", {begin, end}},
          {"settings", MonteCarloSettingsJson(whole)},
          {"truth_si", ExactJson(part.truth)},
          {"crb_si", ExactJson(part.crb)},
          {"records", MonteCarloRunsJson(runs)}};
}

MergedMonteCarlo MergeMonteCarloShards(const std::vector<nlohmann::json>& shards,
                                       const std::vector<std::string>& paths) {
  MergedMonteCarlo m;
  const nlohmann::json& first = shards.at(0)["shard"];
  m.settings = MonteCarloSettingsFromJson(first["settings"], paths[0] + ": shard");
  const MonteCarloSettings& s = m.settings;
  m.result.layout = ParameterLayout(
      EffectsFromNames(s.effects, paths[0] + ": shard.settings.effects"), s.gyro);
  const int n = m.result.layout.size();
  m.result.truth = ExactVector(first["truth_si"], n, paths[0] + ": shard.truth_si");
  m.result.crb = ExactVector(first["crb_si"], n, paths[0] + ": shard.crb_si");
  const int count = first.value("count", 0);
  std::vector<int> owner(std::max(count, 0), -1);
  std::vector<std::vector<MonteCarloRun>> parts(owner.size());
  double seconds = 0.0;
  for (std::size_t f = 0; f < shards.size(); ++f) {
    const std::string& path = paths[f];
    const nlohmann::json& sh = shards[f]["shard"];
    if (sh["settings"] != first["settings"]) {
      throw InputError(path + ": shard.settings: not the job of " + paths[0] +
                       " (settings differ)");
    }
    if (sh["crb_si"] != first["crb_si"] || sh["truth_si"] != first["truth_si"]) {
      throw InputError(path + ": shard.crb_si: differs from " + paths[0] +
                       " (another scenario file or build?)");
    }
    const int c = sh.value("count", 0), i = sh.value("index", 0);
    if (c != count || i < 1 || i > count) {
      throw InputError(path + ": shard: " + std::to_string(i) + "/" + std::to_string(c) +
                       " does not belong to a job of " + std::to_string(count) + " shards");
    }
    if (owner[i - 1] >= 0) {
      throw InputError(path + ": shard: " + std::to_string(i) + "/" + std::to_string(count) +
                       " given twice (also " + paths[owner[i - 1]] + ")");
    }
    owner[i - 1] = static_cast<int>(f);
    const int begin = sh["items"].at(0).get<int>(), end = sh["items"].at(1).get<int>();
    parts[i - 1] = MonteCarloRunsFromJson(sh["records"], s.estimators.size(), n, path + ": shard");
    if (static_cast<int>(parts[i - 1].size()) != end - begin) {
      throw InputError(path + ": shard.records: " + std::to_string(parts[i - 1].size()) +
                       " runs for seeds items [" + std::to_string(begin) + ", " +
                       std::to_string(end) + ")");
    }
    for (int k = begin; k < end; ++k) {
      if (parts[i - 1][k - begin].seed != s.first_seed + static_cast<std::uint64_t>(k)) {
        throw InputError(path + ": shard.records: seed " +
                         std::to_string(parts[i - 1][k - begin].seed) + " where seed " +
                         std::to_string(s.first_seed + k) + " was expected");
      }
    }
    if (shards[f].contains("time_s")) seconds += shards[f]["time_s"].value("total", 0.0);
    m.result.threads = std::max(m.result.threads, shards[f].value("threads", 1));
  }
  std::vector<MonteCarloRun> runs;
  for (int i = 0; i < count; ++i) {
    if (owner[i] < 0) {
      throw InputError(paths[0] + ": shard: shard " + std::to_string(i + 1) + "/" +
                       std::to_string(count) + " is missing from the merge");
    }
    for (MonteCarloRun& r : parts[i]) runs.push_back(std::move(r));
  }
  if (static_cast<int>(runs.size()) != s.runs) {
    throw InputError(paths[0] + ": shard: the shards hold " + std::to_string(runs.size()) +
                     " runs, the job " + std::to_string(s.runs));
  }
  SummariseMonteCarlo(s.estimators, runs, &m.result);
  if (s.per_seed) m.result.runs = std::move(runs);
  m.result.seconds = seconds;
  m.result.crb_seconds = shards[0].contains("time_s") ? shards[0]["time_s"].value("crb", 0.0) : 0.0;
  return m;
}

}  // namespace triadcal
