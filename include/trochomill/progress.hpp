// How a long computation reports progress and is stopped: the caller (the CLI's progress bar
// and Ctrl-C handler, a binding) passes hooks; the library names each phase of the work as it
// begins, calls `progress` now and then and, when `cancel` turns true, stops (by throwing
// Interrupted, or as the computation's own documentation says). None is needed: empty hooks
// do nothing.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <mutex>
#include <string_view>

#include "trochomill/error.hpp"

namespace trochomill {

struct RunHooks {
  /// Called with (work done, work in the phase), in the phase's own units (steps, samples,
  /// files). One call at a time, possibly from a worker thread of the computation.
  std::function<void(std::size_t, std::size_t)> progress;
  /// Called when a phase begins ("pre-roll", "window", "writing outputs"...): the progress
  /// calls that follow count that phase's work. From the calling thread.
  std::function<void(std::string_view)> phase;
  /// When it turns true (a SIGINT handler) the computation stops.
  const std::atomic<bool>* cancel = nullptr;

  [[nodiscard]] bool cancelled() const {
    return cancel != nullptr && cancel->load(std::memory_order_relaxed);
  }
  /// Throws Interrupted (with `what` as its message) when cancelled.
  void check(const char* what = "interrupted") const {
    if (cancelled()) throw Interrupted(what);
  }
  void begin(std::string_view name) const {
    if (phase) phase(name);
  }
  /// Reports `done` of `total` every `total / 200` units and throws Interrupted when
  /// cancelled (checked every 256 units).
  void step(std::size_t done, std::size_t total) const {
    if (done % 256 == 0) check();
    if (progress && total >= 200 && done % (total / 200) == 0) progress(done, total);
  }
};

/// Progress of work shared by threads: each thread adds what it finished; the hooks hear of
/// it about 200 times over the whole, one report at a time (a thread that finds another
/// reporting skips its report).
class SharedProgress {
 public:
  SharedProgress(const RunHooks& hooks, std::size_t total)
      : hooks_(hooks), total_(total), every_(total / 200 + 1) {}
  /// Adds `n` units done; reports when a report is due.
  void add(std::size_t n) {
    const std::size_t before = done_.fetch_add(n, std::memory_order_relaxed);
    if (!hooks_.progress || (before + n) / every_ == before / every_) return;
    const std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (lock.owns_lock()) hooks_.progress(std::min(before + n, total_), total_);
  }

 private:
  const RunHooks& hooks_;
  std::size_t total_, every_;
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
};

}  // namespace trochomill
