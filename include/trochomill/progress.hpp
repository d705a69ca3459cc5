// How a long computation reports progress and is stopped: the caller (the CLI's progress bar
// and Ctrl-C handler, a binding) passes hooks; the library calls `progress` now and then and
// throws Interrupted when `cancel` turns true. Neither is needed: empty hooks do nothing.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>

#include "trochomill/error.hpp"

namespace trochomill {

struct RunHooks {
  /// Called from the calling thread with (work done, work in all), in the computation's units.
  std::function<void(std::size_t, std::size_t)> progress;
  /// When it turns true (a SIGINT handler) the computation stops by throwing Interrupted.
  const std::atomic<bool>* cancel = nullptr;
  /// Reports `done` of `total` every `total / 200` units and throws Interrupted when
  /// cancelled (checked every 256 units).
  void step(std::size_t done, std::size_t total) const {
    if (cancel != nullptr && done % 256 == 0 && cancel->load(std::memory_order_relaxed)) {
      throw Interrupted("interrupted");
    }
    if (progress && total >= 200 && done % (total / 200) == 0) progress(done, total);
  }
};

}  // namespace trochomill
