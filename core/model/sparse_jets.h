// theta as Ceres Jets for a function that reads only some of its entries:
// only those are formed, the first `seeded` of them with derivative slots
// 0, 1, ... A whole array of Jets can cost more than the function it feeds
// (a pass with angle_latency wrote 2-6 kB of Jets per sample). The other
// entries are never read; in a build with assertions they hold NaN, so that
// a read would show in every result (the Jacobian tests against automatic
// differentiation over every entry).
#pragma once

#include <limits>
#include <new>
#include <type_traits>

namespace triadcal {

template <typename J, int kMaxEntries = 64>
class SparseJets {
 public:
  // Entries idx[0..count) of th; idx[q] gets derivative slot q for q < seeded.
  SparseJets(const double* th, const int* idx, int count, int seeded) {
    J* t = mutable_data();
#ifndef NDEBUG
    for (int i = 0; i < kMaxEntries; ++i) new (t + i) J(std::numeric_limits<double>::quiet_NaN());
#endif
    for (int q = 0; q < count; ++q) {
      new (t + idx[q]) J(th[idx[q]]);
      if (q < seeded) t[idx[q]].v[q] = 1.0;
    }
  }
  SparseJets(const SparseJets&) = delete;
  SparseJets& operator=(const SparseJets&) = delete;
  const J* data() const { return reinterpret_cast<const J*>(storage_); }

 private:
  J* mutable_data() { return reinterpret_cast<J*>(storage_); }
  static_assert(std::is_trivially_destructible_v<J>);
  alignas(J) unsigned char storage_[kMaxEntries * sizeof(J)];
};

}  // namespace triadcal
