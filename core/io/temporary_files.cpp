#include "core/io/temporary_files.h"

#include <signal.h>
#include <unistd.h>

#include <cstring>

namespace triadcal {

int TemporaryFiles::Add(const std::string& path) {
  if (path.size() >= kPathBytes) return -1;
  const std::lock_guard<std::mutex> lock(mutex_);
  for (int i = 0; i < kSlots; ++i) {
    if (used_[i].load(std::memory_order_relaxed)) continue;
    std::memcpy(paths_[i], path.c_str(), path.size() + 1);
    used_[i].store(true, std::memory_order_release);  // the path first, then the flag
    return i;
  }
  return -1;
}

void TemporaryFiles::Release(int slot) {
  if (slot < 0 || slot >= kSlots) return;
  const std::lock_guard<std::mutex> lock(mutex_);
  used_[slot].store(false, std::memory_order_release);
}

void TemporaryFiles::UnlinkAll() const noexcept {
  for (int i = 0; i < kSlots; ++i) {
    if (used_[i].load(std::memory_order_acquire)) ::unlink(paths_[i]);
  }
}

void InstallTerminationHandler(void (*handler)(int)) {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_DFL) {
      struct sigaction sa {};
      sa.sa_handler = handler;
      sigemptyset(&sa.sa_mask);
      ::sigaction(sig, &sa, nullptr);
    }
  }
}

void ReraiseWithDefaultAction(int sig) noexcept {
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace triadcal
