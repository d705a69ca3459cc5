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

// TROCHOMILL_PLUGIN_DIR when it is set (not empty), else null.
const char* user_plugin_dir() {
  const char* dir = std::getenv("TROCHOMILL_PLUGIN_DIR");
  return dir != nullptr && *dir != '\0' ? dir : nullptr;
}

// Where libtrochomill_<name>.so may be, in order (see plugin_symbol): `user_dir` alone when
// the user gave one.
std::vector<std::filesystem::path> plugin_candidates(const std::string& file,
                                                     const char* user_dir) {
  std::vector<std::filesystem::path> out;
  if (user_dir != nullptr) {
    out.emplace_back(std::filesystem::path(user_dir) / file);
    return out;
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

// The handles of the plugins loaded (kept for the process's life), by file name.
std::mutex loaded_mutex;
std::map<std::string, void*, std::less<>> loaded;

// Loads `path` if it is a plugin of this build that has `symbol`: its handle, or null with
// the reason in `why`.
void* open_plugin(const std::filesystem::path& path, const std::string& symbol, std::string& why) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    why = "not there";
    return nullptr;
  }
  void* h = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (h == nullptr) {
    const char* e = ::dlerror();
    why = e != nullptr ? e : "cannot be loaded";
    return nullptr;
  }
  // Its tables' layout must be this program's: the same version and plugin headers.
  using Id = const char* (*)();
  const auto id = reinterpret_cast<Id>(::dlsym(h, "trochomill_plugin_id"));
  if (id == nullptr || std::string_view(id()) != TROCHOMILL_PLUGIN_ID) {
    why = fmt::format("a plugin of another build (its id {}, this program's {})",
                      id != nullptr ? id() : "none", TROCHOMILL_PLUGIN_ID);
  } else if (::dlsym(h, symbol.c_str()) == nullptr) {
    why = fmt::format("no {}", symbol);
  } else {
    return h;
  }
  ::dlclose(h);
  return nullptr;
}

}  // namespace

void* plugin_symbol(std::string_view name, std::string_view symbol, std::string_view what) {
  const std::string file = fmt::format("libtrochomill_{}.so", name);
  const std::string sym(symbol);
  const std::lock_guard<std::mutex> lock(loaded_mutex);
  auto it = loaded.find(file);
  if (it == loaded.end()) {
    // Each place in turn until one holds this build's plugin; a failure is not kept (the next
    // call looks again, after the user has put the plugin in place).
    const char* user_dir = user_plugin_dir();
    std::string tried;
    void* handle = nullptr;
    for (const std::filesystem::path& p : plugin_candidates(file, user_dir)) {
      std::string why;
      handle = open_plugin(p, sym, why);
      if (handle != nullptr) break;
      tried += fmt::format("{}{} ({})", tried.empty() ? "" : "; ", p.string(), why);
    }
    if (handle == nullptr) {
      throw Error(fmt::format(
          "{}: the plugin {} could not be loaded: {}; {}", what, file, tried,
          user_dir != nullptr ? "TROCHOMILL_PLUGIN_DIR is set, so only that folder is searched"
                              : "install it with the program (lib/trochomill beside bin/), or set "
                                "TROCHOMILL_PLUGIN_DIR to the folder that holds it"));
    }
    it = loaded.emplace(file, handle).first;
  }
  void* s = ::dlsym(it->second, sym.c_str());
  if (s == nullptr) {
    throw Error(fmt::format("{}: the plugin {} has no {}", what, file, symbol));
  }
  return s;
}

}  // namespace trochomill
