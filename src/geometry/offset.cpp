// Offsets of planar regions and curves through Clipper (Angus Johnson's polygon library,
// Debian's libpolyclipping): the contours are cut into chords within half the tolerance, put on
// a 1 nm integer grid, joined by the even-odd rule and offset with round joins whose chords
// stay within the other half (geometry.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
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

namespace {

// Region a op region b, each by the even-odd rule.
std::vector<Contour> boolean(const std::vector<Contour>& a, const std::vector<Contour>& b,
                             cl::ClipType op, double tolerance_mm) {
  check_tolerance(tolerance_mm);
  const double tol = 0.5 * tolerance_mm;
  std::vector<const Contour*> all;
  for (const auto* set : {&a, &b}) {
    for (std::size_t i = 0; i < set->size(); ++i) {
      if (!(*set)[i].closed) {
        throw InputError(
            fmt::format("region: contour {} is open (a region needs closed ones)", i + 1));
      }
      all.push_back(&(*set)[i]);
    }
  }
  check_size(all, tol);
  cl::Clipper c;
  for (std::size_t i = 0; i < a.size(); ++i) c.AddPath(to_path(a[i], tol, i), cl::ptSubject, true);
  for (std::size_t i = 0; i < b.size(); ++i) c.AddPath(to_path(b[i], tol, i), cl::ptClip, true);
  cl::PolyTree tree;
  c.Execute(op, tree, cl::pftEvenOdd, cl::pftEvenOdd);
  return to_contours(tree);
}

// Even-odd crossings of the horizontal ray from p towards +x with one contour (arcs exact).
int crossings(const Contour& c, const Vec2& p) {
  int n = 0;
  auto line = [&](const Vec2& a, const Vec2& b) {
    if ((a.y() > p.y()) == (b.y() > p.y())) return;
    const double x = a.x() + (p.y() - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
    if (x > p.x()) ++n;
  };
  for (const ContourPiece& piece : c.pieces) {
    if (!piece.is_arc()) {
      line(piece.start, piece.end);
      continue;
    }
    // The arc's crossings with y = p.y: on its circle at x = cx +- sqrt(r^2 - dy^2), counted
    // when they lie on the arc; the half-open rule of the chord test by the arc's monotone
    // pieces: split at its topmost and bottommost points.
    const Vec2 c0 = *piece.centre;
    const double r = piece.radius_mm(), dy = p.y() - c0.y();
    const double a0 = std::atan2(piece.start.y() - c0.y(), piece.start.x() - c0.x());
    const double sweep = piece.sweep_rad();
    std::vector<double> cuts{0.0, 1.0};
    for (const double at : {0.5 * M_PI, -0.5 * M_PI}) {
      double d = at - a0;
      // the fraction of the sweep where the arc reaches angle `at`
      if (sweep > 0) {
        d = std::fmod(d, 2 * M_PI);
        if (d < 0) d += 2 * M_PI;
      } else {
        d = std::fmod(d, 2 * M_PI);
        if (d > 0) d -= 2 * M_PI;
      }
      const double t = d / sweep;
      if (t > 0 && t < 1) cuts.push_back(t);
    }
    std::sort(cuts.begin(), cuts.end());
    if (std::abs(dy) > r) continue;
    const double b1 = std::asin(std::clamp(dy / r, -1.0, 1.0)), b2 = M_PI - b1;
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
      const double t0 = cuts[k], t1 = cuts[k + 1];
      const Vec2 q0 = c0 + r * Vec2(std::cos(a0 + sweep * t0), std::sin(a0 + sweep * t0));
      const Vec2 q1 = c0 + r * Vec2(std::cos(a0 + sweep * t1), std::sin(a0 + sweep * t1));
      if ((q0.y() > p.y()) == (q1.y() > p.y())) continue;
      // One crossing on this piece, monotone in y: the candidate angle within its span.
      for (const double b : {b1, b2}) {
        double d = std::fmod(b - a0, 2 * M_PI);
        if (sweep > 0 && d < 0) d += 2 * M_PI;
        if (sweep < 0 && d > 0) d -= 2 * M_PI;
        const double t = d / sweep;
        if (t >= t0 - 1e-12 && t <= t1 + 1e-12) {
          if (c0.x() + r * std::cos(b) > p.x()) ++n;
          break;
        }
      }
    }
  }
  return n;
}

}  // namespace

std::vector<Contour> region_difference(const std::vector<Contour>& a, const std::vector<Contour>& b,
                                       double tolerance_mm) {
  return boolean(a, b, cl::ctDifference, tolerance_mm);
}

std::vector<Contour> region_intersection(const std::vector<Contour>& a,
                                         const std::vector<Contour>& b, double tolerance_mm) {
  return boolean(a, b, cl::ctIntersection, tolerance_mm);
}

bool region_contains(const std::vector<Contour>& region, const Vec2& p) {
  int n = 0;
  for (const Contour& c : region) n += crossings(c, p);
  return n % 2 == 1;
}

std::vector<std::vector<Contour>> region_parts(const std::vector<Contour>& region) {
  std::vector<std::vector<Contour>> parts;
  std::vector<double> areas;
  for (const Contour& c : region) {
    if (c.signed_area_mm2() > 0) {
      parts.push_back({c});
      areas.push_back(c.signed_area_mm2());
    }
  }
  for (const Contour& c : region) {
    if (c.signed_area_mm2() > 0 || c.pieces.empty()) continue;
    // A hole belongs to the smallest outer boundary around it.
    const Vec2 p = c.pieces.front().start;
    std::size_t best = parts.size();
    for (std::size_t k = 0; k < parts.size(); ++k) {
      if (region_contains({parts[k].front()}, p) &&
          (best == parts.size() || areas[k] < areas[best])) {
        best = k;
      }
    }
    if (best < parts.size()) parts[best].push_back(c);
  }
  return parts;
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

std::vector<Contour> mesh_plan_region(const Mesh& mesh, double z0_mm, double z1_mm) {
  (void)mesh_bounds(mesh);  // every vertex a triangle uses: present, finite, within 1 km
  if (!(std::isfinite(z0_mm) && std::isfinite(z1_mm) && z0_mm <= z1_mm)) {
    throw InputError(fmt::format(
        "the mesh's plan view between z = {} and {} mm: need finite heights, the first the "
        "lower",
        z0_mm, z1_mm));
  }
  const auto& v = mesh.vertices;
  // The point of edge (i, j) at height h, computed from the edge's lexicographically first
  // end, so that the two triangles of an edge put it on the same grid point (whether or not
  // the reader joined their vertices).
  auto edge_at = [&](std::uint32_t i, std::uint32_t j, double h) {
    const Vec3* pa = &v[i];
    const Vec3* pb = &v[j];
    if (std::tie((*pb)[0], (*pb)[1], (*pb)[2]) < std::tie((*pa)[0], (*pa)[1], (*pa)[2])) {
      std::swap(pa, pb);
    }
    const Vec3& a = *pa;
    const Vec3& b = *pb;
    const double t = (h - a.z()) / (b.z() - a.z());
    return cl::IntPoint(
        static_cast<cl::cInt>(std::llround((a.x() + t * (b.x() - a.x())) * kScale)),
        static_cast<cl::cInt>(std::llround((a.y() + t * (b.y() - a.y())) * kScale)));
  };
  auto grid = [&](std::uint32_t i) {
    return cl::IntPoint(static_cast<cl::cInt>(std::llround(v[i].x() * kScale)),
                        static_cast<cl::cInt>(std::llround(v[i].y() * kScale)));
  };
  // The triangle's part in lo <= z <= hi (a convex polygon, the triangle's orientation kept),
  // projected: walking its edges, each vertex in the slab and each crossing of a plane.
  auto clip = [&](const std::array<std::uint32_t, 3>& t, double lo, double hi, cl::Path& out) {
    out.clear();
    for (int q = 0; q < 3; ++q) {
      const std::uint32_t i = t[static_cast<std::size_t>(q)];
      const std::uint32_t j = t[static_cast<std::size_t>((q + 1) % 3)];
      const double za = v[i].z(), zb = v[j].z();
      if (za >= lo && za <= hi) out.push_back(grid(i));
      // The planes the edge crosses strictly, in its direction.
      double hs[2];
      int n = 0;
      for (const double h : {lo, hi}) {
        if (std::isfinite(h) && ((za < h && zb > h) || (za > h && zb < h))) hs[n++] = h;
      }
      if (n == 2 && (hs[0] - za) / (zb - za) > (hs[1] - za) / (zb - za)) std::swap(hs[0], hs[1]);
      for (int k = 0; k < n; ++k) out.push_back(edge_at(i, j, hs[k]));
    }
  };
  const double inf = std::numeric_limits<double>::infinity();
  cl::Clipper section;
  cl::Paths band;
  cl::Path poly;
  for (const auto& t : mesh.triangles) {
    clip(t, -inf, z0_mm, poly);
    if (poly.size() >= 3 && cl::Area(poly) != 0) section.AddPath(poly, cl::ptSubject, true);
    clip(t, z0_mm, z1_mm, poly);
    if (poly.size() >= 3 && cl::Area(poly) != 0) {
      if (!cl::Orientation(poly)) std::reverse(poly.begin(), poly.end());
      band.push_back(poly);
    }
  }
  // Seen from above a face turned down runs clockwise: the section is where the faces turned
  // down below z0 outnumber those turned up (the winding negative).
  cl::Paths inside;
  section.Execute(cl::ctUnion, inside, cl::pftNegative, cl::pftNegative);
  cl::Clipper all;
  all.AddPaths(inside, cl::ptSubject, true);  // outer boundaries positive, holes negative
  all.AddPaths(band, cl::ptSubject, true);    // each positive
  cl::PolyTree tree;
  all.Execute(cl::ctUnion, tree, cl::pftPositive, cl::pftPositive);
  return to_contours(tree);
}

}  // namespace trochomill
