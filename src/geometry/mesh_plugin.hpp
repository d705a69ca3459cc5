// Mesh files (STL, PLY, OBJ) through assimp, behind the plugin libtrochomill_assimp.so
// (mesh_plugin.cpp): linked into the program, assimp and what it brings (zlib, minizip,
// poly2tri, draco) cost every start about 10 ms.
#pragma once

#include <filesystem>
#include <string>

#include "trochomill/geometry.hpp"

namespace trochomill::geometry_detail {

/// The plugin's functions (trochomill_assimp_table()).
struct AssimpTable {
  /// A mesh file's triangles (every mesh of the file; faces triangulated, identical vertices
  /// joined, points and lines left out). Throws InputError for a file assimp cannot read or
  /// one without triangles.
  Mesh (*read)(const std::filesystem::path& file);
  /// The mesh in one of assimp's export formats ("stlb", "plyb", "objnomtl"): the file's bytes.
  /// Throws IoError when assimp cannot export it (`file` names it).
  std::string (*encode)(const std::filesystem::path& file, const Mesh& mesh,
                        const std::string& format);
};
inline constexpr const char* kAssimpSymbol = "trochomill_assimp_table";

}  // namespace trochomill::geometry_detail
