// A minimal parallel loop over independent items (intervals of a run) on the
// machine's cores, for the passes over the samples that do not depend on each
// other (the batch solver's relinearisation, the smoother's fixed-point passes).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace triadcal {

inline int DefaultThreads() {
  return std::max(1u, std::thread::hardware_concurrency());
}

// Calls fn(i) for i in [0, n) on up to `threads` threads; items are handed out
// in chunks so that neighbours share caches.
template <typename Fn>
void ParallelFor(std::size_t n, int threads, Fn fn) {
  threads = std::max(1, std::min<int>(threads, static_cast<int>(n)));
  if (threads <= 1) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  const std::size_t chunk = std::max<std::size_t>(1, n / (16 * threads));
  auto worker = [&] {
    for (;;) {
      const std::size_t begin = next.fetch_add(chunk);
      if (begin >= n) return;
      const std::size_t end = std::min(n, begin + chunk);
      for (std::size_t i = begin; i < end; ++i) fn(i);
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
}

}  // namespace triadcal
