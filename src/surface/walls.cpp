// Slot walls as envelopes (of circles, or of tooth-tip polylines) on a y grid, and the
// bottom imprint density, and the texture of a wall (include/trochomill/surface.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "trochomill/error.hpp"
#include "trochomill/surface.hpp"

namespace trochomill {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Grid {
  double y0, dy;
  int n;
  [[nodiscard]] double y(int k) const { return y0 + dy * k; }
  // Grid indices with y in [lo, hi].
  [[nodiscard]] std::pair<int, int> range(double lo, double hi) const {
    const int a = std::max(0, static_cast<int>(std::ceil((lo - y0) / dy - 1e-9)));
    const int b = std::min(n - 1, static_cast<int>(std::floor((hi - y0) / dy + 1e-9)));
    return {a, b};
  }
};

Grid make_grid(double y_from, double y_to, int points) {
  if (!(y_to > y_from) || points < 3) {
    throw InputError(
        fmt::format("wall profile: need y_to > y_from and >= 3 points (got [{}, {}], {})", y_from,
                    y_to, points));
  }
  return Grid{y_from, (y_to - y_from) / (points - 1), points};
}

WallProfile finish(const Grid& g, std::vector<double> x, bool left, const char* what) {
  WallProfile w;
  w.y_mm.resize(static_cast<std::size_t>(g.n));
  for (int k = 0; k < g.n; ++k) {
    w.y_mm[static_cast<std::size_t>(k)] = g.y(k);
    if (!std::isfinite(x[static_cast<std::size_t>(k)])) {
      throw InputError(fmt::format("{} {} wall: nothing cuts the wall at y = {:.4f} mm", what,
                                   left ? "left" : "right", g.y(k)));
    }
  }
  // The least-cut point: the largest x on the left wall, the smallest on the right.
  const auto [mn, mx] = std::minmax_element(x.begin(), x.end());
  w.waviness_mm = *mx - *mn;
  w.peak_y_mm = w.y_mm[static_cast<std::size_t>((left ? mx : mn) - x.begin())];
  w.x_mm = std::move(x);
  return w;
}

}  // namespace

Walls walls_from_circles(const PathSamples& s, double R, double z_max, double y_from, double y_to,
                         int points) {
  const Grid g = make_grid(y_from, y_to, points);
  std::vector<double> xl(static_cast<std::size_t>(g.n), kInf),
      xr(static_cast<std::size_t>(g.n), -kInf);
  // Only circles that reach near the extreme x can shape a wall: first the extremes, then
  // every circle within a band of them (the band grows until it holds the whole profile).
  double lo = kInf, hi = -kInf;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s.z_mm[i] > z_max || s.y_mm[i] < y_from - R || s.y_mm[i] > y_to + R) continue;
    lo = std::min(lo, s.x_mm[i]);
    hi = std::max(hi, s.x_mm[i]);
  }
  if (!(lo <= hi)) {
    throw InputError(fmt::format(
        "wall profile: no cutting sample within R of y in [{:.4f}, {:.4f}] mm", y_from, y_to));
  }
  for (double band = 0.005;; band *= 2) {
    // A circle lowers the left profile below lo - R + band only within |dy| < sqrt(2 R band).
    const double reach = std::sqrt(std::max(0.0, 2 * R * band - band * band));
    std::fill(xl.begin(), xl.end(), kInf);
    std::fill(xr.begin(), xr.end(), -kInf);
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (s.z_mm[i] > z_max) continue;
      const bool near_l = s.x_mm[i] <= lo + band, near_r = s.x_mm[i] >= hi - band;
      if (!near_l && !near_r) continue;
      const auto [a, b] = g.range(s.y_mm[i] - reach, s.y_mm[i] + reach);
      for (int k = a; k <= b; ++k) {
        const double dy = g.y(k) - s.y_mm[i];
        const double half = std::sqrt(std::max(0.0, R * R - dy * dy));
        const auto kk = static_cast<std::size_t>(k);
        if (near_l) xl[kk] = std::min(xl[kk], s.x_mm[i] - half);
        if (near_r) xr[kk] = std::max(xr[kk], s.x_mm[i] + half);
      }
    }
    // Complete when every grid point is cut and the profile stays inside the band: a
    // circle centred beyond the band reaches no lower than lo + band - R on the left wall,
    // above every point of the profile, so it cannot change it (likewise on the right).
    const double wl = *std::max_element(xl.begin(), xl.end()) - (lo - R);
    const double wr = (hi + R) - *std::min_element(xr.begin(), xr.end());
    if ((std::isfinite(wl) && std::isfinite(wr) && wl < band && wr < band) || band > 4 * R) break;
  }
  return {finish(g, std::move(xl), true, "path-level"),
          finish(g, std::move(xr), false, "path-level")};
}

Walls walls_from_tips(const ToothTracks& tr, double z_max, double y_from, double y_to, int points,
                      double band) {
  const Grid g = make_grid(y_from, y_to, points);
  double gmin = kInf, gmax = -kInf;
  for (int k = 0; k < tr.teeth; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    for (std::size_t i = 0; i < tr.x_mm[kk].size(); ++i) {
      if (tr.z_mm[kk][i] > z_max) continue;
      gmin = std::min(gmin, tr.x_mm[kk][i]);
      gmax = std::max(gmax, tr.x_mm[kk][i]);
    }
  }
  std::vector<double> xl(static_cast<std::size_t>(g.n), kInf),
      xr(static_cast<std::size_t>(g.n), -kInf);
  for (int k = 0; k < tr.teeth; ++k) {
    const auto& X = tr.x_mm[static_cast<std::size_t>(k)];
    const auto& Y = tr.y_mm[static_cast<std::size_t>(k)];
    const auto& Zt = tr.z_mm[static_cast<std::size_t>(k)];
    for (std::size_t i = 0; i + 1 < X.size(); ++i) {
      if (Zt[i] > z_max || Zt[i + 1] > z_max) continue;
      const double xa = std::min(X[i], X[i + 1]), xb = std::max(X[i], X[i + 1]);
      const bool to_left = xa <= gmin + band, to_right = xb >= gmax - band;
      if (!to_left && !to_right) continue;
      const double ya = Y[i], yb = Y[i + 1];
      const auto [a, b] = g.range(std::min(ya, yb), std::max(ya, yb));
      for (int q = a; q <= b; ++q) {
        const double y = g.y(q);
        const double u = yb != ya ? (y - ya) / (yb - ya) : 0.0;
        const double x = X[i] + u * (X[i + 1] - X[i]);
        const auto qq = static_cast<std::size_t>(q);
        if (to_left) xl[qq] = std::min(xl[qq], x);
        if (to_right) xr[qq] = std::max(xr[qq], x);
      }
    }
  }
  return {finish(g, std::move(xl), true, "tooth-level"),
          finish(g, std::move(xr), false, "tooth-level")};
}

ImprintDensity bottom_imprint_density(const std::vector<double>& cx, double R, double hw,
                                      double advance, int points) {
  if (points < 3 || !(advance > 0) || !(hw > 0) || !(R > 0)) {
    throw InputError(fmt::format(
        "bottom imprint density: need >= 3 points, advance > 0 and positive sizes (got {}, {}, "
        "{}, {})",
        points, advance, hw, R));
  }
  ImprintDensity d;
  d.x_mm.resize(static_cast<std::size_t>(points));
  d.crossings_per_mm.assign(static_cast<std::size_t>(points), 0.0);
  for (int k = 0; k < points; ++k)
    d.x_mm[static_cast<std::size_t>(k)] = -hw + 2 * hw * k / (points - 1);
  for (const double x : cx) {
    for (int k = 0; k < points; ++k) {
      // A circle crosses the line x = X twice when |x - X| < R (once when tangent).
      const double dx = std::abs(x - d.x_mm[static_cast<std::size_t>(k)]);
      if (dx < R) d.crossings_per_mm[static_cast<std::size_t>(k)] += 2;
    }
  }
  for (auto& c : d.crossings_per_mm) c /= advance;
  return d;
}

ProfileTexture wall_texture(const WallProfile& wall, bool left, std::optional<double> cutoff_mm) {
  if (wall.x_mm.size() < 3) {
    throw InputError(fmt::format("wall texture: the {} wall's profile has {} points (3 or more)",
                                 left ? "left" : "right", wall.x_mm.size()));
  }
  std::vector<double> z(wall.x_mm.begin(), wall.x_mm.end() - 1);
  if (!left) {
    for (double& v : z) v = -v;
  }
  const double dy =
      (wall.y_mm.back() - wall.y_mm.front()) / static_cast<double>(wall.y_mm.size() - 1);
  return periodic_profile_texture(z, dy, cutoff_mm);
}

}  // namespace trochomill
