#include "app/work_split.h"

#include <cstdio>

#include "core/model/errors.h"

namespace triadcal {

Shard ParseShard(const std::string& text, const std::string& option) {
  Shard s;
  if (text.empty()) return s;
  int i = 0, n = 0, used = 0;
  if (std::sscanf(text.c_str(), "%d/%d%n", &i, &n, &used) != 2 ||
      used != static_cast<int>(text.size()) || n < 1 || i < 1 || i > n) {
    throw InputError(option + ": expected I/N with 1 <= I <= N, got '" + text + "'");
  }
  s.index = i;
  s.count = n;
  return s;
}

ItemRange ShardRange(int items, const Shard& shard) {
  const long long m = items;
  ItemRange r;
  r.begin = static_cast<int>((shard.index - 1) * m / shard.count);
  r.end = static_cast<int>(shard.index * m / shard.count);
  return r;
}

std::vector<int> RankItems(const ItemRange& range, int rank, int ranks) {
  std::vector<int> out;
  for (int k = range.begin + rank; k < range.end; k += ranks) out.push_back(k);
  return out;
}

}  // namespace triadcal
