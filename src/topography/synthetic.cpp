// The synthetic insert generator
// (topography.hpp; docs/models.md section 13).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "contour.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/topography.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

using P2 = std::array<double, 2>;

// The hone: the circle of radius r tangent to two faces through the corner c with outward
// normals n1, n2; returns its centre.
P2 hone_centre(const P2& c, const P2& n1, const P2& n2, double r) {
  // (M - c) . n1 = -r, (M - c) . n2 = -r
  const double det = n1[0] * n2[1] - n1[1] * n2[0];
  const double mx = (-r * n2[1] + r * n1[1]) / det, my = (-r * n1[0] + r * n2[0]) / det;
  return {c[0] + mx, c[1] + my};
}

void append_line(std::vector<P2>& out, const P2& a, const P2& b, double ds) {
  const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
  const int n = std::max(1, static_cast<int>(std::ceil(len / ds)));
  for (int i = out.empty() ? 0 : 1; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
  }
}

// The section profile in (p outward along the contour normal, q along the cutting
// direction), from the flank's far end around the edge to the rake face's.
std::vector<std::array<double, 2>> insert_profile(const SyntheticInsert& s) {
  const double g = deg_to_rad(s.rake_deg), a = deg_to_rad(s.clearance_deg);
  const P2 rake_dir{-std::cos(g), -std::sin(g)}, n_rake{-std::sin(g), std::cos(g)};
  const P2 flank_dir{-std::sin(a), -std::cos(a)}, n_flank{std::cos(a), -std::sin(a)};
  const double L = s.face_mm, r = s.edge_radius_mm;
  // Length of the profile, for an even spacing with at least 24 points on the hone.
  const double ds = (2 * L) / std::max(16, s.profile_points - 24);
  std::vector<P2> out;
  P2 corner{0, 0}, back_dir = flank_dir, n_back = n_flank;
  if (s.vb_mm > 0) {
    // The land: the plane p = -VB tan(alpha) from the flank at q = -VB to the rake face.
    const double pw = -s.vb_mm * std::tan(a);
    append_line(out, {L * flank_dir[0], L * flank_dir[1]}, {pw, -s.vb_mm}, ds);
    corner = {pw, pw * std::tan(g)};
    back_dir = {0, -1}, n_back = {1, 0};
  }
  const P2 far_back{corner[0] + (s.vb_mm > 0 ? 0.0 : L) * back_dir[0],
                    corner[1] + (s.vb_mm > 0 ? 0.0 : L) * back_dir[1]};
  const P2 rake_end{L * rake_dir[0], L * rake_dir[1]};
  if (r > 0) {
    const P2 m = hone_centre(corner, n_back, n_rake, r);
    const P2 tb{m[0] + r * n_back[0], m[1] + r * n_back[1]};
    const P2 tr{m[0] + r * n_rake[0], m[1] + r * n_rake[1]};
    append_line(out, s.vb_mm > 0 ? out.back() : far_back, tb, ds);
    const double a0 = std::atan2(n_back[1], n_back[0]);
    double a1 = std::atan2(n_rake[1], n_rake[0]);
    if (a1 < a0) a1 += kTwoPi;
    const int n = std::max(24, static_cast<int>(std::ceil(r * (a1 - a0) / ds)));
    for (int i = 1; i <= n; ++i) {
      const double t = a0 + (a1 - a0) * i / n;
      out.push_back({m[0] + r * std::cos(t), m[1] + r * std::sin(t)});
    }
    append_line(out, tr, rake_end, ds);
  } else {
    append_line(out, s.vb_mm > 0 ? out.back() : far_back, corner, ds);
    append_line(out, corner, rake_end, ds);
  }
  return out;
}

}  // namespace

Mesh synthetic_insert(const SimTool& tool, const SyntheticInsert& s) {
  // Each broken rule by itself, with the value that broke it.
  std::vector<std::string> problems;
  const auto need = [&](bool ok, std::string what) {
    if (!ok) problems.push_back("synthetic insert: " + std::move(what));
  };
  need(s.edge_radius_mm >= 0, fmt::format("edge radius must be >= 0 mm, got {}", s.edge_radius_mm));
  need(s.vb_mm >= 0, fmt::format("VB must be >= 0 mm, got {}", s.vb_mm));
  need(s.face_mm > s.vb_mm + s.edge_radius_mm,
       fmt::format("the face extent ({} mm) must pass VB plus the hone ({} mm)", s.face_mm,
                   s.vb_mm + s.edge_radius_mm));
  need(s.sections >= 2, fmt::format("need >= 2 sections, got {}", s.sections));
  need(s.profile_points >= 8, fmt::format("need >= 8 profile points, got {}", s.profile_points));
  need(std::abs(s.rake_deg) < 45, fmt::format("|rake| must be < 45 degrees, got {}", s.rake_deg));
  need(s.clearance_deg > 0 && s.clearance_deg < 45,
       fmt::format("clearance must be in (0, 45) degrees, got {}", s.clearance_deg));
  // The mesh is sections x points vertices, two triangles each: refused before allocating.
  const double vertices = static_cast<double>(s.sections) * static_cast<double>(s.profile_points);
  need(vertices <= 2e7, fmt::format("{} sections x {} points is {:.3g} vertices (limit 2e7, about "
                                    "2 GB of mesh); use fewer",
                                    s.sections, s.profile_points, vertices));
  if (!problems.empty()) throw InputError(problems);
  const std::vector<P2> prof = insert_profile(s);
  const double total = tool.edge_length_at(tool.flute_length_mm);
  Mesh m;
  const auto np = static_cast<std::uint32_t>(prof.size());
  for (int i = 0; i < s.sections; ++i) {
    const double sl = total * i / (s.sections - 1);
    const ContourPoint c = contour_at(tool, sl);
    for (const P2& p : prof) {
      m.vertices.push_back({c.r + p[0] * c.nr, p[1], c.h + p[0] * c.nz});
    }
  }
  for (int i = 0; i + 1 < s.sections; ++i) {
    const auto a = static_cast<std::uint32_t>(i) * np, b = a + np;
    for (std::uint32_t j = 0; j + 1 < np; ++j) {
      // Profile runs around the edge and sections run up it: (b, a) x (j, j+1) outward.
      m.triangles.push_back({a + j, a + j + 1, b + j});
      m.triangles.push_back({a + j + 1, b + j + 1, b + j});
    }
  }
  // Orient outward: away from a point inside the tool behind the edge.
  for (auto& t : m.triangles) {
    const auto [n, ctr] = facet_of(m, t);
    const double cx = ctr[0], cy = ctr[1], cz = ctr[2];
    const ContourPoint c = project_on_contour(tool, cx, cz);
    const double ox = c.r - s.face_mm * c.nr, oy = -s.face_mm, oz = c.h - s.face_mm * c.nz;
    if (n[0] * (cx - ox) + n[1] * (cy - oy) + n[2] * (cz - oz) < 0) std::swap(t[1], t[2]);
  }
  return m;
}

}  // namespace trochomill
