// Offsets of planar regions and curves through Clipper (Angus Johnson's polygon library,
// Debian's libpolyclipping): the contours are cut into chords within half the tolerance, put on
// a 1 nm integer grid, joined by the even-odd rule and offset with round joins whose chords
// stay within the other half (geometry.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <polyclipping/clipper.hpp>
#include <tuple>

#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"

namespace trochomill {

namespace {

namespace cl = ClipperLib;

constexpr double kScale = 1e6;      // grid points per mm: 1 nm
constexpr double kMaxCoord = 1e6;   // mm: 1 km, far inside Clipper's 64-bit range
constexpr double kMaxPoints = 2e7;  // chords in all, about 640 MB with Clipper's copies

void check_tolerance(double tolerance_mm) {
  if (!(tolerance_mm >= 1e-5 && tolerance_mm <= 10)) {
    throw InputError(fmt::format("offset tolerance {} mm: allowed 1e-5 to 10 mm", tolerance_mm));
  }
}

// Counts the chords of the contours at the tolerance before any is made (memory first).
void check_size(const std::vector<const Contour*>& contours, double tol) {
  double n = 0;
  for (const Contour* c : contours) {
    for (const ContourPiece& p : c->pieces) {
      const double r = p.radius_mm();
      if (p.is_arc() && tol < r) n += std::abs(p.sweep_rad()) / (2.0 * std::acos(1.0 - tol / r));
      n += 1;
    }
  }
  if (n > kMaxPoints) {
    throw InputError(fmt::format(
        "offset: the contours need {:.3g} chords at a tolerance of {} mm (limit {:.0g}); use a "
        "larger tolerance",
        n, tol, kMaxPoints));
  }
}

cl::Path to_path(const Contour& c, double tol, std::size_t index) {
  cl::Path out;
  for (const Vec2& p : c.points(tol)) {
    if (!(std::abs(p.x()) <= kMaxCoord && std::abs(p.y()) <= kMaxCoord)) {
      throw InputError(fmt::format(
          "offset: contour {} has the point ({}, {}) mm (finite, within 1 km of the origin)",
          index + 1, p.x(), p.y()));
    }
    out.emplace_back(static_cast<cl::cInt>(std::llround(p.x() * kScale)),
                     static_cast<cl::cInt>(std::llround(p.y() * kScale)));
  }
  return out;
}

// Clipper's output as contours in a canonical form: outer boundaries counter-clockwise and
// holes clockwise (from the tree's nesting, not Clipper's orientation conventions), each
// starting at its lowest (then leftmost) vertex, largest area first, then by that vertex.
std::vector<Contour> to_contours(const cl::PolyTree& tree) {
  struct Item {
    double area;
    cl::IntPoint low;
    cl::Path path;
    std::size_t first;
  };
  std::vector<Item> items;
  for (const cl::PolyNode* n = tree.GetFirst(); n != nullptr; n = n->GetNext()) {
    if (n->Contour.size() < 3) continue;
    cl::Path p = n->Contour;
    if (cl::Orientation(p) == n->IsHole()) std::reverse(p.begin(), p.end());
    std::size_t first = 0;
    for (std::size_t i = 1; i < p.size(); ++i) {
      if (std::tie(p[i].Y, p[i].X) < std::tie(p[first].Y, p[first].X)) first = i;
    }
    const cl::IntPoint low = p[first];
    items.push_back({std::abs(cl::Area(p)), low, std::move(p), first});
  }
  std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    if (a.area != b.area) return a.area > b.area;
    return std::tie(a.low.Y, a.low.X) < std::tie(b.low.Y, b.low.X);
  });
  std::vector<Contour> out;
  out.reserve(items.size());
  for (const Item& it : items) {
    const cl::Path& p = it.path;
    std::vector<Vec2> pts;
    pts.reserve(p.size());
    for (std::size_t k = 0; k < p.size(); ++k) {
      const cl::IntPoint& q = p[(it.first + k) % p.size()];
      pts.emplace_back(static_cast<double>(q.X) / kScale, static_cast<double>(q.Y) / kScale);
    }
    out.push_back(Contour::polyline(pts, true));
  }
  return out;
}

std::vector<Contour> run_offset(const cl::Paths& in, cl::EndType end, double distance_mm,
                                double tol) {
  cl::ClipperOffset co(2.0, 0.5 * tol * kScale);
  co.AddPaths(in, cl::jtRound, end);
  cl::PolyTree out;
  co.Execute(out, distance_mm * kScale);
  return to_contours(out);
}

}  // namespace

std::vector<Contour> offset_region(const std::vector<Contour>& closed, double distance_mm,
                                   double tolerance_mm) {
  check_tolerance(tolerance_mm);
  if (!std::isfinite(distance_mm) || std::abs(distance_mm) > kMaxCoord) {
    throw InputError(fmt::format("offset distance {} mm: finite, within 1 km", distance_mm));
  }
  std::vector<const Contour*> all;
  for (std::size_t i = 0; i < closed.size(); ++i) {
    if (!closed[i].closed) {
      throw InputError(
          fmt::format("offset: contour {} is open (a region needs closed ones)", i + 1));
    }
    all.push_back(&closed[i]);
  }
  const double tol = 0.5 * tolerance_mm;
  check_size(all, tol);
  cl::Paths paths;
  for (std::size_t i = 0; i < closed.size(); ++i) paths.push_back(to_path(closed[i], tol, i));
  // The region by the even-odd rule, its outer boundaries positive and holes negative.
  cl::Clipper join;
  join.AddPaths(paths, cl::ptSubject, true);
  cl::PolyTree tree;
  join.Execute(cl::ctUnion, tree, cl::pftEvenOdd, cl::pftEvenOdd);
  if (distance_mm == 0) return to_contours(tree);
  // Outer boundaries positive and holes negative, as ClipperOffset needs them.
  cl::Paths region;
  for (const cl::PolyNode* n = tree.GetFirst(); n != nullptr; n = n->GetNext()) {
    region.push_back(n->Contour);
    if (cl::Orientation(region.back()) == n->IsHole()) {
      std::reverse(region.back().begin(), region.back().end());
    }
  }
  return run_offset(region, cl::etClosedPolygon, distance_mm, tolerance_mm);
}

std::vector<Contour> offset_curve(const Contour& contour, double distance_mm, double tolerance_mm) {
  check_tolerance(tolerance_mm);
  if (!(distance_mm > 0 && distance_mm <= kMaxCoord)) {
    throw InputError(
        fmt::format("offset distance {} mm along a curve: need > 0 mm, within 1 km", distance_mm));
  }
  const double tol = 0.5 * tolerance_mm;
  check_size({&contour}, tol);
  const cl::Paths in{to_path(contour, tol, 0)};
  return run_offset(in, contour.closed ? cl::etClosedLine : cl::etOpenRound, distance_mm,
                    tolerance_mm);
}

}  // namespace trochomill
