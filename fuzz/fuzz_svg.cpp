// The SVG reader (pugixml, path data, transforms, viewports, shapes, biarcs, chaining): every
// input is a drawing whose contours are chains (each piece starts where the one before it
// ends, closed ones end where they start) of finite pieces within 1000 km, or an InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  const auto file = fuzz::scratch_file(".svg");
  fuzz::write_bytes(file, data, size);
  try {
    const Drawing d = read_svg(file, DrawingOptions{});
    if (!(d.mm_per_unit > 0) || !std::isfinite(d.mm_per_unit)) std::abort();
    for (const DrawnContour& c : d.contours) {
      const auto& p = c.contour.pieces;
      if (p.empty()) std::abort();
      for (std::size_t i = 0; i < p.size(); ++i) {
        for (const Vec2* v : {&p[i].start, &p[i].end}) {
          if (!(std::abs(v->x()) <= 1e9 && std::abs(v->y()) <= 1e9)) std::abort();
        }
        if (i > 0 && p[i].start != p[i - 1].end) std::abort();  // joined exactly
      }
      if (c.contour.closed && p.front().start != p.back().end) std::abort();
    }
  } catch (const InputError&) {
  }
  return 0;
}
