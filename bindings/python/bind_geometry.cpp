// read_drawing: a CAD drawing's contours as `trochomill check-drawing --json` reports them.
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "trochomill/geometry/drawing.hpp"
#include "trochomill/report/drawing.hpp"

namespace trochomill::python {

void bind_geometry(py::module_& m) {
  m.def(
      "read_drawing",
      [](const std::string& file, std::optional<std::vector<std::string>> layers,
         double join_tolerance_mm, double arc_tolerance_mm) {
        DrawingOptions o;
        o.join_tolerance_mm = join_tolerance_mm;
        o.arc_tolerance_mm = arc_tolerance_mm;
        if (layers) o.layers = *layers;
        const Drawing d = read_drawing(file, o);
        return from_json(drawing_json(d));
      },
      py::arg("file"), py::kw_only(), py::arg("layers") = py::none(),
      py::arg("join_tolerance_mm") = DrawingOptions{}.join_tolerance_mm,
      py::arg("arc_tolerance_mm") = DrawingOptions{}.arc_tolerance_mm,
      R"(A DXF or SVG drawing read as trochomill reads it (`check-drawing --json`): its unit,
layers and contours (layer, open or closed, orientation, lines and arcs, length_mm, area_mm2,
the entities chained). layers: only these layers (DXF) or layers and ids (SVG);
join_tolerance_mm: ends closer than this are one point (1e-6 to 100 mm); arc_tolerance_mm:
curves that are not arcs become biarcs within this. Bad geometry raises InputError naming
the file and the entity (a gap, a branch, a missing layer).)");
}

}  // namespace trochomill::python
