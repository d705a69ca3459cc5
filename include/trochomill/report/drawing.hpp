// `check-drawing`'s report of a drawing: its unit, layers and contours (open or closed,
// orientation, pieces, length, area, box, the entities chained). Part of the report module
// (trochomill/report.hpp includes every part).
#pragma once

#include <string>

#include "trochomill/geometry/drawing.hpp"

namespace trochomill {

/// JSON: file, units, mm_per_unit, layers, and per contour: layer, closed, orientation
/// ("ccw", "cw"; null when open), lines, arcs, length_mm, area_mm2 (closed: the enclosed area,
/// positive; null when open), start_mm, end_mm, bbox_min_mm, bbox_max_mm, entities.
[[nodiscard]] std::string drawing_json(const Drawing& d);
/// The same as a table, one line per contour.
[[nodiscard]] std::string drawing_text(const Drawing& d);

}  // namespace trochomill
