// The NSGA-II plugin (nsga2.hpp): pagmo's nsga2 over a problem whose fitness is the caller's.
// Built as a module library, loaded by `optimize` with several goals only.
#include <cstdio>
#include <exception>
#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <stdexcept>
#include <utility>

#include "nsga2.hpp"

namespace {

using trochomill::study_detail::Nsga2Call;

// The caller's fitness stopped the run: unwinds pagmo's evolve.
struct Stopped {};

struct Problem {
  const Nsga2Call* call = nullptr;
  [[nodiscard]] pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    pagmo::vector_double f(call->objectives);
    if (!call->fitness(call->context, x.data(), f.data())) throw Stopped{};
    return f;
  }
  [[nodiscard]] std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    return {pagmo::vector_double(call->lo, call->lo + call->dimensions),
            pagmo::vector_double(call->hi, call->hi + call->dimensions)};
  }
  [[nodiscard]] pagmo::vector_double::size_type get_nobj() const { return call->objectives; }
};

}  // namespace

extern "C" __attribute__((visibility("default"))) int trochomill_nsga2_evolve(
    const Nsga2Call* call, char* error, std::size_t error_size) {
  try {
    pagmo::problem prob{Problem{call}};
    pagmo::population population(prob, call->population, call->seed);
    pagmo::algorithm algo{pagmo::nsga2(call->generations, 0.95, 10., 0.01, 50., call->seed)};
    population = algo.evolve(population);
    return 0;
  } catch (const Stopped&) {
    return 1;
  } catch (const std::exception& e) {
    if (error_size > 0) std::snprintf(error, error_size, "%s", e.what());
    return 2;
  }
}
