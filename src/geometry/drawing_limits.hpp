// What the drawing readers (dxf.cpp, svg_pieces.cpp) say when a drawing's curves need more
// arcs than kMaxDrawingArcs (trochomill/geometry/drawing.hpp).
#pragma once

#include <fmt/format.h>

#include <string>

#include "trochomill/geometry/drawing.hpp"

namespace trochomill::drawing_detail {

/// The reason, after the reader's file, element and layer.
inline std::string too_many_arcs(double tolerance_mm) {
  return fmt::format(
      "the drawing's curves need more than {} arcs within {} mm (the arc tolerance): a drawing "
      "traced from an image, or curves far larger than a machine's travel; not read (simplify "
      "the curves or loosen the tolerance)",
      kMaxDrawingArcs, tolerance_mm);
}

}  // namespace trochomill::drawing_detail
