// Which items of a job (Monte Carlo seeds, manifest runs) a Slurm shard and an
// MPI rank do.
//
// A shard "I/N" (1 <= I <= N, e.g. SLURM_ARRAY_TASK_ID of `--array=1-N`) takes
// the contiguous block of items [floor((I-1) M / N), floor(I M / N)) of M
// items, so that a shard's output names a range of seeds. Inside a shard (or
// the whole job) rank r of R takes every R-th item starting at r, which keeps
// the ranks' loads even when items differ in cost. Results are gathered and
// re-ordered by item, so neither split changes what is computed.
#pragma once

#include <string>
#include <vector>

namespace triadcal {

struct Shard {
  int index = 1;  // I, 1-based
  int count = 1;  // N
  bool whole() const { return count == 1; }
};

// "I/N" -> Shard; "" -> 1/1. Throws InputError("OPTION: expected I/N with
// 1 <= I <= N, got 'TEXT'").
Shard ParseShard(const std::string& text, const std::string& option = "--shard");

// The items [begin, end) of `items` that shard takes.
struct ItemRange {
  int begin = 0, end = 0;
};
ItemRange ShardRange(int items, const Shard& shard);

// Items of [range.begin, range.end) that rank `rank` of `ranks` takes.
std::vector<int> RankItems(const ItemRange& range, int rank, int ranks);

}  // namespace triadcal
