// The exact engagement kernel (see include/trochomill/engagement.hpp for the model).
//
// Removed region R = union of discs of radius R at inserted centres. Its boundary is the set
// of exposed arcs: for each "alive" disc, the parts of its circle not covered by any other
// disc. Inserting a disc trims the exposed arcs of its neighbours (dropping those left with
// none) and gives the new disc the part of its circle outside R. The part of any circle
// outside R is found by walking its crossings with exposed arcs from a reference point of
// known status; crossings are counted on half-open arcs [a, b) so a boundary vertex shared
// by two arcs is counted once. Disc positions live in a uniform grid of cell size 2R.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

constexpr double kEps = 1e-12;

double wrap(double a) {  // to [0, 2 pi)
  a = std::fmod(a, kTwoPi);
  if (a < 0) a += kTwoPi;
  return a >= kTwoPi ? 0.0 : a;
}

// A set of angles on a circle: sorted disjoint intervals within [0, 2 pi].
using ArcSet = std::vector<AngleArc>;

bool contains(const ArcSet& set, double a) {  // half-open [start, end)
  for (const auto& arc : set) {
    if (a >= arc.start_rad && a < arc.end_rad) return true;
  }
  return false;
}

// Removes the arc centred on `mid` with half-width `half` (rad) from `set`.
void subtract(ArcSet& set, double mid, double half) {
  if (half >= kPi) {
    set.clear();
    return;
  }
  const double a = wrap(mid - half), b = a + 2 * half;
  auto cut = [&](double lo, double hi) {
    ArcSet out;
    for (const auto& arc : set) {
      if (arc.end_rad <= lo || arc.start_rad >= hi) {
        out.push_back(arc);
        continue;
      }
      if (arc.start_rad < lo) out.push_back({arc.start_rad, lo});
      if (arc.end_rad > hi) out.push_back({hi, arc.end_rad});
    }
    set.swap(out);
  };
  if (b <= kTwoPi) {
    cut(a, b);
  } else {
    cut(a, kTwoPi);
    cut(0.0, b - kTwoPi);
  }
}

struct Disc {
  double x = 0, y = 0;
  ArcSet exposed;
  double bx0 = 0, by0 = 0, bx1 = 0, by1 = 0;  // bounding box of the exposed arcs
  bool alive = true;
};

class Removed {
 public:
  explicit Removed(double radius) : R_(radius), cell_(2 * radius) {}

  // The part of the circle (cx, cy, R) outside the removed region, as an ArcSet.
  [[nodiscard]] ArcSet outside(double cx, double cy) const {
    gather(cx, cy, 2 * R_, true);
    std::vector<double> cross;
    for (const int j : near_) {
      const Disc& d = discs_[j];
      const double dx = d.x - cx, dy = d.y - cy, dist = std::hypot(dx, dy);
      // The circle of an alive disc: only boundary points, no open stock on it.
      if (dist <= 1e-9) return {};
      if (dist >= 2 * R_ - kEps || dist <= kEps) continue;
      const double alpha = std::atan2(dy, dx), beta = std::acos(dist / (2 * R_));
      for (const double th : {alpha - beta, alpha + beta}) {
        const double px = cx + R_ * std::cos(th), py = cy + R_ * std::sin(th);
        if (contains(d.exposed, wrap(std::atan2(py - d.y, px - d.x)))) cross.push_back(wrap(th));
      }
    }
    std::sort(cross.begin(), cross.end());
    // Reference status: a point of the circle towards the most recent disc's centre lies
    // inside that disc, so in R; otherwise (a jump, or nothing cut yet) ray parity decides.
    double ref;
    bool ref_in;
    const double lx = last_x_ - cx, ly = last_y_ - cy, ld = std::hypot(lx, ly);
    if (have_last_ && ld <= 1e-9) {
      // The same centre as the last disc (a pure z move): the circle is that disc's
      // boundary, so no point of it lies in open stock.
      return {};
    }
    if (have_last_ && ld < 2 * R_ - kEps) {
      ref = wrap(std::atan2(ly, lx));
      ref_in = true;
    } else {
      ref = cross.empty()
                ? 0.0
                : wrap(0.5 * (cross[0] + (cross.size() > 1 ? cross[1] : cross[0] + kTwoPi)));
      ref_in = inside(cx + R_ * std::cos(ref), cy + R_ * std::sin(ref));
    }
    ArcSet out;
    if (cross.empty()) {
      if (!ref_in) out.push_back({0.0, kTwoPi});
      return out;
    }
    // Status just after crossing k alternates; find the interval holding ref.
    const std::size_t n = cross.size();
    std::size_t k_ref = n - 1;  // the interval [cross[n-1], cross[0] + 2 pi) by default
    for (std::size_t k = 0; k + 1 < n; ++k) {
      if (ref >= cross[k] && ref < cross[k + 1]) k_ref = k;
    }
    for (std::size_t k = 0; k < n; ++k) {
      const bool in = ((k + n - k_ref) % 2 == 0) ? ref_in : !ref_in;
      const double a = cross[k], b = k + 1 < n ? cross[k + 1] : cross[0] + kTwoPi;
      if (!in && b > a) {
        if (b <= kTwoPi) {
          out.push_back({a, b});
        } else {
          out.push_back({a, kTwoPi});
          out.push_back({0.0, b - kTwoPi});
        }
      }
    }
    normalise(out);
    return out;
  }

  // Distance along the ray from (cx, cy) at angle phi to the last boundary crossing before
  // r_max (mm), or 0 when there is none. Uses the candidates of the last prepare_rays().
  [[nodiscard]] double last_crossing(double cx, double cy, double phi, double r_max) const {
    const double ux = std::cos(phi), uy = std::sin(phi);
    double best = 0;
    for (const int j : near_) {
      const Disc& d = discs_[j];
      const double ox = d.x - cx, oy = d.y - cy;
      const double t = ox * ux + oy * uy;
      const double q = R_ * R_ - (ox * ox + oy * oy - t * t);
      if (q < 0) continue;
      const double sq = std::sqrt(q);
      for (const double r : {t - sq, t + sq}) {
        if (r <= best || r > r_max) continue;
        const double px = cx + r * ux - d.x, py = cy + r * uy - d.y;
        if (contains(d.exposed, wrap(std::atan2(py, px)))) best = r;
      }
    }
    return best;
  }
  void prepare_rays(double cx, double cy) const { gather(cx, cy, 2 * R_, false); }

  // Inserts a disc whose circle's part outside R (before it) is `exposed`.
  void insert(double cx, double cy, ArcSet exposed) {
    have_last_ = true;
    last_x_ = cx;
    last_y_ = cy;
    gather(cx, cy, 2 * R_, false);
    // A disc at the centre of an alive one (a pure z move, a revisited point) adds nothing.
    for (const int j : near_) {
      if (std::hypot(discs_[j].x - cx, discs_[j].y - cy) <= 1e-9) return;
    }
    for (const int j : near_) {
      Disc& d = discs_[j];
      const double dx = cx - d.x, dy = cy - d.y, dist = std::hypot(dx, dy);
      if (dist >= 2 * R_) continue;
      // Bounding-box reject: the exposed arcs lie outside the new disc.
      const double nx = std::clamp(cx, d.bx0, d.bx1), ny = std::clamp(cy, d.by0, d.by1);
      if (std::hypot(nx - cx, ny - cy) >= R_) continue;
      subtract(d.exposed, std::atan2(dy, dx), dist <= kEps ? kPi : std::acos(dist / (2 * R_)));
      if (d.exposed.empty()) {
        d.alive = false;
        ++dead_;
      } else {
        bounds(d);
      }
    }
    if (exposed.empty()) return;
    Disc d;
    d.x = cx;
    d.y = cy;
    d.exposed = std::move(exposed);
    bounds(d);
    const int idx = static_cast<int>(discs_.size());
    discs_.push_back(std::move(d));
    grid_[key(cell_index(cx), cell_index(cy))].push_back(idx);
    min_ix_ = std::min(min_ix_, cell_index(cx));
    max_ix_ = std::max(max_ix_, cell_index(cx));
    if (dead_ > 4096 && dead_ * 2 > discs_.size()) compact();
  }

 private:
  [[nodiscard]] long cell_index(double v) const { return static_cast<long>(std::floor(v / cell_)); }
  static long long key(long ix, long iy) {
    return (static_cast<long long>(ix) << 32) ^ (iy & 0xffffffffLL);
  }

  // Alive discs near (cx, cy) whose exposed arcs can meet the circle of radius R around it
  // (circle_only) or anything inside that circle (the disc).
  void gather(double cx, double cy, double reach, bool circle_only) const {
    near_.clear();
    const long ix = cell_index(cx), iy = cell_index(cy);
    const long span = static_cast<long>(std::ceil(reach / cell_));
    for (long a = ix - span; a <= ix + span; ++a) {
      for (long b = iy - span; b <= iy + span; ++b) {
        const auto it = grid_.find(key(a, b));
        if (it == grid_.end()) continue;
        for (const int j : it->second) {
          const Disc& d = discs_[j];
          if (!d.alive) continue;
          if (std::hypot(d.x - cx, d.y - cy) >= reach + R_) continue;
          // The exposed arcs' bounding box must meet the circle of radius R around the
          // query: nearest box point within R, farthest corner beyond R.
          const double nx = std::clamp(cx, d.bx0, d.bx1), ny = std::clamp(cy, d.by0, d.by1);
          const double fx = std::max(std::abs(cx - d.bx0), std::abs(cx - d.bx1));
          const double fy = std::max(std::abs(cy - d.by0), std::abs(cy - d.by1));
          if (std::hypot(nx - cx, ny - cy) > R_ + 1e-9) continue;
          if (circle_only && std::hypot(fx, fy) < R_ - 1e-9) continue;
          near_.push_back(j);
        }
      }
    }
  }

  // Is (px, py) inside the removed region? Ray parity along +x against the exposed arcs
  // (counted on half-open arcs so boundary vertices count once).
  [[nodiscard]] bool inside(double px, double py) const {
    int count = 0;
    const long iy = cell_index(py);
    for (long a = std::min(cell_index(px) - 1, max_ix_); a <= max_ix_; ++a) {
      for (long b = iy - 1; b <= iy + 1; ++b) {
        const auto it = grid_.find(key(a, b));
        if (it == grid_.end()) continue;
        for (const int j : it->second) {
          const Disc& d = discs_[j];
          if (!d.alive || d.by1 < py || d.by0 > py || d.bx1 < px) continue;
          const double oy = py - d.y;
          const double q = R_ * R_ - oy * oy;
          if (q < 0) continue;
          const double sq = std::sqrt(q);
          for (const double xx : {d.x - sq, d.x + sq}) {
            if (xx <= px) continue;
            if (contains(d.exposed, wrap(std::atan2(oy, xx - d.x)))) ++count;
          }
        }
      }
    }
    return (count % 2) == 1;
  }

  void bounds(Disc& d) const {
    d.bx0 = d.by0 = std::numeric_limits<double>::infinity();
    d.bx1 = d.by1 = -std::numeric_limits<double>::infinity();
    for (const auto& arc : d.exposed) {
      auto add = [&](double th) {
        const double x = d.x + R_ * std::cos(th), y = d.y + R_ * std::sin(th);
        d.bx0 = std::min(d.bx0, x);
        d.bx1 = std::max(d.bx1, x);
        d.by0 = std::min(d.by0, y);
        d.by1 = std::max(d.by1, y);
      };
      add(arc.start_rad);
      add(arc.end_rad);
      for (int q = 0; q <= 4; ++q) {  // axis extremes inside the arc
        const double th = q * 0.5 * kPi;
        if (th > arc.start_rad && th < arc.end_rad) add(th);
      }
    }
  }

  static void normalise(ArcSet& s) {
    std::sort(s.begin(), s.end(),
              [](const AngleArc& a, const AngleArc& b) { return a.start_rad < b.start_rad; });
    ArcSet out;
    for (const auto& a : s) {
      if (a.end_rad - a.start_rad <= 0) continue;
      if (!out.empty() && a.start_rad <= out.back().end_rad) {
        out.back().end_rad = std::max(out.back().end_rad, a.end_rad);
      } else {
        out.push_back(a);
      }
    }
    s.swap(out);
  }

  void compact() {
    for (auto& [k, v] : grid_) {
      v.erase(std::remove_if(v.begin(), v.end(), [&](int j) { return !discs_[j].alive; }), v.end());
    }
    dead_ = 0;
  }

  double R_, cell_;
  std::vector<Disc> discs_;
  std::unordered_map<long long, std::vector<int>> grid_;
  long min_ix_ = std::numeric_limits<long>::max(), max_ix_ = std::numeric_limits<long>::min();
  std::size_t dead_ = 0;
  mutable std::vector<int> near_;
  bool have_last_ = false;
  double last_x_ = 0, last_y_ = 0;
};

// Angular set of the circle (cx, cy, R) inside the rectangle |x| <= hw, y0 <= y <= y1.
ArcSet inside_rect(double cx, double cy, double R, double hw, double y0, double y1) {
  ArcSet s{{0.0, kTwoPi}};
  // Half-plane n.(p) <= c: cos(th - dir) <= (c - n.centre) / R.
  auto clip = [&](double dir, double limit) {
    const double k = limit / R;
    if (k >= 1) return;
    if (k <= -1) {
      s.clear();
      return;
    }
    subtract(s, dir, std::acos(k));
  };
  clip(0.0, hw - cx);        // x <= hw
  clip(kPi, hw + cx);        // -x <= hw
  clip(0.5 * kPi, y1 - cy);  // y <= y1
  clip(1.5 * kPi, cy - y0);  // -y <= -y0
  return s;
}

ArcSet intersect(const ArcSet& a, const ArcSet& b) {
  ArcSet out;
  for (const auto& p : a) {
    for (const auto& q : b) {
      const double lo = std::max(p.start_rad, q.start_rad), hi = std::min(p.end_rad, q.end_rad);
      if (hi > lo) out.push_back({lo, hi});
    }
  }
  std::sort(out.begin(), out.end(),
            [](const AngleArc& x, const AngleArc& y) { return x.start_rad < y.start_rad; });
  return out;
}

// Joins an arc ending at 2 pi with one starting at 0 (an arc through +X).
std::vector<AngleArc> join_wrap(ArcSet s) {
  if (s.size() >= 2 && s.front().start_rad <= kEps && s.back().end_rad >= kTwoPi - kEps) {
    s.back().end_rad = kTwoPi + s.front().end_rad;
    s.erase(s.begin());
  }
  return s;
}

}  // namespace

EngagementSeries compute_engagement(const PathSamples& smp, const Job& job,
                                    const EngagementOptions& opt) {
  if (opt.steps_per_tooth < 1) {
    throw InputError(fmt::format("steps per tooth must be >= 1, got {}", opt.steps_per_tooth));
  }
  if (!(opt.chip_angle_step_deg > 0 && opt.chip_angle_step_deg <= 10)) {
    throw InputError(
        fmt::format("chip angle step must be in (0, 10] degrees, got {}", opt.chip_angle_step_deg));
  }
  const double R = job.tool.radius_mm();
  const double hw = 0.5 * job.slot.width_mm, L = job.slot.length_mm;
  const std::size_t n = smp.size();
  const int m = opt.steps_per_tooth;
  EngagementSeries out;
  out.tool_radius_mm = R;
  out.teeth = job.tool.teeth;
  out.steps_per_tooth = m;
  out.samples = smp;
  out.arcs.resize(n);
  out.engagement_angle_rad.assign(n, 0.0);
  out.radial_engagement_mm.assign(n, 0.0);
  out.h_max_mm.assign(n, 0.0);
  out.h_max_angle_rad.assign(n, 0.0);
  out.teeth_in_cut.assign(n, 0);

  const double omega = rpm_to_rad_per_s(job.cutting.spindle_speed_rpm) *
                       (job.cutting.spindle_direction == SpindleDirection::cw ? -1.0 : 1.0);
  Removed removed(R);
  std::vector<ArcSet> pending(n);  // exposed arcs of discs waiting for insertion (lag m)
  auto cutting = [&](std::size_t i) { return smp.z_mm[i] < 0; };
  const double dphi = deg_to_rad(opt.chip_angle_step_deg);

  for (std::size_t i = 0; i < n; ++i) {
    // The surface the previous tooth left: discs up to i - m.
    if (i >= static_cast<std::size_t>(m)) {
      const std::size_t k = i - m;
      if (cutting(k)) {
        ArcSet e = m == 1 ? std::move(pending[k]) : removed.outside(smp.x_mm[k], smp.y_mm[k]);
        removed.insert(smp.x_mm[k], smp.y_mm[k], std::move(e));
      }
    }
    if (!cutting(i)) continue;
    const double cx = smp.x_mm[i], cy = smp.y_mm[i];
    ArcSet free = removed.outside(cx, cy);
    if (m == 1) pending[i] = free;
    ArcSet eng = intersect(free, inside_rect(cx, cy, R, hw, 0.0, L));
    double total = 0;
    for (const auto& a : eng) total += a.sweep_rad();
    out.engagement_angle_rad[i] = total;
    out.radial_engagement_mm[i] = R * (1 - std::cos(std::min(total, kPi)));
    // h_max: largest R - rho(phi) over the engaged arcs, rho the last boundary crossing of
    // the ray before the tool circle (0 inside fresh stock: the chip is then capped at R).
    removed.prepare_rays(cx, cy);
    double hmax = 0, hang = 0;
    for (const auto& a : eng) {
      const int steps = std::max(2, static_cast<int>(std::ceil(a.sweep_rad() / dphi)));
      for (int k = 0; k <= steps; ++k) {
        const double phi = a.start_rad + a.sweep_rad() * k / steps;
        const double h = std::max(0.0, R - removed.last_crossing(cx, cy, phi, R * (1 + 1e-9)));
        if (h > hmax) {
          hmax = h;
          hang = phi;
        }
      }
    }
    out.h_max_mm[i] = hmax;
    out.h_max_angle_rad[i] = wrap(hang);
    int teeth = 0;
    for (const double alpha : job.tool.tooth_angles_deg) {
      if (contains(eng, wrap(omega * smp.t_s[i] + deg_to_rad(alpha)))) ++teeth;
    }
    out.teeth_in_cut[i] = teeth;
    out.arcs[i] = join_wrap(std::move(eng));
  }
  return out;
}

EngagementSeries compute_engagement(const ToolPath& path, const Job& job,
                                    const EngagementOptions& options) {
  if (options.steps_per_tooth < 1) {
    throw InputError(fmt::format("steps per tooth must be >= 1, got {}", options.steps_per_tooth));
  }
  const double per_tooth_s = 60.0 / (job.cutting.spindle_speed_rpm * job.tool.teeth);
  return compute_engagement(sample_by_time(path, per_tooth_s / options.steps_per_tooth), job,
                            options);
}

}  // namespace trochomill
