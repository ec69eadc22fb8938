// The temporaries a process is writing (core/io/file_util.h WriteFileAtomically),
// for a signal handler to remove. Core defines the registry and never makes
// one: the executable owns the process's one instance (tools/main.cpp), installs
// the handler (InstallTerminationHandler) and passes the instance to the writers
// (WriteOptions::temporaries, through its Session). A library caller or Python
// that passes none gets no removal on a signal; a temporary left behind is
// removed by the next write of the same output (RemoveStaleTemporaries).
//
//   triadcal::TemporaryFiles g_temporaries;        // static storage
//   extern "C" void OnSignal(int sig) {
//     g_temporaries.UnlinkAll();
//     triadcal::ReraiseWithDefaultAction(sig);
//   }
//   ... triadcal::InstallTerminationHandler(&OnSignal);
#pragma once

#include <atomic>
#include <cstddef>
#include <mutex>
#include <string>

namespace triadcal {

class TemporaryFiles {
 public:
  // Fixed storage: the handler may only call async-signal-safe functions (no
  // allocation, no lock).
  static constexpr int kSlots = 16;
  static constexpr std::size_t kPathBytes = 4096;

  // Registers `path` and returns its slot; -1 when every slot is taken or the
  // path is longer than kPathBytes - 1 (the handler does not know it then).
  // Thread-safe.
  int Add(const std::string& path);
  // Forgets the temporary of `slot` (-1: nothing). Thread-safe.
  void Release(int slot);
  // Unlinks every temporary registered now. Async-signal-safe: for a handler.
  void UnlinkAll() const noexcept;

 private:
  static_assert(std::atomic<bool>::is_always_lock_free, "a signal handler reads the flags");
  std::mutex mutex_;  // between Add and Release; the handler takes no lock
  char paths_[kSlots][kPathBytes] = {};
  std::atomic<bool> used_[kSlots] = {};
};

// Registers a temporary for its lifetime (registry may be null: nothing is
// registered).
class TemporaryRegistration {
 public:
  TemporaryRegistration(TemporaryFiles* registry, const std::string& path)
      : registry_(registry), slot_(registry ? registry->Add(path) : -1) {}
  ~TemporaryRegistration() {
    if (registry_) registry_->Release(slot_);
  }
  TemporaryRegistration(const TemporaryRegistration&) = delete;
  TemporaryRegistration& operator=(const TemporaryRegistration&) = delete;

 private:
  TemporaryFiles* registry_;
  int slot_;
};

// Installs `handler` for SIGINT, SIGTERM and SIGHUP, each where its action is
// the default one (a signal the caller ignores or handles stays so).
void InstallTerminationHandler(void (*handler)(int));

// For the end of such a handler: restores the default action of `sig` and
// raises it again, so the process ends as the signal would have ended it.
void ReraiseWithDefaultAction(int sig) noexcept;

}  // namespace triadcal
