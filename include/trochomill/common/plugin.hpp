// Plugins: the parts of the library whose dependencies would cost every start of the program
// (HDF5, assimp, Ceres, Open MPI, libsndfile, pagmo: their loading and static set-up), built as
// modules (libtrochomill_<name>.so in lib/trochomill/) and loaded the first time a call needs
// them. A plugin is built with the library and exports one C function returning its table of
// functions (C++ signatures: the same build on both sides; its exceptions cross as the
// library's own).
#pragma once

#include <string_view>

namespace trochomill {

/// The address of `symbol` in the plugin libtrochomill_<name>.so, loaded on first use and kept
/// for the process's life. Looked for, in order: in TROCHOMILL_PLUGIN_DIR when it is set (and
/// only there); beside the running program as the build and the install lay it out
/// (bin/../lib/trochomill); in the build tree's and the install's folders (for Python, whose
/// program is the interpreter). Throws Error naming `what` (what needs the plugin), every place
/// tried and why it failed.
[[nodiscard]] void* plugin_symbol(std::string_view name, std::string_view symbol,
                                  std::string_view what);

/// A plugin's table: `symbol` is a function `const Table* symbol()` (extern "C").
template <class Table>
[[nodiscard]] const Table& plugin_table(std::string_view name, std::string_view symbol,
                                        std::string_view what) {
  using Entry = const Table* (*)();
  return *reinterpret_cast<Entry>(plugin_symbol(name, symbol, what))();
}

}  // namespace trochomill
