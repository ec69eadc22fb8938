// A Monte Carlo shard (`montecarlo --shard I/N`) and the merge of all N of
// them (`triadcal merge`).
//
// A shard's OUT.json is the ordinary montecarlo output of its own seeds plus
// "shard": {"index": I, "count": N, "items": [begin, end), "settings": what the
// whole job was asked, "truth_si", "crb_si", "records": its runs
// (monte_carlo_records.h)}. The merge checks that the N shards are one job
// (same settings, same CRB bits, every shard once, every seed once), puts the
// runs in seed order and sums them as one process does: the merged OUT.json
// equals the whole job's except the execution fields (threads, ranks, shards,
// time_s).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tools/report/monte_carlo_json.h"

namespace triadcal {

nlohmann::json MonteCarloShardJson(int index, int count, int begin, int end,
                                   const MonteCarloSettings& whole, const MonteCarloResult& part,
                                   const std::vector<MonteCarloRun>& runs);

struct MergedMonteCarlo {
  MonteCarloSettings settings;
  MonteCarloResult result;  // runs kept when settings.per_seed
};

// `shards` are the parsed files, `paths` their names for messages. Throws
// InputError naming the file and what does not fit.
MergedMonteCarlo MergeMonteCarloShards(const std::vector<nlohmann::json>& shards,
                                       const std::vector<std::string>& paths);

}  // namespace triadcal
