// pagmo's NSGA-II for `optimize` with several goals, in a plugin loaded when it runs
// (libtrochomill_nsga2.so): linking pagmo costs every start of the program about 70 ms of
// processor time and 36 MB (its static tables, copied at load), and only this one use needs it.
// The call crosses the plugin's boundary as plain data and C functions.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

namespace trochomill::study_detail {

/// One NSGA-II run: minimise `objectives` values of points x in [lo, hi] (per dimension).
struct Nsga2Call {
  std::size_t dimensions = 0, objectives = 0;
  const double* lo = nullptr;
  const double* hi = nullptr;
  unsigned population = 0, generations = 0, seed = 0;
  void* context = nullptr;
  /// Writes the objectives of x into f; returns false to stop the run (the caller keeps why).
  bool (*fitness)(void* context, const double* x, double* f) = nullptr;
};
/// The plugin's entry, extern "C": 0 when the run ended, 1 when fitness stopped it, 2 when pagmo
/// failed (its message in `error`, at most `error_size` bytes with the terminating zero).
using Nsga2Entry = int (*)(const Nsga2Call* call, char* error, std::size_t error_size);
inline constexpr const char* kNsga2Symbol = "trochomill_nsga2_evolve";

/// Runs NSGA-II through the plugin, calling `fitness` for every point (its exceptions are
/// rethrown here). Throws Error when the plugin cannot be found or loaded (naming where it
/// looked).
void run_nsga2(std::size_t objectives, const std::vector<double>& lo, const std::vector<double>& hi,
               unsigned population, unsigned generations, unsigned seed,
               const std::function<std::vector<double>(const std::vector<double>&)>& fitness);

}  // namespace trochomill::study_detail
