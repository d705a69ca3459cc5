// Machining time with an acceleration limit: the path is discretised, each node gets a speed
// limit (programmed speed, centripetal limit sqrt(a / kappa), junction-deviation limit at
// tangent discontinuities as Grbl plans corners, zero at start and end), then a forward and
// a backward pass apply |dv/dt| <= a. Each piece is then run as fast as its own speed limit
// and a allow between its end speeds: accelerate, cruise at the limit, decelerate (or a
// triangle when the piece is too short to reach the limit). That is exact for the piecewise
// model, and tends to the programmed time as a grows (2 ds / (v0 + v1), which the estimate
// used before, doubled the time of every piece starting or ending at rest however large a).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "trochomill/path.hpp"

namespace trochomill {

double estimate_time_s(const ToolPath& path, const Machine& machine) {
  const double amax = machine.max_acceleration_mm_per_s2;
  if (!(amax > 0) || path.empty()) return path.duration_s();
  const double inf = std::numeric_limits<double>::infinity();
  // Node spacing: fine enough for curvature changes, bounded in count.
  const double total = path.length_mm();
  const double ds_target = std::max(0.05, total / 2e6);

  std::vector<double> ds;    // length of the piece ending at node j (ds[0] = 0)
  std::vector<double> vlim;  // speed limit at node j (mm/s)
  std::vector<double> vcap;  // speed limit inside the piece ending at node j (mm/s)
  ds.push_back(0);
  vlim.push_back(0);  // the machine starts at rest
  vcap.push_back(0);
  const auto& segs = path.segments();
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const Segment& g = segs[i];
    const double F = g.speed_mm_per_min() / 60.0;
    if (i > 0) {
      // Junction between segment i-1 and i: the node already pushed is the shared point.
      const Segment& prev = segs[i - 1];
      const Vec3 t0 = prev.tangent_at(prev.length_mm());
      const Vec3 t1 = g.tangent_at(0);
      const double cos_theta = -t0.dot(t1);
      double vj;
      if (cos_theta > 0.999999) {
        vj = 0;  // reversal
      } else if (cos_theta < -0.999999) {
        vj = inf;  // straight through
      } else {
        const double sin_half = std::sqrt(0.5 * (1.0 - cos_theta));
        vj = std::sqrt(amax * machine.junction_deviation_mm * sin_half / (1.0 - sin_half));
      }
      vlim.back() = std::min({vlim.back(), vj, F});
    }
    const int n = std::max(1, static_cast<int>(std::ceil(g.length_mm() / ds_target)));
    if (g.kind() == Segment::Kind::line) {
      for (int k = 1; k <= n; ++k) {
        ds.push_back(g.length_mm() / n);
        vlim.push_back(F);
        vcap.push_back(F);
      }
      continue;
    }
    // Curves: nodes uniform in the parameter (no arc-length inversion), piece lengths by
    // the midpoint rule scaled so they sum to the exact length (relative error O(du^2)
    // inside a segment, none in its total).
    const double du = (g.u1() - g.u0()) / n;
    const std::size_t first = ds.size();
    double sum = 0;
    for (int k = 1; k <= n; ++k) {
      const double u = g.u0() + du * k;
      const Vec3 d1 = g.derivative_u(u), d2 = g.second_derivative_u(u);
      const double speed = d1.norm();
      const double kappa = speed > 0 ? d1.cross(d2).norm() / (speed * speed * speed) : 0.0;
      double v = F;
      if (kappa > 0) v = std::min(v, std::sqrt(amax / kappa));
      const double piece = g.derivative_u(u - 0.5 * du).norm() * std::abs(du);
      ds.push_back(piece);
      sum += piece;
      vlim.push_back(v);
      vcap.push_back(v);
    }
    if (sum > 0) {
      for (std::size_t j = first; j < ds.size(); ++j) ds[j] *= g.length_mm() / sum;
    }
  }
  vlim.back() = 0;  // and stops at the end
  const std::size_t m = vlim.size();
  std::vector<double> v(vlim);
  for (std::size_t j = 1; j < m; ++j)
    v[j] = std::min(v[j], std::sqrt(v[j - 1] * v[j - 1] + 2 * amax * ds[j]));
  for (std::size_t j = m - 1; j-- > 0;)
    v[j] = std::min(v[j], std::sqrt(v[j + 1] * v[j + 1] + 2 * amax * ds[j + 1]));
  double t = 0;
  for (std::size_t j = 1; j < m; ++j) {
    const double v0 = v[j - 1], v1 = v[j];
    const double top = std::max({vcap[j], v0, v1});
    if (!(top > 0)) continue;
    const double d_up = (top * top - v0 * v0) / (2 * amax);
    const double d_down = (top * top - v1 * v1) / (2 * amax);
    if (d_up + d_down <= ds[j]) {
      t += (top - v0) / amax + (top - v1) / amax + (ds[j] - d_up - d_down) / top;
    } else {  // a triangle: the peak speed where accelerating and braking meet
      const double peak =
          std::sqrt(std::max({v0 * v0, v1 * v1, 0.5 * (2 * amax * ds[j] + v0 * v0 + v1 * v1)}));
      t += (peak - v0) / amax + (peak - v1) / amax;
    }
  }
  return t;
}

}  // namespace trochomill
