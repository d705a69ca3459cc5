// The tool's edge contour in the (radial, axial) plane: a point at a length along it and the
// projection of a point onto it (src/topography/, not public).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "trochomill/cutter.hpp"
#include "trochomill/topography.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

struct ContourPoint {
  double s = 0;           ///< length along the edge from the tip (mm)
  double r = 0, h = 0;    ///< radius and height above the tip (mm)
  double nr = 1, nz = 0;  ///< outward normal (radial, axial)
};

/// The point at edge length s (corner arc, then the main edge), as SimTool and edge_grid
/// define the contour.
inline ContourPoint contour_at(const SimTool& t, double s) {
  ContourPoint c;
  c.s = s;
  c.h = t.height_at_length(s);
  c.r = t.profile_radius(c.h);
  const double rc = t.corner_radius_mm, phit = kPi - t.lead_rad;
  c.nr = std::sin(t.lead_rad), c.nz = std::cos(t.lead_rad);
  if (rc > 0 && s <= rc * phit) c.nr = std::sin(s / rc), c.nz = -std::cos(s / rc);
  return c;
}

/// The nearest contour point to (x radial, z axial) (arc or main edge, whichever is nearer).
inline ContourPoint project_on_contour(const SimTool& t, double x, double z) {
  const double rc = t.corner_radius_mm, R = t.radius_mm, phit = kPi - t.lead_rad;
  ContourPoint best;
  double best_d = 1e300;
  if (rc > 0) {
    const double dx = x - (R - rc), dz = z - rc;
    const double phi = std::clamp(std::atan2(dx, -dz), 0.0, phit);
    ContourPoint c = contour_at(t, rc * phi);
    const double d = std::hypot(x - c.r, z - c.h);
    if (d < best_d) best_d = d, best = c;
  }
  // The main edge: from the arc's end along (-cos kappa_r, sin kappa_r).
  const ContourPoint c0 = contour_at(t, rc * phit);
  const double tx = -std::cos(t.lead_rad), tz = std::sin(t.lead_rad);
  const double u = std::max(0.0, (x - c0.r) * tx + (z - c0.h) * tz);
  ContourPoint c = contour_at(t, rc * phit + u);
  c.r = c0.r + u * tx, c.h = c0.h + u * tz;  // the line itself (profile_radius clips at 0)
  const double d = std::hypot(x - c.r, z - c.h);
  if (d < best_d) best = c;
  return best;
}

/// A triangle's normal (p1 - p0) x (p2 - p0), not normalised (twice its area), and centroid.
struct Facet {
  std::array<double, 3> n, c;
};
inline Facet facet_of(const Mesh& m, const std::array<std::uint32_t, 3>& t) {
  const auto& p0 = m.vertices[t[0]];
  const auto& p1 = m.vertices[t[1]];
  const auto& p2 = m.vertices[t[2]];
  const double ux = p1[0] - p0[0], uy = p1[1] - p0[1], uz = p1[2] - p0[2];
  const double vx = p2[0] - p0[0], vy = p2[1] - p0[1], vz = p2[2] - p0[2];
  return {{uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx},
          {(p0[0] + p1[0] + p2[0]) / 3, (p0[1] + p1[1] + p2[1]) / 3, (p0[2] + p1[2] + p2[2]) / 3}};
}

}  // namespace trochomill
