// The mesh reader (STL ascii or binary, PLY, OBJ through assimp, by content): every input is
// a mesh whose triangles index its vertices, or an InputError.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  const auto file = fuzz::scratch_file(".stl");
  fuzz::write_bytes(file, data, size);
  try {
    const Mesh m = read_mesh(file);
    for (const auto& t : m.triangles) {
      for (const auto i : t) {
        if (i >= m.vertices.size()) std::abort();  // an index past the vertices
      }
    }
  } catch (const InputError&) {
  }
  return 0;
}
