// The machined slot read off the tri-dexel workpiece: wall profiles from the X board, floor
// profiles and the machined surface (a height field) from the Z board
// (include/trochomill/sim.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"

namespace trochomill {

namespace {

// Every `stride`-th index of [0, n), always including the last.
std::vector<int> strided(int n, int stride) {
  std::vector<int> out;
  for (int k = 0; k < n; k += std::max(1, stride)) out.push_back(k);
  if (n > 0 && out.back() != n - 1) out.push_back(n - 1);
  return out;
}

// The top of the Z board's ray (i, j) (mm): its highest material, the stock's bottom when
// it holds none.
double top_of(const DexelBoard& zb, int i, int j) {
  const std::span<const Interval> ray = zb.intervals(i, j);
  return ray.empty() ? zb.full().lo : ray.back().hi;
}

}  // namespace

std::vector<WallPoint> wall_profiles(const TriDexel& work, double centre_x_mm, int levels) {
  const DexelBoard& xb = work.boards[0];  // rays along x at (y, z) = (u, v)
  std::vector<WallPoint> out;
  const int stride = std::max(1, xb.count_v() / std::max(1, levels));
  for (const int k : strided(xb.count_v(), stride)) {
    for (int i = 0; i < xb.count_u(); ++i) {
      if (!xb.touched(i, k)) continue;
      // The slot's walls: the material boundaries nearest the centre line on either side
      // (the stock's edge where the cut runs out of it); no wall where material crosses it.
      double left = xb.full().lo, right = xb.full().hi;
      bool solid = false;
      for (const Interval& v : xb.intervals(i, k)) {
        if (v.hi <= centre_x_mm) left = v.hi;
        if (v.lo >= centre_x_mm) {
          right = v.lo;
          break;
        }
        if (v.lo < centre_x_mm && v.hi > centre_x_mm) solid = true;
      }
      if (solid) continue;
      out.push_back({xb.u_of(i), xb.v_of(k), left, right});
    }
  }
  return out;
}

std::vector<FloorPoint> floor_profiles(const TriDexel& work, int rows) {
  const DexelBoard& zb = work.boards[2];  // rays along z at (x, y) = (u, v)
  std::vector<FloorPoint> out;
  const int stride = std::max(1, zb.count_v() / std::max(1, rows));
  for (const int j : strided(zb.count_v(), stride)) {
    bool any = false;
    for (int i = 0; i < zb.count_u() && !any; ++i) any = zb.touched(i, j);
    if (!any) continue;
    for (int i = 0; i < zb.count_u(); ++i) {
      out.push_back({zb.u_of(i), zb.v_of(j), top_of(zb, i, j)});
    }
  }
  return out;
}

HeightField surface_height_field(const TriDexel& work, double step_mm) {
  const DexelBoard& zb = work.boards[2];
  const double d = zb.spacing();
  const int stride = std::max(1, static_cast<int>(std::lround(std::max(step_mm, d) / d)));
  HeightField f;
  f.x_mm_of_column.reserve(static_cast<std::size_t>(zb.count_u() / stride + 2));
  const std::vector<int> cols = strided(zb.count_u(), stride);
  const std::vector<int> rows = strided(zb.count_v(), stride);
  for (const int i : cols) f.x_mm_of_column.push_back(zb.u_of(i));
  for (const int j : rows) f.y_mm_of_row.push_back(zb.v_of(j));
  f.z_mm.resize(cols.size() * rows.size());
  f.bottom_mm = zb.full().lo;
  for (std::size_t a = 0; a < cols.size(); ++a) {
    for (std::size_t b = 0; b < rows.size(); ++b) {
      f.z_mm[a * rows.size() + b] = top_of(zb, cols[a], rows[b]);
    }
  }
  return f;
}

HeightMap floor_height_map(const TriDexel& work, double x_from_mm, double x_to_mm,
                           double below_mm) {
  const DexelBoard& zb = work.boards[2];
  // The columns within [x_from, x_to].
  int c0 = zb.count_u(), c1 = -1;
  for (int i = 0; i < zb.count_u(); ++i) {
    if (zb.u_of(i) >= x_from_mm && zb.u_of(i) <= x_to_mm) c0 = std::min(c0, i), c1 = i;
  }
  auto top = [&](int i, int j) { return top_of(zb, i, j); };
  // The longest run of rows cut across the whole range.
  int best0 = 0, best_n = 0;
  for (int j = 0, run0 = 0, run = 0; j < zb.count_v() && c1 >= c0; ++j) {
    bool cut = true;
    for (int i = c0; i <= c1 && cut; ++i) cut = top(i, j) < below_mm;
    run = cut ? run + 1 : 0;
    if (run == 1) run0 = j;
    if (run > best_n) best0 = run0, best_n = run;
  }
  if (c1 - c0 + 1 < 2 || best_n < 2) {
    throw InputError(fmt::format(
        "floor: no two rows of the workpiece are cut below z = {:g} mm across x = {:g} to {:g} "
        "mm (simulate more of the path, or a window where the tool crosses the slot)",
        below_mm, x_from_mm, x_to_mm));
  }
  HeightMap m;
  m.nx = static_cast<std::size_t>(c1 - c0 + 1);
  m.ny = static_cast<std::size_t>(best_n);
  m.dx_mm = m.dy_mm = zb.spacing();
  m.x0_mm = zb.u_of(c0);
  m.y0_mm = zb.v_of(best0);
  m.z_mm.reserve(m.nx * m.ny);
  for (int j = best0; j < best0 + best_n; ++j) {
    for (int i = c0; i <= c1; ++i) m.z_mm.push_back(top(i, j));
  }
  m.description = fmt::format("floor, simulated: x {:.4g} to {:.4g} mm, y {:.4g} to {:.4g} mm",
                              m.x0_mm, zb.u_of(c1), m.y0_mm, zb.v_of(best0 + best_n - 1));
  return m;
}

}  // namespace trochomill

namespace trochomill {

double default_surface_step_mm(const TriDexel& work) {
  const DexelBoard& zb = work.boards[2];
  const double cells = static_cast<double>(zb.count_u()) * static_cast<double>(zb.count_v());
  return zb.spacing() * std::max(1.0, std::ceil(std::sqrt(2.0 * cells / 4e6)));
}

}  // namespace trochomill
