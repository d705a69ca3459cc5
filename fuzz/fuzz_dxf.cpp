// The DXF reader (libdxflib, entities into pieces, biarcs, chaining): every input is a drawing
// whose contours are chains (each piece starts where the one before it ends, closed ones end
// where they start) of finite pieces, or an InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  const auto file = fuzz::scratch_file(".dxf");
  fuzz::write_bytes(file, data, size);
  try {
    const Drawing d = read_dxf(file, DrawingOptions{});
    for (const DrawnContour& c : d.contours) {
      const auto& p = c.contour.pieces;
      if (p.empty()) std::abort();
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (!std::isfinite(p[i].start.x()) || !std::isfinite(p[i].end.y())) std::abort();
        if (i > 0 && p[i].start != p[i - 1].end) std::abort();  // joined exactly
      }
      if (c.contour.closed && p.front().start != p.back().end) std::abort();
    }
  } catch (const InputError&) {
  }
  return 0;
}
