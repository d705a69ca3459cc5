// Pocket clearing at a guaranteed engagement (see include/trochomill/pocket.hpp and
// docs/models.md, "Pockets").
#include "trochomill/pocket.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

constexpr double kClipperTol = 1e-3;  // mm: offset_region's chords (vertices on the exact offset)
// Degrees: a step whose engagement stays below this cuts nothing (a sliver under 0.2 um deep
// at R = 5 mm): it does not keep a pass's target steering going.
constexpr double kCutting = 0.5;
// How far a cutting pass's fitted arcs may bulge off the steps' chords towards the stock, as a
// share of the tool's radius (an arc turning away from the stock bulges towards it): arcs
// through the passes' turns down to a radius of 6 mm at 0.5 mm steps (R = 5 mm) instead of a
// line a step. A share of R, not a length: the engagement a bulge b adds is about
// b / (R sin phi), the same at every tool size (a fixed 0.005 mm gave a 1 mm tool 57.1 degrees
// for a 53 target where 0.0005 mm gives 52.6). (0.01 mm at R = 5 mm gave a program 15 % smaller
// still, but the kernel then found 50.17 degrees on a test pocket for a 50 target.)
constexpr double kBulgeShare = 0.001;
double bulge_mm(double R) { return kBulgeShare * R; }

Vec2 dir(double a) { return {std::cos(a), std::sin(a)}; }

// The box of a region's piece starts (its vertices; arcs bulge within the callers' margins).
Box3 vertex_box(const std::vector<Contour>& region) {
  Box3 box;
  for (const Contour& c : region) {
    for (const ContourPiece& p : c.pieces) box.extend(Vec3(p.start.x(), p.start.y(), 0));
  }
  return box;
}
double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Whether segments [a, b] and [c, d] cross (proper or touching).
bool segments_cross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
  const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

// A fast inside test for a region of closed polylines (offset_region's form): a grid whose
// cells know the status of their centre and the edges that pass through them; a point is
// its cell's centre status, flipped once per edge the segment from the centre to it crosses.
class RegionGrid {
 public:
  RegionGrid(const std::vector<Contour>& region, double cell_mm) : cell_(cell_mm) {
    Box3 box;
    for (const Contour& c : region) {
      for (const ContourPiece& p : c.pieces) {
        edges_.push_back({p.start, p.end});
        box.extend(Vec3(p.start.x(), p.start.y(), 0));
      }
    }
    if (edges_.empty()) {
      nx_ = ny_ = 1;
      x0_ = y0_ = 0;
      cells_.resize(1);
      return;
    }
    // At most about 4e6 cells (64 MB of cells' headers), however large the region.
    cell_ = std::max(
        cell_, std::sqrt((box.hi.x() - box.lo.x() + 1) * (box.hi.y() - box.lo.y() + 1) / 4e6));
    x0_ = box.lo.x() - 2 * cell_;
    y0_ = box.lo.y() - 2 * cell_;
    nx_ = static_cast<long>(std::ceil((box.hi.x() - x0_) / cell_)) + 2;
    ny_ = static_cast<long>(std::ceil((box.hi.y() - y0_) / cell_)) + 2;
    if (static_cast<double>(nx_) * static_cast<double>(ny_) > 2e7) {
      throw Error("pocket: the region grid would exceed 2e7 cells (a bug: the cell is sized)");
    }
    cells_.resize(static_cast<std::size_t>(nx_ * ny_));
    std::vector<std::vector<int>> rows(static_cast<std::size_t>(ny_));
    for (int k = 0; k < static_cast<int>(edges_.size()); ++k) {
      const Vec2 a = edges_[k].first, b = edges_[k].second;
      const long r0 = row(std::min(a.y(), b.y())), r1 = row(std::max(a.y(), b.y()));
      for (long r = r0; r <= r1; ++r) {
        rows[static_cast<std::size_t>(r)].push_back(k);
        // The edge's x range within this row's band.
        const double ylo = y0_ + static_cast<double>(r) * cell_, yhi = ylo + cell_;
        double xa = a.x(), xb = b.x();
        if (std::abs(b.y() - a.y()) > 1e-15) {
          const double t0 = std::clamp((ylo - a.y()) / (b.y() - a.y()), 0.0, 1.0);
          const double t1 = std::clamp((yhi - a.y()) / (b.y() - a.y()), 0.0, 1.0);
          xa = a.x() + t0 * (b.x() - a.x());
          xb = a.x() + t1 * (b.x() - a.x());
        }
        for (long c = col(std::min(xa, xb)); c <= col(std::max(xa, xb)); ++c) {
          cells_[static_cast<std::size_t>(r * nx_ + c)].edges.push_back(k);
        }
      }
    }
    // Centre status by even-odd crossings of the row's centre line towards +x.
    std::vector<double> xs;
    for (long r = 0; r < ny_; ++r) {
      const double yc = y0_ + (static_cast<double>(r) + 0.5) * cell_;
      xs.clear();
      for (const int k : rows[static_cast<std::size_t>(r)]) {
        const Vec2 a = edges_[k].first, b = edges_[k].second;
        if ((a.y() > yc) == (b.y() > yc)) continue;
        xs.push_back(a.x() + (yc - a.y()) / (b.y() - a.y()) * (b.x() - a.x()));
      }
      std::sort(xs.begin(), xs.end());
      std::size_t passed = 0;
      for (long c = 0; c < nx_; ++c) {
        const double xc = x0_ + (static_cast<double>(c) + 0.5) * cell_;
        while (passed < xs.size() && xs[passed] <= xc) ++passed;
        cells_[static_cast<std::size_t>(r * nx_ + c)].inside = (xs.size() - passed) % 2 == 1;
      }
    }
  }

  [[nodiscard]] bool contains(const Vec2& p) const {
    const long r = row(p.y()), c = col(p.x());
    if (p.x() < x0_ || p.y() < y0_ || p.x() > x0_ + static_cast<double>(nx_) * cell_ ||
        p.y() > y0_ + static_cast<double>(ny_) * cell_) {
      return false;
    }
    const Cell& cell = cells_[static_cast<std::size_t>(r * nx_ + c)];
    bool in = cell.inside;
    const Vec2 centre(x0_ + (static_cast<double>(c) + 0.5) * cell_,
                      y0_ + (static_cast<double>(r) + 0.5) * cell_);
    for (const int k : cell.edges) {
      if (segments_cross(centre, p, edges_[k].first, edges_[k].second)) in = !in;
    }
    return in;
  }

 private:
  struct Cell {
    bool inside = false;
    std::vector<int> edges;
  };
  [[nodiscard]] long row(double y) const {
    return std::clamp(static_cast<long>(std::floor((y - y0_) / cell_)), 0L, ny_ - 1);
  }
  [[nodiscard]] long col(double x) const {
    return std::clamp(static_cast<long>(std::floor((x - x0_) / cell_)), 0L, nx_ - 1);
  }
  double cell_;
  double x0_ = 0, y0_ = 0;
  long nx_ = 0, ny_ = 0;
  std::vector<std::pair<Vec2, Vec2>> edges_;
  std::vector<Cell> cells_;
};

// The material the clearing must remove, on a grid: cells whose centre a tool centre in the
// region reaches by less than R - h (so that a pass along the region's edge covers them).
class Coverage {
 public:
  static constexpr double kMaxCells = 4e8;  // a byte each
  // kHeld: remaining, but kept for a channel's trochoid (or out of reach until one is cut): the
  // clearing passes do not head for it.
  enum : std::uint8_t { kNone = 0, kRemaining = 1, kCovered = 2, kGivenUp = 3, kHeld = 4 };

  Coverage(const std::vector<Contour>& reach, double cell_mm, double R)
      : h_(cell_mm), R_(R), test_(reach, std::max(cell_mm, 0.25 * R)) {
    const Box3 box = vertex_box(reach);
    x0_ = box.lo.x() - h_;
    y0_ = box.lo.y() - h_;
    const double cells =
        std::ceil((box.hi.x() - x0_) / h_ + 2) * std::ceil((box.hi.y() - y0_) / h_ + 2);
    if (!(cells <= kMaxCells)) {
      throw InputError(fmt::format(
          "[pocket] boundary: a region of {:.0f} x {:.0f} mm needs {:.3g} cells of {:g} mm to "
          "track "
          "the stock a {:g} mm tool leaves (at most {:.0g}): clear it with a larger tool or "
          "split it into smaller pockets",
          box.hi.x() - box.lo.x(), box.hi.y() - box.lo.y(), cells, h_, 2 * R, kMaxCells));
    }
    nx_ = static_cast<long>(std::ceil((box.hi.x() - x0_) / h_)) + 2;
    ny_ = static_cast<long>(std::ceil((box.hi.y() - y0_) / h_)) + 2;
    state_.assign(static_cast<std::size_t>(nx_ * ny_), kNone);
    for (long r = 0; r < ny_; ++r) {
      for (long c = 0; c < nx_; ++c) {
        if (test_.contains(centre(c, r))) {
          state_[static_cast<std::size_t>(r * nx_ + c)] = kRemaining;
          ++remaining_;
        }
      }
    }
  }

  [[nodiscard]] Vec2 centre(long c, long r) const {
    return {x0_ + (static_cast<double>(c) + 0.5) * h_, y0_ + (static_cast<double>(r) + 0.5) * h_};
  }
  [[nodiscard]] double cell_mm() const { return h_; }
  [[nodiscard]] long remaining() const { return remaining_; }
  [[nodiscard]] long given_up() const { return given_up_; }

  // Marks the cells within R of c as covered (a given-up cell a later pass takes too);
  // returns how many were remaining.
  long cut(const Vec2& p) { return cut_segment(p, p); }
  // The same for the cells within R of the segment [a, b] (what the tool sweeps from a to b).
  long cut_segment(const Vec2& a, const Vec2& b) {
    long n = 0;
    for_cells(a, b, R_, [&](std::uint8_t& s) {
      if (s == kRemaining) {
        s = kCovered;
        ++n;
      } else if (s == kGivenUp) {
        s = kCovered;
        --given_up_;
      } else if (s == kHeld) {
        s = kCovered;
        --held_;
      }
    });
    remaining_ -= n;
    return n;
  }
  // Holds the remaining cells within `radius` of the segment [a, b] (Coverage::kHeld).
  void hold(const Vec2& a, const Vec2& b, double radius) {
    for_cells(a, b, radius, [&](std::uint8_t& s) {
      if (s == kRemaining) {
        s = kHeld;
        --remaining_;
        ++held_;
      }
    });
  }
  // The held cells within `radius` of [a, b] remaining again (all of them: radius < 0).
  void release(const Vec2& a, const Vec2& b, double radius) {
    auto f = [&](std::uint8_t& s) {
      if (s != kHeld) return;
      s = kRemaining;
      --held_;
      ++remaining_;
    };
    if (radius >= 0) {
      for_cells(a, b, radius, f);
    } else {
      for (std::uint8_t& s : state_) f(s);
    }
  }
  [[nodiscard]] long held() const { return held_; }
  // Gives up the remaining cells within `radius` of p.
  void give_up(const Vec2& p, double radius) {
    for_cells(p, p, radius, [&](std::uint8_t& s) {
      if (s == kRemaining) {
        s = kGivenUp;
        --remaining_;
        ++given_up_;
      }
    });
  }
  // The remaining cell nearest to p.
  [[nodiscard]] std::optional<Vec2> nearest_remaining(const Vec2& p) const {
    double best = std::numeric_limits<double>::infinity();
    std::optional<Vec2> out;
    for (long r = 0; r < ny_; ++r) {
      for (long c = 0; c < nx_; ++c) {
        if (state_[static_cast<std::size_t>(r * nx_ + c)] != kRemaining) continue;
        const double d = (centre(c, r) - p).squaredNorm();
        if (d < best) {
          best = d;
          out = centre(c, r);
        }
      }
    }
    return out;
  }

 private:
  // Applies f to the state of every cell whose centre lies within `radius` of the segment
  // [a, b] (a disc where a = b).
  template <class F>
  void for_cells(const Vec2& a, const Vec2& b, double radius, F&& f) {
    const long c0 =
        std::max(0L, static_cast<long>(std::floor((std::min(a.x(), b.x()) - radius - x0_) / h_)));
    const long c1 = std::min(
        nx_ - 1, static_cast<long>(std::floor((std::max(a.x(), b.x()) + radius - x0_) / h_)));
    const long r0 =
        std::max(0L, static_cast<long>(std::floor((std::min(a.y(), b.y()) - radius - y0_) / h_)));
    const long r1 = std::min(
        ny_ - 1, static_cast<long>(std::floor((std::max(a.y(), b.y()) + radius - y0_) / h_)));
    const Vec2 ab = b - a;
    const double L2 = ab.squaredNorm(), r2 = radius * radius;
    for (long r = r0; r <= r1; ++r) {
      for (long c = c0; c <= c1; ++c) {
        const Vec2 q = centre(c, r) - a;
        const double t = L2 > 0 ? std::clamp(q.dot(ab) / L2, 0.0, 1.0) : 0.0;
        if ((q - t * ab).squaredNorm() < r2) f(state_[static_cast<std::size_t>(r * nx_ + c)]);
      }
    }
  }

  double h_, R_;
  RegionGrid test_;
  double x0_ = 0, y0_ = 0;
  long nx_ = 0, ny_ = 0;
  std::vector<std::uint8_t> state_;
  long remaining_ = 0, given_up_ = 0, held_ = 0;
};

// One planar move of the clearing sequence of a part (z added per level).
struct Move2 {
  // arc_or_line: clearing at the feed; air: a pass's run through cleared area (at the link
  // feed); link_down: a link at the level; lift: a link over the stock.
  enum Kind { arc_or_line, air, link_down, lift } kind = arc_or_line;
  ContourPiece piece;  // arc_or_line, air: the piece; links: start -> end (a line)
  bool entry = false;  // part of the helix's flat circle
};

// A clearing pass: its step points (straight steps between them) and, for each step i >= 1
// (from points[i - 1] to points[i]), whether it cuts: the planner's uncut arcs at its points
// (an upper bound of the kernel's) are wider than a graze (Settings::graze_deg). cuts[0] is
// unused.
struct Pass {
  std::vector<Vec2> points;
  std::vector<bool> cuts;
  void add(const Vec2& end, bool cutting) {
    points.push_back(end);
    cuts.push_back(cutting);
  }
};

struct Settings {
  double R = 0;            // tool radius
  double step = 0;         // the planner's step along the path (mm)
  double aim_deg = 0;      // the engagement the steps hold (target less a margin)
  double kernel_step = 0;  // the kernel's sample spacing (f_z): its front arc's half width
  // The tooth's advance at the link feed (mm): the feed marks a run through cleared area
  // leaves on the frontier it grazes, f^2 / 8R deep (4 um at 0.42 mm a tooth and R = 5 mm).
  double air_tooth = 0;
  // The widest uncut arc (degrees) of a tool that only grazes the stock: one whose depth
  // R (1 - cos(w / 2)) is twice the feed marks' f_z^2 / 8R at the feed (0.81 degrees at f_z =
  // 0.05 mm, R = 5 mm). Every frontier the clearing leaves has those marks, in the model (its
  // discs a tooth apart) and in the program, their tips not in the same places: a tool
  // following such a frontier meets both. (At once the marks' depth, the planner's own
  // frontier read at the threshold and the example ran 424 s; at twice, 379 s, the target
  // held on it and the test pockets; at four times a test pocket reached 50.00 degrees for a
  // 50 target.) A step or a link that only grazes may run at the link feed: the frontier it
  // leaves differs from the model's by less than that.
  double graze_deg = 0;
  double sigma = 1;              // +1: stock on the right (climb, cw spindle); -1: mirrored
  double fit_tolerance = 0.002;  // [pocket] fit_tolerance (mm)
  // The channels' family ([path] type in a pocket's job): none, the default loops (circles
  // about the axis' points, joined along the axis); else the straight slot's family's cycles
  // carried along the axis, as wide as the channel (docs/models.md, "Channels").
  std::optional<PathType> family;
  double aspect = 1;     // [path] aspect_ratio: b / a of elliptical and linear-elliptical
  double linear_mm = 0;  // [path] linear_distance: linear-elliptical's wall moves (mm)
};

// A channel: a run of the medial axis of the tool centre's region (unrounded) where the pocket
// is narrower than [pocket] channel_width, cleared by trochoidal loops along it: circles about
// its points, each as wide as the region there (the point's clearance), a step apart. Its
// points are medial_axis's samples (the loops' centres are chosen among them, so that each
// radius is an exact clearance: the loop's disc lies in the region, the tool R + stock from
// every wall).
struct Channel {
  std::vector<Vec2> c;       // the axis' points
  std::vector<double> r;     // their clearances (mm)
  std::vector<double> u;     // arc length from the first (mm)
  double hold_front = 0;     // the clearing passes clear this much of it from the first point
  double hold_back = 0;      // ... and from the last
  std::vector<Vec2> beyond;  // points of the region just past its open ends
  bool done = false;
  [[nodiscard]] std::size_t size() const { return c.size(); }
  // The axis' direction at point k (mm), towards the last point.
  [[nodiscard]] Vec2 tangent(std::size_t k) const {
    const std::size_t a = k == 0 ? 0 : k - 1, b = std::min(size() - 1, k + 1);
    const Vec2 d = c[b] - c[a];
    return d.norm() > 0 ? Vec2(d / d.norm()) : Vec2(1, 0);
  }
  // The swept band's area (mm^2): the loops' discs grown by R, along the axis.
  [[nodiscard]] double band_mm2(double R) const {
    double a = 0;
    for (std::size_t k = 1; k < size(); ++k) a += (r[k - 1] + r[k] + 2 * R) * (u[k] - u[k - 1]);
    return a;
  }
};

// A family's cycle along a channel, from axis point k in the direction of travel (towards the
// last point when forward): the axis there modelled by the circle (or line) through the axis'
// points at the cycle's rearmost and foremost reach and at point k, and a width linear along
// it, so that the cycle planned in the straight slot's frame (x across, y along from the
// cycle's start; family_cycle with half-width a) maps smoothly:
//   (x, y) -> A(y) + x w(y) / a N(y),
// A the model's point y along it from point k, N its right-hand normal of travel. The axis'
// polyline itself wiggles by microns (the medial axis of Clipper's chords), which a map
// through it would write into the cycle's arcs.
//
// Every point lies in the region: w(y) <= r(y) - |A(y) - C(y)| at the axis' samples (r the
// clearance, C the axis point at that arc length), less half the samples' largest spacing d
// between them. Between samples i and i + 1 (at the fraction t) the interpolated axis point's
// clearance is at least the interpolated r less 2 t (1 - t) d (the clearance is 1-Lipschitz:
// each sample's r_i - t d holds there, and so does their weighted mean), which the half spacing
// covers; 1e-4 mm covers the model's chord sag over d.
class CycleOnAxis final : public PlanarCurve {
 public:
  // Where the model fits (ylo, yhi: the cycle's reach behind and ahead of point k, mm, in the
  // axis), the width at every reach at least half the clearance at k.
  static std::optional<CycleOnAxis> make(const Channel& ch, std::size_t k, bool forward, double ylo,
                                         double yhi, double a, double hair) {
    const double sk = ch.u[k];
    const auto sigma = [&](double y) { return forward ? sk + y : sk - y; };
    const double s_lo = std::min(sigma(ylo), sigma(yhi)), s_hi = std::max(sigma(ylo), sigma(yhi));
    if (s_lo < ch.u.front() || s_hi > ch.u.back()) return std::nullopt;
    const auto at = [&](double sg) {
      const auto it = std::upper_bound(ch.u.begin(), ch.u.end(), sg);
      std::size_t i = it == ch.u.begin() ? 0 : static_cast<std::size_t>(it - ch.u.begin()) - 1;
      i = std::min(i, ch.size() - 2);
      const double du = ch.u[i + 1] - ch.u[i];
      const double t = du > 0 ? std::clamp((sg - ch.u[i]) / du, 0.0, 1.0) : 0.0;
      return std::pair<Vec2, double>((1 - t) * ch.c[i] + t * ch.c[i + 1],
                                     (1 - t) * ch.r[i] + t * ch.r[i + 1]);
    };
    const auto [p1, r1] = at(sigma(ylo));
    const auto [p3, r3] = at(sigma(yhi));
    const Vec2 p2 = ch.c[k];
    CycleOnAxis m;
    m.c0_ = p2;
    m.a_ = a;
    // The signed curvature of the circle through p1, p2, p3 (positive turning left).
    const Vec2 d12 = p2 - p1, d23 = p3 - p2, d13 = p3 - p1;
    const double l12 = d12.norm(), l23 = d23.norm(), l13 = d13.norm();
    if (!(l13 > 0)) return std::nullopt;
    m.kappa_ = l12 > 0 && l23 > 0 ? 2 * cross2(d12, d23) / (l12 * l23 * l13) : 0.0;
    if (std::abs(m.kappa_) * (yhi - ylo) < 1e-9) {
      m.kappa_ = 0;
      m.t0_ = d13 / l13;
    } else {
      // The circle's tangent at p2: normal to p2 - O, O its centre, oriented along p1 -> p3.
      // The circumcentre O of p1, p2, p3.
      const Vec2 b = p2 - p1, c = p3 - p1;
      const double D = 2 * cross2(b, c);
      const Vec2 O = p1 + Vec2(b.squaredNorm() * c.y() - c.squaredNorm() * b.y(),
                               c.squaredNorm() * b.x() - b.squaredNorm() * c.x()) /
                              D;
      const Vec2 rad = p2 - O;
      Vec2 t(-rad.y(), rad.x());
      if (t.dot(d13) < 0) t = -t;
      m.t0_ = t / t.norm();
    }
    // The width: the clearance's slope between the reaches, lowered to the bound at every sample.
    m.g_ = (r3 - r1) / (yhi - ylo);
    double w0 = std::numeric_limits<double>::infinity(), dmax = 0;
    std::size_t i0 =
        static_cast<std::size_t>(std::upper_bound(ch.u.begin(), ch.u.end(), s_lo) - ch.u.begin());
    i0 = i0 > 0 ? i0 - 1 : 0;
    for (std::size_t i = i0; i < ch.size() && (i == 0 || ch.u[i - 1] <= s_hi); ++i) {
      const double y = forward ? ch.u[i] - sk : sk - ch.u[i];
      const double delta = (m.axis(y) - ch.c[i]).norm();
      w0 = std::min(w0, ch.r[i] - delta - m.g_ * y);
      if (i > i0) dmax = std::max(dmax, ch.u[i] - ch.u[i - 1]);
    }
    m.w0_ = w0 - 0.5 * dmax - 1e-4 - hair;
    if (!(std::min(m.width(ylo), m.width(yhi)) >= 0.5 * ch.r[k])) return std::nullopt;
    return m;
  }
  void set(const Segment& seg) { seg_ = &seg; }
  void set_half_width(double a) { a_ = a; }
  [[nodiscard]] double width(double y) const { return w0_ + g_ * y; }
  [[nodiscard]] Vec3 point(double u) const override {
    const Vec3 q = seg_->point_u(u);
    const Vec2 t = tangent(q.y());
    const Vec2 p = axis(q.y()) + q.x() / a_ * width(q.y()) * Vec2(t.y(), -t.x());
    return Vec3(p.x(), p.y(), 0);
  }
  [[nodiscard]] Vec3 unit_tangent(double u) const override {
    const double h = 1e-6 * std::max(1.0, std::abs(seg_->u1() - seg_->u0()));
    const Vec3 d = point(u + h) - point(u - h);
    const double n = d.norm();
    return n > 0 ? Vec3(d / n) : Vec3::Zero();
  }

 private:
  CycleOnAxis() = default;
  [[nodiscard]] Vec2 axis(double y) const {
    const Vec2 left(-t0_.y(), t0_.x());
    if (kappa_ == 0) return c0_ + y * t0_;
    return c0_ + t0_ * (std::sin(kappa_ * y) / kappa_) +
           left * ((1 - std::cos(kappa_ * y)) / kappa_);
  }
  [[nodiscard]] Vec2 tangent(double y) const {
    const Vec2 left(-t0_.y(), t0_.x());
    return t0_ * std::cos(kappa_ * y) + left * std::sin(kappa_ * y);
  }
  const Segment* seg_ = nullptr;
  Vec2 c0_ = Vec2::Zero(), t0_ = Vec2(1, 0);
  double kappa_ = 0, w0_ = 0, g_ = 0, a_ = 1;
};

// A channel's loop circle is cut into this many arcs, each at the feed or, where it only grazes
// (its back, and the sides along the walls between the last loops' scallops), the link feed;
// the moves join those of one kind again.
constexpr int kLoopPieces = 16;

// The overlap of two sets of arcs of one circle (uncut_arcs' form: each within [0, 4 pi) and
// shorter than a turn), in degrees: its total and its widest piece.
std::pair<double, double> arcs_overlap_deg(const std::vector<AngleArc>& a,
                                           const std::vector<AngleArc>& b) {
  double total = 0, widest = 0;
  for (const AngleArc& x : a) {
    for (const AngleArc& y : b) {
      for (const double shift : {-kTwoPi, 0.0, kTwoPi}) {
        const double o =
            std::min(x.end_rad, y.end_rad + shift) - std::max(x.start_rad, y.start_rad + shift);
        if (o > 0) {
          total += o;
          widest = std::max(widest, o);
        }
      }
    }
  }
  return {rad_to_deg(total), rad_to_deg(widest)};
}

// The planner of one part: its region, the removed region and the coverage.
class PartPlanner {
 public:
  PartPlanner(const Settings& s, const std::vector<Contour>& part, const Vec2& lo, const Vec2& hi)
      : s_(s),
        inside_(part, std::max(0.25, 0.25 * s.R)),
        removed_(s.R, lo, hi),
        coverage_(offset_region(part, s.R - cell_size(s.R), kClipperTol), cell_size(s.R), s.R) {}

  static double cell_size(double R) { return std::clamp(R / 20.0, 0.02, 0.25); }

  [[nodiscard]] bool in_region(const Vec2& p) const { return inside_.contains(p); }
  // Whether the tool's disc at p lies in the removed region: its circle (no uncut arc) and,
  // for stock left inside it by an earlier program (a pillar between its passes), its centre
  // and 8 points on each of the circles of R/3 and 2R/3.
  [[nodiscard]] bool disc_cleared(const Vec2& p) const {
    if (!removed_.uncut_arcs(p).empty() || !removed_.contains(p)) return false;
    for (const double r : {s_.R / 3, 2 * s_.R / 3}) {
      for (int k = 0; k < 8; ++k) {
        if (!removed_.contains(p + r * dir(kTwoPi * k / 8))) return false;
      }
    }
    return true;
  }
  [[nodiscard]] const RegionGrid& region() const { return inside_; }
  Coverage& coverage() { return coverage_; }

  // Cuts the disc at p; returns how many coverage cells it took.
  long cut(const Vec2& p) {
    removed_.cut(p);
    return coverage_.cut(p);
  }
  // Cuts the step from a to b: the removed region's discs a tooth's advance apart along it
  // (the kernel's, and the teeth's, feed marks: at the feed, or at the link feed for a step
  // that cuts nothing, which may run there), the last at b, and the coverage the tool sweeps;
  // returns how many coverage cells it took. (Discs a whole step apart would leave scallops of
  // step^2 / 8R between them, 6 um at R = 5 mm: enough for a later pass along the frontier to
  // read 3 to 6 degrees of engagement where the tool cuts nothing.)
  long cut_step(const Vec2& a, const Vec2& b, bool air) {
    const double tooth = std::min(s_.step, air ? s_.air_tooth : s_.kernel_step);
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / tooth)));
    for (int k = 1; k <= n; ++k) removed_.cut(a + (b - a) * (static_cast<double>(k) / n));
    return coverage_.cut_segment(a, b);
  }

  // The engagement and its widest uncut arc (degrees).
  struct Eng {
    double total = 0, widest = 0;
  };
  [[nodiscard]] Eng uncut(const Vec2& at) const {
    Eng e;
    for (const AngleArc& a : removed_.uncut_arcs(at)) {
      e.total += a.sweep_rad();
      e.widest = std::max(e.widest, a.sweep_rad());
    }
    return {rad_to_deg(e.total), rad_to_deg(e.widest)};
  }
  // The same less what the disc at `back` covers (the tool one tooth before: the tooth at
  // `to` cuts only what that tooth left, as the kernel has it): the arc within
  // acos(d / 2R) of the direction to it, d its distance.
  [[nodiscard]] Eng engagement(const Vec2& to, const Vec2& back) const {
    const auto arcs = removed_.uncut_arcs(to);
    if (arcs.empty()) return {};
    const Vec2 b = back - to;
    const double d = b.norm();
    if (!(d < 2 * s_.R)) return uncut(to);
    const double mid = std::atan2(b.y(), b.x());
    const double half = d > 0 ? std::acos(d / (2 * s_.R)) : 0.5 * kPi;
    double lo = std::fmod(mid - half, kTwoPi);
    if (lo < 0) lo += kTwoPi;
    const double hi = lo + 2 * half;  // the covered arc [lo, hi], hi may pass 2 pi
    Eng e;
    for (const AngleArc& a : arcs) {
      double len = a.sweep_rad();
      // Overlap of [a.start, a.end] with [lo, hi] and its copies 2 pi either side.
      for (const double shift : {-kTwoPi, 0.0, kTwoPi}) {
        const double o0 = std::max(a.start_rad, lo + shift), o1 = std::min(a.end_rad, hi + shift);
        if (o1 > o0) len -= o1 - o0;
      }
      len = std::max(0.0, len);
      e.total += len;
      e.widest = std::max(e.widest, len);
    }
    return {rad_to_deg(e.total), rad_to_deg(e.widest)};
  }

  // A step from p: the line of length s in the direction psi. Allowed when every tooth's
  // point of it (s / ceil(s / f_z) apart) lies in the region and the engagement there, the
  // tooth before it taken off, stays within the aim. The quarter points are checked first
  // (most steps that fail, fail there); the search for a step checks only them and the first
  // tooth, the step it finds is checked in `full`. `incoming`: the direction the tool arrives at p
  // along; where it is not psi (a corner) teeth a fraction of a tooth past the corner are
  // checked too, their tooth before on the way in (the kernel's samples fall anywhere about a
  // corner, and the engagement peaks there).
  struct Probe {
    bool ok = false;
    double eng = 0;     // the largest at the points checked (degrees)
    double widest = 0;  // the widest uncut arc at the points checked (degrees)
    Vec2 end;
    void add(const Eng& e) {
      eng = std::max(eng, e.total);
      widest = std::max(widest, e.widest);
    }
  };
  [[nodiscard]] Probe probe(const Vec2& p, double psi, const Vec2& incoming,
                            bool full = false) const {
    Probe out;
    const Vec2 u = dir(psi);
    out.end = p + s_.step * u;
    const double tooth = s_.kernel_step;
    const int n = std::max(1, static_cast<int>(std::ceil(s_.step / tooth)));
    for (int k = 1; k <= n; ++k) {
      if (!in_region(p + (s_.step * k / n) * u)) return out;
    }
    auto value = [&](double l) {
      const Vec2 back = l >= tooth ? Vec2(p + (l - tooth) * u) : Vec2(p - (tooth - l) * incoming);
      const Eng e = engagement(p + l * u, back);
      out.add(e);
      return e.total;
    };
    auto check = [&](double l) {
      value(l);
      return out.eng <= s_.aim_deg;
    };
    for (const double f : {1.0, 0.75, 0.5, 0.25}) {
      if (!check(f * s_.step)) return out;
    }
    if (!full) {  // the search's quick probe: the quarter points and the first tooth
      out.ok = check(std::min(tooth, s_.step));
      return out;
    }
    if ((incoming - u).squaredNorm() > 1e-18) {
      // Three phases, and one more a 10 degrees of turn: the engagement past a sharp corner
      // changes within a fraction of a tooth (a 136 degree corner: 47.5, 48.9, 45.9 degrees
      // at a quarter, a half, three quarters of a tooth, 50.3 between).
      const double turn = std::acos(std::clamp(incoming.dot(u), -1.0, 1.0));
      const int m = 3 + static_cast<int>(turn / deg_to_rad(10));
      for (int k = 1; k <= m; ++k) {
        if (!check(std::min(tooth, s_.step) * k / (m + 1))) return out;
      }
    }
    // Every tooth, then between two teeth whose engagement differs by more than 2 degrees
    // (the tool meeting a corner of the stock: 30 to 54 degrees within a tooth), halves down
    // to an eighth of a tooth.
    std::array<double, 64> at{};
    const int m = std::min(n, 63);
    for (int k = 1; k <= m; ++k) {
      at[static_cast<std::size_t>(k)] = value(s_.step * k / m);
      if (out.eng > s_.aim_deg) return out;
    }
    at[0] = value(0);
    auto refine = [&](auto& self, double la, double ea, double lb, double eb, int depth) -> bool {
      if (depth == 0 || std::abs(ea - eb) <= 2.0) return true;
      const double lm = 0.5 * (la + lb), em = value(lm);
      if (out.eng > s_.aim_deg) return false;
      return self(self, la, ea, lm, em, depth - 1) && self(self, lm, em, lb, eb, depth - 1);
    };
    for (int k = 0; k < m; ++k) {
      const auto a = static_cast<std::size_t>(k);
      if (!refine(refine, s_.step * k / m, at[a], s_.step * (k + 1) / m, at[a + 1], 3)) return out;
    }
    out.ok = true;
    return out;
  }
  // Whether a probe's step only grazes the stock: no uncut arc wider than the feed marks'
  // (Settings::graze_deg).
  [[nodiscard]] bool grazes(const Probe& pr) const { return pr.widest < s_.graze_deg; }

  // The next step from p with heading psi (the last step's turn theta_prev), in the frame
  // where turning towards the stock is negative: the step that turns furthest towards the
  // stock while allowed, found from the last turn by scanning and bisection; where that finds
  // no edge between allowed and not, the edge of least turn on a grid of 57 turns, else the
  // allowed step that cuts most. None: no step is allowed.
  struct Choice {
    double theta = 0;
    Probe probe;
  };
  [[nodiscard]] std::optional<Choice> choose(const Vec2& p, double psi, double theta_prev) const {
    const double kMaxTurn = 0.95 * kPi;  // a turn of 171 degrees: nearly straight back
    const double kScan = std::min(deg_to_rad(4), kMaxTurn / 4);
    const Vec2 incoming = dir(psi);
    auto at = [&](double th) { return probe(p, psi + s_.sigma * th, incoming); };
    auto bisect = [&](double ok_th, Probe ok_pr, double bad_th) {
      for (int k = 0; k < 7; ++k) {  // 4 degrees / 2^7: 0.03 degrees
        const double mid = 0.5 * (ok_th + bad_th);
        const Probe pm = at(mid);
        if (pm.ok) {
          ok_th = mid;
          ok_pr = pm;
        } else {
          bad_th = mid;
        }
      }
      return Choice{ok_th, ok_pr};
    };
    const double start = std::clamp(theta_prev, -kMaxTurn, kMaxTurn);
    const Probe first = at(start);
    if (first.ok) {
      double ok_th = start;
      Probe ok_pr = first;
      for (double next = start - kScan; next >= -kMaxTurn; next -= kScan) {
        const Probe pn = at(next);
        if (!pn.ok) return bisect(ok_th, ok_pr, next);
        ok_th = next;
        ok_pr = pn;
      }
    } else {
      double bad_th = start;
      for (double next = start + kScan; next <= kMaxTurn; next += kScan) {
        const Probe pn = at(next);
        if (pn.ok) return bisect(next, pn, bad_th);
        bad_th = next;
      }
    }
    // The whole circle of turns on a grid.
    constexpr int kHalf = 28;
    const double d = kMaxTurn / kHalf;
    std::vector<Probe> grid;
    for (int k = -kHalf; k <= kHalf; ++k) grid.push_back(at(k * d));
    std::optional<Choice> best;
    for (int k = 1; k < static_cast<int>(grid.size()); ++k) {
      // An edge: allowed here, not one grid step towards the stock.
      if (!grid[k].ok || grid[k - 1].ok) continue;
      const double th = (k - kHalf) * d;
      if (!best || std::abs(th) < std::abs(best->theta)) best = bisect(th, grid[k], th - d);
    }
    if (best) return best;
    for (int k = 0; k < static_cast<int>(grid.size()); ++k) {
      if (grid[k].ok && (!best || grid[k].eng > best->probe.eng)) {
        best = Choice{(k - kHalf) * d, grid[k]};
      }
    }
    return best;
  }

  // The step `c` that choose() found on quick probes, checked in full; where that fails, the
  // turn moved away from the stock by 0.25, 0.5, 1, ... 32 degrees until it holds. None when
  // nothing holds.
  [[nodiscard]] std::optional<Choice> verified(const Vec2& p, double psi,
                                               std::optional<Choice> c) const {
    if (!c) return c;
    const Vec2 incoming = dir(psi);
    double th = c->theta;
    for (int k = 0; k <= 8; ++k) {
      const Probe f = probe(p, psi + s_.sigma * th, incoming, true);
      if (f.ok) return Choice{th, f};
      th = std::min(0.95 * kPi, c->theta + deg_to_rad(0.25) * std::pow(2.0, k));
    }
    return std::nullopt;
  }

  // Runs one pass from p with heading psi (the helix's end, or a start next to stock).
  // `target`: head straight for it until the tool cuts. Ends where no step is allowed or after
  // 2R of steps that take no coverage cell. Returns the pass's points.
  Pass run_pass(Vec2 p, double psi, std::optional<Vec2> target) {
    Pass pass;
    pass.add(p, false);
    double theta = 0;
    double air = 0;  // the length run since the coverage last gained
    for (std::size_t n = 0; n < 4000000; ++n) {
      // Every point this step's search and checks ask about lies within a step of p.
      removed_.focus(p, s_.step * (1 + 1e-9));
      if (target) {
        const Vec2 to = *target - p;
        const double want = std::atan2(to.y(), to.x());
        const Probe pr = probe(p, want, dir(psi), true);
        if (to.norm() > s_.step && pr.ok && pr.eng < kCutting) {
          cut_step(p, pr.end, grazes(pr));
          pass.add(pr.end, !grazes(pr));
          p = pr.end;
          psi = want;
          continue;
        }
        // Cutting, there, or blocked: steer from here with the stock on the right.
        psi = want + s_.sigma * 0.5 * kPi;
        theta = 0;
        target.reset();
      }
      const auto c = verified(p, psi, choose(p, psi, theta));
      if (!c) break;  // no step allowed
      planned_max_ = std::max(planned_max_, c->probe.eng);
      psi += s_.sigma * c->theta;
      theta = c->theta;
      const long gain = cut_step(p, c->probe.end, grazes(c->probe));
      pass.add(c->probe.end, !grazes(c->probe));
      p = c->probe.end;
      // Progress is what the coverage gains: slivers below a cell do not keep a pass going.
      if (gain > 0) {
        air = 0;
      } else {
        air += s_.step;
        if (air > 2 * s_.R) break;
      }
    }
    return pass;
  }

  [[nodiscard]] double planned_max_deg() const { return planned_max_; }

  // Records a point the program's tool centre passes exactly at the level (a fitted piece's
  // end: the fit runs through the step points only within its tolerance).
  void add_exact(const Vec2& p) { exact_.push_back(p); }

  // The exact point nearest to p: the tool's cylinder there is cut from the top down to the
  // level, at every level (the levels repeat the moves), so a lift may descend there fast.
  [[nodiscard]] Vec2 nearest_exact(const Vec2& p) const {
    double best = std::numeric_limits<double>::infinity();
    Vec2 out = p;
    for (const Vec2& c : exact_) {
      const double d = (c - p).squaredNorm();
      if (d < best) {
        best = d;
        out = c;
      }
    }
    return out;
  }

  // Whether the line from a to b lies in the region (checked half a step apart).
  [[nodiscard]] bool line_in_region(const Vec2& a, const Vec2& b) const {
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / s_.step)));
    for (int k = 1; k <= 2 * n; ++k) {
      if (!in_region(a + (b - a) * (0.5 * k / n))) return false;
    }
    return true;
  }
  // Whether the tool can go from a to b at the level cutting nothing: the line in the region,
  // the tool at each tooth's point (a tooth at the feed apart) only grazing the stock
  // (Settings::graze_deg).
  [[nodiscard]] bool link_ok(const Vec2& a, const Vec2& b) const {
    const double L = (b - a).norm();
    if (!line_in_region(a, b)) return false;
    if (L <= 0) return true;
    const Vec2 t = (b - a) / L;
    const int m = std::max(1, static_cast<int>(std::ceil(L / s_.kernel_step)));
    for (int k = 1; k <= m; ++k) {
      // The tooth before a tooth's advance at the link feed back (a smaller disc of the
      // circle's back than the feed's: the larger estimate).
      const Vec2 q = a + (b - a) * (static_cast<double>(k) / m);
      if (engagement(q, q - s_.air_tooth * t).widest >= s_.graze_deg) return false;
    }
    return true;
  }
  // The same, and where it can the line is cut.
  bool link_down(const Vec2& a, const Vec2& b) {
    if (!link_ok(a, b)) return false;
    cut_step(a, b, true);
    return true;
  }
  // Where the line from a to b leaves the region (round an island, past a wall's corner) or
  // meets stock: a point the tool passed exactly at the level through which two lines do not,
  // the one of shortest way at most `longest` mm, the two lines cut. None: no such point
  // (the tool lifts over).
  std::optional<Vec2> link_via(const Vec2& a, const Vec2& b, double longest) {
    std::vector<std::pair<double, std::size_t>> by_way;
    for (std::size_t i = 0; i < exact_.size(); ++i) {
      const double way = (exact_[i] - a).norm() + (b - exact_[i]).norm();
      if (way <= longest) by_way.emplace_back(way, i);
    }
    std::sort(by_way.begin(), by_way.end());
    // The shortest first; the lines' region test is cheap, their stock test is not: at most
    // kTries points whose lines stay in the region are tested for stock.
    constexpr int kTries = 8;
    int tried = 0;
    for (const auto& [way, i] : by_way) {
      const Vec2 v = exact_[i];
      if (!line_in_region(a, v) || !line_in_region(v, b)) continue;
      if (++tried > kTries) break;
      if (link_ok(a, v) && link_ok(v, b)) {
        cut_step(a, v, true);
        cut_step(v, b, true);
        return v;
      }
    }
    return std::nullopt;
  }

  // A channel's loop: from `from` (the last loop's end) straight to the back point of the
  // circle of radius rho about channel point k (rho behind it along the axis), then round
  // the circle back to that point (counter-clockwise with the stock on the right). Its pieces
  // (the line, the circle in kLoopPieces arcs: the parts that only graze, the loop's back,
  // go at the link feed), whether each cuts (an uncut arc at one of its
  // teeth wider than a graze) and the largest engagement at the teeth (a tooth's advance at
  // the feed apart; each tooth against the removed region and the teeth of the loop before
  // it). Stops early (ok = false) where a tooth's engagement passes `limit_deg`.
  struct Loop {
    bool ok = true;
    bool off_axis = false;  // a family's cycle that would reach past the channel's axis
    double eng = 0;
    std::vector<ContourPiece> pieces;
    std::vector<bool> cuts;
    Vec2 end = Vec2::Zero();
  };
  [[nodiscard]] Loop loop(const Channel& ch, std::size_t k, double rho, const Vec2& from,
                          bool forward, double limit_deg) const {
    Loop out;
    const Vec2 t = forward ? ch.tangent(k) : Vec2(-ch.tangent(k));
    const Vec2 c = ch.c[k];
    const Vec2 back = c - rho * t;
    out.end = back;
    if ((back - from).norm() > 1e-9) out.pieces.push_back(ContourPiece::line(from, back));
    if (rho > 1e-9) {
      const bool ccw = s_.sigma > 0;
      Vec2 a = back;
      for (int q = 1; q <= kLoopPieces; ++q) {
        // The back point turned by q sixteenths of a turn about c.
        const double ang = (ccw ? 1.0 : -1.0) * kTwoPi * q / kLoopPieces;
        const Vec2 d = back - c;
        const Vec2 b = q == kLoopPieces
                           ? back
                           : Vec2(c + Vec2(std::cos(ang) * d.x() - std::sin(ang) * d.y(),
                                           std::sin(ang) * d.x() + std::cos(ang) * d.y()));
        out.pieces.push_back(ContourPiece::arc(a, b, c, ccw));
        a = b;
      }
    }
    judge(out, from, limit_deg);
    return out;
  }
  // A family's cycle along a channel ([path] type): from `from` (a line to the cycle's start
  // where it is not there: after a circle) the cycle from point k to point j (the step their
  // distance along the axis), as wide as the channel. Judged as loop's, together with the next
  // cycle at the same step where the axis has room for it: a trochoid's front advances by a
  // quarter of its own step and three quarters of the step before, so a step that holds alone
  // may leave the next cycle no step that does; with the look-ahead the same step holds next
  // (the loop keeps only the first cycle's pieces). ok = false also where the fit finds no arcs
  // (a cusp where the axis turns tighter than the cycle is wide); off_axis where the cycle would
  // reach past the axis' ends (the loops' there).
  [[nodiscard]] Loop family_loop(const Channel& ch, std::size_t k, std::size_t j, const Vec2& from,
                                 bool forward, double limit_deg) const {
    Loop out;
    Vec2 at = from;
    const CycleFit first = family_cycle_pieces(ch, k, j, forward, at, out.pieces);
    if (first != CycleFit::ok) {
      out.ok = false;
      out.off_axis = first == CycleFit::off_axis;
      return out;
    }
    out.end = at;
    const std::size_t n1 = out.pieces.size();
    const long by = static_cast<long>(j) - static_cast<long>(k);
    const long j2 = std::clamp(static_cast<long>(j) + by, 0L, static_cast<long>(ch.size()) - 1);
    if (j2 != static_cast<long>(j) &&
        family_cycle_pieces(ch, j, static_cast<std::size_t>(j2), forward, at, out.pieces) !=
            CycleFit::ok) {
      out.pieces.resize(n1);
    }
    judge(out, from, limit_deg);
    out.pieces.resize(n1);  // the look-ahead's judged, not kept
    out.cuts.resize(std::min(n1, out.cuts.size()));
    return out;
  }
  enum class CycleFit { ok, off_axis, no_fit };
  // Appends the pieces of the family's cycle from channel point k to j to `pieces`, from `at`
  // (moved to the cycle's end).
  CycleFit family_cycle_pieces(const Channel& ch, std::size_t k, std::size_t j, bool forward,
                               Vec2& at, std::vector<ContourPiece>& pieces) const {
    const double a = loop_radius(ch, k);
    const double step = std::abs(ch.u[j] - ch.u[k]);
    if (!(a > 1e-6) || !(step > 0)) return CycleFit::no_fit;
    const ToolPath cycle =
        family_cycle(*s_.family, a, s_.aspect, step, s_.linear_mm, s_.sigma > 0, 1.0);
    // Its reach behind and ahead of point k (sampled, 2 % of a more for the samples' gaps).
    double back = 0, ahead = step;
    for (const Segment& seg : cycle.segments()) {
      for (int q = 0; q <= 64; ++q) {
        const double y = seg.point_u(seg.u0() + (seg.u1() - seg.u0()) * q / 64).y();
        back = std::min(back, y);
        ahead = std::max(ahead, y);
      }
    }
    // Only on the axis: a cycle reaching past its ends (its back half at a channel's end) is
    // the loops' (a circle there); so is one the axis turns too tightly under.
    auto map = CycleOnAxis::make(ch, k, forward, back - 0.02 * a, ahead + 0.02 * a, a, ch.r[k] - a);
    if (!map) return CycleFit::off_axis;
    // The cycle again with the map's width at its start as its half-width a (and b = r_e a):
    // within the first's reach, and in a straight channel of constant width the family's own
    // cycle (the map then a rigid motion).
    const double a2 = map->width(0);
    map->set_half_width(a2);
    const std::size_t first = pieces.size();
    const ToolPath cycle2 =
        family_cycle(*s_.family, a2, s_.aspect, step, s_.linear_mm, s_.sigma > 0, 1.0);
    try {
      for (const Segment& seg : cycle2.segments()) {
        map->set(seg);
        const bool curve = seg.kind() == Segment::Kind::curve;
        const double u0 = seg.u0(), u1 = seg.u1();
        const int spans =
            curve ? std::max(1, static_cast<int>(std::ceil(std::abs(u1 - u0) / kPi))) : 1;
        const Vec3 p0 = map->point(u0);
        if (const Vec2 start(p0.x(), p0.y()); (start - at).norm() > 1e-9) {
          pieces.push_back(ContourPiece::line(at, start));
          at = start;
        }
        for (const FitArc& f : fit_biarcs_at_cusps(*map, u0, u1, spans, s_.fit_tolerance, 4096)) {
          const Vec2 e(f.end.x(), f.end.y());
          if ((e - at).norm() <= 1e-12) continue;
          // An arc turning less than 1e-6 rad is its chord (within L 1e-6 / 8 mm); a line
          // on from a line of this cycle in its direction (the biarcs of a wall move) joins it.
          if (f.is_line || std::abs(f.sweep_rad) < 1e-6) {
            const auto joins = [&](const ContourPiece& last) {
              const Vec2 d = last.end - last.start;
              return !last.is_arc() && d.dot(e - at) > 0 &&
                     std::abs(cross2(d, e - at)) <= 1e-12 * d.norm() * (e - at).norm();
            };
            if (pieces.size() > first && joins(pieces.back())) {
              pieces.back().end = e;
            } else {
              pieces.push_back(ContourPiece::line(at, e));
            }
          } else {
            pieces.push_back(ContourPiece::arc(at, e, Vec2(f.cx, f.cy), f.sweep_rad >= 0));
          }
          at = e;
        }
      }
    } catch (const Error&) {
      return CycleFit::no_fit;
    } catch (const ArcLimit&) {
      return CycleFit::no_fit;
    }
    return CycleFit::ok;
  }
  // Whether each of a loop's pieces cuts and the largest engagement of its teeth (see loop).
  void judge(Loop& out, const Vec2& from, double limit_deg) const {
    Box3 box;
    box.extend(Vec3(from.x(), from.y(), 0));
    for (const ContourPiece& piece : out.pieces) {
      box.extend(Vec3(piece.end.x(), piece.end.y(), 0));
      if (piece.is_arc()) {
        // The arc's points furthest along +-x and +-y within its sweep.
        const Vec2 c = *piece.centre;
        const double r = piece.radius_mm(), sweep = piece.sweep_rad();
        const double a0 = std::atan2(piece.start.y() - c.y(), piece.start.x() - c.x());
        for (int q = 0; q < 4; ++q) {
          double d =
              0.5 * kPi * q - a0;  // from the start to the axis direction, in the sweep's sense
          d = sweep > 0 ? std::fmod(std::fmod(d, kTwoPi) + kTwoPi, kTwoPi)
                        : -std::fmod(std::fmod(-d, kTwoPi) + kTwoPi, kTwoPi);
          if (std::abs(d) <= std::abs(sweep)) {
            const Vec2 e = c + r * dir(0.5 * kPi * q);
            box.extend(Vec3(e.x(), e.y(), 0));
          }
        }
      }
    }
    const Vec2 lo(box.lo.x(), box.lo.y()), hi(box.hi.x(), box.hi.y());
    RemovedRegion local(s_.R, lo, hi);
    local.cut(from);
    removed_.focus(0.5 * (lo + hi), 0.5 * (hi - lo).norm() + 1e-6);
    const double tooth = s_.kernel_step;
    for (const ContourPiece& piece : out.pieces) {
      bool cuts = false;
      const int n = std::max(1, static_cast<int>(std::ceil(piece.length_mm() / tooth)));
      for (int j = 1; j <= n; ++j) {
        const Vec2 q = piece.point_at(static_cast<double>(j) / n);
        const auto there = removed_.uncut_arcs(q);
        if (!there.empty()) {
          const auto [total, widest] = arcs_overlap_deg(there, local.uncut_arcs(q));
          out.eng = std::max(out.eng, total);
          cuts = cuts || widest >= s_.graze_deg;
          if (out.eng > limit_deg) {
            out.ok = false;
            return;
          }
        }
        local.cut(q);
      }
      out.cuts.push_back(cuts);
    }
  }
  // Cuts a loop's pieces into the removed region and the coverage (as cut_step: discs a
  // tooth's advance apart, at the link feed's for a piece that only grazes).
  void cut_loop(const Loop& l) {
    for (std::size_t i = 0; i < l.pieces.size(); ++i) {
      const ContourPiece& piece = l.pieces[i];
      const double tooth = std::min(s_.step, l.cuts[i] ? s_.kernel_step : s_.air_tooth);
      const int n = std::max(1, static_cast<int>(std::ceil(piece.length_mm() / tooth)));
      Vec2 prev = piece.start;
      for (int j = 1; j <= n; ++j) {
        const Vec2 q = piece.point_at(static_cast<double>(j) / n);
        removed_.cut(q);
        coverage_.cut_segment(prev, q);
        prev = q;
      }
    }
    planned_max_ = std::max(planned_max_, l.eng);
  }
  // The loop's radius at channel point k: its clearance, a hair less.
  static double loop_radius(const Channel& ch, std::size_t k) {
    return std::max(0.0, ch.r[k] * (1 - 1e-9) - 1e-6);
  }

  // Where a channel's trochoid may start from its first point (forward) or its last: the tool's
  // disc there cleared. Then the loops about its points from there on that would cut nothing
  // are passed over (scanned R / 4 apart): the start is the last of them, with the largest
  // radius that cuts nothing. None: the disc at the end is not cleared.
  struct Start {
    std::size_t k = 0;
    double rho = 0;
    Vec2 point = Vec2::Zero();  // the loop's back point: where the tool comes to
  };
  [[nodiscard]] std::optional<Start> channel_start(const Channel& ch, bool forward) const {
    const std::size_t n = ch.size();
    const std::size_t k0 = forward ? 0 : n - 1;
    if (!disc_cleared(ch.c[k0])) return std::nullopt;
    auto idle = [&](std::size_t k, double rho) {
      const Vec2 t = forward ? ch.tangent(k) : Vec2(-ch.tangent(k));
      const int m = std::max(8, static_cast<int>(std::ceil(kTwoPi * rho / (0.25 * s_.step))));
      removed_.focus(ch.c[k], rho + 1e-6);
      for (int j = 0; j < m; ++j) {
        const Vec2 q = ch.c[k] - rho * dir(std::atan2(t.y(), t.x()) + kTwoPi * j / m);
        if (uncut(q).widest >= s_.graze_deg) return false;
      }
      return true;
    };
    Start st{k0, 0, ch.c[k0]};
    const double stride = 0.25 * s_.R;
    std::size_t k = k0;
    for (;;) {
      if (!idle(k, loop_radius(ch, k))) break;
      st.k = k;
      st.rho = loop_radius(ch, k);
      // The next point a stride on.
      std::size_t next = k;
      while (next != (forward ? n - 1 : 0) && std::abs(ch.u[next] - ch.u[k]) < stride) {
        next = forward ? next + 1 : next - 1;
      }
      if (next == k) break;
      k = next;
    }
    if (st.k == k0 && st.rho == 0) {
      // Not even the loop at the end: the largest radius there that cuts nothing.
      double lo = 0, hi = loop_radius(ch, k0);
      for (int i = 0; i < 12; ++i) {
        const double mid = 0.5 * (lo + hi);
        (idle(k0, mid) ? lo : hi) = mid;
      }
      st.rho = lo;
    }
    const Vec2 t = forward ? ch.tangent(st.k) : Vec2(-ch.tangent(st.k));
    st.point = ch.c[st.k] - st.rho * t;
    return st;
  }

  // The largest radius in (lo, hi) of a loop about channel point k that holds the aim, by
  // bisection (10 halvings), and its loop; a loop with ok = false where none did.
  [[nodiscard]] std::pair<double, Loop> largest_loop(const Channel& ch, std::size_t k, double lo,
                                                     double hi, const Vec2& from,
                                                     bool forward) const {
    Loop best;
    best.ok = false;
    for (int i = 0; i < 10; ++i) {
      const double mid = 0.5 * (lo + hi);
      Loop l = loop(ch, k, mid, from, forward, s_.aim_deg);
      if (l.ok) {
        lo = mid;
        best = std::move(l);
      } else {
        hi = mid;
      }
    }
    return {lo, std::move(best)};
  }

  // The trochoid along a channel from a start: loop after loop, each the furthest step on
  // (bisection over the channel's points, up to R) whose teeth hold the aim; where the loop's
  // radius is below the channel's there (a start), it first grows in place. The pieces and
  // whether each cuts, cut into the model as they go. Stops where no loop holds (the rest is
  // left to the clearing passes).
  struct Trochoid {
    std::vector<ContourPiece> pieces;
    std::vector<bool> cuts;
    bool complete = false;
    // The axis' length (mm) it stepped along by the family's cycles ([path] type), by the
    // loops (circles: the default, and a family's at the channels' ends and starts) and by
    // loops where no cycle of the family held the aim.
    double family_mm = 0, loops_mm = 0, unheld_mm = 0;
  };
  Trochoid trochoid(const Channel& ch, bool forward, const Start& st) {
    Trochoid out;
    const std::size_t n = ch.size();
    const std::size_t last = forward ? n - 1 : 0;
    std::size_t k = st.k;
    double rho = st.rho;
    Vec2 at = st.point;
    auto index = [&](std::size_t from, long by) {
      const long i = static_cast<long>(from) + (forward ? by : -by);
      return static_cast<std::size_t>(std::clamp(i, 0L, static_cast<long>(n) - 1));
    };
    auto emit = [&](const Loop& l) {
      cut_loop(l);
      for (std::size_t i = 0; i < l.pieces.size(); ++i) {
        out.pieces.push_back(l.pieces[i]);
        out.cuts.push_back(l.cuts[i]);
      }
      at = l.end;
    };
    long stride = 1;          // the last step, in points
    bool circle_at_k = true;  // the last loop was a circle about point k (not a family's cycle)
    for (int guard = 0; guard < 1000000; ++guard) {
      const double r_here = loop_radius(ch, k);
      if (rho < r_here - 1e-6) {
        // Grow in place: the largest radius up to the channel's that holds.
        Loop best = loop(ch, k, r_here, at, forward, s_.aim_deg);
        if (!best.ok) {
          auto [r, l] = largest_loop(ch, k, rho, r_here, at, forward);
          if (!l.ok || r - rho < 1e-3 * s_.R) return out;  // stuck
          rho = r;
          best = std::move(l);
        } else {
          rho = r_here;
        }
        emit(best);
        continue;
      }
      if (k == last) break;
      // Step on: the furthest point within R whose loop holds, from the last step doubled.
      long max_by = 0;
      while (index(k, max_by + 1) != k && std::abs(ch.u[index(k, max_by + 1)] - ch.u[k]) <= s_.R) {
        ++max_by;
        if (index(k, max_by) == last) break;
      }
      if (max_by == 0) break;
      // The furthest step of the family's cycles (fam) or of the loops: doubled from the last
      // step until one fails, then bisected. A family's cycle that would reach past the axis
      // fails.
      bool family_failed = false;  // a cycle of the family failed the aim (not only the axis)
      const auto search = [&](bool fam) {
        const auto attempt = [&](long by) {
          const std::size_t j = index(k, by);
          Loop l = fam ? family_loop(ch, k, j, at, forward, s_.aim_deg)
                       : loop(ch, j, loop_radius(ch, j), at, forward, s_.aim_deg);
          if (fam && !l.ok && !l.off_axis) family_failed = true;
          return l;
        };
        long ok_by = 0, bad_by = max_by + 1;
        Loop ok_loop;
        for (long by = std::min(std::max(1L, stride), max_by);;) {
          Loop l = attempt(by);
          if (l.ok) {
            ok_by = by;
            ok_loop = std::move(l);
            if (by == max_by) break;
            by = std::min(max_by, 2 * by);
          } else {
            bad_by = by;
            break;
          }
        }
        while (bad_by - ok_by > std::max(1L, ok_by / 16)) {
          const long mid = (ok_by + bad_by) / 2;
          if (mid <= 0) break;
          Loop l = attempt(mid);
          if (l.ok) {
            ok_by = mid;
            ok_loop = std::move(l);
          } else {
            bad_by = mid;
          }
        }
        return std::pair<long, Loop>(ok_by, std::move(ok_loop));
      };
      // The family where one of its cycles holds the aim, else the loops.
      bool ok_family = s_.family.has_value();
      auto [ok_by, ok_loop] = search(ok_family);
      if (ok_by == 0 && ok_family) {
        ok_family = false;
        std::tie(ok_by, ok_loop) = search(false);
      }
      if (ok_by == 0) {
        // Not even one point on at its full radius: a smaller loop there, to grow next.
        const std::size_t j = index(k, 1);
        auto [r, best] = largest_loop(ch, j, 0, loop_radius(ch, j), at, forward);
        if (!best.ok) return out;  // stuck
        out.loops_mm += std::abs(ch.u[j] - ch.u[k]);
        k = j;
        rho = r;
        emit(best);
        circle_at_k = true;
        stride = 1;
        continue;
      }
      (ok_family       ? out.family_mm
       : family_failed ? out.unheld_mm
                       : out.loops_mm) += std::abs(ch.u[index(k, ok_by)] - ch.u[k]);
      k = index(k, ok_by);
      rho = loop_radius(ch, k);
      stride = ok_by;
      emit(ok_loop);
      circle_at_k = !ok_family;
    }
    if (k == last && !circle_at_k) {
      // A family's cycles end on the wall at the last point: a circle there as wide as the
      // channel clears the end's disc (a dead end's round end, the slot's end circle).
      const Loop cap = loop(ch, last, loop_radius(ch, last), at, forward, s_.aim_deg);
      if (cap.ok) emit(cap);
    }
    out.complete = k == last;
    return out;
  }

 private:
  Settings s_;
  RegionGrid inside_;
  RemovedRegion removed_;
  Coverage coverage_;
  std::vector<Vec2> exact_;
  double planned_max_ = 0;
};

// A pass's run of steps [first, last] (point indices): through cleared area (air) or cutting.
struct Run {
  std::size_t first = 0, last = 0;
  bool air = false;
};

// A run through cleared area shorter than this (in tool radii) stays at the feed: fewer feed
// changes (at R/10 the example pocket's time is 0.6 % shorter, 376.5 s against 378.7 s, 0.2 %
// with the machine's acceleration, and its program 2 % longer, 249 kB against 244 kB).
constexpr double kMinAirRun = 0.25;

// The pass's runs: its steps grouped by whether they cut, the air runs shorter than
// min_air_mm joined to the cutting around them.
std::vector<Run> pass_runs(const Pass& pass, double min_air_mm) {
  std::vector<Run> runs;
  for (std::size_t i = 1; i < pass.points.size(); ++i) {
    const bool air = !pass.cuts[i];
    if (runs.empty() || runs.back().air != air) {
      runs.push_back({i - 1, i, air});
    } else {
      runs.back().last = i;
    }
  }
  auto length = [&](const Run& r) {
    double l = 0;
    for (std::size_t i = r.first + 1; i <= r.last; ++i) {
      l += (pass.points[i] - pass.points[i - 1]).norm();
    }
    return l;
  };
  std::vector<Run> out;
  for (Run r : runs) {
    if (r.air && length(r) < min_air_mm) r.air = false;
    if (!out.empty() && out.back().air == r.air) {
      out.back().last = r.last;
    } else {
      out.push_back(r);
    }
  }
  return out;
}

// A polyline's length (mm).
double polyline_length(const std::vector<Vec2>& pts) {
  double l = 0;
  for (std::size_t i = 1; i < pts.size(); ++i) l += (pts[i] - pts[i - 1]).norm();
  return l;
}

// The polyline split at `at` mm along it (0 < at < its length): its points up to the split
// point and from it, that point in both (not repeated where it is a vertex, to 1e-9 mm).
std::pair<std::vector<Vec2>, std::vector<Vec2>> split_polyline(const std::vector<Vec2>& pts,
                                                               double at) {
  std::vector<Vec2> a{pts.front()}, b;
  double done = 0;
  std::size_t i = 1;
  for (; i < pts.size(); ++i) {
    const double L = (pts[i] - pts[i - 1]).norm();
    if (done + L >= at) break;
    a.push_back(pts[i]);
    done += L;
  }
  if (i == pts.size()) return {a, {pts.back()}};
  const double L = (pts[i] - pts[i - 1]).norm();
  const Vec2 q = pts[i - 1] + (pts[i] - pts[i - 1]) * ((at - done) / L);
  if ((q - a.back()).norm() > 1e-9) a.push_back(q);
  b.push_back(a.back());
  const std::size_t from = (pts[i] - b.front()).norm() > 1e-9 ? i : i + 1;
  b.insert(b.end(), pts.begin() + static_cast<long>(from), pts.end());
  return {a, b};
}

// The piece split at `length` mm from its start (0 < length < its length).
std::pair<ContourPiece, ContourPiece> split_piece(const ContourPiece& p, double length) {
  const Vec2 q = p.point_at(length / p.length_mm());
  if (!p.is_arc()) return {ContourPiece::line(p.start, q), ContourPiece::line(q, p.end)};
  return {ContourPiece::arc(p.start, q, *p.centre, p.ccw),
          ContourPiece::arc(q, p.end, *p.centre, p.ccw)};
}

// A run through cleared area as moves: its first `head` and last `tail` mm at the feed, the
// rest at the link feed (Move2::air); all at the feed where that rest would be shorter than
// max(head, tail) (a 0 given where the cutting run beside it took that tooth already). The kernel,
// like the teeth, samples a move at the link feed a tooth's advance there apart, so that the disc
// of the corner where a run turns off into cleared area, or in from it, would fall between two of
// them; with a tooth's advance at the feed on either side of it, one sample lies within a tooth's
// advance at the feed of it, as on every corner of a cutting run and as the planner's model has it.
std::vector<Move2> air_moves(const std::vector<ContourPiece>& pieces, double head, double tail) {
  double total = 0;
  for (const ContourPiece& p : pieces) total += p.length_mm();
  std::vector<Move2> out;
  if (total <= head + tail + std::max(head, tail)) {
    for (const ContourPiece& p : pieces) out.push_back({Move2::arc_or_line, p});
    return out;
  }
  double at = 0;  // the length before the piece
  for (const ContourPiece& p : pieces) {
    const double L = p.length_mm();
    ContourPiece rest = p;
    double from = at;
    if (from < head) {  // the head: at the feed up to `head`
      if (at + L <= head) {
        out.push_back({Move2::arc_or_line, p});
        at += L;
        continue;
      }
      auto [fed, after] = split_piece(rest, head - from);
      out.push_back({Move2::arc_or_line, fed});
      rest = after;
      from = head;
    }
    const double end = at + L;
    if (end > total - tail) {  // the tail: at the feed from total - tail
      if (from >= total - tail) {
        out.push_back({Move2::arc_or_line, rest});
      } else {
        auto [mid, fed] = split_piece(rest, total - tail - from);
        out.push_back({Move2::air, mid});
        out.push_back({Move2::arc_or_line, fed});
      }
    } else {
      out.push_back({Move2::air, rest});
    }
    at = end;
  }
  return out;
}

// The centre of the part's widest place (largest distance to its contours), on a grid
// refined twice, and that distance.
std::pair<Vec2, double> widest_point(const std::vector<Contour>& part, const RegionGrid& inside) {
  const Box3 box = vertex_box(part);
  auto clearance = [&](const Vec2& p) {
    double d = std::numeric_limits<double>::infinity();
    for (const Contour& c : part) d = std::min(d, c.distance_mm(p));
    return d;
  };
  Vec2 best((box.lo.x() + box.hi.x()) / 2, (box.lo.y() + box.hi.y()) / 2);
  double best_d = -1;
  const double span = std::max(box.hi.x() - box.lo.x(), box.hi.y() - box.lo.y());
  double h = std::max(span / 64, 1e-3);
  Vec2 lo(box.lo.x(), box.lo.y()), hi(box.hi.x(), box.hi.y());
  for (int round = 0; round < 3; ++round) {
    for (double y = lo.y() + 0.5 * h; y < hi.y(); y += h) {
      for (double x = lo.x() + 0.5 * h; x < hi.x(); x += h) {
        const Vec2 p(x, y);
        if (!inside.contains(p)) continue;
        const double d = clearance(p);
        if (d > best_d) {
          best_d = d;
          best = p;
        }
      }
    }
    lo = best - Vec2(2 * h, 2 * h);
    hi = best + Vec2(2 * h, 2 * h);
    h /= 8;
  }
  return {best, std::max(0.0, best_d)};
}

// The centres of discs of radius R clear of the stock in plan (`stock`: the region where it
// stands, offset_region's form: the [stock] box, or a stock mesh's plan view at a level), for
// a tool centre region spanning lo..hi: the stock grown by R is their outline, discs `spacing`
// apart along it (their scallops spacing^2 / 8 R deep), and beyond it a grid of 0.9 R (a point
// of the outline's band lies within R of an outline disc; one further out within 0.64 R of a
// grid point, itself beyond). Empty where the stock covers the region and the tool around it.
std::vector<Vec2> air_discs(const std::vector<Contour>& stock, double R, double spacing,
                            const Vec2& lo, const Vec2& hi) {
  std::vector<Vec2> out;
  // The stock grown by two spacings more: where the tool's circle meets the stock's edge from
  // inside, the stock between them is a sliver microns thick, yet its arc is one with the rest
  // of the tool's arc in the stock (the engagement jumps as the circle leaves the edge). The
  // planner, checking a tooth's advance apart, must see that: it takes a band two advances
  // wide beyond the edge as stock. And by Clipper's chords more (they lie within its tolerance
  // inside the exact offset), so that every disc is clear of the band.
  const std::vector<Contour> grown =
      stock.empty() ? std::vector<Contour>{}
                    : offset_region(stock, R + 2 * spacing + kClipperTol, kClipperTol);
  // Only discs that may meet a tool centred in lo..hi.
  const auto near = [&](const Vec2& p) {
    return p.x() > lo.x() - 2 * R && p.x() < hi.x() + 2 * R && p.y() > lo.y() - 2 * R &&
           p.y() < hi.y() + 2 * R;
  };
  for (const Contour& c : grown) {
    const std::vector<Vec2> pts = c.points(kClipperTol);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const Vec2& a = pts[i];
      const Vec2& b = pts[(i + 1) % pts.size()];
      // An edge wholly beside the window gives none.
      if (std::max(a.x(), b.x()) <= lo.x() - 2 * R || std::min(a.x(), b.x()) >= hi.x() + 2 * R ||
          std::max(a.y(), b.y()) <= lo.y() - 2 * R || std::min(a.y(), b.y()) >= hi.y() + 2 * R) {
        continue;
      }
      const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing)));
      // Only the steps whose points may be near (the edge's part in the window, Liang and
      // Barsky's clip), so that a stock far larger than the pocket costs no more than its part
      // near it; the points are the whole edge's, k / n along it.
      double t0 = 0, t1 = 1;
      for (int d = 0; d < 2; ++d) {
        const double w0 = (d == 0 ? lo.x() : lo.y()) - 2 * R,
                     w1 = (d == 0 ? hi.x() : hi.y()) + 2 * R;
        const double step = b[d] - a[d];
        if (step == 0) continue;  // within the window's range on this axis (checked above)
        const double ta = (w0 - a[d]) / step, tb = (w1 - a[d]) / step;
        t0 = std::max(t0, std::min(ta, tb));
        t1 = std::min(t1, std::max(ta, tb));
      }
      if (t0 > t1) continue;
      const int k0 = std::max(0, static_cast<int>(std::floor(t0 * n)) - 1);
      const int k1 = std::min(n, static_cast<int>(std::ceil(t1 * n)) + 1);
      for (int k = k0; k < k1; ++k) {
        const Vec2 p = a + (b - a) * (static_cast<double>(k) / n);
        if (near(p)) out.push_back(p);
      }
    }
  }
  const double g = 0.9 * R;
  for (double y = lo.y() - 2 * R + 0.5 * g; y < hi.y() + 2 * R; y += g) {
    for (double x = lo.x() - 2 * R + 0.5 * g; x < hi.x() + 2 * R; x += g) {
      if (!region_contains(grown, Vec2(x, y))) out.emplace_back(x, y);
    }
  }
  return out;
}

// Where the stock stands in plan for a tool tip at height z (mm): the [stock] mesh's plan view
// from z up to its top (the column above the tip: the tool comes down from above where there is
// none, so a finite flute length does not shorten it), else the [stock] box's rectangle.
std::vector<Contour> stock_plan(const Job& job, double z) {
  if (job.stock_mesh) {
    const double top = (*job.stock_max_mm)[2];
    if (z > top) return {};  // nothing above the tip: the level is air
    return mesh_plan_region(*job.stock_mesh, z, top);
  }
  if (!job.stock_min_mm || !job.stock_max_mm) return {};
  const Vec3& a = *job.stock_min_mm;
  const Vec3& b = *job.stock_max_mm;
  return {Contour::polyline(
      {Vec2(a.x(), a.y()), Vec2(b.x(), a.y()), Vec2(b.x(), b.y()), Vec2(a.x(), b.y())}, true)};
}

// The clearing of one part, as planar moves (the helix's flat circle first).
struct PartPlan {
  Vec2 helix_centre = Vec2::Zero();
  double helix_radius = 0;
  // Rest machining: the part has no stock left (no moves), or is entered from above where
  // the earlier program cleared the tool's disc (at helix_centre, no helix).
  bool nothing = false, from_above = false;
  bool from_hole = false;    // fed straight down a pre-drilled hole at helix_centre
  std::vector<Move2> moves;  // from the helix's end point
  int passes = 0, links_down = 0, lifts = 0;
  double clearing_length = 0;  // at the feed
  double air_length = 0;       // the passes' runs through cleared area, at the link feed
  double planned_max_deg = 0;
  double given_up_mm2 = 0;
  double rest_cleared_mm2 = 0;   // of the coverage, what the earlier program had removed
  double open_mm2 = 0;           // of the coverage, the air beside the [stock] box
  int channels = 0;              // channels cleared by trochoids
  double channels_left_mm2 = 0;  // the bands of channels no trochoid could start into
  // Trochoid::family_mm, loops_mm, unheld_mm summed
  double channel_family_mm = 0, channel_loops_mm = 0, channel_unheld_mm = 0;
  // Its planner as the plan left it (the removed region: what the level's tool swept, and
  // what was not there), which deeper levels' lifts ask where they may come down fast.
  std::shared_ptr<const PartPlanner> planner;
};

void plan_passes(const Settings& s, PartPlanner& planner, Vec2 p, PartPlan& out,
                 std::vector<Channel>& channels);

// A channel split at its point k: the part from k to its last point and the part from k back
// to its first, each starting at k (where the entry cleared the tool's disc).
std::pair<Channel, Channel> split_channel(const Channel& ch, std::size_t k) {
  Channel a, b;
  for (std::size_t i = k; i < ch.size(); ++i) {
    a.c.push_back(ch.c[i]);
    a.r.push_back(ch.r[i]);
    a.u.push_back(ch.u[i] - ch.u[k]);
  }
  for (std::size_t i = k + 1; i-- > 0;) {
    b.c.push_back(ch.c[i]);
    b.r.push_back(ch.r[i]);
    b.u.push_back(ch.u[k] - ch.u[i]);
  }
  a.hold_back = ch.hold_back;
  b.hold_back = ch.hold_front;
  return {a, b};
}

// The channels' cells held from the clearing passes (but for hold_front and hold_back from
// their ends, which the passes clear and the trochoids start from), after splitting the channel
// whose loops hold the entry point `entry` there.
void hold_channels(const Settings& s, PartPlanner& planner, const Vec2& entry,
                   std::vector<Channel>& channels) {
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const Channel& ch = channels[i];
    std::size_t best = ch.size();
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < ch.size(); ++k) {
      const double d = (ch.c[k] - entry).norm();
      if (d < ch.r[k] && d < best_d) {
        best_d = d;
        best = k;
      }
    }
    if (best == ch.size()) continue;
    auto [a, b] = split_channel(ch, best);
    channels[i] = std::move(a);
    channels.insert(channels.begin() + static_cast<long>(i) + 1, std::move(b));
    ++i;
  }
  std::erase_if(channels, [](const Channel& ch) { return ch.size() < 2; });
  for (const Channel& ch : channels) {
    const double L = ch.u.back();
    for (std::size_t k = 0; k + 1 < ch.size(); ++k) {
      if (ch.u[k + 1] < ch.hold_front || ch.u[k] > L - ch.hold_back) continue;
      planner.coverage().hold(ch.c[k], ch.c[k + 1], std::max(ch.r[k], ch.r[k + 1]) + s.R);
    }
  }
}

// The channels of a tool centre region `region0` (unrounded; its convex corners sharp): the
// runs of its medial axis where the pocket is narrower than `channel_width_mm` (the region's
// clearance at most half that less `keep`, the tool's radius and the margins) and the loops
// would be at least R / 20 wide, as Channel. A run that ends where the pocket widens leaves
// 2R + its half-width there to the clearing passes (the trochoid starts from what they
// cleared); a run shorter than both of those and R is theirs whole, unless the passes' region
// (`rounded`: region0 with its corners rounded) leaves it out.
std::vector<Channel> trochoid_channels(const std::vector<Contour>& region0,
                                       const std::vector<Contour>& rounded, double R,
                                       double r_max) {
  std::vector<Channel> out;
  // Where the rounded region leaves the channel out (narrower than 2 rc = R / 2 across):
  // always a channel.
  r_max = std::max(r_max, 0.25 * R);
  const double r_min = 0.05 * R;
  const double spacing = std::clamp(0.01 * R, 0.005, 0.05);
  const std::vector<MedialBranch> axis = medial_axis(region0, 120, spacing);
  for (MedialBranch b : axis) {
    if (b.points.size() < 2) continue;
    if (b.closed) {
      // Start at the widest point, so that no run wraps round; a channel all round is opened
      // there and closed by repeating its first point.
      const auto widest = static_cast<std::size_t>(
          std::max_element(b.clearance_mm.begin(), b.clearance_mm.end()) - b.clearance_mm.begin());
      std::rotate(b.points.begin(), b.points.begin() + static_cast<long>(widest), b.points.end());
      std::rotate(b.clearance_mm.begin(), b.clearance_mm.begin() + static_cast<long>(widest),
                  b.clearance_mm.end());
      b.points.push_back(b.points.front());
      b.clearance_mm.push_back(b.clearance_mm.front());
    }
    const std::size_t m = b.points.size();
    std::size_t i = 0;
    while (i < m) {
      auto in = [&](std::size_t k) {
        return b.clearance_mm[k] >= r_min && b.clearance_mm[k] <= r_max;
      };
      if (!in(i)) {
        ++i;
        continue;
      }
      std::size_t j = i;
      while (j < m && in(j)) ++j;
      Channel ch;
      double u = 0;
      for (std::size_t k = i; k < j; ++k) {
        if (k > i) u += (b.points[k] - b.points[k - 1]).norm();
        ch.c.push_back(b.points[k]);
        ch.r.push_back(b.clearance_mm[k]);
        ch.u.push_back(u);
      }
      // An end where the pocket goes on: where it widens beyond the channel, or where the
      // region goes on R / 4 past the end's disc along the axis (a junction, or where the
      // axis was pruned as the walls open out); not a dead end against a wall.
      auto goes_on = [&](std::size_t e, std::size_t inner) {
        const Vec2 t = b.points[e] - b.points[inner];
        if (!(t.norm() > 0)) return false;
        return region_contains(region0,
                               b.points[e] + (b.clearance_mm[e] + 0.25 * R) * t / t.norm());
      };
      const bool wide_front = i > 0 ? b.clearance_mm[i - 1] > r_max : goes_on(i, j - 1);
      const bool wide_back = j < m ? b.clearance_mm[j] > r_max : goes_on(j - 1, i);
      auto past = [&](std::size_t e, std::size_t inner) {
        const Vec2 t = (b.points[e] - b.points[inner]).normalized();
        return Vec2(b.points[e] + (b.clearance_mm[e] + 0.25 * R) * t);
      };
      if (wide_front) ch.beyond.push_back(i > 0 ? b.points[i - 1] : past(i, j - 1));
      if (wide_back) ch.beyond.push_back(j < m ? b.points[j] : past(j - 1, i));
      ch.hold_front = wide_front ? 2 * R + ch.r.front() : 0;
      ch.hold_back = wide_back ? 2 * R + ch.r.back() : 0;
      bool outside = false;  // a part the passes' region leaves out
      for (const Vec2& p : ch.c) outside = outside || !region_contains(rounded, p);
      if (ch.size() >= 2 && (outside || u > ch.hold_front + ch.hold_back + R)) {
        out.push_back(std::move(ch));
      }
      i = j;
    }
  }
  return out;
}

// `before`: the discs of what an earlier program removed at the level (rest_disc_centres), or
// empty; `air`: those of the air beside the stock at the level (air_discs: a [stock] box the
// pocket runs past, a stock mesh), or empty; `holes`: [pocket] entry_holes in the part.
// `channels`: those of the part (trochoid_channels).
PartPlan plan_part(const Job& job, const Settings& s, const std::vector<Contour>& part,
                   const std::vector<Vec2>& before, const std::vector<Vec2>& air,
                   const std::vector<Vec2>& holes, std::vector<Channel> channels) {
  const Box3 box = vertex_box(part);
  const Vec2 lo(box.lo.x() - s.R, box.lo.y() - s.R), hi(box.hi.x() + s.R, box.hi.y() + s.R);
  const auto owned = std::make_shared<PartPlanner>(s, part, lo, hi);
  PartPlanner& planner = *owned;
  PartPlan out;
  out.planner = owned;
  const auto [centre, room] = widest_point(part, planner.region());
  std::optional<Vec2> above;  // where to come down from above
  if (!before.empty() || !air.empty()) {
    // What is not there: the discs of each that may meet a tool in the box.
    const auto cut_all = [&](const std::vector<Vec2>& discs) {
      const long uncovered = planner.coverage().remaining();
      for (const Vec2& c : discs) {
        if (c.x() > lo.x() - s.R && c.x() < hi.x() + s.R && c.y() > lo.y() - s.R &&
            c.y() < hi.y() + s.R) {
          planner.cut(c);
        }
      }
      const double cell = planner.coverage().cell_mm();
      return static_cast<double>(uncovered - planner.coverage().remaining()) * cell * cell;
    };
    out.open_mm2 = cut_all(air);
    out.rest_cleared_mm2 = cut_all(before);
    if (planner.coverage().remaining() == 0 && channels.empty()) {
      out.nothing = true;
      return out;
    }
    // The stock left nearest the widest place (or a channel's first point), and the place
    // nearest it (on a grid of R / 4) where the tool's disc lies in the removed region: the
    // tool comes down there.
    const auto left = planner.coverage().nearest_remaining(centre);
    const Vec2 q = left ? *left : channels.front().c.front();
    const double g = 0.25 * s.R;
    double best = std::numeric_limits<double>::infinity();
    for (double y = lo.y() + 0.5 * g; y < hi.y(); y += g) {
      for (double x = lo.x() + 0.5 * g; x < hi.x(); x += g) {
        const Vec2 p(x, y);
        const double d = (p - q).squaredNorm();
        if (d >= best || !planner.in_region(p) || !planner.disc_cleared(p)) continue;
        best = d;
        above = p;
      }
    }
  }
  if (above) {
    out.from_above = true;
    out.helix_centre = *above;
    planner.add_exact(*above);
    hold_channels(s, planner, *above, channels);
    plan_passes(s, planner, *above, out, channels);
    return out;
  }
  // A pre-drilled hole in the part (the first listed) is the entry instead of the helix: fed
  // straight down it, out to the same flat circle about it and round (a hole of the tool's
  // width leaves no way out within the target: the circle opens it, as the helix's does).
  Vec2 c = centre;
  double room_c = room;
  if (!holes.empty()) {
    out.from_hole = true;
    c = holes.front();
    room_c = std::numeric_limits<double>::infinity();
    for (const Contour& k : part) room_c = std::min(room_c, k.distance_mm(c));
  }
  double rh = job.path.entry_radius_mm;
  if (rh > 0 && rh > room_c) {
    throw InputError(fmt::format(
        "[path] entry_radius: the {} of radius {:g} mm does not fit {} at ({:.3f}, {:.3f}), "
        "where the tool centre has {:.4g} mm of room; give at most that or 0 (automatic)",
        out.from_hole ? "circle" : "helix", rh,
        out.from_hole ? "about the entry hole" : "in the pocket's widest place", c.x(), c.y(),
        room_c));
  }
  if (rh <= 0) rh = std::min(0.5 * s.R, 0.9 * room_c);
  out.helix_centre = c;
  out.helix_radius = rh;
  // The flat circle at the level: counter-clockwise with the stock on the right.
  const double turn = s.sigma;  // +1 counter-clockwise
  const Vec2 start = c + Vec2(rh, 0);
  const int n_circle = std::max(8, static_cast<int>(std::ceil(kTwoPi * rh / s.step)));
  if (out.from_hole) planner.cut(c);
  for (int k = 0; k <= n_circle; ++k) {
    planner.cut(c + rh * dir(turn * kTwoPi * k / n_circle));
  }
  planner.add_exact(start);
  hold_channels(s, planner, c, channels);
  if (rh > 0) {
    const Vec2 half = c - Vec2(rh, 0);
    out.moves.push_back({Move2::arc_or_line, ContourPiece::arc(start, half, c, turn > 0), true});
    out.moves.push_back({Move2::arc_or_line, ContourPiece::arc(half, start, c, turn > 0), true});
  }
  plan_passes(s, planner, start, out, channels);
  return out;
}

// One run's pieces as moves: at the link feed (air_moves: all but a tooth's advance at each
// end, or at the end the cutting run beside it did not take already) where `air`, else at the
// feed; each piece's end recorded as a point the tool passes.
void add_run_moves(const Settings& s, PartPlanner& planner, const std::vector<ContourPiece>& run,
                   bool air, PartPlan& out, bool head_taken = false, bool tail_taken = false) {
  std::vector<Move2> moves;
  if (air) {
    moves = air_moves(run, head_taken ? 0.0 : s.kernel_step, tail_taken ? 0.0 : s.kernel_step);
  } else {
    for (const ContourPiece& piece : run) moves.push_back({Move2::arc_or_line, piece});
  }
  for (const Move2& m : moves) {
    out.moves.push_back(m);
    planner.add_exact(m.piece.end);
    (m.kind == Move2::air ? out.air_length : out.clearing_length) += m.piece.length_mm();
  }
}

// Moves of a path given as pieces that each cut or not: the runs of pieces that do not cut,
// at least kMinAirRun R long, at the link feed (air_moves), the rest at the feed.
void add_piece_moves(const Settings& s, PartPlanner& planner,
                     const std::vector<ContourPiece>& pieces, const std::vector<bool>& cuts,
                     PartPlan& out) {
  std::size_t i = 0;
  while (i < pieces.size()) {
    std::size_t j = i;
    double len = 0;
    while (j < pieces.size() && cuts[j] == cuts[i]) len += pieces[j++].length_mm();
    // Arcs of one circle joined (a loop's pieces), up to a turn.
    std::vector<ContourPiece> run;
    double sweep = 0;
    for (std::size_t k = i; k < j; ++k) {
      const ContourPiece& q = pieces[k];
      if (!run.empty() && run.back().is_arc() && q.is_arc() && run.back().ccw == q.ccw &&
          (*run.back().centre - *q.centre).norm() <= 1e-12 &&
          sweep + q.length_mm() / q.radius_mm() < kTwoPi - 1e-6) {
        run.back() = ContourPiece::arc(run.back().start, q.end, *q.centre, q.ccw);
        sweep += q.length_mm() / q.radius_mm();
        continue;
      }
      run.push_back(q);
      sweep = q.is_arc() ? q.length_mm() / q.radius_mm() : 0;
    }
    add_run_moves(s, planner, run, !cuts[i] && len >= kMinAirRun * s.R, out);
    i = j;
  }
}

// The passes of a part from p (the helix's end, heading along the circle, or a point the tool
// came down to from above), until the coverage is done; the channels' trochoids as soon as
// one can start (the nearest first), their cells held from the passes until then.
void plan_passes(const Settings& s, PartPlanner& planner, Vec2 p, PartPlan& out,
                 std::vector<Channel>& channels) {
  double psi = s.sigma * 0.5 * kPi;  // the helix circle's tangent at angle 0
  std::optional<Vec2> target;
  if (out.from_above) {
    // Straight for the stock nearest.
    if (const auto next = planner.coverage().nearest_remaining(p)) {
      const Vec2 to = *next - p;
      psi = std::atan2(to.y(), to.x());
      target = *next;
    }
  }
  const double cell = planner.coverage().cell_mm();
  // A pass runs on through cleared area for up to 2R after its last cut, in case it meets
  // stock again (run_pass). Where it did not, that tail is written only if the next pass goes
  // on from its end; a link or a channel elsewhere leaves from the last cut instead (on the
  // example that is 6.3 m of path at the link feed in all, and its lifts' rapids).
  Pass tail;  // the last pass's tail not yet written: from the tool's point to p
  // Arcs and lines through a pass's points within the fit tolerance of them and of the chords
  // between (the planner checked the chords: an arc bulging off them would not be), fitted
  // run by run: the runs through cleared area at least kMinAirRun long go at the link feed,
  // the rest at the feed.
  auto write_pass = [&](const Pass& pass) {
    const std::vector<Run> runs = pass_runs(pass, kMinAirRun * s.R);
    std::vector<std::vector<Vec2>> polys;
    for (const Run& run : runs) {
      polys.emplace_back(pass.points.begin() + static_cast<long>(run.first),
                         pass.points.begin() + static_cast<long>(run.last) + 1);
    }
    // A run through cleared area between two cutting runs gives them its first and last
    // tooth's advance (at the feed, air_moves): each is fitted with the run it ends or starts
    // rather than written as a move of its own (1,666 of the example's 8,970 lines).
    const double edge = s.kernel_step;
    std::vector<char> head_taken(runs.size(), 0), tail_taken(runs.size(), 0);
    for (std::size_t r = 0; r < runs.size(); ++r) {
      const double length = polyline_length(polys[r]);
      if (!runs[r].air || length <= 3 * edge) continue;
      if (r > 0) {
        auto [fed, rest] = split_polyline(polys[r], edge);
        polys[r - 1].push_back(fed.back());
        polys[r] = std::move(rest);
        head_taken[r] = 1;
      }
      if (r + 1 < runs.size()) {
        // (The head given, the run is edge shorter.)
        auto [rest, fed] = split_polyline(polys[r], length - (head_taken[r] ? 2 : 1) * edge);
        polys[r + 1].insert(polys[r + 1].begin(), fed.front());
        polys[r] = std::move(rest);
        tail_taken[r] = 1;
      }
    }
    for (std::size_t r = 0; r < runs.size(); ++r) {
      // A cutting run's arcs may bulge off the chords towards the stock by bulge_mm: they cut
      // that much more than the model has (later steps find less stock than they expect),
      // and engage at most 0.07 degrees more near a 50 degree target (bulge_mm / R sin 50).
      // A run at the link feed keeps to the chords: it must only graze.
      const bool air = runs[r].air;
      add_run_moves(s, planner,
                    fit_polyline(polys[r], s.fit_tolerance, air ? 0.0 : bulge_mm(s.R), s.sigma > 0),
                    air, out, head_taken[r] != 0, tail_taken[r] != 0);
    }
  };
  // The tool's point: p, or the start of the tail not written.
  auto tool = [&]() { return tail.points.empty() ? p : tail.points.front(); };
  // Goes to q at the level where the tool only grazes on the way, else over the stock.
  auto go_to = [&](const Vec2& q) {
    const Vec2 from = tool();
    tail = Pass{};
    if ((q - from).norm() <= 1e-9) {
      p = q;
      return;
    }
    const bool down = planner.link_down(from, q);
    if (!down) {
      // Round what the line meets, through a point the tool passed, where that is shorter than
      // a lift's climb and descent (about 4R at the link feed).
      if (const auto v = planner.link_via(from, q, (q - from).norm() + 4 * s.R)) {
        out.moves.push_back({Move2::link_down, ContourPiece::line(from, *v)});
        out.moves.push_back({Move2::link_down, ContourPiece::line(*v, q)});
        ++out.links_down;
        p = q;
        return;
      }
    }
    out.moves.push_back({down ? Move2::link_down : Move2::lift, ContourPiece::line(from, q)});
    ++(down ? out.links_down : out.lifts);
    p = q;
  };
  // Every channel that can start, the nearest start first; whether one ran.
  auto run_channels = [&]() {
    bool any = false;
    for (;;) {
      std::optional<PartPlanner::Start> best;
      Channel* best_ch = nullptr;
      bool best_forward = true;
      for (Channel& ch : channels) {
        if (ch.done) continue;
        for (const bool forward : {true, false}) {
          const auto st = planner.channel_start(ch, forward);
          if (st && (!best || (st->point - p).norm() < (best->point - p).norm())) {
            best = st;
            best_ch = &ch;
            best_forward = forward;
          }
        }
      }
      if (!best) return any;
      // The start's disc is cleared: the tool may come down there.
      planner.add_exact(best->point);
      go_to(best->point);
      const auto tro = planner.trochoid(*best_ch, best_forward, *best);
      add_piece_moves(s, planner, tro.pieces, tro.cuts, out);
      out.channel_family_mm += tro.family_mm;
      out.channel_loops_mm += tro.loops_mm;
      out.channel_unheld_mm += tro.unheld_mm;
      if (!tro.pieces.empty()) p = tro.pieces.back().end;
      ++out.channels;
      best_ch->done = true;
      // What the loops did not take is the passes' again.
      for (std::size_t k = 0; k + 1 < best_ch->size(); ++k) {
        planner.coverage().release(best_ch->c[k], best_ch->c[k + 1], best_ch->r[k] + s.R);
      }
      target.reset();
      any = true;
    }
  };
  // Where to go on: the remaining stock nearest to here, from the cut centre nearest to it.
  auto go_on = [&]() {
    const auto next = planner.coverage().nearest_remaining(p);
    if (!next) return false;
    go_to(planner.nearest_exact(*next));
    const Vec2 to = *next - p;
    psi = std::atan2(to.y(), to.x());
    target = *next;
    return true;
  };
  if (run_channels() && !go_on()) target.reset();
  // (A guard: each pass gains coverage or gives some up, so the cells bound the count.)
  for (int guard = 0; guard < 10000000; ++guard) {
    if (planner.coverage().remaining() == 0) {
      // The channels that can start now, then the passes for what they left; else the
      // cells held for channels that never could start are given up.
      if (run_channels() && go_on()) continue;
      if (planner.coverage().held() > 0) {
        // No channel can start (the passes did not clear where one would): their cells are the
        // passes' (which may clear a channel's end, and a trochoid start there after all).
        planner.coverage().release(Vec2::Zero(), Vec2::Zero(), -1);
        if (go_on()) continue;
      }
      for (Channel& ch : channels) {
        if (ch.done) continue;
        ch.done = true;
        out.channels_left_mm2 += ch.band_mm2(s.R);
      }
      break;
    }
    const long before = planner.coverage().remaining();
    if (tail.points.size() >= 2) write_pass(tail);  // this pass goes on from the tail's end
    tail = Pass{};
    Pass pass = planner.run_pass(p, psi, target);
    const long gained = before - planner.coverage().remaining();
    if (pass.points.size() >= 2) {
      // Up to the last cutting step now; the steps after it wait as the tail.
      std::size_t last = 0;
      for (std::size_t i = 0; i < pass.points.size(); ++i) {
        if (pass.cuts[i]) last = i;
      }
      if (last + 1 < pass.points.size()) {
        tail.points.assign(pass.points.begin() + static_cast<long>(last), pass.points.end());
        tail.cuts.assign(pass.cuts.begin() + static_cast<long>(last), pass.cuts.end());
        tail.cuts.front() = false;
        pass.points.resize(last + 1);
        pass.cuts.resize(last + 1);
      }
      if (pass.points.size() >= 2) write_pass(pass);
      ++out.passes;
      p = tail.points.empty() ? pass.points.back() : tail.points.back();
    }
    if (run_channels()) {
      go_on();  // where nothing remains, the top of the loop decides
      continue;
    }
    if (!planner.coverage().nearest_remaining(p)) continue;
    if (gained < 2 && target) {
      // The last pass made for this stock and took (almost) none: it is out of reach at the
      // target (an inside corner's last material): left to the finishing pass.
      planner.coverage().give_up(*target, 0.5 * s.R);
      target.reset();
      continue;
    }
    go_on();
  }
  out.planned_max_deg = planner.planned_max_deg();
  out.given_up_mm2 = static_cast<double>(planner.coverage().given_up()) * cell * cell;
}

// [pocket] rest_of read: its moves at constant heights below the stock's top, by height, as
// chains of plan-view pieces (arcs exact, other curves as chords within 0.5 um).
RestStock read_rest(const Job& job) {
  const Pocket& pk = job.pocket;
  const std::string name = pk.rest_of;
  GcodeReadOptions ro = gcode_options(job.machine).read;
  GcodeProgram prog;
  try {
    prog = read_gcode_file(pk.rest_of_path, ro);
  } catch (const InputError& e) {
    throw InputError(fmt::format("[pocket] rest_of = \"{}\": {}", name, e.what()));
  }
  // One earlier tool: moves of several, each taken as the one of rest_tool_diameter, would
  // count a smaller tool's as the larger's sweep (stock left in the model as gone).
  for (const auto& [t, at] : prog.info.tool_changes) {
    if (t != prog.info.tool_changes.front().first) {
      throw InputError(fmt::format(
          "[pocket] rest_of = \"{}\": the program changes tools (T{} at {}, T{} at {}): rest "
          "machining follows one earlier tool; give a program of one tool",
          name, prog.info.tool_changes.front().first, prog.info.tool_changes.front().second, t,
          at));
    }
  }
  RestStock rest;
  rest.name = name;
  double d = pk.rest_tool_diameter_mm;
  if (!(d > 0)) {
    for (const auto& [key, value] : prog.info.header_keys) {
      if (key != "tool.diameter") continue;
      char* end = nullptr;
      d = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != '\0' || !std::isfinite(d) || !(d > 0)) {
        throw InputError(fmt::format(
            "[pocket] rest_of = \"{}\": its header's tool.diameter = {} is no diameter (a "
            "number > 0, mm): give [pocket] rest_tool_diameter",
            name, value));
      }
    }
  }
  if (!(d > 0)) {
    throw InputError(fmt::format(
        "[pocket] rest_tool_diameter: give the diameter (mm) of rest_of's tool: \"{}\" has no "
        "trochomill header naming it (tool.diameter)",
        name));
  }
  if (d > 1000) {  // as [pocket] rest_tool_diameter allows
    throw InputError(fmt::format(
        "[pocket] rest_of = \"{}\": its tool diameter {:g} mm is above 1000 mm; give [pocket] "
        "rest_tool_diameter",
        name, d));
  }
  if (d < job.tool.diameter_mm * (1 - 1e-12)) {
    throw InputError(fmt::format(
        "[pocket] rest_tool_diameter: rest_of's tool (D = {:g} mm) is smaller than this job's "
        "(D = {:g} mm): rest machining follows a larger tool",
        d, job.tool.diameter_mm));
  }
  rest.tool_radius_mm = 0.5 * d;
  const double top = stock_top_mm(job, nullptr);
  const Segment* prev = nullptr;
  for (const Segment& g : prog.path.segments()) {
    const Vec3 a = g.start(), b = g.end();
    const bool flat = std::abs(a.z() - b.z()) <= kLevelTolMm && g.is_flat_xy() &&
                      a.z() < top - kLevelTolMm && g.length_mm() > 0;
    if (!flat) {
      prev = nullptr;
      continue;
    }
    auto level = std::find_if(rest.levels.begin(), rest.levels.end(), [&](const auto& l) {
      return std::abs(l.z_mm - a.z()) <= kLevelTolMm;
    });
    if (level == rest.levels.end()) {
      rest.levels.push_back({a.z(), {}});
      level = rest.levels.end() - 1;
    }
    const bool joins = prev != nullptr && !level->chains.empty() &&
                       std::abs(prev->end().z() - a.z()) <= kLevelTolMm &&
                       (level->chains.back().pieces.back().end - Vec2(a.x(), a.y())).norm() <= 1e-9;
    if (!joins) level->chains.emplace_back();
    Contour& chain = level->chains.back();
    auto add = [&](const ContourPiece& piece) {
      if (!chain.pieces.empty()) {
        ContourPiece q = piece;
        q.start = chain.pieces.back().end;  // exactly joined
        chain.pieces.push_back(q);
      } else {
        chain.pieces.push_back(piece);
      }
    };
    const Vec2 a2(a.x(), a.y()), b2(b.x(), b.y());
    if (g.kind() == Segment::Kind::line) {
      add(ContourPiece::line(a2, b2));
    } else if (g.is_circular()) {
      // Halves at most: an arc's ends and centre fix it up to a half turn.
      const Vec2 c(g.center().x(), g.center().y());
      const Vec3 t = g.derivative_u(g.u0()) * (g.u1() >= g.u0() ? 1.0 : -1.0);
      const bool ccw = cross2(a2 - c, Vec2(t.x(), t.y())) > 0;
      const int n = std::abs(g.u1() - g.u0()) > 0.9 * kPi ? 2 : 1;
      Vec2 from = a2;
      for (int k = 1; k <= n; ++k) {
        const Vec3 q = g.point_u(g.u0() + (g.u1() - g.u0()) * k / n);
        const Vec2 to = k == n ? b2 : Vec2(q.x(), q.y());
        add(ContourPiece::arc(from, to, c, ccw));
        from = to;
      }
    } else {
      const int n = std::max(1, static_cast<int>(std::ceil(g.length_mm() / 0.05)));
      Vec2 from = a2;
      for (int k = 1; k <= n; ++k) {
        const Vec3 q = g.point_at(g.length_mm() * k / n);
        const Vec2 to = k == n ? b2 : Vec2(q.x(), q.y());
        add(ContourPiece::line(from, to));
        from = to;
      }
    }
    prev = &g;
  }
  if (rest.levels.empty()) {
    throw InputError(fmt::format(
        "[pocket] rest_of = \"{}\": the program never moves across at a constant height below "
        "the stock's top (z = {:g} mm): it removed nothing to rest-machine after",
        name, top));
  }
  std::sort(rest.levels.begin(), rest.levels.end(),
            [](const auto& x, const auto& y) { return x.z_mm < y.z_mm; });
  rest.path = std::move(prog.path);
  return rest;
}

// The planner's step along the path (mm): 0.1 R within 0.05 to 1 mm.
double pocket_step_mm(double R) { return std::clamp(0.1 * R, 0.05, 1.0); }

// The pocket's depth levels: equal, each at most max_step_down deep (one without it).
int pocket_levels(const Pocket& pk) {
  return pk.max_step_down_mm > 0
             ? std::max(1, static_cast<int>(std::ceil(pk.depth_mm / pk.max_step_down_mm - 1e-9)))
             : 1;
}

// The region of the pocket: its boundaries and islands (even-odd).
std::vector<Contour> pocket_region(const Pocket& pk) {
  std::vector<Contour> region;
  for (const DrawnContour& c : *pk.boundary_contours) region.push_back(c.contour);
  if (pk.island_contours) {
    for (const DrawnContour& c : *pk.island_contours) region.push_back(c.contour);
  }
  return region;
}

Vec2 mean_vertex(const Contour& c) {
  Vec2 m = Vec2::Zero();
  for (const ContourPiece& p : c.pieces) m += p.start;
  return c.pieces.empty() ? m : Vec2(m / static_cast<double>(c.pieces.size()));
}

}  // namespace

namespace {

// The [stock] box against the pocket, once before planning: its top above z = 0
// (check_stock_top), and a box that leaves nothing of the pocket to cut (in the wrong place,
// in another frame than the drawing's, over an island only, below the floor), for which the
// program would be a finishing pass through the air. (A box over only the walls' stock to
// leave is the finishing pass's: not refused.)
void check_pocket_stock(const Job& job) {
  check_stock_top(job);
  if (!job.stock_min_mm || !job.stock_max_mm) return;
  const Pocket& pk = job.pocket;
  const Vec3& a = *job.stock_min_mm;
  const Vec3& b = *job.stock_max_mm;
  const bool mesh = job.stock_mesh != nullptr;
  if (b.z() <= -pk.depth_mm) {
    throw InputError(fmt::format(
        "{}: [stock] {}: the {}'s top z = {:g} mm is at or below the pocket's floor z = {:g} mm: "
        "nothing to cut; give the {} in the drawing's frame (its top at z = 0) or no [stock]",
        job.source, mesh ? "mesh" : "max", mesh ? "mesh" : "box", b.z(), -pk.depth_mm,
        mesh ? "mesh" : "box"));
  }
  const std::vector<Contour> region = pocket_region(pk);
  // Where the stock stands above the floor. 1e-6 mm^2: Clipper's rounding of an empty overlap.
  if (region_area_mm2(region_intersection(region, stock_plan(job, -pk.depth_mm), kClipperTol)) <=
      1e-6) {
    const Box3 box = vertex_box(region);
    const std::string what =
        mesh ? fmt::format(
                   "the mesh '{}' (x {:.4g} .. {:.4g}, y {:.4g} .. {:.4g} mm, above the "
                   "floor z = {:g} mm)",
                   job.stock_mesh_file, a.x(), b.x(), a.y(), b.y(), -pk.depth_mm)
             : fmt::format("the box ({:g}, {:g}) .. ({:g}, {:g}) mm", a.x(), a.y(), b.x(), b.y());
    throw InputError(fmt::format(
        "{}: [stock] {}: {} leaves none of the pocket of layer '{}' (x {:.4g} .. {:.4g}, y "
        "{:.4g} .. {:.4g} mm, less its islands) to cut: give {} over the pocket, in the "
        "drawing's frame, or no [stock]",
        job.source, mesh ? "mesh" : "min, max", what, pk.boundary, box.lo.x(), box.hi.x(),
        box.lo.y(), box.hi.y(), mesh ? "a stock" : "a box"));
  }
}

// The pocket planned with the steps' aim `margin_deg` below the target.
PlannedPocket plan_pocket_at(const Job& job, double margin_deg) {
  const Pocket& pk = job.pocket;
  if (!pk.defined()) throw Error("plan_pocket: the job has no [pocket]");
  const double R = job.tool.radius_mm();
  const double feed = feed_rate_mm_per_min(job);
  if (!(feed > 0)) throw InputError("[cutting]: the feed rate must be > 0 mm/min");
  const double entry_feed =
      job.path.entry_feed_mm_per_min > 0 ? job.path.entry_feed_mm_per_min : 0.5 * feed;
  const double rapid = job.machine.rapid_rate_mm_per_min;
  const double safe_z = job.machine.safe_z_mm, clearance = job.path.clearance_mm;
  const double stl = pk.stock_to_leave_mm;
  const std::vector<Contour> region = pocket_region(pk);
  // The tool centre's region, kept the fit's largest deviation (its tolerance, or an arc's
  // bulge towards the stock) and three times Clipper's chords (the offset, the corners'
  // rounding twice) further in, so that the fitted arcs stay R + stock from every wall and
  // island.
  const double keep = R + stl + std::max(pk.fit_tolerance_mm, bulge_mm(R)) + 3 * kClipperTol;
  // Its convex corners rounded (the region shrunk by rc more, then grown back by rc): the
  // clearing stays out of the sharp corners, where no path holds the target (the last tool
  // position in a corner of angle alpha touches both walls: its arc in the stock is
  // 180 - alpha degrees); their material is the finishing pass's (docs/models.md, "Pockets").
  const double rc = 0.25 * R;
  std::vector<Contour> centre_region = offset_region(region, -(keep + rc), kClipperTol);
  if (!centre_region.empty() && rc > 0)
    centre_region = offset_region(centre_region, rc, kClipperTol);
  // Unrounded: the channels' loops reach its walls (and its parts narrower than 2 rc, which
  // the rounding leaves out).
  const std::vector<Contour> centre_region0 = offset_region(region, -keep, kClipperTol);
  if (centre_region0.empty()) {
    throw InputError(fmt::format(
        "[pocket] boundary: the tool (D = {:g} mm) with stock_to_leave = {:g} mm fits nowhere in "
        "layer '{}' (the pocket is narrower than D + 2 stock everywhere)",
        job.tool.diameter_mm, stl, pk.boundary));
  }
  // Links that stay down, and the passes' runs through cleared area, only graze the stock
  // (Settings::graze_deg): fed at the link feed, as a curved slot's.
  const double link_feed = link_feed_mm_per_min(job.machine);
  Settings s;
  s.R = R;
  s.step = pocket_step_mm(R);
  // Margin: the kernel samples every tooth at its own phase, on the fitted arcs (within the fit
  // tolerance of the planner's chords); see kAimMargin.
  s.aim_deg = std::max(0.5 * pk.max_engagement_deg, pk.max_engagement_deg - margin_deg);
  s.kernel_step = std::max(1e-4, job.cutting.feed_per_tooth_mm);
  s.air_tooth = s.kernel_step * std::max(1.0, link_feed / feed);
  s.graze_deg = rad_to_deg(2 * std::acos(1 - s.kernel_step * s.kernel_step / (4 * R * R)));
  const bool mirror = (job.path.direction == Direction::conventional) !=
                      (job.cutting.spindle_direction == SpindleDirection::ccw);
  s.sigma = mirror ? -1.0 : 1.0;
  s.fit_tolerance = pk.fit_tolerance_mm;
  if (pk.channel_family) {
    s.family = *pk.channel_family;
    s.aspect = job.path.aspect_ratio;
    s.linear_mm = job.path.linear_distance_mm;
  }

  PlannedPocket out;
  PocketInfo& info = out.info;
  info.target_engagement_deg = pk.max_engagement_deg;
  info.tooth_advance_share = job.cutting.feed_per_tooth_mm / R;
  // The channels: narrower than [pocket] channel_width (2 D where 0).
  const double channel_width = pk.channel_width_mm > 0 ? pk.channel_width_mm : 4 * R;
  info.channel_width_mm = channel_width;
  if (pk.channel_family) info.channel_family = std::string(to_string(*pk.channel_family));
  std::vector<Channel> channels =
      trochoid_channels(centre_region0, centre_region, R, 0.5 * channel_width - keep);
  // The parts: the rounded region's, those a channel joins (its loops run from one into the
  // other) as one; a part of the unrounded region that holds none of them (a pocket that is
  // all narrow channel) is one itself. A part the rounded region has that no channel reaches
  // stays a part of its own (entered by its own helix), though a channel too narrow for loops
  // may join it to another in the unrounded region.
  std::vector<std::vector<Contour>> parts;
  std::vector<std::vector<Channel>> channels_of;
  {
    const auto rounded_parts = region_parts(centre_region);
    const std::size_t n = rounded_parts.size();
    std::vector<std::size_t> root(n);
    for (std::size_t i = 0; i < n; ++i) root[i] = i;
    const auto find = [&](std::size_t i) {
      while (root[i] != i) i = root[i] = root[root[i]];
      return i;
    };
    const auto part_of = [&](const Vec2& q) {
      for (std::size_t i = 0; i < n; ++i) {
        if (region_contains(rounded_parts[i], q)) return i;
      }
      return n;
    };
    // Each channel's parts: those holding a point beyond its open ends or its middle.
    std::vector<std::vector<std::size_t>> touched(channels.size());
    for (std::size_t c = 0; c < channels.size(); ++c) {
      std::vector<Vec2> at = channels[c].beyond;
      at.push_back(channels[c].c[channels[c].size() / 2]);
      for (const Vec2& q : at) {
        const std::size_t k = part_of(q);
        if (k < n) touched[c].push_back(k);
      }
      for (std::size_t k = 1; k < touched[c].size(); ++k) {
        root[find(touched[c][k])] = find(touched[c][0]);
      }
    }
    std::vector<std::size_t> group_of(n, n);  // rounded part's root -> index in parts
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t r = find(i);
      if (group_of[r] == n) {
        group_of[r] = parts.size();
        parts.emplace_back();
        channels_of.emplace_back();
      }
      parts[group_of[r]].insert(parts[group_of[r]].end(), rounded_parts[i].begin(),
                                rounded_parts[i].end());
    }
    const auto parts0 = region_parts(centre_region0);
    std::vector<std::size_t> thin_part(parts0.size(), 0);  // parts index + 1 of one holding none
    for (std::size_t c = 0; c < channels.size(); ++c) {
      if (!touched[c].empty()) {
        channels_of[group_of[find(touched[c][0])]].push_back(channels[c]);
        continue;
      }
      // In a part of the unrounded region: its rounded parts' group (the nearest by the
      // channel's middle), else the part itself.
      const Vec2 mid = channels[c].c[channels[c].size() / 2];
      for (std::size_t q = 0; q < parts0.size(); ++q) {
        if (!region_contains(parts0[q], mid)) continue;
        std::size_t best = n;
        double best_d = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < n; ++i) {
          if (!region_contains(parts0[q], rounded_parts[i].front().pieces.front().start)) continue;
          double d = std::numeric_limits<double>::infinity();
          for (const Contour& k : rounded_parts[i]) d = std::min(d, k.distance_mm(mid));
          if (d < best_d) {
            best_d = d;
            best = i;
          }
        }
        if (best < n) {
          channels_of[group_of[find(best)]].push_back(channels[c]);
        } else {
          if (thin_part[q] == 0) {
            parts.push_back(parts0[q]);
            channels_of.emplace_back();
            thin_part[q] = parts.size();
          }
          channels_of[thin_part[q] - 1].push_back(channels[c]);
        }
        break;
      }
    }
  }
  // Pre-drilled holes: each where the tool centre may go, given to the part holding it.
  std::vector<std::vector<Vec2>> holes_of(parts.size());
  for (std::size_t i = 0; i < pk.entry_holes_mm.size(); ++i) {
    const Vec2& h = pk.entry_holes_mm[i];
    std::size_t j = 0;
    while (j < parts.size() && !region_contains(parts[j], h)) ++j;
    if (j == parts.size()) {
      // Why, the first reason that applies.
      std::string why;
      double wall = std::numeric_limits<double>::infinity();
      for (const Contour& c : region) wall = std::min(wall, c.distance_mm(h));
      std::vector<Contour> walls;
      for (const DrawnContour& b : *pk.boundary_contours) walls.push_back(b.contour);
      bool in_some = false;  // inside one of the boundary's contours (a nested one's hole)
      for (const Contour& w : walls) in_some = in_some || region_contains({w}, h);
      if (!in_some) {
        why = fmt::format("outside the boundary (layer '{}')", pk.boundary);
      } else if (!region_contains(walls, h)) {
        why = fmt::format(
            "in a hole of the boundary (a contour of layer '{}' nested in another: "
            "an island)",
            pk.boundary);
      } else if (!region_contains(region, h)) {
        why = fmt::format("in an island (layer '{}')", pk.islands);
      } else if (wall < keep) {
        why = fmt::format(
            "{:.4g} mm from a wall or island, within R + stock_to_leave + {:g} = {:.4g} mm (the "
            "tool would cut the wall going down it)",
            wall, keep - R - stl, keep);
      } else {
        why = fmt::format(
            "in a corner the clearing rounds off (by R / 4 = {:g} mm beyond R + stock_to_leave + "
            "{:g} = {:.4g} mm from the walls: the finishing pass's)",
            rc, keep - R - stl, keep);
      }
      throw InputError(fmt::format(
          "{}: [pocket] entry_holes: hole {} (counting from 1) at ({:g}, {:g}) mm is where the "
          "tool centre may not go: {}; give a hole where the tool's disc clears every wall and "
          "island by stock_to_leave",
          job.source, i + 1, h.x(), h.y(), why));
    }
    holes_of[j].push_back(h);
  }
  // The air beside the stock: a [stock] box the pocket runs past (the same at every level), or
  // a stock mesh's, level by level.
  const Box3 centre_box = vertex_box(centre_region.empty() ? centre_region0 : centre_region);
  auto air_at = [&](double z) {
    return air_discs(stock_plan(job, z), R, rest_spacing_mm(job),
                     Vec2(centre_box.lo.x(), centre_box.lo.y()),
                     Vec2(centre_box.hi.x(), centre_box.hi.y()));
  };
  const double depth = pk.depth_mm;
  const int levels = pocket_levels(pk);
  // Rest machining: what the earlier program removed at each level. Levels where its removed
  // region and the air are the same (the same discs) share one plan; a plan per level
  // otherwise.
  std::shared_ptr<const RestStock> rest = pk.rest;
  if (!pk.rest_of.empty() && !rest) rest = std::make_shared<const RestStock>(read_rest(job));
  std::vector<std::size_t> plan_of(static_cast<std::size_t>(levels), 0);  // per level
  std::vector<std::vector<PartPlan>> plans;
  std::vector<Vec2> before_last, air_last;  // the last plan's
  const auto same_discs = [](const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
    return a.size() == b.size() &&
           std::equal(a.begin(), a.end(), b.begin(),
                      [](const Vec2& p, const Vec2& q) { return (p - q).norm() <= 1e-9; });
  };
  const bool by_level = rest || job.stock_mesh;
  std::vector<Vec2> air = by_level ? std::vector<Vec2>{} : air_at(0.0);
  for (int k = 1; k <= levels; ++k) {
    const double z = -depth * k / levels;
    std::vector<Vec2> before;
    if (by_level) {
      if (rest) before = rest_disc_centres(*rest, z, R, rest_spacing_mm(job));
      if (job.stock_mesh) air = air_at(z);
      if (k > 1 && same_discs(before, before_last) && same_discs(air, air_last)) {
        plan_of[static_cast<std::size_t>(k - 1)] = plans.size() - 1;
        continue;
      }
      before_last = before;
      air_last = air;
    } else if (k > 1) {
      continue;  // one plan for every level
    }
    plan_of[static_cast<std::size_t>(k - 1)] = plans.size();
    plans.emplace_back();
    for (std::size_t j = 0; j < parts.size(); ++j) {
      plans.back().push_back(plan_part(job, s, parts[j], before, air, holes_of[j], channels_of[j]));
    }
  }
  // The figures of a level: the deepest's plan (every level's without rest_of).
  for (const PartPlan& pp : plans.back()) {
    info.passes += pp.passes;
    info.links_down += pp.links_down;
    info.lifts += pp.lifts;
    info.clearing_length_mm += pp.clearing_length;
    info.air_length_mm += pp.air_length;
    info.left_for_finish_mm2 += pp.given_up_mm2;
    info.rest_cleared_mm2 += pp.rest_cleared_mm2;
    info.open_mm2 += pp.open_mm2;
    info.channels += pp.channels;
    info.channels_left_mm2 += pp.channels_left_mm2;
    info.channel_family_mm += pp.channel_family_mm;
    info.channel_loops_mm += pp.channel_loops_mm;
    info.channel_unheld_mm += pp.channel_unheld_mm;
    if (pp.nothing) continue;
    ++(pp.from_hole ? info.hole_entries : pp.from_above ? info.open_entries : info.helix_entries);
  }
  for (const auto& level : plans) {
    for (const PartPlan& pp : level) {
      info.planned_max_engagement_deg =
          std::max(info.planned_max_engagement_deg, pp.planned_max_deg);
    }
  }
  if (job.stock_mesh) {
    for (int k = 0; k < levels; ++k) {
      double a = 0;
      for (const PartPlan& pp : plans[plan_of[static_cast<std::size_t>(k)]]) a += pp.open_mm2;
      info.open_mm2_by_level.push_back(a);
    }
  }
  info.plans = static_cast<int>(plans.size());
  for (const std::size_t k : plan_of) {
    int passes = 0;
    double clearing = 0, rest_cleared = 0;
    for (const PartPlan& pp : plans[k]) {
      passes += pp.passes;
      clearing += pp.clearing_length;
      rest_cleared += pp.rest_cleared_mm2;
    }
    info.passes_by_level.push_back(passes);
    info.clearing_length_by_level_mm.push_back(clearing);
    if (rest) info.rest_cleared_by_level_mm2.push_back(rest_cleared);
  }
  if (rest) info.rest_tool_diameter_mm = 2 * rest->tool_radius_mm;
  info.parts = static_cast<int>(parts.size());

  // The parts of the tool centre's region too narrow for a channel's loops (narrower than
  // 2 R / 20, as trochoid_channels): what an opening by R / 20 takes off it, where longer than
  // R / 2 (not a corner's tip). The pocket there is about that long and D + 2 stock wide.
  std::vector<Vec2> slot_points;  // the outlines of those parts (the finishing pass slots there)
  {
    const double r_min = 0.05 * R;
    // (Grown by Clipper's chords three times more: the slivers between its chords and the
    // region's are no part.)
    const auto opened = offset_region(offset_region(centre_region0, -r_min, kClipperTol),
                                      r_min + 3 * kClipperTol, kClipperTol);
    for (const auto& part : region_parts(region_difference(centre_region0, opened, kClipperTol))) {
      double perimeter = 0;
      for (const Contour& c : part) perimeter += c.length_mm();
      if (0.5 * perimeter > 0.5 * R) {
        info.slotted.push_back({0.5 * perimeter * 2 * (R + stl), mean_vertex(part.front())});
        for (const Contour& c : part) {
          for (const Vec2& v : c.points(kClipperTol)) slot_points.push_back(v);
        }
      }
    }
  }
  // What no tool centre in the region reaches: the pocket less the region grown back.
  {
    const auto reach = offset_region(region, -keep, kClipperTol);
    const auto swept = offset_region(reach, keep, kClipperTol);
    const auto left = region_difference(region, swept, kClipperTol);
    const double cusp = 1.5 * (1 - kPi / 4) * keep * keep;
    for (const auto& part : region_parts(left)) {
      const double a = region_area_mm2(part);
      if (a > cusp) {
        info.unreachable.push_back({a, mean_vertex(part.front())});
      } else {
        info.cusps_mm2 += a;
      }
    }
  }

  // Levels of equal depth.
  info.levels = levels;
  ToolPath& path = out.path;
  auto at = [](const Vec2& p, double z) { return Vec3(p.x(), p.y(), z); };
  auto here = [&]() { return path.segments().back().end(); };
  auto line_to = [&](const Vec3& b, Motion m, double speed) {
    const Vec3 a = here();
    if ((b - a).norm() > 1e-12) path.append(Segment::line(a, b, m, speed));
  };
  auto piece_at = [&](const ContourPiece& p, double z0, double z1, Motion m, double speed) {
    if (!p.is_arc()) {
      path.append(Segment::line(at(p.start, z0), at(p.end, z1), m, speed));
      return;
    }
    const Vec2 c = *p.centre;
    const double a0 = std::atan2(p.start.y() - c.y(), p.start.x() - c.x());
    path.append(Segment::arc_xy(c.x(), c.y(), p.radius_mm(), a0, p.sweep_rad(), z0, z1, m, speed));
  };
  // Goes to p at height z from anywhere: up to the safe plane, across, down to z_clear, then
  // at the entry feed to z.
  auto travel = [&](const Vec2& p, double z_clear, double z) {
    if (path.empty()) {
      path.append(Segment::line(at(p, safe_z), at(p, z_clear), Motion::rapid, rapid));
    } else {
      const Vec3 h = here();
      line_to(Vec3(h.x(), h.y(), std::max(h.z(), safe_z)), Motion::rapid, rapid);
      line_to(at(p, safe_z), Motion::rapid, rapid);
      line_to(at(p, z_clear), Motion::rapid, rapid);
    }
    line_to(at(p, z), Motion::feed, entry_feed);
  };
  const double pitch = std::max(1e-3, job.path.entry_pitch_mm);
  for (int k = 1; k <= levels; ++k) {
    const double z_prev = k == 1 ? 0.0 : -depth * (k - 1) / levels;
    const double z = -depth * k / levels;
    const std::size_t plan = plan_of[static_cast<std::size_t>(k - 1)];
    for (std::size_t part = 0; part < plans[plan].size(); ++part) {
      const PartPlan& pp = plans[plan][part];
      // How low the tool may come down fast at p before this level's move there: to `below`
      // (this level, at a relink point the tool centre passed exactly at this level; the level
      // above, for an entry) where every level above cleared the tool's disc at p (one running
      // this level's plan passed p exactly too; another's plan holds the disc in its removed
      // region: cut, or nothing there), else only to the top of the highest level that did not
      // (its stock stands there).
      const auto clear_down_to = [&](const Vec2& p, double below) {
        for (int i = 1; i < k; ++i) {
          const std::size_t q = plan_of[static_cast<std::size_t>(i - 1)];
          if (q != plan && !plans[q][part].planner->disc_cleared(p)) {
            return i == 1 ? 0.0 : -depth * (i - 1) / levels;
          }
        }
        return below;
      };
      if (pp.nothing) continue;
      const Vec2 c = pp.helix_centre;
      const double rh = pp.helix_radius;
      const Vec2 start = c + Vec2(rh, 0);
      const std::size_t first = path.segments().size();
      if (pp.from_above) {
        // The earlier program cleared the tool's disc here down to this level: in from above.
        travel(start, z + clearance, z);
      } else if (pp.from_hole) {
        // Down the hole, then out to the circle.
        travel(c, z_prev + clearance, z_prev + (k == 1 ? clearance : 0.0));
        line_to(at(c, z), Motion::feed, entry_feed);
        line_to(at(start, z), Motion::feed, entry_feed);
      } else {
        // The helix starts at the top of the stock above it: the level above's, or higher
        // where a level above left stock there (its plan another than this one's).
        const double top = clear_down_to(start, z_prev);
        travel(start, top + clearance, top + (top == 0.0 ? clearance : 0.0));
      }
      // The helix down to z: whole turns at the pitch or less, and on a circle narrower than
      // R / 2 (a part with little room) at a drop a turn that keeps it no steeper than a
      // helix of radius R / 2 at the pitch, the descent the finishing pass's ramps keep too.
      const double drop = here().z() - z;
      if (!pp.from_above && !pp.from_hole && rh > 0) {
        const double per_turn = pitch * std::min(1.0, 2 * rh / R);
        const int turns = std::max(1, static_cast<int>(std::ceil(drop / per_turn - 1e-9)));
        for (int t = 0; t < turns; ++t) {
          const double za = here().z(), zb = za - drop / turns;
          path.append(Segment::arc_xy(c.x(), c.y(), rh, 0.0, s.sigma * kTwoPi, za, zb, Motion::feed,
                                      entry_feed));
        }
      } else if (!pp.from_above && !pp.from_hole) {
        line_to(at(start, z), Motion::feed, entry_feed);
      }
      std::size_t entry_end = path.segments().size();
      for (std::size_t i = 0; i < pp.moves.size(); ++i) {
        const Move2& m = pp.moves[i];
        switch (m.kind) {
          case Move2::arc_or_line:
            piece_at(m.piece, z, z, Motion::feed, feed);
            break;
          case Move2::air:
            info.air_segments.push_back(path.segments().size());
            piece_at(m.piece, z, z, Motion::feed, link_feed);
            break;
          case Move2::link_down: {
            // Its first and last tooth's advance at the feed, as a pass's runs through cleared
            // area (air_moves).
            for (const Move2& e : air_moves({m.piece}, s.kernel_step, s.kernel_step)) {
              if (e.kind == Move2::air) info.air_segments.push_back(path.segments().size());
              line_to(at(e.piece.end, z), Motion::feed, e.kind == Move2::air ? link_feed : feed);
            }
            break;
          }
          case Move2::lift:
            // A relink point is one the tool centre passed exactly at this level (and so at
            // every level above): its cylinder is cut down to z, so the rapid goes down to
            // the clearance above z.
            travel(m.piece.end, clear_down_to(m.piece.end, z) + clearance, z);
            break;
        }
        if (m.entry) entry_end = path.segments().size();  // the helix's flat circle
      }
      info.entries.emplace_back(first, entry_end);
    }
  }

  // The finishing pass: along the walls and islands at full depth, climb or conventional,
  // entered and left by quarter arcs from the cleared area.
  info.finish_first_segment = path.segments().size();
  if (pk.finish_pass) {
    const double z = -depth;
    const double margin = 2 * kClipperTol;  // the chords and the fit, inside the walls' offset
    auto finish = offset_region(region, -(R + margin), kClipperTol);
    // Cleared: where the passes went (the rounded centre region: where it is empty, no pass
    // went anywhere, and a part only the unrounded region holds was never cleared), or within
    // a channel's loops (the disc of a sample's clearance).
    const RegionGrid cleared(centre_region, std::max(0.25, 0.25 * R));
    const auto is_cleared = [&](const Vec2& q) {
      if (cleared.contains(q)) return true;
      for (const Channel& ch : channels) {
        for (std::size_t k = 0; k < ch.size(); ++k) {
          if ((q - ch.c[k]).squaredNorm() < ch.r[k] * ch.r[k]) return true;
        }
      }
      return false;
    };
    for (Contour& c : finish) {
      if (mirror) c = c.reversed();
      std::vector<Vec2> pts = c.points(kClipperTol);
      if (pts.size() < 3) continue;
      // Start in the middle of an edge (away from corners), the longest whose lead arcs (below)
      // start and end in the cleared region; else the longest.
      std::vector<std::size_t> order(pts.size());
      for (std::size_t i = 0; i < pts.size(); ++i) order[i] = i;
      const auto edge_len = [&](std::size_t i) {
        return (pts[(i + 1) % pts.size()] - pts[i]).norm();
      };
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t x, std::size_t y) { return edge_len(x) > edge_len(y); });
      // The 16 longest: a contour of many short chords (arcs) does not test them all against
      // every channel sample.
      order.resize(std::min<std::size_t>(order.size(), 16));
      // The cleared side: the left for a counter-clockwise (stock on the right) run.
      const double side = mirror ? -1.0 : 1.0;
      std::size_t best = order.front();
      double rl = 0;
      std::optional<Vec2> lead;
      for (const std::size_t i : order) {
        const Vec2 ea = pts[i], eb = pts[(i + 1) % pts.size()];
        const Vec2 S0 = 0.5 * (ea + eb), t0 = (eb - ea).normalized();
        const Vec2 n0 = side * Vec2(-t0.y(), t0.x());
        // The largest lead radius (from R/2 + stock down, by 0.7) whose arcs start and end in
        // the cleared region.
        double r = std::max(stl + 0.5 * R, 0.25 * R);
        for (int tries = 0; tries < 12; ++tries) {
          const Vec2 cl = S0 + n0 * r;
          if (is_cleared(cl - t0 * r) && is_cleared(cl + t0 * r)) {
            lead = cl;
            break;
          }
          r *= 0.7;
        }
        if (lead) {
          best = i;
          rl = r;
          break;
        }
      }
      const Vec2 a = pts[best], b = pts[(best + 1) % pts.size()];
      const Vec2 S = 0.5 * (a + b), t = (b - a).normalized();
      std::vector<Vec2> loop{S};
      for (std::size_t k = 1; k <= pts.size(); ++k) loop.push_back(pts[(best + k) % pts.size()]);
      loop.push_back(S);
      const std::size_t first = path.segments().size();
      // A contour through a part barely wider than the tool slots it: there, at every level
      // (max_step_down), not at full depth alone.
      bool slots = false;
      for (std::size_t i = 0; i < pts.size() && !slots; ++i) {
        for (const Vec2& v : slot_points) {
          if ((pts[i] - v).squaredNorm() <= std::pow(stl + 0.1 * R, 2)) {
            slots = true;
            break;
          }
        }
      }
      if (lead) {
        const Vec2 cl = *lead;
        const Vec2 p0 = cl - t * rl, p1 = cl + t * rl;
        for (int k = slots ? 1 : levels; k <= levels; ++k) {
          const double z_k = -depth * k / levels;
          const std::size_t start = path.segments().size();
          travel(p0, clearance, z_k);
          piece_at(ContourPiece::arc(p0, S, cl, side > 0), z_k, z_k, Motion::feed, feed);
          info.entries.emplace_back(k == (slots ? 1 : levels) ? first : start,
                                    path.segments().size());
          for (const ContourPiece& p : fit_polyline(loop, kClipperTol)) {
            piece_at(p, z_k, z_k, Motion::feed, feed);
          }
          piece_at(ContourPiece::arc(S, p1, cl, side > 0), z_k, z_k, Motion::feed, feed);
        }
      } else if (is_cleared(S)) {
        travel(S, clearance, z);
        info.entries.emplace_back(first, path.segments().size());
        for (const ContourPiece& p : fit_polyline(loop, kClipperTol)) {
          piece_at(p, z, z, Motion::feed, feed);
        }
      } else {
        // Nothing cleared reaches this contour (a part the clearing could not enter): no
        // straight plunge into the stock. Level by level (max_step_down), down along the loop
        // itself no steeper than the helix entry (entry_pitch a turn of a circle of radius
        // R / 2), as many times round as that takes, then once round at the level.
        const std::vector<ContourPiece> pieces = fit_polyline(loop, kClipperTol);
        double L = 0;
        for (const ContourPiece& p : pieces) L += p.length_mm();
        const double slope = pitch / (kPi * R);
        travel(S, clearance, 0.0);
        double z_top = 0.0;
        for (int k = 1; k <= levels; ++k) {
          const double z_k = -depth * k / levels;
          const std::size_t ramp = path.segments().size();
          const int turns = std::max(1, static_cast<int>(std::ceil((z_top - z_k) / (slope * L))));
          double done = 0;  // the length ramped so far
          for (int j = 0; j < turns; ++j) {
            for (const ContourPiece& p : pieces) {
              const double z0 = z_top - (z_top - z_k) * done / (turns * L);
              done += p.length_mm();
              const double z1 = z_top - (z_top - z_k) * done / (turns * L);
              piece_at(p, z0, z1, Motion::feed, entry_feed);
            }
          }
          info.entries.emplace_back(k == 1 ? first : ramp, path.segments().size());
          for (const ContourPiece& p : pieces) piece_at(p, z_k, z_k, Motion::feed, feed);
          z_top = z_k;
        }
      }
    }
  }
  if (path.empty()) {
    throw InputError(fmt::format(
        "[pocket] finish_pass = false: nothing to cut in layer '{}': every part is too narrow "
        "for the clearing (less than R / 10 wider than the tool with the stock: only the "
        "finishing pass, as a slot, reaches them); give finish_pass = true or a smaller tool",
        pk.boundary));
  }
  const Vec3 e = here();
  line_to(Vec3(e.x(), e.y(), std::max(e.z(), safe_z)), Motion::rapid, rapid);
  return out;
}

}  // namespace

PocketProof prove_pocket(const Job& job, const PlannedPocket& pocket, const RunHooks& hooks) {
  EngagementOptions opt;
  opt.hooks = hooks;
  if (!job.pocket.rest_of.empty() && !job.pocket.rest) {  // the stock the earlier program left
    Job with_rest = job;
    attach_rest_stock(with_rest);
    return prove_pocket(pocket.info, compute_engagement(pocket.path, with_rest, opt));
  }
  return prove_pocket(pocket.info, compute_engagement(pocket.path, job, opt));
}

void attach_rest_stock(Job& job) {
  Pocket& pk = job.pocket;
  if (pk.rest_of.empty()) {
    pk.rest.reset();
    return;
  }
  if (pk.rest && pk.rest->name == pk.rest_of &&
      (!(pk.rest_tool_diameter_mm > 0) ||
       2 * pk.rest->tool_radius_mm == pk.rest_tool_diameter_mm)) {
    return;  // read already
  }
  pk.rest = std::make_shared<const RestStock>(read_rest(job));
}

PocketProof prove_pocket(const PocketInfo& info, const EngagementSeries& e) {
  PocketProof out;
  const double R = e.tool_radius_mm;
  long cutting = 0, above = 0;
  for (std::size_t i = 0; i < e.samples.size(); ++i) {
    const std::size_t seg = e.samples.segment[i];
    bool entry = false;
    for (const auto& [a, b] : info.entries) entry = entry || (seg >= a && seg < b);
    if (entry) continue;
    const double eng = rad_to_deg(e.engagement_angle_rad[i]);
    const double chip = radial_chip_mm(e, i, R);
    const Vec3 at(e.samples.x_mm[i], e.samples.y_mm[i], e.samples.z_mm[i]);
    if (seg >= info.finish_first_segment) {
      if (eng > out.finish_max_engagement_deg) {
        out.finish_max_engagement_deg = eng;
        out.finish_max_at_mm = at;
      }
      out.finish_max_chip_mm = std::max(out.finish_max_chip_mm, chip);
      continue;
    }
    const bool air = std::binary_search(info.air_segments.begin(), info.air_segments.end(), seg);
    if (air) {
      if (eng > out.air_max_engagement_deg) {
        out.air_max_engagement_deg = eng;
        out.air_max_at_mm = at;
      }
      out.air_max_chip_mm = std::max(out.air_max_chip_mm, chip);
      if (i > 0) {
        out.air_removed_mm3 +=
            e.removal_rate_mm3_per_s[i] * (e.samples.t_s[i] - e.samples.t_s[i - 1]);
      }
    }
    if (eng > 0.5) ++cutting;
    if (eng > info.target_engagement_deg) ++above;
    if (eng > out.clearing_max_engagement_deg) {
      out.clearing_max_engagement_deg = eng;
      out.clearing_max_at_mm = at;
    }
    // The chip at the feed: at the link feed a tooth advances 8 times as far, and the tips
    // of cusps it meets read as chips up to that (the link feed's own figure above).
    if (!air) out.clearing_max_chip_mm = std::max(out.clearing_max_chip_mm, chip);
  }
  out.clearing_share_above_target =
      cutting > 0 ? static_cast<double>(above) / static_cast<double>(cutting) : 0.0;
  return out;
}

double estimate_pocket_memory(const Job& job) {
  const Pocket& pk = job.pocket;
  if (!pk.defined()) return 30e6;
  Box3 box;
  double area = 0;
  for (const DrawnContour& c : *pk.boundary_contours) {
    area += std::abs(c.contour.signed_area_mm2());
    for (const Vec2& p : c.contour.points(0.1)) box.extend(Vec3(p.x(), p.y(), 0));
  }
  const double R = job.tool.radius_mm();
  if (!(R > 0) || box.empty()) return 30e6;
  const double h = PartPlanner::cell_size(R);
  const Vec3 size = box.size_mm();
  const double cells = (size.x() / h + 3) * (size.y() / h + 3);
  const double side = R * (1 - std::cos(deg_to_rad(std::min(90.0, pk.max_engagement_deg))));
  const double step = pocket_step_mm(R);
  const int levels = pocket_levels(pk);
  // A level's path: the area over the step-over twice, and six times the walls' and islands'
  // length (links and crescents' ends along them). Measured against the plans of 14 pockets
  // (the example with 6, 10 and 16 mm tools, the cored blank, the test pockets, three drawings
  // of other authors from 100 to 300 mm): the path is 1.3 to 1.9 times area / step-over, the
  // more the more wall a pocket has for its area (5 area / step-over before: 2.1 to 3.7 times
  // the peak, and a 1 x 1.8 m panel was refused at 47 GB).
  // The walls' length, and the channels' medial axis: the Voronoi diagram of the region's
  // chords (within Clipper's 1 um), a few hundred bytes each, and its samples.
  double walls_mm = 0, chords = 0;
  for (const auto* layer : {pk.boundary_contours.get(), pk.island_contours.get()}) {
    if (layer == nullptr) continue;
    for (const DrawnContour& c : *layer) {
      walls_mm += c.contour.length_mm();
      chords += static_cast<double>(c.contour.points(kClipperTol).size());
    }
  }
  const double clearing_mm = 2 * area / std::max(side, 1e-3) + 6 * walls_mm;  // a level
  const double feed_mm_s = std::max(feed_rate_mm_per_min(job), 1e-3) / 60;
  const double samples =
      levels * clearing_mm / feed_mm_s * job.cutting.spindle_speed_rpm * job.tool.teeth / 60;
  // The planners of every distinct plan are kept till the program is written (deeper levels'
  // lifts ask them): one a level where rest_of or a [stock] mesh makes the levels differ. A
  // stock mesh: its plan views through Clipper, a few hundred bytes a triangle.
  const double plans = pk.rest_of.empty() && !job.stock_mesh ? 1.0 : levels;
  const double mesh =
      job.stock_mesh ? 1000.0 * static_cast<double>(job.stock_mesh->triangles.size()) : 0.0;
  const double medial = 1000 * chords + 50 * clearing_mm / std::clamp(0.01 * R, 0.005, 0.05);
  return 30e6 + plans * (cells + 200 * clearing_mm / step) + mesh + medial + 450 * samples;
}

PlannedPocket plan_pocket(const Job& job) {
  // The steps' aim below the target: 1.2 degrees held the kernel's largest within the target on
  // the test pockets and the example; where the proof finds more than the target + 2 % all
  // the same (a pass's end hooking into the frontier the last pass left beside a wall, read by
  // the kernel at its own teeth: 55.83 degrees for a 53 target on the example with a [stock]
  // box from x = 18.2 mm), the pocket is planned again with the aim 0.5 degrees lower, up to
  // three times (docs/models.md, "Pockets").
  constexpr double kAimMargin = 1.2, kAimMarginStep = 0.5;
  constexpr int kReplans = 3;
  const double target = job.pocket.max_engagement_deg;
  const double limit = target * (1 + kProofTolerance);
  // The aim plan_pocket_at takes (its floor: half the target).
  const auto aim = [&](int k) {
    return std::max(0.5 * target, target - (kAimMargin + k * kAimMarginStep));
  };
  if (!job.pocket.defined()) throw Error("plan_pocket: the job has no [pocket]");
  check_pocket_stock(job);  // (once: the plans sent back would only repeat it)
  std::optional<PlannedPocket> best;
  int tried = 0;
  for (int k = 0; k <= kReplans; ++k) {
    if (k > 0 && aim(k) == aim(k - 1)) break;  // at the floor: the same plan again
    tried = k;
    const double margin = kAimMargin + k * kAimMarginStep;
    PlannedPocket p = plan_pocket_at(job, margin);
    p.proof = prove_pocket(job, p);
    p.info.aim_margin_deg = margin;
    p.info.replans = k;
    if (k > 0) {
      p.info.first_proof_max_deg = best->info.first_proof_max_deg;
      p.info.first_proof_at_mm = best->info.first_proof_at_mm;
    } else {
      p.info.first_proof_max_deg = p.proof.clearing_max_engagement_deg;
      p.info.first_proof_at_mm = p.proof.clearing_max_at_mm;
    }
    p.info.proven = p.proof.clearing_max_engagement_deg <= limit;
    if (p.info.proven) return p;
    if (!best || p.proof.clearing_max_engagement_deg < best->proof.clearing_max_engagement_deg) {
      best = std::move(p);
    }
  }
  best->info.replans = tried;  // (the least of the plans: every one was tried)
  if (job.pocket.channel_family) {
    // No plan with the family's cycles held: the loops instead, where they hold.
    Job loops = job;
    loops.pocket.channel_family.reset();
    PlannedPocket p = plan_pocket(loops);
    if (p.info.proven ||
        p.proof.clearing_max_engagement_deg < best->proof.clearing_max_engagement_deg) {
      p.info.channel_family_dropped = std::string(to_string(*job.pocket.channel_family));
      p.info.channel_family_dropped_deg = best->proof.clearing_max_engagement_deg;
      return p;
    }
  }
  return std::move(*best);
}

int pocket_level_count(const Pocket& pk) { return pocket_levels(pk); }

PlannedPath plan_job(const Job& job) {
  if (!job.pocket.defined()) return plan_slot(job);
  PlannedPocket p = plan_pocket(job);
  PlannedPath out;
  out.path = std::move(p.path);
  out.info.cycles = p.info.passes;
  out.info.levels = p.info.levels;
  out.info.closed_start = true;
  return out;
}

}  // namespace trochomill
