// check-drawing: a CAD drawing's contours as trochomill reads them.
#include <fmt/format.h>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"
#include "trochomill/report/drawing.hpp"

namespace trochomill::cli {

void register_geometry_commands(CLI::App& app, int& exit_code) {
  struct Args {
    std::string file, json, units;
    std::vector<std::string> layers;
    DrawingOptions options;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "check-drawing",
      "read a DXF or SVG drawing as trochomill does and list its contours (layer, open or closed, "
      "orientation, length, area, the entities chained)");
  cmd->add_option("FILE", a->file, "DXF or SVG file")->required();
  cmd->add_option("--layer", a->layers,
                  "read only this layer (SVG: or the element or group of this id; repeatable)");
  cmd->add_option("--join-tolerance", a->options.join_tolerance_mm,
                  "ends closer than this are one point, mm")
      ->capture_default_str()
      ->check(finite_in(1e-6, 100));
  cmd->add_option("--arc-tolerance", a->options.arc_tolerance_mm,
                  "splines, ellipses and Bezier curves become arcs within this, mm")
      ->capture_default_str()
      ->check(finite_above(0, 100));
  cmd->add_option("--units", a->units,
                  "the unit of a DXF that gives none (no $INSUNITS): mm, cm, m, in or ft (a "
                  "job's [geometry] units)");
  cmd->add_option("--json", a->json, "write the report as JSON (- for stdout)");
  cmd->final_callback([a, &exit_code] {
    check_outputs({&a->json}, {&a->file});
    a->options.layers = a->layers;
    if (!a->units.empty()) {
      if (!drawing_unit_mm(a->units)) {
        throw InputError(
            fmt::format("--units '{}': a unit trochomill reads is mm, cm, m, in or ft", a->units));
      }
      a->options.unitless_unit = a->units;
    }
    const Drawing d = read_drawing(a->file, a->options);
    if (!a->json.empty()) emit(a->json, drawing_json(d));
    if (summary_to_stdout({&a->json})) fmt::print("{}", drawing_text(d));
    exit_code = 0;
  });
}

}  // namespace trochomill::cli
