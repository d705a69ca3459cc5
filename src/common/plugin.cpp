// Finding and loading plugins (common/plugin.hpp).
#include "trochomill/common/plugin.hpp"

#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include "trochomill/error.hpp"

namespace trochomill {
namespace {

// Where libtrochomill_<name>.so may be, in order (see plugin_symbol).
std::vector<std::filesystem::path> plugin_candidates(const std::string& file) {
  std::vector<std::filesystem::path> out;
  if (const char* dir = std::getenv("TROCHOMILL_PLUGIN_DIR"); dir != nullptr && *dir != '\0') {
    out.emplace_back(std::filesystem::path(dir) / file);
    return out;  // the user's choice: nothing else is tried
  }
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec)
    out.push_back((exe.parent_path() / TROCHOMILL_PLUGIN_FROM_BIN / file).lexically_normal());
  for (const char* dir : {TROCHOMILL_BUILD_PLUGIN_DIR, TROCHOMILL_INSTALL_PLUGIN_DIR}) {
    const std::filesystem::path p = std::filesystem::path(dir) / file;
    if (std::find(out.begin(), out.end(), p) == out.end()) out.push_back(p);  // each place once
  }
  return out;
}

struct Loaded {
  void* handle = nullptr;
  std::string why;  // the places tried, when none loaded
};

}  // namespace

void* plugin_symbol(std::string_view name, std::string_view symbol, std::string_view what) {
  static std::mutex mu;
  static std::map<std::string, Loaded, std::less<>> plugins;
  const std::string file = fmt::format("libtrochomill_{}.so", name);
  const std::lock_guard<std::mutex> lock(mu);
  auto it = plugins.find(file);
  if (it == plugins.end()) {
    Loaded l;
    for (const std::filesystem::path& p : plugin_candidates(file)) {
      std::error_code ec;
      if (!std::filesystem::exists(p, ec)) {
        l.why += fmt::format("{}{} (not there)", l.why.empty() ? "" : "; ", p.string());
        continue;
      }
      l.handle = ::dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (l.handle != nullptr) break;  // kept loaded for the process's life
      const char* e = ::dlerror();
      l.why += fmt::format("{}{} ({})", l.why.empty() ? "" : "; ", p.string(), e ? e : "?");
    }
    it = plugins.emplace(file, std::move(l)).first;
  }
  if (it->second.handle == nullptr) {
    const char* dir = std::getenv("TROCHOMILL_PLUGIN_DIR");
    throw Error(
        fmt::format("{}: the plugin {} could not be loaded: {}; {}", what, file, it->second.why,
                    dir != nullptr && *dir != '\0'
                        ? "TROCHOMILL_PLUGIN_DIR is set, so only that folder is searched"
                        : "install it with the program (lib/trochomill beside bin/), or set "
                          "TROCHOMILL_PLUGIN_DIR to the folder that holds it"));
  }
  void* s = ::dlsym(it->second.handle, std::string(symbol).c_str());
  if (s == nullptr) {
    throw Error(fmt::format("{}: the plugin {} has no {} (a plugin of another build?)", what, file,
                            symbol));
  }
  return s;
}

}  // namespace trochomill
