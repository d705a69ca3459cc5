// Loads the NSGA-II plugin (nsga2.hpp) on first use and runs it.
#include "nsga2.hpp"

#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>

#include "trochomill/error.hpp"

namespace trochomill::study_detail {
namespace {

constexpr const char* kPluginFile = "libtrochomill_nsga2.so";

// Where the plugin may be, in order: TROCHOMILL_PLUGIN_DIR; beside the running program as the
// build and the install lay it out (bin/ and lib/trochomill/, TROCHOMILL_PLUGIN_FROM_BIN); the
// build tree's and the install's directories (for Python, whose program is the interpreter).
std::vector<std::filesystem::path> plugin_candidates() {
  std::vector<std::filesystem::path> out;
  if (const char* dir = std::getenv("TROCHOMILL_PLUGIN_DIR"); dir != nullptr && *dir != '\0') {
    out.emplace_back(std::filesystem::path(dir) / kPluginFile);
  }
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    out.push_back(
        (exe.parent_path() / TROCHOMILL_PLUGIN_FROM_BIN / kPluginFile).lexically_normal());
  }
  for (const char* dir : {TROCHOMILL_BUILD_PLUGIN_DIR, TROCHOMILL_INSTALL_PLUGIN_DIR}) {
    const std::filesystem::path p = std::filesystem::path(dir) / kPluginFile;
    if (std::find(out.begin(), out.end(), p) == out.end()) out.push_back(p);  // each place once
  }
  return out;
}

Nsga2Entry load_entry() {
  static std::once_flag once;
  static Nsga2Entry entry = nullptr;
  static std::string why;
  std::call_once(once, [] {
    const auto passed = [](const std::filesystem::path& p, std::string_view reason) {
      why += fmt::format("{}{} ({})", why.empty() ? "" : "; ", p.string(), reason);
    };
    for (const std::filesystem::path& p : plugin_candidates()) {
      std::error_code ec;
      if (!std::filesystem::exists(p, ec)) {
        passed(p, "not there");
        continue;
      }
      void* h = ::dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (h == nullptr) {
        const char* e = ::dlerror();
        passed(p, e != nullptr ? e : "?");
        continue;
      }
      entry = reinterpret_cast<Nsga2Entry>(::dlsym(h, kNsga2Symbol));
      if (entry != nullptr) return;  // kept loaded for the process's life
      passed(p, fmt::format("no {}", kNsga2Symbol));
      ::dlclose(h);
    }
  });
  if (entry == nullptr) {
    throw Error(fmt::format(
        "optimize with several goals runs pagmo's NSGA-II from the plugin {}, which was not "
        "loaded: {} (set TROCHOMILL_PLUGIN_DIR to the folder that holds it)",
        kPluginFile, why));
  }
  return entry;
}

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
  const Nsga2Entry entry = load_entry();
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
