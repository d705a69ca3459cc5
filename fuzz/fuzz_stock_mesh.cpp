// A stock given as a triangle mesh, for both chip sources: the simulation's boards
// (stock_from_mesh) and the engagement kernel's plan-view stock (EngagementOptions::
// stock_mesh). The bytes are the mesh itself, not a file: the first chooses the vertex count
// (3 to 16), then three per vertex (signed, 1/16 mm: coordinates within 8 mm, many on the
// rays' centres and on each other's lines), then three per triangle (indices modulo the count,
// at most 32 triangles): closed, open, flat, degenerate and self-crossing meshes alike. Every
// input is an InputError or boards whose rays hold sorted, disjoint intervals within the box,
// an engagement whose arcs are each at most a turn from an angle on the circle and whose
// numbers are finite, and a plan view (mesh_plan_region) of closed contours within the box
// whose medial axis' discs lie inside it.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"
#include "trochomill/units.hpp"

namespace {

using namespace trochomill;

void check_boards(const TriDexel& work) {
  for (const DexelBoard& b : work.boards) {
    const Interval full = b.full();
    for (int i = 0; i < b.count_u(); ++i) {
      for (int j = 0; j < b.count_v(); ++j) {
        if (!b.touched(i, j)) continue;
        double last = -INFINITY;
        for (const Interval& v : b.intervals(i, j)) {
          // Sorted, disjoint, non-empty and within the box along the ray.
          if (!(v.lo < v.hi) || !(v.lo > last) || v.lo < full.lo || v.hi > full.hi) std::abort();
          last = v.hi;
        }
      }
    }
  }
}

const Job& job() {
  static const Job j = parse_job(R"(
[tool]
diameter = 4.0
teeth = 2
flute_length = 3.0
[slot]
width = 6.0
length = 10.0
depth = 2.0
[path]
type = "linear"
step = 1.0
[cutting]
feed_rate = 600.0
spindle_speed = 6000.0
)",
                                 "fuzz.toml");
  return j;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::size_t nv = 3 + data[0] % 14;
  if (size < 1 + 3 * nv) return 0;
  Mesh m;
  for (std::size_t k = 0; k < nv; ++k) {
    Vec3 p = Vec3::Zero();
    for (std::size_t c = 0; c < 3; ++c) {
      p[c] = static_cast<std::int8_t>(data[1 + 3 * k + c]) / 16.0;
    }
    m.vertices.push_back(p);
  }
  for (std::size_t at = 1 + 3 * nv; at + 3 <= size && m.triangles.size() < 32; at += 3) {
    m.triangles.push_back({static_cast<std::uint32_t>(data[at] % nv),
                           static_cast<std::uint32_t>(data[at + 1] % nv),
                           static_cast<std::uint32_t>(data[at + 2] % nv)});
  }
  try {
    check_boards(stock_from_mesh(m, 0.25));
  } catch (const InputError&) {
  }
  try {
    // A pass through the mesh's middle height, across it and round a half circle back.
    const Box3 b = mesh_bounds(m);
    const double z = 0.5 * (b.lo[2] + b.hi[2]);
    ToolPath path;
    path.append(Segment::line(Vec3(-10, 0, z), Vec3(0, 0, z), Motion::feed, 600));
    path.append(Segment::arc_xy(0, 2, 2, -0.5 * kPi, kPi, z, z, Motion::feed, 600));
    EngagementOptions o;
    o.stock_mesh = &m;
    const EngagementSeries e = compute_engagement(path, job(), o);
    for (std::size_t i = 0; i < e.arcs.size(); ++i) {
      for (const AngleArc& a : e.arcs[i]) {
        // As engagement.hpp promises: from start in [0, 2 pi] on, at most a turn (an arc
        // across 0 ends past 2 pi).
        if (!(a.start_rad >= 0 && a.start_rad <= kTwoPi && a.end_rad >= a.start_rad &&
              a.end_rad - a.start_rad <= kTwoPi)) {
          std::abort();
        }
      }
      if (!std::isfinite(e.h_max_mm[i]) || !(e.h_max_mm[i] >= 0) ||
          !std::isfinite(e.removal_rate_mm3_per_s[i])) {
        std::abort();
      }
    }
  } catch (const InputError&) {
  }
  try {
    // The planner's plan view of it (mesh_plan_region) between two heights: closed polylines
    // of finite points within the mesh's box (Clipper's 1 nm grid), no larger in area.
    const Box3 b = mesh_bounds(m);
    const double z0 = b.lo[2] + 0.3 * (b.hi[2] - b.lo[2]), z1 = b.lo[2] + 0.7 * (b.hi[2] - b.lo[2]);
    const std::vector<Contour> region = mesh_plan_region(m, z0, z1);
    for (const Contour& c : region) {
      if (!c.closed) std::abort();
      for (const Vec2& p : c.points(1e-3)) {
        if (!(p.x() >= b.lo[0] - 1e-6 && p.x() <= b.hi[0] + 1e-6 && p.y() >= b.lo[1] - 1e-6 &&
              p.y() <= b.hi[1] + 1e-6)) {
          std::abort();
        }
      }
    }
    const double area = region_area_mm2(region);
    if (!(area >= -1e-9 && area <= (b.hi[0] - b.lo[0]) * (b.hi[1] - b.lo[1]) + 1e-6)) std::abort();
    // Its medial axis (the pocket planner's channels): finite points with finite clearances,
    // each point's disc of its clearance inside the region (8 points on its circle, a hair in).
    for (const MedialBranch& br : medial_axis(region, 120, 0.05)) {
      if (br.points.size() != br.clearance_mm.size()) std::abort();
      for (std::size_t i = 0; i < br.points.size(); ++i) {
        const Vec2& p = br.points[i];
        const double r = br.clearance_mm[i];
        if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !(r >= 0) || !std::isfinite(r)) {
          std::abort();
        }
        const double in = r * (1 - 1e-6) - 1e-5;
        if (in <= 0) continue;
        for (int k = 0; k < 8; ++k) {
          const double a = kTwoPi * k / 8;
          if (!region_contains(region, p + in * Vec2(std::cos(a), std::sin(a)))) std::abort();
        }
      }
    }
  } catch (const InputError&) {
  }
  return 0;
}
