// check-drawing's report (report/drawing.hpp).
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "trochomill/report/drawing.hpp"

namespace trochomill {
namespace {

struct Summary {
  std::size_t lines = 0, arcs = 0;
  double length_mm = 0;
  std::optional<double> area_mm2;
  const char* orientation = nullptr;
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity());
  Vec2 hi = Vec2::Constant(-std::numeric_limits<double>::infinity());
};

Summary summarize(const Contour& c) {
  Summary s;
  for (const ContourPiece& p : c.pieces) {
    (p.is_arc() ? s.arcs : s.lines) += 1;
  }
  s.length_mm = c.length_mm();
  // The box from chords within a micrometre of the contour.
  for (const Vec2& q : c.points(1e-3)) s.lo = s.lo.cwiseMin(q), s.hi = s.hi.cwiseMax(q);
  if (c.closed) {
    const double a = c.signed_area_mm2();
    s.area_mm2 = std::abs(a);
    s.orientation = a > 0 ? "ccw" : "cw";
  }
  return s;
}

}  // namespace

std::string drawing_json(const Drawing& d) {
  nlohmann::json contours = nlohmann::json::array();
  for (const DrawnContour& c : d.contours) {
    const Summary s = summarize(c.contour);
    const Vec2 a = c.contour.pieces.front().start, b = c.contour.pieces.back().end;
    contours.push_back({
        {"layer", c.layer},
        {"closed", c.contour.closed},
        {"orientation", s.orientation ? nlohmann::json(s.orientation) : nlohmann::json()},
        {"lines", s.lines},
        {"arcs", s.arcs},
        {"length_mm", s.length_mm},
        {"area_mm2", s.area_mm2 ? nlohmann::json(*s.area_mm2) : nlohmann::json()},
        {"start_mm", {a.x(), a.y()}},
        {"end_mm", {b.x(), b.y()}},
        {"bbox_min_mm", {s.lo.x(), s.lo.y()}},
        {"bbox_max_mm", {s.hi.x(), s.hi.y()}},
        {"entities", c.entities},
    });
  }
  const nlohmann::json j = {{"file", d.file.string()},
                            {"units", d.units},
                            {"mm_per_unit", d.mm_per_unit},
                            {"layers", d.layers},
                            {"contours", contours}};
  return j.dump(2) + "\n";
}

std::string drawing_text(const Drawing& d) {
  std::string out = fmt::format("{}: {} contours on {} layers (units: {})\n", d.file.string(),
                                d.contours.size(), d.layers.size(), d.units);
  out += fmt::format("{:>4}  {:<16} {:<10} {:>6} {:>5} {:>12} {:>12}  {}\n", "#", "layer", "shape",
                     "lines", "arcs", "length mm", "area mm^2", "entities");
  for (std::size_t i = 0; i < d.contours.size(); ++i) {
    const DrawnContour& c = d.contours[i];
    const Summary s = summarize(c.contour);
    const std::string shape = c.contour.closed ? fmt::format("closed {}", s.orientation) : "open";
    const std::string ents = c.entities.size() <= 3
                                 ? fmt::format("{}", fmt::join(c.entities, ", "))
                                 : fmt::format("{}, {} ... ({} in all)", c.entities[0],
                                               c.entities[1], c.entities.size());
    out += fmt::format("{:>4}  {:<16} {:<10} {:>6} {:>5} {:>12.4f} {:>12}  {}\n", i + 1, c.layer,
                       shape, s.lines, s.arcs, s.length_mm,
                       s.area_mm2 ? fmt::format("{:.4f}", *s.area_mm2) : "-", ents);
  }
  return out;
}

}  // namespace trochomill
