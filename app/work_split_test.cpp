#include "app/work_split.h"

#include <gtest/gtest.h>

#include <set>

#include "core/model/errors.h"

namespace triadcal {
namespace {

TEST(WorkSplit, ShardsCoverEveryItemOnceInOrder) {
  for (int items : {0, 1, 7, 20, 101}) {
    for (int n : {1, 2, 3, 8}) {
      int next = 0;
      for (int i = 1; i <= n; ++i) {
        const ItemRange r = ShardRange(items, Shard{i, n});
        EXPECT_EQ(r.begin, next) << items << " " << i << "/" << n;
        EXPECT_LE(r.end - r.begin, items / n + 1);
        next = r.end;
      }
      EXPECT_EQ(next, items);
    }
  }
}

TEST(WorkSplit, RanksCoverAShardOnce) {
  const ItemRange r{5, 18};
  std::multiset<int> seen;
  for (int rank = 0; rank < 3; ++rank) {
    for (int k : RankItems(r, rank, 3)) seen.insert(k);
  }
  ASSERT_EQ(seen.size(), 13u);
  for (int k = 5; k < 18; ++k) EXPECT_EQ(seen.count(k), 1u) << k;
  EXPECT_EQ(RankItems(r, 0, 3), (std::vector<int>{5, 8, 11, 14, 17}));
}

TEST(WorkSplit, ParseShard) {
  const Shard s = ParseShard("3/4");
  EXPECT_EQ(s.index, 3);
  EXPECT_EQ(s.count, 4);
  EXPECT_TRUE(ParseShard("").whole());
  for (const char* bad : {"0/4", "5/4", "3", "3/4x", "a/b", "-1/2", "1/0"}) {
    try {
      ParseShard(bad);
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string("--shard: expected I/N with 1 <= I <= N, got '") + bad + "'");
    }
  }
}

}  // namespace
}  // namespace triadcal
