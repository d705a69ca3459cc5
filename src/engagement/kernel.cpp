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
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"
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

// Appends the arc [a, b] (0 <= a < 2 pi, b <= a + 2 pi), split at 2 pi.
void push_wrapped(ArcSet& out, double a, double b) {
  if (b <= kTwoPi) {
    out.push_back({a, b});
  } else {
    out.push_back({a, kTwoPi});
    out.push_back({0.0, b - kTwoPi});
  }
}

// Is angle a (in [0, 2 pi)) within 1e-9 rad of an end of an arc of the set?
bool near_end(const ArcSet& set, double a) {
  constexpr double kTol = 1e-9;
  for (const auto& arc : set) {
    for (const double e : {arc.start_rad, arc.end_rad}) {
      const double d = std::abs(a - e);
      if (d < kTol || kTwoPi - d < kTol) return true;
    }
  }
  return false;
}

// Removes the arc centred on `mid` with half-width `half` (rad) from `set`. Whether the set
// changed.
bool subtract(ArcSet& set, double mid, double half) {
  if (half >= kPi) {
    const bool had = !set.empty();
    set.clear();
    return had;
  }
  const double a = wrap(mid - half), b = a + 2 * half;
  bool changed = false;
  auto cut = [&](double lo, double hi) {
    // Nothing to cut (the common case where the tooth before's disc is already the region's):
    // no new set.
    if (std::none_of(set.begin(), set.end(),
                     [&](const AngleArc& arc) { return arc.end_rad > lo && arc.start_rad < hi; })) {
      return;
    }
    changed = true;
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
  return changed;
}

// A direction on a circle: its angle (rad), cosine and sine.
struct Unit {
  double angle = 0, c = 1, s = 0;
};
// The ends of an arc.
struct ArcEnds {
  Unit start, end;
};

struct Disc {
  double x = 0, y = 0;
  ArcSet exposed;
  /// Per exposed arc: its start's and its end's direction (set with its box).
  std::vector<ArcEnds> ends;
  std::size_t cell = 0;  // grid cell holding the centre
};

// The bounding box of a disc's exposed arcs (mm).
struct Box {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

class Removed {
 public:
  // Discs live in a dense grid of cell size R over the box [x0, x1] x [y0, y1] (mm), which
  // must hold every centre that will be inserted or queried (the sampled path's box).
  Removed(double radius, double x0, double y0, double x1, double y1)
      : R_(radius), cell_(radius), x0_(x0 - 3 * radius), y0_(y0 - 3 * radius) {
    nx_ = static_cast<long>(std::ceil((x1 - x0_ + 3 * radius) / cell_)) + 1;
    ny_ = static_cast<long>(std::ceil((y1 - y0_ + 3 * radius) / cell_)) + 1;
    grid_.resize(static_cast<std::size_t>(nx_ * ny_));
    all_.resize(grid_.size());
  }

  // The part of the circle (cx, cy, R) outside the removed region, as an ArcSet.
  [[nodiscard]] ArcSet outside(double cx, double cy) const {
    gather_cached(cx, cy);
    std::vector<double> cross;
    bool degenerate = false;
    for (std::size_t k = 0; k < near_.size(); ++k) {
      const Disc& d = discs_[near_[k]];
      const double dist = near_dist(k);
      // The circle of an alive disc: only boundary points, no open stock on it.
      if (dist <= 1e-9) return {};
      if (dist >= 2 * R_ - kEps || dist <= kEps) continue;
      const double alpha = near_alpha(k), beta = near_beta(k);
      // Equal circles: the crossing at angle alpha -+ beta on this circle sits at
      // alpha + pi +- beta on the disc's.
      for (const double sgn : {-1.0, 1.0}) {
        const double th = alpha + sgn * beta;
        const double on = wrap(alpha + kPi - sgn * beta);
        // A crossing within rounding of an arc end (a boundary vertex) may be counted by
        // neither or both arcs that meet there: parity is then not to be trusted, and the
        // crossing is kept as a split point for direct tests.
        if (near_end(d.exposed, on)) {
          degenerate = true;
          cross.push_back(wrap(th));
        } else if (contains(d.exposed, on)) {
          cross.push_back(wrap(th));
        }
      }
    }
    std::sort(cross.begin(), cross.end());
    // Reference status: a point of the circle towards the most recent disc's centre lies
    // inside that disc, so in R; otherwise (a jump, or nothing cut yet) a direct test decides.
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
    if (cross.empty()) {  // (degenerate implies at least one split point)
      if (!ref_in) out.push_back({0.0, kTwoPi});
      return out;
    }
    const std::size_t n = cross.size();
    // Crossings closer than 1e-9 rad (the circle through a point where several boundary
    // arcs meet, e.g. the centre of a circular orbit of radius R that every disc's circle
    // passes through), crossings at arc ends or an odd count make the parity of rounded
    // crossings unreliable: then the status of each interval is tested directly at its
    // midpoint.
    if (n % 2 == 1) degenerate = true;
    for (std::size_t k = 0; k < n; ++k) {
      const double next = k + 1 < n ? cross[k + 1] : cross[0] + kTwoPi;
      if (next - cross[k] < 1e-9) degenerate = true;
    }
    if (degenerate) {
      for (std::size_t k = 0; k < n; ++k) {
        const double a = cross[k], b = k + 1 < n ? cross[k + 1] : cross[0] + kTwoPi;
        if (b - a < 1e-9) continue;
        const double mid = 0.5 * (a + b);
        if (inside(cx + R_ * std::cos(mid), cy + R_ * std::sin(mid))) continue;
        push_wrapped(out, a, b);
      }
      normalise(out);
      return out;
    }
    // Status just after crossing k alternates; find the interval holding ref.
    std::size_t k_ref = n - 1;  // the interval [cross[n-1], cross[0] + 2 pi) by default
    for (std::size_t k = 0; k + 1 < n; ++k) {
      if (ref >= cross[k] && ref < cross[k + 1]) k_ref = k;
    }
    for (std::size_t k = 0; k < n; ++k) {
      const bool in = ((k + n - k_ref) % 2 == 0) ? ref_in : !ref_in;
      const double a = cross[k], b = k + 1 < n ? cross[k + 1] : cross[0] + kTwoPi;
      if (!in && b > a) push_wrapped(out, a, b);
    }
    normalise(out);
    return out;
  }

  // Alive discs whose exposed arcs may meet the disc of radius R around (cx, cy).
  [[nodiscard]] const std::vector<int>& near_disc(double cx, double cy) const {
    gather_cached(cx, cy);
    return near_;
  }
  [[nodiscard]] const Disc& disc(int j) const { return discs_[j]; }
  // Of the k-th disc near_disc (or outside) listed, as seen from the centre it listed them
  // for: the distance to its centre, that centre's direction (rad) and acos(distance / 2R)
  // (the half-angle of the two circles' crossings), each computed once for all who ask.
  [[nodiscard]] double near_dist(std::size_t k) const {
    return memo(near_dist_, k, [&](const Disc& d) { return std::hypot(d.x - gx_, d.y - gy_); });
  }
  [[nodiscard]] double near_alpha(std::size_t k) const {
    return memo(near_alpha_, k, [&](const Disc& d) { return std::atan2(d.y - gy_, d.x - gx_); });
  }
  [[nodiscard]] double near_beta(std::size_t k) const {
    return memo(near_beta_, k, [&](const Disc&) { return std::acos(near_dist(k) / (2 * R_)); });
  }
  [[nodiscard]] bool covers(double px, double py) const { return inside(px, py); }
  // Calls f(x, y, arc) for every exposed arc of every disc: the region's outline.
  template <class F>
  void for_exposed(F&& f) const {
    for (const Disc& d : discs_) {
      for (const AngleArc& a : d.exposed) f(d.x, d.y, a);
    }
  }

  // Adds another region's discs from its `from`-th on (the union of both), in the order they
  // were inserted there. Returns how many discs the other region has.
  std::size_t merge(const Removed& o, std::size_t from) {
    for (std::size_t k = from; k < o.discs_.size(); ++k) {
      const Disc& d = o.discs_[k];
      add(d.x, d.y);
    }
    return o.discs_.size();
  }

  // Pins the candidates of every query within `slack` of (cx, cy): those gather() would meet
  // for a reach of R + slack, in its order, until the next insert. A query there filters
  // them instead of scanning the cells: the same list, in the same order.
  void pin(double cx, double cy, double slack) const {
    gather_within(cx, cy, R_ + slack + 1e-9);
    pinned_ = near_;
    pin_x_ = cx;
    pin_y_ = cy;
    pin_slack_ = slack;
    pin_valid_ = true;
    cache_valid_ = false;
  }

  // Adds the disc about (cx, cy).
  void add(double cx, double cy) { insert(cx, cy, outside(cx, cy)); }

  // Inserts a disc whose circle's part outside R (before it) is `exposed`.
  void insert(double cx, double cy, ArcSet exposed) {
    // The discs near the centre: those outside() gathered for it if nothing was inserted
    // since (the kernel asks for a sample's free circle, then inserts its disc a tooth later).
    if (!(cache_valid_ && cache_x_ == cx && cache_y_ == cy)) gather(cx, cy);
    cache_valid_ = false;
    pin_valid_ = false;  // boxes and lists change below
    have_last_ = true;
    last_x_ = cx;
    last_y_ = cy;
    // A disc at the centre of an alive one (a pure z move, a revisited point) adds nothing.
    for (std::size_t k = 0; k < near_.size(); ++k) {
      if (near_dist(k) <= 1e-9) return;
    }
    for (std::size_t k = 0; k < near_.size(); ++k) {
      const int j = near_[k];
      Disc& d = discs_[j];
      // (The distance as from the disc: hypot's value does not depend on the signs.)
      const double dx = cx - d.x, dy = cy - d.y, dist = near_dist(k);
      if (dist >= 2 * R_) continue;
      // Bounding-box reject: the exposed arcs lie outside the new disc.
      const Box& b = box_[static_cast<std::size_t>(j)];
      const double nx = std::clamp(cx, b.x0, b.x1), ny = std::clamp(cy, b.y0, b.y1);
      if (std::hypot(nx - cx, ny - cy) >= R_) continue;
      if (!subtract(d.exposed, std::atan2(dy, dx), dist <= kEps ? kPi : near_beta(k))) {
        continue;  // nothing of its arcs lay in the new disc: the same box
      }
      const auto u = static_cast<std::size_t>(j);
      if (d.exposed.empty()) {
        // A dead disc leaves its cells: the candidate sets hold only boundary discs.
        delist(j, span_[u], Span{});
      } else {
        // Its arcs shrank, so did their box (within the old one): it leaves the cells the
        // box no longer meets.
        box_[u] = bounds(d);
        const Span now = span_of(box_[u]);
        delist(j, span_[u], now);
        span_[u] = now;
      }
    }
    if (exposed.empty()) return;
    Disc d;
    d.x = cx;
    d.y = cy;
    d.exposed = std::move(exposed);
    d.cell = cell_of(cell_x(cx), cell_y(cy));
    box_.push_back(bounds(d));
    span_.push_back(span_of(box_.back()));
    seen_.push_back(0);
    const int idx = static_cast<int>(discs_.size());
    const Span& sp = span_.back();
    for (long b = sp.iy0; b <= sp.iy1; ++b) {
      for (long a = sp.ix0; a <= sp.ix1; ++a) grid_[cell_of(a, b)].push_back(idx);
    }
    all_[d.cell].push_back(idx);
    discs_.push_back(std::move(d));
  }

 private:
  [[nodiscard]] long cell_x(double v) const {
    return std::clamp(static_cast<long>(std::floor((v - x0_) / cell_)), 0L, nx_ - 1);
  }
  [[nodiscard]] long cell_y(double v) const {
    return std::clamp(static_cast<long>(std::floor((v - y0_) / cell_)), 0L, ny_ - 1);
  }
  [[nodiscard]] std::size_t cell_of(long ix, long iy) const {
    return static_cast<std::size_t>(iy * nx_ + ix);
  }

  // cache[k] (NaN: not yet computed) of the k-th listed disc, computed by f(disc) once.
  template <class F>
  double memo(std::vector<double>& cache, std::size_t k, const F& f) const {
    double& v = cache[k];
    if (std::isnan(v)) v = f(discs_[static_cast<std::size_t>(near_[k])]);
    return v;
  }

  // The cells [ix0, ix1] x [iy0, iy1] an alive disc is listed in (those its exposed arcs'
  // box meets; none: ix1 < ix0).
  struct Span {
    long ix0 = 0, iy0 = 0, ix1 = -1, iy1 = -1;
    [[nodiscard]] bool holds(long a, long b) const {
      return a >= ix0 && a <= ix1 && b >= iy0 && b <= iy1;
    }
  };
  [[nodiscard]] Span span_of(const Box& b) const {
    return {cell_x(b.x0), cell_y(b.y0), cell_x(b.x1), cell_y(b.y1)};
  }
  // Takes disc j out of the cells of `from` that `keep` does not hold.
  void delist(int j, const Span& from, const Span& keep) {
    for (long b = from.iy0; b <= from.iy1; ++b) {
      for (long a = from.ix0; a <= from.ix1; ++a) {
        if (keep.holds(a, b)) continue;
        auto& cell = grid_[cell_of(a, b)];
        cell.erase(std::find(cell.begin(), cell.end(), j));
      }
    }
  }

  // gather(cx, cy) unless its result for this centre is still valid (no insertion since):
  // outside() and the chip query at one sample share it.
  void gather_cached(double cx, double cy) const {
    if (cache_valid_ && cache_x_ == cx && cache_y_ == cy) return;
    gather(cx, cy);
    cache_valid_ = true;
    cache_x_ = cx;
    cache_y_ = cy;
  }

  // Alive discs whose exposed arcs' box comes within R of (cx, cy), in the order of their
  // centres' cells (row by row) and, within a cell, of insertion. A disc is listed in every
  // cell its box meets, so only the cells within R of the query are read (a box within R
  // meets one of them): about a third of the candidates of binning by centre, which needs
  // the cells within 2R.
  void gather(double cx, double cy) const {
    const double reach = R_ + 1e-9;
    if (pin_valid_ && std::hypot(cx - pin_x_, cy - pin_y_) <= pin_slack_) {
      near_.clear();
      gx_ = cx;
      gy_ = cy;
      const double near2 = reach * reach;
      for (const int j : pinned_) {
        if (box_meets(j, cx, cy, near2)) near_.push_back(j);
      }
      forget_memos();
      return;
    }
    gather_within(cx, cy, reach);
  }

  void gather_within(double cx, double cy, double reach) const {
    near_.clear();
    gx_ = cx;
    gy_ = cy;
    if (++stamp_ == 0) {  // the stamps wrapped: none is current
      std::fill(seen_.begin(), seen_.end(), 0U);
      stamp_ = 1;
    }
    const double near2 = reach * reach;
    for (long b = cell_y(cy - reach); b <= cell_y(cy + reach); ++b) {
      for (long a = cell_x(cx - reach); a <= cell_x(cx + reach); ++a) {
        for (const int j : grid_[cell_of(a, b)]) {
          const auto u = static_cast<std::size_t>(j);
          if (seen_[u] == stamp_) continue;  // listed in an earlier cell too
          seen_[u] = stamp_;
          if (box_meets(j, cx, cy, near2)) near_.push_back(j);
        }
      }
    }
    // The order a scan of the centres' cells gave (the chip's angle among equal chips, and
    // so every output, depends on it).
    std::sort(near_.begin(), near_.end(), [&](int p, int q) {
      const std::size_t cp = discs_[static_cast<std::size_t>(p)].cell,
                        cq = discs_[static_cast<std::size_t>(q)].cell;
      return cp != cq ? cp < cq : p < q;
    });
    forget_memos();
  }

  // Whether disc j's exposed arcs' bounding box meets the disc of radius sqrt(near2) about
  // (cx, cy): its nearest point within it (squared distances).
  [[nodiscard]] bool box_meets(int j, double cx, double cy, double near2) const {
    const Box& d = box_[static_cast<std::size_t>(j)];
    const double nx = std::clamp(cx, d.x0, d.x1) - cx, ny = std::clamp(cy, d.y0, d.y1) - cy;
    return nx * nx + ny * ny <= near2;
  }

  // The per-neighbour memos of near_ not yet asked (NaN).
  void forget_memos() const {
    const double unknown = std::numeric_limits<double>::quiet_NaN();
    near_dist_.assign(near_.size(), unknown);
    near_alpha_.assign(near_.size(), unknown);
    near_beta_.assign(near_.size(), unknown);
  }

  // Is (px, py) inside the removed region? Directly: within R of any inserted disc.
  [[nodiscard]] bool inside(double px, double py) const {
    const double r2 = R_ * R_;
    for (long b = cell_y(py - R_); b <= cell_y(py + R_); ++b) {
      for (long a = cell_x(px - R_); a <= cell_x(px + R_); ++a) {
        for (const int j : all_[cell_of(a, b)]) {
          const double dx = discs_[j].x - px, dy = discs_[j].y - py;
          if (dx * dx + dy * dy < r2) return true;
        }
      }
    }
    return false;
  }

  // The box of d's exposed arcs; sets d.ends (an end that was an end before keeps its
  // cosine and sine).
  [[nodiscard]] Box bounds(Disc& d) const {
    Box b;
    old_ends_.swap(d.ends);
    d.ends.clear();
    const auto unit = [&](double angle) {
      for (const ArcEnds& o : old_ends_) {
        if (o.start.angle == angle) return o.start;
        if (o.end.angle == angle) return o.end;
      }
      return Unit{angle, std::cos(angle), std::sin(angle)};
    };
    b.x0 = b.y0 = std::numeric_limits<double>::infinity();
    b.x1 = b.y1 = -std::numeric_limits<double>::infinity();
    for (const auto& arc : d.exposed) {
      auto add = [&](double ux, double uy) {
        const double x = d.x + R_ * ux, y = d.y + R_ * uy;
        b.x0 = std::min(b.x0, x);
        b.x1 = std::max(b.x1, x);
        b.y0 = std::min(b.y0, y);
        b.y1 = std::max(b.y1, y);
      };
      d.ends.push_back({unit(arc.start_rad), unit(arc.end_rad)});
      add(d.ends.back().start.c, d.ends.back().start.s);
      add(d.ends.back().end.c, d.ends.back().end.s);
      static constexpr double kAxis[5][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 0}};
      for (int q = 0; q <= 4; ++q) {  // axis extremes inside the arc
        const double th = q * 0.5 * kPi;
        if (th > arc.start_rad && th < arc.end_rad) add(kAxis[q][0], kAxis[q][1]);
      }
    }
    return b;
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

  double R_, cell_, x0_, y0_;
  long nx_ = 0, ny_ = 0;
  std::vector<Disc> discs_;
  std::vector<Box> box_;                     // per disc
  std::vector<Span> span_;                   // per disc: the cells it is listed in (alive discs)
  mutable std::vector<std::uint32_t> seen_;  // per disc: the gather that last met it
  mutable std::uint32_t stamp_ = 0;
  std::vector<std::vector<int>> grid_;  // alive discs per cell their box meets
  std::vector<std::vector<int>> all_;   // every stored disc per cell (for point tests)
  mutable std::vector<int> near_;
  mutable std::vector<ArcEnds> old_ends_;  // bounds()'s scratch
  mutable double gx_ = 0, gy_ = 0;         // the centre near_ was gathered for
  mutable std::vector<double> near_dist_, near_alpha_, near_beta_;  // NaN: not yet asked
  mutable bool cache_valid_ = false;
  mutable double cache_x_ = 0, cache_y_ = 0;
  mutable std::vector<int> pinned_;  // pin()'s candidates
  mutable bool pin_valid_ = false;
  mutable double pin_x_ = 0, pin_y_ = 0, pin_slack_ = 0;
  bool have_last_ = false;
  double last_x_ = 0, last_y_ = 0;
};

// Angular set of the circle (cx, cy, R) inside the rectangle x0 <= x <= x1, y0 <= y <= y1.
ArcSet inside_rect(double cx, double cy, double R, double x0, double x1, double y0, double y1) {
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
  clip(0.0, x1 - cx);        // x <= x1
  clip(kPi, cx - x0);        // -x <= -x0
  clip(0.5 * kPi, y1 - cy);  // y <= y1
  clip(1.5 * kPi, cy - y0);  // -y <= -y0
  return s;
}

// The angles (in [0, 2 pi)) where the circle (cx, cy, R) crosses the segment from (px, py) to
// (rx, ry), appended to `cut`.
void circle_crossings(double px, double py, double rx, double ry, double cx, double cy, double R,
                      std::vector<double>& cut) {
  const double dx = rx - px, dy = ry - py;
  const double a = dx * dx + dy * dy;
  if (!(a > 0)) return;
  const double fx = px - cx, fy = py - cy;
  const double b = 2 * (fx * dx + fy * dy), c = fx * fx + fy * fy - R * R;
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return;
  const double sq = std::sqrt(disc);
  for (const double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
    if (t < 0 || t > 1) continue;
    cut.push_back(wrap(std::atan2(fy + t * dy, fx + t * dx)));
  }
}

// The arcs of a circle over a region, from the angles where the circle crosses the region's
// outline (`cut`, sorted here) and `inside_at(angle)`, whether the circle's point at an angle
// lies in it: each piece between crossings tested at its middle, sorted and merged.
template <class InsideAt>
ArcSet arcs_inside(std::vector<double>& cut, InsideAt inside_at) {
  std::sort(cut.begin(), cut.end());
  ArcSet out;
  if (cut.empty()) {
    if (inside_at(0.0)) out.push_back({0.0, kTwoPi});
    return out;
  }
  for (std::size_t q = 0; q < cut.size(); ++q) {
    const double a = cut[q], b = q + 1 < cut.size() ? cut[q + 1] : cut[0] + kTwoPi;
    if (b - a < 1e-12 || !inside_at(0.5 * (a + b))) continue;
    if (b <= kTwoPi) {
      out.push_back({a, b});
    } else {
      out.push_back({a, kTwoPi});
      out.push_back({0.0, b - kTwoPi});
    }
  }
  std::sort(out.begin(), out.end(),
            [](const AngleArc& x, const AngleArc& y) { return x.start_rad < y.start_rad; });
  ArcSet merged;
  for (const AngleArc& a : out) {
    if (!merged.empty() && a.start_rad <= merged.back().end_rad) {
      merged.back().end_rad = std::max(merged.back().end_rad, a.end_rad);
    } else {
      merged.push_back(a);
    }
  }
  return merged;
}

// A plan view of the stock (mesh_plan_region: the region's outline, closed polylines), its
// edges on a grid of cells: the arcs of a circle over it are split at the circle's crossings
// with the edges and each piece tested at its midpoint (even-odd, a ray towards +x along the
// cells of its row).
class PlanView {
 public:
  PlanView(const std::vector<Contour>& region, double x0, double y0, double cell, long nx, long ny)
      : x0_(x0), y0_(y0), cell_(cell), nx_(nx), ny_(ny) {
    grid_.resize(static_cast<std::size_t>(nx_ * ny_));
    for (const Contour& c : region) {
      const std::vector<Vec2> pts = c.points(1e-3);  // polylines: their own vertices
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const Vec2& a = pts[i];
        const Vec2& b = pts[(i + 1) % pts.size()];
        if (a == b) continue;
        const auto k = static_cast<std::uint32_t>(edges_.size());
        edges_.push_back({a, b});
        for (long j = cy(std::min(a.y(), b.y())); j <= cy(std::max(a.y(), b.y())); ++j) {
          for (long q = cx(std::min(a.x(), b.x())); q <= cx(std::max(a.x(), b.x())); ++q) {
            grid_[static_cast<std::size_t>(j * nx_ + q)].push_back(k);
          }
        }
      }
    }
    stamp_.assign(edges_.size(), 0);
  }
  [[nodiscard]] ArcSet inside(double cx0, double cy0, double R) const {
    std::vector<double>& cut = cut_;
    cut.clear();
    ++tick_;
    for (long j = cy(cy0 - R); j <= cy(cy0 + R); ++j) {
      for (long i = cx(cx0 - R); i <= cx(cx0 + R); ++i) {
        for (const std::uint32_t k : grid_[static_cast<std::size_t>(j * nx_ + i)]) {
          if (stamp_[k] == tick_) continue;
          stamp_[k] = tick_;
          const auto& [p, r] = edges_[k];
          circle_crossings(p.x(), p.y(), r.x(), r.y(), cx0, cy0, R, cut);
        }
      }
    }
    return arcs_inside(
        cut, [&](double th) { return contains(cx0 + R * std::cos(th), cy0 + R * std::sin(th)); });
  }

 private:
  [[nodiscard]] long cx(double x) const {
    return std::clamp(static_cast<long>(std::floor((x - x0_) / cell_)), 0L, nx_ - 1);
  }
  [[nodiscard]] long cy(double y) const {
    return std::clamp(static_cast<long>(std::floor((y - y0_) / cell_)), 0L, ny_ - 1);
  }
  // Even-odd: the edges the ray from (x, y) towards +x crosses (half-open in y).
  [[nodiscard]] bool contains(double x, double y) const {
    ++tick_;
    bool in = false;
    const long j = cy(y);
    for (long i = cx(x); i < nx_; ++i) {
      for (const std::uint32_t k : grid_[static_cast<std::size_t>(j * nx_ + i)]) {
        if (stamp_[k] == tick_) continue;
        stamp_[k] = tick_;
        const auto& [a, b] = edges_[k];
        if ((a.y() > y) == (b.y() > y)) continue;
        const double xc = a.x() + (y - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
        if (xc > x) in = !in;
      }
    }
    return in;
  }
  double x0_, y0_, cell_;
  long nx_, ny_;
  std::vector<std::pair<Vec2, Vec2>> edges_;
  std::vector<std::vector<std::uint32_t>> grid_;
  mutable std::vector<std::uint32_t> stamp_;
  mutable std::uint32_t tick_ = 0;
  mutable std::vector<double> cut_;
};

// The stock as a closed mesh: at a tool tip height z0, the plan-view region where the vertical
// line through a point meets the solid between z0 and z1 (the tool's reach). Its outline lies
// on the projected edges of the triangles' parts between z0 and z1 (the sections at z0 and z1,
// the faces' silhouettes between): the circle is split at its crossings with all of them and
// each piece tested at its midpoint with the vertical line (line_crossing, even-odd).
class MeshStock {
 public:
  MeshStock(const Mesh& mesh, double radius) : m_(mesh) {
    const Box3 bounds = mesh_bounds(m_);  // checks every vertex a triangle uses
    const double x0 = bounds.lo[0], y0 = bounds.lo[1], x1 = bounds.hi[0], y1 = bounds.hi[1];
    for (const auto& t : m_.triangles) {
      Tri b{};
      b.x0 = b.y0 = b.z0 = std::numeric_limits<double>::infinity();
      b.x1 = b.y1 = b.z1 = -b.x0;
      for (const std::uint32_t i : t) {
        const auto& p = m_.vertices[i];
        b.x0 = std::min(b.x0, p[0]), b.x1 = std::max(b.x1, p[0]);
        b.y0 = std::min(b.y0, p[1]), b.y1 = std::max(b.y1, p[1]);
        b.z0 = std::min(b.z0, p[2]), b.z1 = std::max(b.z1, p[2]);
      }
      tris_.push_back(b);
    }
    // Cells of the tool's radius, at most 1000 a side (a mesh far larger than the tool).
    x0_ = x0, y0_ = y0;
    cell_ = std::max({radius, (x1 - x0) / 1000.0, (y1 - y0) / 1000.0});
    nx_ = static_cast<long>((x1 - x0) / cell_) + 1;
    ny_ = static_cast<long>((y1 - y0) / cell_) + 1;
    grid_.resize(static_cast<std::size_t>(nx_ * ny_));
    for (std::size_t k = 0; k < tris_.size(); ++k) {
      const Tri& b = tris_[k];
      for (long j = cy(b.y0); j <= cy(b.y1); ++j) {
        for (long i = cx(b.x0); i <= cx(b.x1); ++i) {
          grid_[static_cast<std::size_t>(j * nx_ + i)].push_back(static_cast<std::uint32_t>(k));
        }
      }
    }
    stamp_.assign(tris_.size(), 0);
    // A closed solid (each edge between two triangles: check_closed_mesh) may be taken level
    // by level through its plan views; another only by the triangles (which say where a
    // vertical line crosses it an odd number of times).
    try {
      check_closed_mesh(m_);
      closed_ = true;
    } catch (const InputError&) {
      closed_ = false;
    }
  }
  // The arcs of the circle (cx, cy, R) over the region of the stock between heights z0 and z1.
  // `level`: the position is on a horizontal move, whose heights (a level's) recur: the plan
  // view between them is made once (mesh_plan_region: the region's outline alone, not every
  // triangle's edges) and asked from then on, up to kMaxViews of them; the other positions (a
  // ramp's, a helix's), and the levels past that, ask the triangles. The two agree to Clipper's
  // grid of 1e-6 mm (`Analysis.AStockMeshIsTheStock`,
  // `Analysis.AStockMeshsPlanViewsAgreeWithItsTriangles`: 6.8e-7 rad at most).
  [[nodiscard]] ArcSet inside(double cx0, double cy0, double R, double z0, double z1,
                              bool level) const {
    if (level && closed_) {
      const auto key = std::pair{z0, z1};
      auto it = views_.find(key);
      if (it == views_.end() && views_.size() < kMaxViews) {
        it = views_
                 .emplace(key, std::make_unique<PlanView>(mesh_plan_region(m_, z0, z1), x0_, y0_,
                                                          cell_, nx_, ny_))
                 .first;
      }
      if (it != views_.end()) return it->second->inside(cx0, cy0, R);
    }
    return by_triangles(cx0, cy0, R, z0, z1);
  }

 private:
  static constexpr std::size_t kMaxViews = 256;  // heights of horizontal moves (a view: kB)

  [[nodiscard]] ArcSet by_triangles(double cx0, double cy0, double R, double z0, double z1) const {
    std::vector<double>& cut = cut_;  // the crossing angles, the buffer reused
    cut.clear();
    ++tick_;
    for (long j = cy(cy0 - R); j <= cy(cy0 + R); ++j) {
      for (long i = cx(cx0 - R); i <= cx(cx0 + R); ++i) {
        for (const std::uint32_t k : grid_[static_cast<std::size_t>(j * nx_ + i)]) {
          if (stamp_[k] == tick_) continue;
          stamp_[k] = tick_;
          const Tri& b = tris_[k];
          if (b.z1 < z0 || b.z0 > z1 || b.x0 > cx0 + R || b.x1 < cx0 - R || b.y0 > cy0 + R ||
              b.y1 < cy0 - R) {
            continue;
          }
          crossings(k, cx0, cy0, R, z0, z1, cut);
        }
      }
    }
    return arcs_inside(cut, [&](double th) {
      return covered(cx0 + R * std::cos(th), cy0 + R * std::sin(th), z0, z1);
    });
  }

  struct Tri {
    double x0, x1, y0, y1, z0, z1;
  };
  [[nodiscard]] long cx(double x) const {
    return std::clamp(static_cast<long>(std::floor((x - x0_) / cell_)), 0L, nx_ - 1);
  }
  [[nodiscard]] long cy(double y) const {
    return std::clamp(static_cast<long>(std::floor((y - y0_) / cell_)), 0L, ny_ - 1);
  }

  // The angles where the circle crosses the projected edges of triangle k's part between z0
  // and z1 (the triangle clipped by the two planes).
  void crossings(std::size_t k, double cx0, double cy0, double R, double z0, double z1,
                 std::vector<double>& cut) const {
    Vec3 poly[6], next[6];
    int n = 3;
    for (int q = 0; q < 3; ++q) poly[q] = m_.vertices[m_.triangles[k][static_cast<std::size_t>(q)]];
    auto clip = [&](double h, bool keep_above) {
      int m = 0;
      for (int q = 0; q < n; ++q) {
        const auto& p = poly[q];
        const auto& r = poly[(q + 1) % n];
        const bool pin = keep_above ? p[2] >= h : p[2] <= h;
        const bool rin = keep_above ? r[2] >= h : r[2] <= h;
        if (pin) next[m++] = p;
        if (pin != rin) {
          const double t = (h - p[2]) / (r[2] - p[2]);
          next[m++] = {p[0] + t * (r[0] - p[0]), p[1] + t * (r[1] - p[1]), h};
        }
      }
      n = m;
      std::copy(next, next + m, poly);
    };
    clip(z0, true);
    if (n > 0) clip(z1, false);
    for (int q = 0; q < n; ++q) {
      const auto& p = poly[q];
      const auto& r = poly[(q + 1) % n];
      circle_crossings(p[0], p[1], r[0], r[1], cx0, cy0, R, cut);
    }
  }

  // Does the vertical line through (x, y) meet the solid between z0 and z1 (a stretch of
  // positive length)?
  [[nodiscard]] bool covered(double x, double y, double z0, double z1) const {
    std::vector<double>& w = w_;
    w.clear();
    for (const std::uint32_t k : grid_[static_cast<std::size_t>(cy(y) * nx_ + cx(x))]) {
      const Tri& b = tris_[k];
      if (x < b.x0 || x > b.x1 || y < b.y0 || y > b.y1) continue;
      const auto& t = m_.triangles[k];
      if (const auto h =
              line_crossing(m_.vertices[t[0]], m_.vertices[t[1]], m_.vertices[t[2]], 2, x, y)) {
        w.push_back(*h);
      }
    }
    if (w.size() % 2 != 0) {
      throw InputError(fmt::format(
          "the stock mesh is not closed: the vertical line at x = {:.6g}, y = {:.6g} mm "
          "crosses its surface {} times (an even number for a closed solid)",
          x, y, w.size()));
    }
    std::sort(w.begin(), w.end());
    for (std::size_t q = 0; q < w.size(); q += 2) {
      if (std::min(w[q + 1], z1) > std::max(w[q], z0)) return true;
    }
    return false;
  }

  const Mesh& m_;
  std::vector<Tri> tris_;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  long nx_ = 1, ny_ = 1;
  std::vector<std::vector<std::uint32_t>> grid_;
  mutable std::vector<std::uint32_t> stamp_;
  mutable std::uint32_t tick_ = 0;
  mutable std::vector<double> w_;
  mutable std::vector<double> cut_;
  bool closed_ = false;
  mutable std::map<std::pair<double, double>, std::unique_ptr<PlanView>> views_;
};

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

// The part of a not in b.
ArcSet minus(const ArcSet& a, const ArcSet& b) {
  ArcSet gaps;  // the complement of b in [0, 2 pi]
  double from = 0;
  for (const auto& q : b) {
    if (q.start_rad > from) gaps.push_back({from, q.start_rad});
    from = std::max(from, q.end_rad);
  }
  if (from < kTwoPi) gaps.push_back({from, kTwoPi});
  return intersect(a, gaps);
}

// Joins an arc ending at 2 pi with one starting at 0 (an arc through +X).
std::vector<AngleArc> join_wrap(ArcSet s) {
  if (s.size() >= 2 && s.front().start_rad <= kEps && s.back().end_rad >= kTwoPi - kEps) {
    s.back().end_rad = kTwoPi + s.front().end_rad;
    s.erase(s.begin());
  }
  return s;
}

// The local uncut chip thickness h(phi) = R - rho(phi) at the point of the tool circle at
// angle phi, rho the distance from the centre to the last point of the ray in the region
// the earlier tooth passes removed, before the circle (Wagih 2023 Section 3: the chip
// between the tool circle and the surface the previous tooth left; the slot's own edges do
// not cut it short). Exact: the maximum over the engaged arcs is taken over every angle
// where h can have a local maximum. rho is the largest of the ray's crossings with the
// exposed arcs; along one arc a crossing distance is smooth, with local minima only towards
// or away from the disc centre, at a tangent direction or at the arc's ends, so h's local
// maxima are at those angles, at kinks where two arcs meet (arc ends) and at the engaged
// arcs' ends. Angles next to a jump or kink are evaluated
// 1e-9 rad to each side (an error below 1e-9 R in h).
class ChipQuery {
 public:
  explicit ChipQuery(double R) : R_(R) {}

  // Collects the boundary pieces near the tool at (cx, cy) and returns h_max over `eng`
  // (sorted arcs within [0, 2 pi]) and its angle.
  std::pair<double, double> h_max(const Removed& removed, double cx, double cy, const ArcSet& eng) {
    cx_ = cx;
    cy_ = cy;
    pieces_.clear();
    for (auto& b : bins_) b.clear();
    cand_.clear();
    const std::vector<int>& near = removed.near_disc(cx, cy);
    for (std::size_t k = 0; k < near.size(); ++k) {
      const Disc& d = removed.disc(near[k]);
      const double ox = d.x - cx, oy = d.y - cy, dist = removed.near_dist(k);
      const double alpha = removed.near_alpha(k);
      for (std::size_t q = 0; q < d.exposed.size(); ++q) {
        const AngleArc& arc = d.exposed[q];
        const auto& e = d.ends[q];
        // Only arcs reaching into the tool disc can bound a chip: the arc's nearest point
        // to the centre is the foot towards it (if on the arc) or an end.
        // The arc's ends relative to the tool centre.
        const double ax = ox + R_ * e.start.c, ay = oy + R_ * e.start.s;
        const double bx = ox + R_ * e.end.c, by = oy + R_ * e.end.s;
        {
          const double foot = wrap(alpha + kPi);
          const bool foot_on =
              (foot >= arc.start_rad && foot <= arc.end_rad) || foot + kTwoPi <= arc.end_rad;
          const double mind = foot_on ? std::abs(dist - R_)
                                      : std::sqrt(std::min(ax * ax + ay * ay, bx * bx + by * by));
          if (mind > R_ * (1 + 1e-9)) continue;
        }
        const int idx = static_cast<int>(pieces_.size());
        pieces_.push_back({d.x, d.y, arc, e});
        // Polar range of the arc seen from the centre, and the candidate angles.
        auto polar = [&](double th) {
          return std::atan2(oy + R_ * std::sin(th), ox + R_ * std::cos(th));
        };
        const double pa = std::atan2(ay, ax), pb = std::atan2(by, bx);
        cand_.push_back(pa);
        cand_.push_back(pb);
        if (dist > 1e-12) {
          cand_.push_back(alpha);
          cand_.push_back(alpha + kPi);
        }
        double lo, sweep;
        if (dist < R_) {  // inside the disc the polar angle grows with the arc angle
          lo = pa;
          sweep = arc.sweep_rad() >= kTwoPi - 1e-12 ? kTwoPi : wrap(pb - pa);
        } else {  // outside: within the tangent wedge, extremes at ends or tangent points
          const double half = std::asin(std::min(1.0, R_ / dist));
          cand_.push_back(alpha - half);
          cand_.push_back(alpha + half);
          double mn = rel(pa - alpha), mx = mn;
          auto take = [&](double v) {
            mn = std::min(mn, v);
            mx = std::max(mx, v);
          };
          take(rel(pb - alpha));
          const double gamma = std::acos(std::min(1.0, R_ / dist));
          for (const double th : {alpha + kPi - gamma, alpha + kPi + gamma}) {
            const double w = wrap(th);
            if ((w >= arc.start_rad && w <= arc.end_rad) ||
                (w + kTwoPi >= arc.start_rad && w + kTwoPi <= arc.end_rad)) {
              take(rel(polar(w) - alpha));
            }
          }
          lo = alpha + mn;
          sweep = mx - mn;
        }
        add_to_bins(idx, lo - 1e-7, sweep + 2e-7);
      }
    }
    for (const auto& a : eng) {
      cand_.push_back(a.start_rad);
      cand_.push_back(a.end_rad);
    }
    double best = -1, best_phi = 0;
    auto try_at = [&](double phi) {
      phi = wrap(phi);
      if (!in_arcs(eng, phi)) return;
      const double h = R_ - rho(phi);
      if (h > best) {
        best = h;
        best_phi = phi;
      }
    };
    for (const double c : cand_) {
      try_at(c - 1e-9);
      try_at(c + 1e-9);
    }
    return {std::max(best, 0.0), best_phi};
  }

 private:
  struct Piece {
    double x, y;
    AngleArc arc;
    ArcEnds ends;
    // Whether the direction (vx, vy) from the centre lies on the arc [start, end), by the
    // signs of cross products with the ends (a ray of the chip query passes an arc's end by
    // at least 1e-9 rad, far outside their rounding).
    [[nodiscard]] bool holds(double vx, double vy) const {
      const double sweep = arc.end_rad - arc.start_rad;
      if (sweep >= kTwoPi) return true;
      const Unit &a = ends.start, &b = ends.end;
      if (sweep <= kPi) return a.c * vy - a.s * vx >= 0 && vx * b.s - vy * b.c > 0;
      // More than a half turn: not in the rest, [end, start).
      return !(b.c * vy - b.s * vx >= 0 && vx * a.s - vy * a.c > 0);
    }
  };
  static constexpr int kBins = 256;

  static double rel(double a) {  // to (-pi, pi]
    a = std::remainder(a, kTwoPi);
    return a;
  }
  static bool in_arcs(const ArcSet& s, double a) {  // closed arcs, wrap-tolerant
    for (const auto& arc : s) {
      if ((a >= arc.start_rad && a <= arc.end_rad) ||
          (a + kTwoPi >= arc.start_rad && a + kTwoPi <= arc.end_rad)) {
        return true;
      }
    }
    return false;
  }
  static int bin_of(double a) {
    return std::min(kBins - 1, static_cast<int>(wrap(a) * (kBins / kTwoPi)));
  }
  void add_to_bins(int idx, double lo, double sweep) {
    if (sweep >= kTwoPi) {
      for (auto& b : bins_) b.push_back(idx);
      return;
    }
    const int b0 = bin_of(lo);
    const int nb = std::min(kBins, static_cast<int>(std::ceil(sweep * (kBins / kTwoPi))) + 1);
    for (int k = 0; k < nb; ++k) bins_[static_cast<std::size_t>((b0 + k) % kBins)].push_back(idx);
  }

  // The last non-stock point of the ray at phi before the circle (0 if none).
  [[nodiscard]] double rho(double phi) const {
    const double ux = std::cos(phi), uy = std::sin(phi), r_max = R_ * (1 + 1e-12);
    double best = 0;
    for (const int idx : bins_[static_cast<std::size_t>(bin_of(phi))]) {
      const Piece& p = pieces_[static_cast<std::size_t>(idx)];
      const double ox = p.x - cx_, oy = p.y - cy_;
      const double t = ox * ux + oy * uy;
      const double q = R_ * R_ - (ox * ox + oy * oy - t * t);
      if (q < 0) continue;
      const double sq = std::sqrt(q);
      for (const double r : {t + sq, t - sq}) {
        if (r <= best || r > r_max) continue;
        if (p.holds(cx_ + r * ux - p.x, cy_ + r * uy - p.y)) {
          best = r;
          break;
        }
      }
    }
    return best;
  }

  double R_;
  double cx_ = 0, cy_ = 0;
  std::vector<Piece> pieces_;
  std::array<std::vector<int>, kBins> bins_;
  std::vector<double> cand_;
};

// Horizontal speed (mm/s) at sample i from the neighbouring samples' arc length and time.
double horizontal_speed(const PathSamples& s, std::size_t i) {
  const std::size_t n = s.size();
  const std::size_t a = i > 0 ? i - 1 : i, b = i + 1 < n ? i + 1 : i;
  const double dt = s.t_s[b] - s.t_s[a];
  if (!(dt > 0)) return 0.0;
  return (s.s_mm[b] - s.s_mm[a]) / dt * std::hypot(s.tx[i], s.ty[i]);
}

// v R * integral over the engaged arcs of max(0, cos(phi - phi_v)) (see the header).
double swept_rate(const PathSamples& s, std::size_t i, double R, const ArcSet& eng) {
  const double v = horizontal_speed(s, i);
  if (v <= 0 || eng.empty()) return 0.0;
  const double pv = std::atan2(s.ty[i], s.tx[i]);
  double integral = 0;
  for (const auto& arc : eng) {
    const double a = arc.start_rad - pv, b = arc.end_rad - pv;
    for (int k = -2; k <= 2; ++k) {  // the advancing half [-pi/2, pi/2] + 2 pi k
      const double lo = std::max(a, -0.5 * kPi + k * kTwoPi);
      const double hi = std::min(b, 0.5 * kPi + k * kTwoPi);
      if (hi > lo) integral += std::sin(hi) - std::sin(lo);
    }
  }
  return v * R * integral;
}

// The lowest height the tool centre reached at a plan place: the plan binned in square cells
// of the side given, each cell's lowest kept (one hash lookup a position).
class Bottoms {
 public:
  explicit Bottoms(double cell_mm) : cell_(cell_mm) {}
  [[nodiscard]] double deepest(double x, double y) const {
    const auto it = cells_.find(key(x, y));
    return it == cells_.end() ? std::numeric_limits<double>::infinity() : it->second;
  }
  void add(double x, double y, double z) {
    const auto [it, fresh] = cells_.try_emplace(key(x, y), z);
    if (!fresh) it->second = std::min(it->second, z);
  }

 private:
  [[nodiscard]] std::uint64_t key(double x, double y) const {
    const auto ix = static_cast<std::int64_t>(std::floor(x / cell_));
    const auto iy = static_cast<std::int64_t>(std::floor(y / cell_));
    return (static_cast<std::uint64_t>(ix) << 32) ^ (static_cast<std::uint64_t>(iy) & 0xffffffffu);
  }
  double cell_;
  std::unordered_map<std::uint64_t, double> cells_;
};

}  // namespace

double stock_top_mm(const Job& job, const Mesh* stock_mesh) {
  if (stock_mesh) return mesh_bounds(*stock_mesh).hi[2];
  if (job.stock_max_mm) return (*job.stock_max_mm)[2];
  return 0.0;
}

EngagementSeries compute_engagement(const PathSamples& smp, const Job& job,
                                    const EngagementOptions& opt) {
  if (opt.steps_per_tooth < 1) {
    throw InputError(fmt::format("steps per tooth must be >= 1, got {}", opt.steps_per_tooth));
  }
  const double R = job.tool.radius_mm();
  // The stock: the slot (|x| <= W/2, 0 <= y <= L, below z = 0), or the job's [stock] box
  // (its x and y range, below its top).
  const double hw = 0.5 * job.slot.width_mm;
  double sx0 = -hw, sx1 = hw, sy0 = 0, sy1 = job.slot.length_mm;
  // The stock mesh given, else the job's [stock] mesh, else the box.
  const Mesh* stock_mesh = opt.stock_mesh ? opt.stock_mesh : job.stock_mesh.get();
  const double top = stock_top_mm(job, stock_mesh);
  std::optional<MeshStock> mesh_stock;
  if (stock_mesh) {
    mesh_stock.emplace(*stock_mesh, R);
  } else if (job.stock_min_mm && job.stock_max_mm) {
    sx0 = (*job.stock_min_mm)[0];
    sy0 = (*job.stock_min_mm)[1];
    sx1 = (*job.stock_max_mm)[0];
    sy1 = (*job.stock_max_mm)[1];
  }
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
  out.swept_rate_mm2_per_s.assign(n, 0.0);
  out.removal_rate_mm3_per_s.assign(n, 0.0);
  out.axial_chip_mm.assign(n, 0.0);
  const double tooth_s = tooth_period_s(job.tool, job.cutting);
  // The end face cuts only stock at least this deep under its edge (mm): the feed marks of a
  // tooth's advance f are f^2 / 8R deep (4.3 um at 0.42 mm a tooth, R = 5 mm: a pocket's
  // link feed), a machine's positioning a few microns.
  constexpr double kFaceGrazeMm = 0.01;
  const double flute = job.tool.flute_length_mm > 0 ? job.tool.flute_length_mm
                                                    : std::numeric_limits<double>::infinity();

  const double omega = rpm_to_rad_per_s(job.cutting.spindle_speed_rpm) *
                       (job.cutting.spindle_direction == SpindleDirection::cw ? -1.0 : 1.0);
  // The box holding every centre in the material (the kernel's grid).
  double bx0 = 0, by0 = 0, bx1 = 0, by1 = 0;
  bool any = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (smp.z_mm[i] >= top) continue;
    if (!any) {
      bx0 = bx1 = smp.x_mm[i];
      by0 = by1 = smp.y_mm[i];
      any = true;
    }
    bx0 = std::min(bx0, smp.x_mm[i]);
    bx1 = std::max(bx1, smp.x_mm[i]);
    by0 = std::min(by0, smp.y_mm[i]);
    by1 = std::max(by1, smp.y_mm[i]);
  }
  // The removed region per Z level (2.5D). A level is the height of horizontal cutting
  // moves; its region holds the discs of the positions made in it. A ramp, plunge or helix
  // below the current level starts a new, empty region (the material under the level is
  // untouched: the descent is a plunge, its feed kept), which becomes the level it comes down
  // to, or hands over to that level's region if it has one (back from a lift). A level takes
  // the discs of the levels below it when it is entered (enter). One level (a slot, its entry
  // helix) is one region, as before levels.
  // docs/models.md section 7.
  constexpr double kLevelTol = kLevelTolMm;
  struct Level {
    double z_mm;  // NaN until its first horizontal cutting position
    std::unique_ptr<Removed> removed;
    std::vector<std::size_t> taken;  // per level below: how many of its discs this one holds
  };
  std::vector<Level> levels;
  Removed* current = nullptr;
  double current_z = std::numeric_limits<double>::quiet_NaN();
  // A level entered (new, back to, or reached by a descent) takes the discs the levels below it
  // within the flute length gained since it last took theirs: their passes removed its
  // material too (a lift's link moves, a climb back up, a pass over pockets cut deeper).
  auto enter = [&](Level& l) {
    l.taken.resize(levels.size(), 0);
    for (std::size_t j = 0; j < levels.size(); ++j) {
      const Level& o = levels[j];
      if (&o == &l || std::isnan(o.z_mm) || !(o.z_mm < l.z_mm - kLevelTol) ||
          l.z_mm - o.z_mm > flute) {
        continue;
      }
      l.taken[j] = l.removed->merge(*o.removed, l.taken[j]);
    }
    current = l.removed.get();
    current_z = l.z_mm;
    return current;
  };
  auto region_of = [&](std::size_t i) -> Removed* {
    const double z = smp.z_mm[i];
    auto start_region = [&](double level_z) -> Level& {
      levels.push_back({level_z, std::make_unique<Removed>(R, bx0, by0, bx1, by1), {}});
      current = levels.back().removed.get();
      current_z = level_z;
      return levels.back();
    };
    if (!current) {
      start_region(std::numeric_limits<double>::quiet_NaN());
    } else if (std::abs(smp.tz[i]) >= 1e-9) {
      // Ramps, plunges, helices: below the current level they cut untouched stock.
      if (!std::isnan(current_z) && z < current_z - kLevelTol) {
        start_region(std::numeric_limits<double>::quiet_NaN());
      }
      return current;
    }
    if (std::abs(smp.tz[i]) >= 1e-9) return current;  // the program's first position
    // A horizontal move: its level's region if it has one (back from a lift, back up).
    if (!std::isnan(current_z) && std::abs(z - current_z) <= kLevelTol) return current;
    for (Level& l : levels) {
      if (std::abs(l.z_mm - z) <= kLevelTol) return enter(l);
    }
    if (std::isnan(current_z)) {  // the level a descent (or the start) came down to
      for (Level& l : levels) {
        if (l.removed.get() == current) {
          l.z_mm = z;
          return enter(l);
        }
      }
    }
    // A new level.
    return enter(start_region(z));
  };
  // An earlier program's removal ([pocket] rest_of): per count of its levels at or below a
  // position's height (by increasing z), the region of the discs that stand for it
  // (rest_disc_centres, a tooth's advance apart on its outline), built when first met.
  const RestStock* earlier = job.pocket.rest.get();
  if (!job.pocket.rest_of.empty() && !earlier) {
    throw Error("compute_engagement: [pocket] rest_of was not read (attach_rest_stock)");
  }
  std::vector<std::unique_ptr<Removed>> rest_regions(earlier ? earlier->levels.size() + 1 : 0);
  auto rest_region = [&](double z) -> const Removed* {
    if (!earlier) return nullptr;
    std::size_t k = 0;
    while (k < earlier->levels.size() && earlier->levels[k].z_mm <= z + kLevelTol) ++k;
    if (k == 0) return nullptr;
    if (!rest_regions[k]) {
      const std::vector<Vec2> c =
          rest_disc_centres(*earlier, earlier->levels[k - 1].z_mm, R, rest_spacing_mm(job));
      double x0 = bx0, y0 = by0, x1 = bx1, y1 = by1;
      for (const Vec2& p : c) {
        x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
        y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
      }
      rest_regions[k] = std::make_unique<Removed>(R, x0, y0, x1, y1);
      for (const Vec2& p : c) rest_regions[k]->add(p.x(), p.y());
    }
    return rest_regions[k].get();
  };
  std::vector<Removed*> home(n, nullptr);  // each cutting position's region
  std::vector<char> above(n, 0);           // a ramp above its region's level: no disc
  ChipQuery chip(R);
  Bottoms bottoms(R / 20);
  std::vector<ArcSet> pending(n);  // exposed arcs of discs waiting for insertion (lag m)
  auto cutting = [&](std::size_t i) { return smp.z_mm[i] < top; };

  for (std::size_t i = 0; i < n; ++i) {
    opt.hooks.step(i, n);
    if (opt.on_samples && i > 0 && i % 256 == 0) opt.on_samples(out, i);  // [0, i) final
    if (cutting(i)) {
      home[i] = region_of(i);
      // A ramp or lift above its level queries the level (whose discs removed that material
      // too) but adds no disc to it: the level's material under it is still there.
      // (region_of leaves the position's region current, current_z its level.)
      above[i] = std::abs(smp.tz[i]) >= 1e-9 && smp.z_mm[i] > current_z + kLevelTol;
    }
    // The surface the previous tooth left: discs up to i - m, in their own regions.
    if (i >= static_cast<std::size_t>(m)) {
      const std::size_t k = i - m;
      if (cutting(k)) {
        if (!above[k]) {
          ArcSet e = m == 1 ? std::move(pending[k]) : home[k]->outside(smp.x_mm[k], smp.y_mm[k]);
          home[k]->insert(smp.x_mm[k], smp.y_mm[k], std::move(e));
        }
      }
    }
    if (!cutting(i)) continue;
    const double cx = smp.x_mm[i], cy = smp.y_mm[i];
    const Removed& removed = *home[i];
    ArcSet free = removed.outside(cx, cy);
    if (m == 1) pending[i] = free;
    ArcSet in_stock =
        mesh_stock ? mesh_stock->inside(cx, cy, R, smp.z_mm[i], std::min(top, smp.z_mm[i] + flute),
                                        std::abs(smp.tz[i]) < 1e-9)
                   : inside_rect(cx, cy, R, sx0, sx1, sy0,
                                 opt.open_ahead ? std::numeric_limits<double>::infinity() : sy1);
    if (const Removed* before = rest_region(smp.z_mm[i])) {
      in_stock = intersect(in_stock, before->outside(cx, cy));
    }
    ArcSet eng = intersect(free, in_stock);
    // A descent in its own region (its level not reached) cuts only what no level at or below
    // its height removed: a lead-in dropping from a link back into a pocket a deeper level has
    // cleared meets air, not a fresh layer (each such level removed its stock up to the
    // flute length above it).
    ArcSet under = in_stock;              // the end face's stock
    std::vector<const Removed*> cleared;  // those levels' regions, for the chip
    if (std::isnan(current_z) && !(eng.empty() && under.empty())) {
      const double z = smp.z_mm[i];
      for (const Level& l : levels) {
        if (std::isnan(l.z_mm) || l.removed.get() == &removed || l.z_mm > z + kLevelTol ||
            z - l.z_mm > flute) {
          continue;
        }
        const ArcSet left = l.removed->outside(cx, cy);
        cleared.push_back(l.removed.get());
        eng = intersect(eng, left);
        under = intersect(under, left);
        if (eng.empty() && under.empty()) break;
      }
    }
    // The end edges' axial cut: a descending position's end face cuts the stock under it that
    // no earlier position removed. In a descent's own region (its level not yet reached) that
    // is all the stock under the face (the region's premise: nothing below the level it left
    // was cut); descending above a level, the part outside the level's region. The area is
    // taken as pi R^2 times the share of the tool circle over it (exact for a face wholly in or
    // out, and for a straight stock edge through its centre). The axial chip is the descent
    // per tooth there. Where an earlier position stood deeper at the same place (in the same
    // R / 20 square of the plan: the pecks of a drilling cycle, a plunge into a hole) the
    // descent cuts only below it.
    // docs/models.md section 7.
    double axial_rate = 0;
    if (i > 0 && smp.z_mm[i] < smp.z_mm[i - 1] && smp.t_s[i] > smp.t_s[i - 1]) {
      const double done = bottoms.deepest(cx, cy);
      const double dz = std::min({smp.z_mm[i - 1], top, done}) - smp.z_mm[i];
      const ArcSet& face = std::isnan(current_z) ? under : eng;
      double share = 0;
      for (const auto& a : face) share += a.sweep_rad();
      share = std::min(1.0, share / kTwoPi);
      // The stock under the face's edge must be kFaceGrazeMm deep (the chip model's depth of
      // the uncut material along the arcs' rays, against the region and each cleared level's):
      // a descent where the tool passed before meets slivers (its samples' discs a tooth apart,
      // the program's rounding to 1e-4 mm) as wide arcs of the circle but fractions of a
      // micron deep, which were read as the rapid's whole descent per tooth (0.4167 mm and 4
      // "descents into stock" on the pocket example, where it had none).
      if (dz > 0 && share > 0 && share < 1) {
        double depth = chip.h_max(removed, cx, cy, face).first;
        for (const Removed* r : cleared)
          depth = std::min(depth, chip.h_max(*r, cx, cy, face).first);
        if (depth < kFaceGrazeMm) share = 0;
      }
      if (dz > 0 && share > 0) {
        const double vz = dz / (smp.t_s[i] - smp.t_s[i - 1]);
        axial_rate = kPi * R * R * share * vz;
        out.axial_chip_mm[i] = vz * tooth_s;
      }
    }
    bottoms.add(cx, cy, smp.z_mm[i]);
    // A tooth cuts with its flutes only what the tooth before it left: that tooth's disc is
    // gone up its flutes, and what lies below it (a descent's new depth, or the layer under
    // the stock's top where the tooth before was above it) is the end edges' axial chip. The
    // 2.5D region holds that disc but where the region changed under the tool: a descent
    // (a ramp, a helix, a lead-in) starts an empty region, a rise above its level (a
    // lead-out) adds no discs, a new level reached by a rise has none of the rise's. The
    // flutes' engagement and chip are taken against that disc here too, the chip at most the
    // horizontal advance per tooth. (The axial chip is not a radial chip: radial_chip_mm.)
    double own_limit = std::numeric_limits<double>::infinity();
    if (i >= static_cast<std::size_t>(m)) {
      const std::size_t k = i - m;
      const double dx = smp.x_mm[k] - cx, dy = smp.y_mm[k] - cy, d = std::hypot(dx, dy);
      // The same centre (a plunge, a dwell): the circle lies on that disc's edge, all cut.
      if (d <= 1e-12 * R) {
        eng.clear();
      } else if (d < 2 * R) {
        subtract(eng, std::atan2(dy, dx), std::acos(d / (2 * R)));
      }
      own_limit = d;
    }
    double total = 0;
    for (const auto& a : eng) total += a.sweep_rad();
    out.engagement_angle_rad[i] = total;
    out.radial_engagement_mm[i] = R * (1 - std::cos(std::min(total, kPi)));
    auto [hmax, hang] = eng.empty() ? std::pair{0.0, 0.0} : chip.h_max(removed, cx, cy, eng);
    // Against the union with the cleared levels' regions the chip is at most each one's (the
    // farthest removed point of a ray is the farther of the two): the smallest, a bound on
    // the safe side (exact where one region holds the other's part of the ray).
    for (const Removed* r : cleared) {
      if (eng.empty()) break;
      const auto [h, a] = chip.h_max(*r, cx, cy, eng);
      if (h < hmax) {
        hmax = h;
        hang = a;
      }
    }
    out.h_max_mm[i] = std::min(hmax, own_limit);
    out.h_max_angle_rad[i] = wrap(hang);
    int teeth = 0;
    for (const double alpha : job.tool.tooth_angles_deg) {
      if (contains(eng, wrap(omega * smp.t_s[i] + deg_to_rad(alpha)))) ++teeth;
    }
    out.teeth_in_cut[i] = teeth;
    out.swept_rate_mm2_per_s[i] = swept_rate(smp, i, R, eng);
    if (!eng.empty()) {
      // The removal rate: each part of the engaged arcs sweeps stock from the position's
      // height up to the nearest level above whose region removed it there (the program's,
      // or an earlier program's: rest_of), or up to the stock's top (at most the flute
      // length).
      const double z = smp.z_mm[i];
      std::vector<std::pair<double, const Removed*>> upper;
      for (const Level& l : levels) {
        if (!std::isnan(l.z_mm) && l.z_mm > z + kLevelTol && l.z_mm < top) {
          upper.emplace_back(l.z_mm, l.removed.get());
        }
      }
      if (earlier) {
        for (const RestStock::Level& l : earlier->levels) {
          if (l.z_mm > z + kLevelTol && l.z_mm < top)
            upper.emplace_back(l.z_mm, rest_region(l.z_mm));
        }
      }
      std::sort(upper.begin(), upper.end(),
                [](const auto& a, const auto& b) { return a.first < b.first; });
      ArcSet rest = eng;
      double rate = 0;
      for (const auto& [level_z, removed_above] : upper) {
        const ArcSet stock_above = removed_above->outside(cx, cy);
        rate += swept_rate(smp, i, R, minus(rest, stock_above)) * std::min(flute, level_z - z);
        rest = intersect(rest, stock_above);
        if (rest.empty()) break;
      }
      rate += swept_rate(smp, i, R, rest) * std::min(flute, top - z);
      out.removal_rate_mm3_per_s[i] = rate;
    }
    out.removal_rate_mm3_per_s[i] += axial_rate;
    out.arcs[i] = join_wrap(std::move(eng));
  }
  return out;
}

PathSamples engagement_samples(const ToolPath& path, const Job& job, int steps_per_tooth) {
  if (steps_per_tooth < 1) {
    throw InputError(fmt::format("steps per tooth must be >= 1, got {}", steps_per_tooth));
  }
  return sample_by_time(path, tooth_period_s(job.tool, job.cutting) / steps_per_tooth);
}

EngagementSeries compute_engagement(const ToolPath& path, const Job& job,
                                    const EngagementOptions& options) {
  return compute_engagement(engagement_samples(path, job, options.steps_per_tooth), job, options);
}

std::vector<Vec2> rest_disc_centres(const RestStock& rest, double z_mm, double radius_mm,
                                    double spacing_mm) {
  if (!(rest.tool_radius_mm >= radius_mm * (1 - 1e-12))) {
    throw InputError(fmt::format(
        "[pocket] rest_of: {}'s tool (D = {:g} mm) is smaller than this job's (D = {:g} mm): "
        "rest machining follows a larger tool",
        rest.name, 2 * rest.tool_radius_mm, 2 * radius_mm));
  }
  if (!(spacing_mm > 0)) throw Error("rest_disc_centres: the spacing must be > 0 mm");
  std::vector<const Contour*> chains;
  constexpr double kBig = std::numeric_limits<double>::infinity();
  double x0 = kBig, y0 = kBig, x1 = -kBig, y1 = -kBig, pad = 0;
  for (const RestStock::Level& l : rest.levels) {
    if (l.z_mm > z_mm + kLevelTolMm) continue;
    for (const Contour& c : l.chains) {
      chains.push_back(&c);
      for (const ContourPiece& p : c.pieces) {
        for (const Vec2& q : {p.start, p.end}) {
          x0 = std::min(x0, q.x()), x1 = std::max(x1, q.x());
          y0 = std::min(y0, q.y()), y1 = std::max(y1, q.y());
        }
        if (p.is_arc()) pad = std::max(pad, p.radius_mm());  // an arc bulges within its radius
      }
    }
  }
  std::vector<Vec2> out;
  if (chains.empty()) return out;
  // Points along the chains at most `step` apart.
  auto along = [&](double step, auto&& f) {
    for (const Contour* c : chains) {
      for (const ContourPiece& p : c->pieces) {
        const int n = std::max(1, static_cast<int>(std::ceil(p.length_mm() / step)));
        for (int k = 0; k <= n; ++k) f(p.point_at(static_cast<double>(k) / n));
      }
    }
  };
  const double grow = rest.tool_radius_mm - radius_mm;
  if (grow < 1e-3) {
    // Tools alike (within a micron, the smaller counted): the discs along the moves themselves.
    along(spacing_mm, [&](const Vec2& p) { out.push_back(p); });
    return out;
  }
  // The region within `grow` of the moves: discs of that radius a fine step apart along them
  // (their scallops step^2 / 8 grow: 0.01 um at 5 mm), in this kernel's removed region; its
  // outline is their exposed arcs.
  const double fine = std::min(spacing_mm, 0.1 * grow);
  const double bx0 = x0 - pad, by0 = y0 - pad, bx1 = x1 + pad, by1 = y1 + pad;
  Removed within(grow, bx0, by0, bx1, by1);
  along(fine, [&](const Vec2& p) { within.add(p.x(), p.y()); });
  within.for_exposed([&](double cx, double cy, const AngleArc& a) {
    const int n = std::max(1, static_cast<int>(std::ceil(a.sweep_rad() * grow / spacing_mm)));
    for (int k = 0; k <= n; ++k) {
      const double th = a.start_rad + a.sweep_rad() * k / n;
      out.emplace_back(cx + grow * std::cos(th), cy + grow * std::sin(th));
    }
  });
  // Inside: a grid of 0.9 R (the outline's discs cover the band within R of it; a point
  // further in lies within 0.64 R of a grid point, itself inside).
  const double g = 0.9 * radius_mm;
  for (double y = by0 - grow + 0.5 * g; y < by1 + grow; y += g) {
    for (double x = bx0 - grow + 0.5 * g; x < bx1 + grow; x += g) {
      if (within.covers(x, y)) out.emplace_back(x, y);
    }
  }
  return out;
}

struct RemovedRegion::Impl {
  Removed removed;
};

RemovedRegion::RemovedRegion(double radius_mm, const Vec2& lo_mm, const Vec2& hi_mm)
    : impl_(std::make_unique<Impl>(
          Impl{Removed(radius_mm, lo_mm.x(), lo_mm.y(), hi_mm.x(), hi_mm.y())})) {}
RemovedRegion::RemovedRegion(RemovedRegion&&) noexcept = default;
RemovedRegion& RemovedRegion::operator=(RemovedRegion&&) noexcept = default;
RemovedRegion::~RemovedRegion() = default;

std::vector<AngleArc> RemovedRegion::uncut_arcs(const Vec2& c) const {
  return join_wrap(impl_->removed.outside(c.x(), c.y()));
}

void RemovedRegion::focus(const Vec2& c, double slack_mm) const {
  impl_->removed.pin(c.x(), c.y(), slack_mm);
}

void RemovedRegion::cut(const Vec2& c) { impl_->removed.add(c.x(), c.y()); }

bool RemovedRegion::contains(const Vec2& p) const { return impl_->removed.covers(p.x(), p.y()); }

}  // namespace trochomill
