// Loads the NSGA-II plugin (nsga2.hpp) on first use and runs it.
#include "nsga2.hpp"

#include <fmt/format.h>

#include <exception>
#include <string>

#include "trochomill/common/plugin.hpp"
#include "trochomill/error.hpp"

namespace trochomill::study_detail {
namespace {

struct Context {
  const std::function<std::vector<double>(const std::vector<double>&)>* fitness = nullptr;
  std::size_t dimensions = 0, objectives = 0;
  std::exception_ptr failure;
};

bool call_fitness(void* context, const double* x, double* f) {
  auto* c = static_cast<Context*>(context);
  try {
    const std::vector<double> v = (*c->fitness)(std::vector<double>(x, x + c->dimensions));
    for (std::size_t k = 0; k < c->objectives; ++k) f[k] = v.at(k);
    return true;
  } catch (...) {
    c->failure = std::current_exception();
    return false;
  }
}

}  // namespace

void run_nsga2(std::size_t objectives, const std::vector<double>& lo, const std::vector<double>& hi,
               unsigned population, unsigned generations, unsigned seed,
               const std::function<std::vector<double>(const std::vector<double>&)>& fitness) {
  const auto entry = reinterpret_cast<Nsga2Entry>(
      plugin_symbol("nsga2", kNsga2Symbol, "optimize with several goals (pagmo's NSGA-II)"));
  Context context{&fitness, lo.size(), objectives, nullptr};
  Nsga2Call call;
  call.dimensions = lo.size();
  call.objectives = objectives;
  call.lo = lo.data();
  call.hi = hi.data();
  call.population = population;
  call.generations = generations;
  call.seed = seed;
  call.context = &context;
  call.fitness = &call_fitness;
  char error[512] = {0};
  const int code = entry(&call, error, sizeof error);
  if (context.failure) std::rethrow_exception(context.failure);
  if (code != 0) throw Error(fmt::format("pagmo's NSGA-II failed: {}", error));
}

}  // namespace trochomill::study_detail
