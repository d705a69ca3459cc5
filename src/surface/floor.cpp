// The floor the teeth's end edges leave along a line (see include/trochomill/surface.hpp and
// docs/models.md section 14).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "common/sincos.hpp"
#include "surface/floor_look.hpp"
#include "trochomill/error.hpp"
#include "trochomill/surface.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

struct V2 {
  double x, y;
};
double cross(V2 u, V2 v) { return u.x * v.y - u.y * v.x; }
double dot(V2 u, V2 v) { return u.x * v.x + u.y * v.y; }

// One tooth's end edge: its angle, reach, tip offset below the sample's z (mm).
struct EndEdge {
  double angle_rad, reach_mm, tip_dz_mm;
};

// One edge over one step of the spindle, as the points' first look sees it (floor_profile's
// secant estimate): the edge's direction and axis at the step's ends, its heights and reach.
struct EdgeStep {
  double x0, y_from, dy;      // the line and its points
  double uax, uay, ubx, uby;  // the edge's direction at the step's start and end
  double aax, aay, abx, aby;  // the axis at both
  double za, zb, tip, reach, rc, tan_dish, turn2, slack;
};

// The points q in [j0, j0 + n) the first look cannot pass over, marked nonzero in keep[q - j0]:
// those the edge's line passes exactly at the step's start (ga = 0), and those it passes
// through whose secant estimate lies within the reach and not above the floor found so far
// by more than the slack. floor_profile's loop passes over every other point at once, and
// looks again at these (so a point marked here in excess changes nothing). Four points an AVX
// register (GCC's and Clang's vector types), on processors with AVX2 (with SSE2 alone the
// vectors in pairs of registers took longer than the loop's own look, 25.6 ms against 21.4 ms
// for BM_FloorProfileWagih), by the loop's operations in its order (so the same doubles) but
// for the corner's rise: its lower bound m^2 / 2 rc (rc - sqrt(rc^2 - m^2) = m^2 / (rc +
// sqrt(rc^2 - m^2))), which spares a square root a point, with a margin of 1e-9 mm for its
// rounding (the heights' is below 1e-12 mm up to 10 m).
using V4 = double __attribute__((vector_size(32)));
using M4 = long long __attribute__((vector_size(32)));  // a comparison's lanes: -1 or 0

#if defined(__x86_64__)
#define TROCHOMILL_FIRST_LOOK 1
// Whether the processor has AVX2 (asked once).
bool has_avx2() {
  static const bool yes = __builtin_cpu_supports("avx2") != 0;
  return yes;
}

__attribute__((target("avx2"))) void first_look(const EdgeStep& e, const double* z, std::size_t j0,
                                                std::size_t n, long long* keep) {
  const double flat = e.reach - e.rc;
  const V4 x0 = V4{} + e.x0, uax = V4{} + e.uax, uay = V4{} + e.uay, ubx = V4{} + e.ubx,
           uby = V4{} + e.uby, aax = V4{} + e.aax, aay = V4{} + e.aay, abx = V4{} + e.abx,
           aby = V4{} + e.aby, rc = V4{} + e.rc, vflat = V4{} + flat, slack = V4{} + e.slack,
           zero = V4{}, lanes = {0, 1, 2, 3};
  const double inv_2rc = 0.5 / e.rc;  // inf for a sharp corner: its lanes marked (NaN)
  for (std::size_t k = 0; k < n; k += 4) {
    V4 zq;
    if (k + 4 <= n) {
      std::memcpy(&zq, z + j0 + k, sizeof zq);
    } else {
      // The last vector's lanes past n repeat its last point (their marks are not read).
      for (std::size_t l = 0; l < 4; ++l) zq[l] = z[j0 + std::min(k + l, n - 1)];
    }
    // The points' y: whole numbers as doubles, exact.
    const V4 py = e.y_from + e.dy * (static_cast<double>(j0 + k) + lanes);
    const V4 ga = uax * (py - aay) - uay * (x0 - aax);
    const V4 gb = ubx * (py - aby) - uby * (x0 - abx);
    const M4 through = ((ga < zero) & (gb > zero)) | ((ga > zero) & (gb < zero));
    const V4 u = ga / (ga - gb);
    const V4 a0x = aax + u * (abx - aax), a0y = aay + u * (aby - aay);
    const V4 u0x = uax + u * (ubx - uax), u0y = uay + u * (uby - uay);
    const V4 x = u * (1 - u) * e.turn2;
    const V4 r0 = (u0x * (x0 - a0x) + u0y * (py - a0y)) * (1 + x * (0.5 + 0.375 * x));
    const M4 within = ~((r0 < -slack) | (r0 > e.reach + slack));
    // rise(reach, r0): (flat - r0) tan(dish) up to the flat's end, the corner arc beyond.
    const V4 over = r0 - vflat;
    const M4 capped = rc < over;
    const V4 m = (V4)((capped & (M4)rc) | (~capped & (M4)over));
    const V4 corner = m * m * inv_2rc;
    const V4 dished = (vflat - r0) * e.tan_dish;
    const M4 on_flat = r0 <= vflat;
    const V4 rise = (V4)((on_flat & (M4)dished) | (~on_flat & (M4)corner));
    const V4 h0 = e.za + u * (e.zb - e.za) + e.tip + rise;
    const M4 low = ~(h0 > zq + slack + 1e-9);
    // (Copied, not stored as a vector: the buffer need not be aligned for one.)
    const M4 mark = (ga == zero) | (through & within & low);
    std::memcpy(keep + k, &mark, sizeof mark);
  }
}
#endif

}  // namespace

std::atomic<bool>& detail::floor_vector_look() {
#ifdef TROCHOMILL_FIRST_LOOK
  static std::atomic<bool> on{has_avx2()};
#else
  static std::atomic<bool> on{false};
#endif
  return on;
}

FloorProfile floor_profile(const PathSamples& s, const Tool& tool, double omega, double x0,
                           double y_from, double dy, std::size_t points) {
  const double R = tool.radius_mm(), rc = tool.corner_radius_mm;
  if (!(std::isfinite(x0) && std::isfinite(y_from) && dy > 0 && std::isfinite(dy) && points >= 2 &&
        points <= 50'000'000)) {
    throw InputError(fmt::format(
        "floor profile: need a finite line, a positive spacing and 2 to 5e7 points (x {} mm, "
        "from {} mm, spacing {} mm, {} points)",
        x0, y_from, dy, points));
  }
  if (!(R > 0) || !(rc >= 0 && rc <= R) || tool.teeth < 1 ||
      tool.tooth_angles_deg.size() != static_cast<std::size_t>(tool.teeth) ||
      !(tool.dish_angle_deg >= 0 && tool.dish_angle_deg < 10) || !std::isfinite(omega) ||
      omega == 0) {
    throw InputError(
        "floor profile: the tool needs a radius, a corner radius within it, one angle per tooth, "
        "a dish angle in [0, 10) degrees and a turning spindle");
  }
  const double tan_dish = std::tan(deg_to_rad(tool.dish_angle_deg));
  const double e = tool.runout_radial_mm, lambda = deg_to_rad(tool.runout_phase_deg);
  std::vector<EndEdge> edges;
  for (std::size_t k = 0; k < tool.tooth_angles_deg.size(); ++k) {
    const double alpha = deg_to_rad(tool.tooth_angles_deg[k]);
    const double radial = k < tool.insert_radial_mm.size() ? tool.insert_radial_mm[k] : 0.0;
    const double axial = k < tool.insert_axial_mm.size() ? tool.insert_axial_mm[k] : 0.0;
    edges.push_back({alpha, R + radial, -tool.runout_axial_mm * std::cos(alpha - lambda) - axial});
  }
  // The edge's height above its tip at distance r from the axis.
  auto rise = [&](double reach, double r) {
    const double flat = reach - rc;
    if (r <= flat) return (flat - r) * tan_dish;
    const double u = std::min(r - flat, rc);
    return rc - std::sqrt(rc * rc - u * u);
  };
  FloorProfile f;
  f.x_mm = x0;
  f.y_from_mm = y_from;
  f.dy_mm = dy;
  f.z_mm.assign(points, std::numeric_limits<double>::infinity());
  const double y_to = y_from + dy * static_cast<double>(points - 1);
  const double max_step = deg_to_rad(5.0);
  double reach = 0;
  for (const EndEdge& ed : edges) reach = std::max(reach, ed.reach_mm);
  reach += e;
  const std::size_t n = s.size();
  struct Turn {
    double c, s;  // cosine and sine of a fixed angle
  };
  const Turn runout_turn{std::cos(lambda), std::sin(lambda)};
  std::vector<Turn> tooth_turn;
  for (const EndEdge& ed : edges)
    tooth_turn.push_back({std::cos(ed.angle_rad), std::sin(ed.angle_rad)});
  // The spindle's angles grow with the program's time (thousands of radians): their sines
  // and cosines from the table (within 2.2e-16 of libm's up to 2e7 rad, several times faster;
  // they were a third of the floor's time).
  const detail::SinCosTable& sc = detail::sincos_table();
  const auto dir = [&](double th) {
    const detail::SinCos q = sc(th);
    return V2{q.c, q.s};
  };
  // The first look four points a vector where the processor has AVX2 (the switch alone never
  // turns it on).
#ifdef TROCHOMILL_FIRST_LOOK
  const bool vector_look =
      has_avx2() && detail::floor_vector_look().load(std::memory_order_relaxed);
#else
  constexpr bool vector_look = false;
#endif
  std::vector<long long> keep;  // first_look's marks of a range
  // One sweep over the path: the passes of the edges' parts at least `inner` from the axis,
  // over the points `todo` marks (all when empty).
  auto sweep = [&](double inner, const std::vector<char>& todo) {
    // The last spindle angle whose cosine and sine were taken: a step's end is the next
    // one's start (the same double), so each is taken once.
    double last_p = std::numeric_limits<double>::quiet_NaN();
    V2 last_u{1, 0};
    const auto spindle = [&](double ph) {
      if (ph != last_p) {
        last_p = ph;
        last_u = dir(ph);
      }
      return last_u;
    };
    for (std::size_t i = 0; i + 1 < n; ++i) {
      const double dt = s.t_s[i + 1] - s.t_s[i];
      if (!(dt > 0)) continue;
      // Skip intervals whose tool cannot reach the line within the profile's y range.
      const double xlo = std::min(s.x_mm[i], s.x_mm[i + 1]) - reach;
      const double xhi = std::max(s.x_mm[i], s.x_mm[i + 1]) + reach;
      const double ylo = std::min(s.y_mm[i], s.y_mm[i + 1]) - reach;
      const double yhi = std::max(s.y_mm[i], s.y_mm[i + 1]) + reach;
      if (x0 < xlo || x0 > xhi || yhi < y_from || ylo > y_to) continue;
      const int m = std::max(1, static_cast<int>(std::ceil(std::abs(omega) * dt / max_step)));
      for (int j = 0; j < m; ++j) {
        const double fa = static_cast<double>(j) / m, fb = static_cast<double>(j + 1) / m;
        const double ta = s.t_s[i] + fa * dt, tb = s.t_s[i] + fb * dt;
        const V2 ca{s.x_mm[i] + fa * (s.x_mm[i + 1] - s.x_mm[i]),
                    s.y_mm[i] + fa * (s.y_mm[i + 1] - s.y_mm[i])};
        const V2 cb{s.x_mm[i] + fb * (s.x_mm[i + 1] - s.x_mm[i]),
                    s.y_mm[i] + fb * (s.y_mm[i + 1] - s.y_mm[i])};
        const double za = s.z_mm[i] + fa * (s.z_mm[i + 1] - s.z_mm[i]);
        const double zb = s.z_mm[i] + fb * (s.z_mm[i + 1] - s.z_mm[i]);
        const double pa = omega * ta, pb = omega * tb;
        // The spindle's direction at both ends and halfway (one sine and cosine each), the
        // teeth's and the runout's turned from it by their fixed angles.
        const V2 sa = spindle(pa), sb = spindle(pb);
        const double pm = 0.5 * (pa + pb);
        const V2 sm = dir(pm);
        auto turned = [](V2 u, const Turn& t) {
          return V2{u.x * t.c - u.y * t.s, u.x * t.s + u.y * t.c};
        };
        // The axis: the centre plus the runout offset turning with the spindle.
        const V2 ra = turned(sa, runout_turn), rb = turned(sb, runout_turn);
        const V2 aa{ca.x + e * ra.x, ca.y + e * ra.y};
        const V2 ab{cb.x + e * rb.x, cb.y + e * rb.y};
        const double half = 0.5 * std::abs(pb - pa);
        const double cos_half = std::cos(half);  // the same for every edge
        for (std::size_t k = 0; k < edges.size(); ++k) {
          const EndEdge& ed = edges[k];
          const V2 ua = turned(sa, tooth_turn[k]), ub = turned(sb, tooth_turn[k]);
          const V2 um = turned(sm, tooth_turn[k]);
          // The region the edge sweeps lies in the hull of its ends and the tangents' meeting
          // points (reach / cos(half the turn) along the middle direction); runout's axis arc
          // bulges by at most e (1 - cos half), padded.
          const double far = ed.reach_mm / cos_half;
          // Most edges point away from the line: none of the hull's points on either side of
          // it (then no pair below straddles it). The points' x first: most steps end here.
          const std::array<double, 6> hx = {aa.x + inner * ua.x,       ab.x + inner * ub.x,
                                            aa.x + ed.reach_mm * ua.x, ab.x + ed.reach_mm * ub.x,
                                            aa.x + far * um.x,         ab.x + far * um.x};
          bool left = false, right = false;
          for (const double x : hx) {
            left = left || x <= x0;
            right = right || x >= x0;
          }
          if (!(left && right)) continue;
          const std::array<V2, 6> hull = {
              V2{hx[0], aa.y + inner * ua.y},       V2{hx[1], ab.y + inner * ub.y},
              V2{hx[2], aa.y + ed.reach_mm * ua.y}, V2{hx[3], ab.y + ed.reach_mm * ub.y},
              V2{hx[4], aa.y + far * um.y},         V2{hx[5], ab.y + far * um.y}};
          const double tha = pa + ed.angle_rad;
          const double turn2 = 2 * (1 - dot(ua, ub));  // 2 (1 - cos) of the step's turn
          double lo = std::numeric_limits<double>::infinity(), hi = -lo;
          for (std::size_t p = 0; p < hull.size(); ++p) {
            for (std::size_t q = p; q < hull.size(); ++q) {
              const V2 A = hull[p], B = hull[q];
              if ((A.x - x0) * (B.x - x0) > 0) continue;
              if (A.x == B.x) {  // both on the line
                lo = std::min({lo, A.y, B.y});
                hi = std::max({hi, A.y, B.y});
                continue;
              }
              const double y = A.y + (x0 - A.x) / (B.x - A.x) * (B.y - A.y);
              lo = std::min(lo, y);
              hi = std::max(hi, y);
            }
          }
          if (!(lo <= hi)) continue;
          const double pad = e * half * half + 1e-9;
          lo -= pad;
          hi += pad;
          if (hi < y_from || lo > y_to) continue;
          const auto j0 = static_cast<std::size_t>(std::max(0.0, std::ceil((lo - y_from) / dy)));
          const auto j1 = static_cast<std::size_t>(
              std::min(static_cast<double>(points - 1), std::floor((hi - y_from) / dy)));
          if (j0 > j1 || j0 >= points) continue;
          const std::size_t count = std::min(j1, points - 1) - j0 + 1;
          // The secant estimate's error bound (below).
          const double slack = e * half * half + 1e-6;
          // The first look at every point of the range at once (first_look) where the
          // processor has AVX2; the rest of the look where it could not pass over the point.
#ifdef TROCHOMILL_FIRST_LOOK
          if (vector_look) {
            if (keep.size() < count + 3) keep.resize(count + 3);  // whole vectors
            first_look(EdgeStep{x0, y_from, dy, ua.x, ua.y, ub.x, ub.y, aa.x, aa.y, ab.x, ab.y, za,
                                zb, ed.tip_dz_mm, ed.reach_mm, rc, tan_dish, turn2, slack},
                       f.z_mm.data(), j0, count, keep.data());
          }
#endif
          for (std::size_t q = j0; q < j0 + count; ++q) {
            if (vector_look && keep[q - j0] == 0) continue;
            if (!todo.empty() && !todo[q]) continue;
            const V2 p{x0, y_from + dy * static_cast<double>(q)};
            const double ga = cross(ua, V2{p.x - aa.x, p.y - aa.y});
            const double gb = cross(ub, V2{p.x - ab.x, p.y - ab.y});
            // The edge's line passes the point where the cross product changes sign (at the
            // step's start when it is zero there; a zero at the end is the next step's start).
            const bool through = (ga < 0 && gb > 0) || (ga > 0 && gb < 0);
            if (!(ga == 0 || through)) continue;
            // The edge at a fraction of the step: the axis on the centre's chord plus the runout
            // turning with the spindle, the direction turning evenly.
            auto edge_at = [&](double u, V2& a, double& th) {
              const double ph = pa + u * (pb - pa);
              const detail::SinCos r = sc(ph + lambda);
              a = V2{ca.x + u * (cb.x - ca.x) + e * r.c, ca.y + u * (cb.y - ca.y) + e * r.s};
              th = ph + ed.angle_rad;
            };
            double u = 0, lo_u = 0, hi_u = 1, g_lo = ga, g_hi = gb;
            V2 a = aa;
            double th = tha;
            if (ga != 0) {
              // The secant's estimate first: a pass it puts well above the floor found so far
              // (by more than its error, `slack`) or on the
              // flat of a flat end face at a constant height (where the time does not matter)
              // needs no more.
              // (Without trigonometry: the axis on the chord between the step's ends, off the
              // runout's arc by e (1 - cos half) <= 3e-6 mm for e <= 0.1 mm; the direction
              // interpolated and normalised, off by third order in the step.)
              u = ga / (ga - gb);
              const V2 a0{aa.x + u * (ab.x - aa.x), aa.y + u * (ab.y - aa.y)};
              const V2 u0{ua.x + u * (ub.x - ua.x), ua.y + u * (ub.y - ua.y)};
              // |u0|^2 = 1 - u (1 - u) turn2 for unit ua, ub: 1 / |u0| by its series to the
              // second order (the third, 0.32 x^3 with x <= 0.0019 for a 5 degree step, is
              // 2e-9 of r0: far inside `slack`, whose tests it only feeds).
              const double x = u * (1 - u) * turn2;
              const double r0 = dot(u0, V2{p.x - a0.x, p.y - a0.y}) * (1 + x * (0.5 + 0.375 * x));
              if (r0 < -slack || r0 > ed.reach_mm + slack) continue;
              const double h0 = za + u * (zb - za) + ed.tip_dz_mm + rise(ed.reach_mm, r0);
              if (h0 > f.z_mm[q] + slack) continue;
              if (tan_dish == 0 && za == zb && r0 >= slack && r0 < ed.reach_mm - rc - slack) {
                f.z_mm[q] = std::min(f.z_mm[q], za + ed.tip_dz_mm);
                continue;
              }
              // The secant's zero, refined twice by regula falsi on the exact edge: the crossing
              // time to rounding (one secant leaves a third-order error in the step).
              for (int it = 0; it < 3; ++it) {
                u = lo_u + (hi_u - lo_u) * g_lo / (g_lo - g_hi);
                edge_at(u, a, th);
                const double g = cross(dir(th), V2{p.x - a.x, p.y - a.y});
                if (g == 0) break;
                if ((g < 0) == (g_lo < 0)) {
                  lo_u = u;
                  g_lo = g;
                } else {
                  hi_u = u;
                  g_hi = g;
                }
              }
            }
            const double r = dot(dir(th), V2{p.x - a.x, p.y - a.y});
            if (r < 0 || r > ed.reach_mm) continue;  // behind the axis or beyond the corner
            const double z = za + u * (zb - za) + ed.tip_dz_mm + rise(ed.reach_mm, r);
            f.z_mm[q] = std::min(f.z_mm[q], z);
          }
        }
      }
    }
  };
  // A dished edge is lowest at its corner: a pass of the part within `band` of the flat's end
  // leaves at most band tan(dish) above the lowest tip, a pass further in more. So the outer
  // band first, then everything only where that left the floor higher (or uncut): exact, and
  // most points see only the band's passes (a fraction of the edge's sweep over the line).
  double flat_end = std::numeric_limits<double>::infinity(), low_tip = flat_end, low_z = flat_end;
  for (const EndEdge& ed : edges) {
    flat_end = std::min(flat_end, ed.reach_mm - rc);
    low_tip = std::min(low_tip, ed.tip_dz_mm);
  }
  for (const double z : s.z_mm) low_z = std::min(low_z, z);
  const double band = 0.05 * R;
  if (tan_dish > 0 && flat_end > band) {
    sweep(flat_end - band, {});
    std::vector<char> todo(points, 0);
    bool any = false;
    const double sure = low_z + low_tip + band * tan_dish;
    for (std::size_t q = 0; q < points; ++q) {
      if (!(f.z_mm[q] <= sure)) todo[q] = any = 1;
    }
    if (any) sweep(0.0, todo);
  } else {
    sweep(0.0, {});
  }
  for (double& z : f.z_mm) {
    if (std::isinf(z)) z = std::nan("");
  }
  return f;
}

}  // namespace trochomill
