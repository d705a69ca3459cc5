// A slot along a drawing's contour (docs/models.md, "Slots along a curve"): the family's
// cycles planned in the straight slot's frame, one at a time, and carried onto the centreline
// by the tube map (x across, y along) -> C(y) + x N(y), C the centreline by arc length and N
// its right-hand normal. The map keeps every point's distance from the centreline (|x| for
// |x| below the radius of curvature), so the tool centre stays within the orbit's half width
// a = (W - D) / 2 of the centreline as in the straight slot; it shortens the steps inside a
// bend (by 1 + kappa x) and stretches them outside. Each cycle's step is the one whose
// steady-state chip in a ring of the bend's curvature equals the straight slot's at [path]
// step, solved with the exact engagement kernel (the chip's judge everywhere else too). The
// mapped cycles are curves no G-code holds, so they are written as tangent-continuous biarcs
// within [machine] arc_tolerance, fitted to the orbit narrowed by that tolerance so that the
// arcs stay within a of the centreline.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "families.hpp"
#include "trochomill/error.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill::path_detail {
namespace {

// The centreline by arc length sigma (mm): point, unit tangent, right-hand normal and signed
// curvature (1/mm, positive turning left). An open one continues straight along its end
// tangents beyond its ends; a closed one wraps.
class Centreline {
 public:
  explicit Centreline(const Contour& c) : c_(c) {
    double s = 0;
    for (const ContourPiece& p : c_.pieces) {
      start_.push_back(s);
      s += p.length_mm();
    }
    length_ = s;
  }
  [[nodiscard]] double length() const { return length_; }
  [[nodiscard]] bool closed() const { return c_.closed; }

  struct Frame {
    Vec2 p, t, n;  // point, tangent, right normal
    double kappa = 0;
  };
  [[nodiscard]] Frame at(double sigma) const {
    double over = 0;
    if (c_.closed) {
      sigma = std::fmod(sigma, length_);
      if (sigma < 0) sigma += length_;
    } else if (sigma < 0) {
      over = sigma;
      sigma = 0;
    } else if (sigma > length_) {
      over = sigma - length_;
      sigma = length_;
    }
    const auto it = std::upper_bound(start_.begin(), start_.end(), sigma);
    const std::size_t i =
        it == start_.begin() ? 0 : static_cast<std::size_t>(it - start_.begin()) - 1;
    const ContourPiece& piece = c_.pieces[i];
    const double len = piece.length_mm();
    const double t = len > 0 ? std::clamp((sigma - start_[i]) / len, 0.0, 1.0) : 0.0;
    Frame f;
    f.t = piece.tangent_at(t);
    f.p = piece.point_at(t) + over * f.t;
    f.n = Vec2(f.t.y(), -f.t.x());
    if (piece.is_arc() && over == 0) f.kappa = (piece.ccw ? 1.0 : -1.0) / piece.radius_mm();
    return f;
  }
  // The curvatures of the pieces the stretch [s0, s1] touches (mm along the centreline).
  [[nodiscard]] std::vector<double> curvatures(double s0, double s1) const {
    std::vector<double> out;
    if (c_.closed && s1 - s0 >= length_) {
      s0 = 0;
      s1 = length_;
    }
    const int laps = c_.closed ? 2 : 1;
    for (int lap = -1; lap < laps; ++lap) {
      const double shift = c_.closed ? lap * length_ : 0.0;
      for (std::size_t i = 0; i < c_.pieces.size(); ++i) {
        const double a = start_[i] + shift, b = a + c_.pieces[i].length_mm();
        if (b < s0 || a > s1) continue;
        const ContourPiece& p = c_.pieces[i];
        out.push_back(p.is_arc() ? (p.ccw ? 1.0 : -1.0) / p.radius_mm() : 0.0);
      }
    }
    if (!c_.closed && (s0 < 0 || s1 > length_)) out.push_back(0.0);  // the straight extensions
    return out;
  }

 private:
  const Contour& c_;
  std::vector<double> start_;
  double length_ = 0;
};

// One segment of a cycle planned in the straight frame (x across, y from the cycle's start)
// carried onto the centreline from arc length `base`: a planar curve at height z.
class Mapped final : public PlanarCurve {
 public:
  Mapped(const Segment& seg, const Centreline& c, double base, double z)
      : seg_(seg), c_(c), base_(base), z_(z) {}
  [[nodiscard]] Vec3 point(double u) const override {
    const Vec3 q = seg_.point_u(u);
    const Centreline::Frame f = c_.at(base_ + q.y());
    const Vec2 p = f.p + q.x() * f.n;
    return Vec3(p.x(), p.y(), z_);
  }
  // d/du of C(y) + x N(y) = T y' (1 + kappa x) + N x' (N' = kappa T for the right normal).
  [[nodiscard]] Vec3 unit_tangent(double u) const override {
    const Vec3 q = seg_.point_u(u), d = seg_.derivative_u(u);
    const Centreline::Frame f = c_.at(base_ + q.y());
    const Vec2 v = f.t * (d.y() * (1 + f.kappa * q.x())) + f.n * d.x();
    const double n = v.norm();
    return n > 0 ? Vec3(v.x() / n, v.y() / n, 0) : Vec3(f.t.x(), f.t.y(), 0);
  }

 private:
  const Segment& seg_;
  const Centreline& c_;
  double base_, z_;
};

// Appends the biarcs of every segment of `local` (planned from y = 0) carried onto the
// centreline from arc length `base`, at height z and the segments' feed. Consecutive pieces
// that are one line (collinear) or one circle (the same centre and radius, turning the same
// way, together at most a half turn: every dialect writes that as one block) are joined: on a
// straight stretch a circular cycle's mapped circle is two half arcs, not the fit's quarters.
void append_mapped(ToolPath& out, const ToolPath& local, const Centreline& c, double base, double z,
                   double tolerance_mm) {
  struct Piece {
    bool line = false;
    Vec3 start, end;
    double cx = 0, cy = 0, r = 0, start_rad = 0, sweep_rad = 0, speed = 0;
  };
  std::optional<Piece> pending;
  const auto flush = [&] {
    if (!pending) return;
    const Piece& p = *pending;
    out.append(p.line ? Segment::line(p.start, p.end, Motion::feed, p.speed)
                      : Segment::arc_xy(p.cx, p.cy, p.r, p.start_rad, p.sweep_rad, z, z,
                                        Motion::feed, p.speed));
    pending.reset();
  };
  const auto joins = [](const Piece& a, const Piece& b) {
    if (a.line != b.line || a.speed != b.speed) return false;
    if (a.line) {
      const Vec3 da = a.end - a.start, db = b.end - b.start;
      const double la = da.norm(), lb = db.norm();
      return la > 0 && lb > 0 && (da / la - db / lb).norm() < 1e-12;
    }
    // Within 1e-6 mm (the fit's centres of one circle differ in the last digits; the arc
    // tolerance is 1e-3 mm by default and a program's resolution 1e-4).
    return std::abs(a.cx - b.cx) < 1e-6 && std::abs(a.cy - b.cy) < 1e-6 &&
           std::abs(a.r - b.r) < 1e-6 && a.sweep_rad * b.sweep_rad > 0 &&
           std::abs(a.sweep_rad + b.sweep_rad) <= kPi + 1e-12;
  };
  const auto push = [&](const Piece& p) {
    if (pending && joins(*pending, p)) {
      pending->sweep_rad += p.sweep_rad;
      // The joined arc's own end (on the first piece's centre), where the next piece starts.
      pending->end = p.line
                         ? p.end
                         : Segment::arc_xy(pending->cx, pending->cy, pending->r, pending->start_rad,
                                           pending->sweep_rad, z, z, Motion::feed, pending->speed)
                               .end();
      return;
    }
    flush();
    pending = p;
  };
  for (const Segment& seg : local.segments()) {
    const Mapped m(seg, c, base, z);
    // Half turns of a curve's parameter, lines whole, then halved until within tolerance.
    const int pieces =
        seg.kind() == Segment::Kind::curve
            ? std::max(1, static_cast<int>(std::ceil(std::abs(seg.u1() - seg.u0()) / kPi)))
            : 1;
    const double u0 = seg.kind() == Segment::Kind::curve ? seg.u0() : 0.0;
    const double u1 = seg.kind() == Segment::Kind::curve ? seg.u1() : 1.0;
    Vec3 from = pending ? pending->end : out.empty() ? m.point(u0) : out.segments().back().end();
    for (const FitArc& a : fit_biarcs(m, u0, u1, pieces, tolerance_mm)) {
      Piece p;
      p.line = a.is_line;
      p.start = from;
      p.end = a.end;
      p.speed = seg.speed_mm_per_min();
      if (!a.is_line) {
        // Through the piece's actual start (the end before it, as computed, which may differ
        // from the fit's start in the last digits: the radius follows it so that the arc
        // starts exactly there), and its end as the segment computes it (where the next
        // piece starts).
        p.cx = a.cx, p.cy = a.cy, p.sweep_rad = a.sweep_rad;
        p.r = std::hypot(from.x() - a.cx, from.y() - a.cy);
        p.start_rad = std::atan2(from.y() - a.cy, from.x() - a.cx);
        p.end =
            Segment::arc_xy(p.cx, p.cy, p.r, p.start_rad, p.sweep_rad, z, z, Motion::feed, p.speed)
                .end();
      }
      push(p);
      from = pending->end;
    }
  }
  flush();
}

// One cycle of the family in the straight frame from y = 0 with step s (the start cap and the
// end cap are whole circles of the orbit: `circle`).
ToolPath local_cycle(const Geometry& g, double s, bool mirror, bool circle) {
  ToolPath local;
  Builder bld(local, mirror);
  bld.start_at(Vec3(-g.a, 0, 0));
  if (circle) {
    bld.curve(Vec3(0, 0, 0), Vec3(-g.a, 0, 0), Vec3(0, g.a, 0), Vec3::Zero(), 0.0, kTwoPi, g.feed);
  } else {
    Geometry gk = g;
    gk.s = s;
    gk.zf = 0;
    emit_cycle(bld, gk, 0.0);
  }
  return local;
}

// How far the family's cycles reach behind their start and beyond their end past what the
// slot's round ends allow (mm): a point (x, y) of a cycle from C(sigma) lies y past C(0) or
// C(L) when the cycle starts there, and is in the slot when within a of that end, so it
// needs -y (behind) or y (beyond) at most sqrt(a^2 - x^2). The cycle without drift (its
// largest reach either way; a drift only moves it forward), every segment at 256 points.
std::pair<double, double> end_overshoot_mm(const Geometry& g, bool mirror) {
  const ToolPath local = local_cycle(g, 0.0, mirror, false);
  double back = 0, front = 0;
  for (const Segment& seg : local.segments()) {
    const bool curve = seg.kind() == Segment::Kind::curve;
    const double u0 = curve ? seg.u0() : 0.0, u1 = curve ? seg.u1() : 1.0;
    for (int k = 0; k <= 256; ++k) {
      const Vec3 p = seg.point_u(u0 + (u1 - u0) * k / 256);
      const double allow = std::sqrt(std::max(0.0, g.a * g.a - p.x() * p.x()));
      back = std::max(back, -p.y() - allow);
      front = std::max(front, p.y() - allow);
    }
  }
  // Rounding (1e-9 of the orbit: a trochoid's circle touches the allowance exactly) is no
  // overshoot; a real one gets a margin for the points between the samples (1e-6 of it).
  const double eps = 1e-9 * g.a;
  return {back > eps ? back + 1e-6 * g.a : 0.0, front > eps ? front + 1e-6 * g.a : 0.0};
}

// The steady-state chip (mm) of the family in a ring of curvature kappa at step s: the largest
// chip of the engagement kernel in the last cycle after enough cycles for the tool to meet
// only material they left (2 (a + R) / s of them).
double ring_chip_mm(const Job& job, const ChipJudge& judge, const Geometry& g, bool mirror,
                    double kappa, double s, double tolerance_mm) {
  const int warm = static_cast<int>(std::ceil(2 * (g.a + g.R) / s)) + 1;
  const double length = (warm + 2) * s + 2 * (g.a + g.R);
  Contour ring;
  if (std::abs(kappa) < 1e-12) {
    ring = Contour::polyline({Vec2(0, 0), Vec2(0, length)}, false);
  } else {
    const double r = 1 / std::abs(kappa), sweep = std::min(length / r, 1.9 * kPi);
    const Vec2 centre(kappa > 0 ? -r : r, 0);
    const double a0 = kappa > 0 ? 0.0 : kPi, a1 = a0 + (kappa > 0 ? sweep : -sweep);
    ring.pieces.push_back(ContourPiece::arc(centre + r * Vec2(std::cos(a0), std::sin(a0)),
                                            centre + r * Vec2(std::cos(a1), std::sin(a1)), centre,
                                            kappa > 0));
  }
  const Centreline c(ring);
  ToolPath path;
  double sigma = g.a + g.R;
  double last_start = 0;
  for (int k = 0; k <= warm; ++k) {
    if (k == warm) last_start = path.length_mm();
    append_mapped(path, local_cycle(g, s, mirror, false), c, sigma, g.zf, tolerance_mm);
    sigma += s;
  }
  Job j = job;
  Box3 box = bounding_box(path);
  j.stock_min_mm = Vec3(box.lo.x() - g.R - 1, box.lo.y() - g.R - 1, g.zf - 0.5);
  j.stock_max_mm = Vec3(box.hi.x() + g.R + 1, box.hi.y() + g.R + 1, 0);
  return judge(j, path, last_start);
}

// The step (mm) of each curvature (1/mm): the one whose ring chip equals the straight slot's
// at the job's step, found by the secant method on the chip (to 0.2 %), cached per curvature.
class StepRule {
 public:
  StepRule(const Job& job, const ChipJudge& judge, const Geometry& g, bool mirror,
           double tolerance_mm)
      : job_(job), judge_(judge), g_(g), mirror_(mirror), tol_(tolerance_mm) {
    target_ = ring_chip_mm(job_, judge_, g_, mirror_, 0.0, g_.s, tol_);
  }
  [[nodiscard]] double target_chip_mm() const { return target_; }
  double step(double kappa) {
    if (std::abs(kappa) < 1e-9) return g_.s;
    const auto it = cache_.find(kappa);
    if (it != cache_.end()) return it->second;
    // The steps a slot allows: above a hundredth of the job's and below the diameter.
    const double lo = 0.01 * g_.s, hi = std::min(1.5 * g_.s, 1.95 * g_.R);
    auto f = [&](double s) {
      return ring_chip_mm(job_, judge_, g_, mirror_, kappa, s, tol_) - target_;
    };
    double s0 = g_.s, f0 = f(s0);
    // First guess: the step outside the bend at the wall stretched back to the straight one.
    double s1 = std::clamp(g_.s / (1 + std::abs(kappa) * 0.5 * g_.W), lo, hi), f1 = f(s1);
    for (int round = 0; round < 12 && std::abs(f1) > 2e-3 * target_; ++round) {
      if (f1 == f0) break;
      const double s2 = std::clamp(s1 - f1 * (s1 - s0) / (f1 - f0), lo, hi);
      s0 = s1;
      f0 = f1;
      s1 = s2;
      f1 = f(s1);
    }
    // Never a chip above the target: step down until below it (the secant may stop above).
    for (int round = 0; f1 > 2e-3 * target_ && round < 20 && s1 > lo; ++round) {
      s1 = std::max(lo, 0.97 * s1);
      f1 = f(s1);
    }
    cache_[kappa] = s1;
    return s1;
  }

 private:
  const Job& job_;
  const ChipJudge& judge_;
  Geometry g_;
  bool mirror_;
  double tol_, target_ = 0;
  std::map<double, double> cache_;
};

// Entry to depth at the centreline's start C (its tangent t, right normal n), arriving at the
// first cycle's start p (on the orbit, a from C). The tool starts at safe z above.
// `z_top`: where feeding starts (the clearance above the top face, or above the level cut
// before). A path that already holds moves is joined by a rapid at safe z; with `link_feed`
// (> 0) the tool is already down at z_top in cleared material (at C, the level before's
// floor below it) and moves on there at that feed to where the entry starts, which lies
// within the orbit of C (plunge, ramp, helix; the outside entry always comes from safe z).
void emit_curve_entry(ToolPath& out, const Geometry& g, const PathSpec& spec, const Vec2& c,
                      const Vec2& t, const Vec2& p, bool mirror, double z_top,
                      double link_feed = 0) {
  auto at = [](const Vec2& q, double z) { return Vec3(q.x(), q.y(), z); };
  bool first = true;
  auto line = [&](const Vec3& a, const Vec3& b, Motion m, double speed) {
    if (first && link_feed > 0 && spec.entry != EntryType::outside) {
      // The descent from safe z becomes a move at z_top from where the tool is.
      first = false;
      const Vec3 here = out.segments().back().end();
      const Vec3 to(b.x(), b.y(), z_top);
      if ((to - here).norm() > 1e-12) out.append(Segment::line(here, to, Motion::feed, link_feed));
      return;
    }
    first = false;
    if (!out.empty() && (out.segments().back().end() - a).norm() > 1e-12) {
      out.append(Segment::line(out.segments().back().end(), a, Motion::rapid, g.rapid));
    }
    out.append(Segment::line(a, b, m, speed));
  };
  switch (spec.entry) {
    case EntryType::outside: {
      // Along the slot's start tangent from outside the stock, as a straight slot's.
      const Vec2 q = p - (g.a + g.R + g.clearance) * t;
      line(at(q, g.safe_z), at(q, z_top), Motion::rapid, g.rapid);
      line(at(q, z_top), at(q, g.zf), Motion::feed, g.entry_feed);
      line(at(q, g.zf), at(p, g.zf), Motion::feed, g.feed);
      return;
    }
    case EntryType::plunge:
      line(at(c, g.safe_z), at(c, z_top), Motion::rapid, g.rapid);
      line(at(c, z_top), at(c, g.zf), Motion::feed, g.entry_feed);
      line(at(c, g.zf), at(p, g.zf), Motion::feed, g.entry_feed);
      return;
    case EntryType::ramp: {
      // Legs across the slot through C, within the orbit (a either side of C).
      const Vec2 u = (p - c).normalized();
      const Vec2 e0 = c - g.a * u, e1 = c + g.a * u;
      const double len = 2 * g.a, drop = z_top - g.zf;
      const double per_leg = len * std::tan(deg_to_rad(spec.entry_angle_deg));
      if (!(per_leg > 1e-9)) {
        throw InputError("[path] entry = \"ramp\": the slot leaves no room for a ramp");
      }
      const int legs = std::max(1, static_cast<int>(std::ceil(drop / per_leg - 1e-12)));
      line(at(e0, g.safe_z), at(e0, z_top), Motion::rapid, g.rapid);
      bool at_far = false;
      for (int k = 1; k <= legs; ++k) {
        const double z = z_top - drop * k / legs;
        line(out.segments().back().end(), at(at_far ? e0 : e1, z), Motion::feed, g.entry_feed);
        at_far = !at_far;
      }
      if (!at_far) line(out.segments().back().end(), at(e1, g.zf), Motion::feed, g.entry_feed);
      line(out.segments().back().end(), at(p, g.zf), Motion::feed, g.entry_feed);
      return;
    }
    case EntryType::helix: {
      const double r = spec.entry_radius_mm > 0 ? spec.entry_radius_mm : 0.5 * g.a;
      if (r > g.a + 1e-12) {
        throw InputError(fmt::format(
            "[path] entry_radius: a helix of radius {:g} mm leaves the slot; at most {:.4g} mm "
            "fits (the orbit's radius)",
            r, g.a));
      }
      // Turning as the orbit turns (counter-clockwise for climb with a cw spindle), ending on the
      // line from C to p; one more turn at depth cleans the bore's floor, then out to p.
      const double dir = mirror ? 1.0 : -1.0;
      const double end = std::atan2(p.y() - c.y(), p.x() - c.x());
      const double turns = (z_top - g.zf) / spec.entry_pitch_mm;
      const double sweep = dir * kTwoPi * turns, start = end - sweep;
      const Vec2 h0 = c + r * Vec2(std::cos(start), std::sin(start));
      line(at(h0, g.safe_z), at(h0, z_top), Motion::rapid, g.rapid);
      if (!(turns > 0)) break;
      out.append(
          Segment::arc_xy(c.x(), c.y(), r, start, sweep, z_top, g.zf, Motion::feed, g.entry_feed));
      out.append(Segment::arc_xy(c.x(), c.y(), r, end, dir * kTwoPi, g.zf, g.zf, Motion::feed,
                                 g.entry_feed));
      line(out.segments().back().end(), at(p, g.zf), Motion::feed, g.entry_feed);
      return;
    }
  }
}

}  // namespace

PlannedPath plan_along_curve(const Job& job, const Geometry& g0, bool mirror,
                             const ChipJudge& judge) {
  const Contour& contour = job.slot.centreline->contour;
  const Centreline c(contour);
  const double tol = job.machine.arc_tolerance_mm;
  PlannedPath out;
  if (g0.type == PathType::linear) {
    // W = D: the tool centre on the centreline.
    if (g0.a > 0) {
      throw InputError(
          "[path] type = \"linear\" along a drawing's contour needs W = D (a slot as wide as "
          "the tool); use a trochoidal family for a wider slot");
    }
    if (job.path.entry == EntryType::helix || job.path.entry == EntryType::ramp) {
      throw InputError(
          "[path] entry: a linear slot along a contour (W = D) has no room beside its start for "
          "a helix or a ramp; use entry = \"plunge\" or \"outside\"");
    }
  } else if (!(g0.a > tol)) {
    throw InputError(fmt::format("[slot] width: a {} path needs a slot wider than the tool",
                                 to_string(g0.type)));
  }
  if (g0.type != PathType::linear && (!(g0.s > 0) || g0.s >= 2 * g0.R)) {
    throw InputError(fmt::format("[path] step: must be in (0, {:g}) mm, got {:g}", 2 * g0.R, g0.s));
  }
  // The orbit narrowed by the arc tolerance (the biarcs stay within a of the centreline) and
  // by the finishing allowance (the cycles leave it on the walls).
  Geometry g = g0;
  const double wall_a = g0.a - tol;  // the finishing pass's offset from the centreline
  if (g.type != PathType::linear) {
    const double a = wall_a - job.slot.finish_allowance_mm;
    if (!(a > 0)) {
      throw InputError("[slot] finish_allowance: the cycles' orbit would vanish; lower it");
    }
    g.b *= a / g0.a;
    g.a = a;
  }
  const double L = c.length();
  const Centreline::Frame f0 = c.at(0);
  const Vec2 p0 = f0.p + (mirror ? g.a : -g.a) * f0.n;  // the first cycle's start

  // Levels of equal depth, each at most max_step_down; each entered from the clearance above
  // the level before (cut already, so the tool descends into air there) and left at safe z.
  const double depth = -g.zf;
  const double step_down = job.slot.max_step_down_mm > 0 ? job.slot.max_step_down_mm : depth;
  const int levels = checked_count(std::ceil(depth / step_down - 1e-9));
  // Every level's cycles at the nominal step, before any work.
  if (g.type != PathType::linear) (void)checked_count(levels * std::ceil(L / g.s));
  std::optional<StepRule> rule;
  if (g.type != PathType::linear) {
    (void)checked_count(std::ceil(L / (0.01 * g.s)));
    rule.emplace(job, judge, g, mirror, tol);
  }
  const double reach = g.a + g.b + g.R;  // how far along a cycle's cut reaches
  // Between levels the tool stays down where it can (every entry but the outside one starts
  // within the orbit of the centreline's start): up to the next level's feeding height, the
  // clearance above the floor just cut, and back along the centreline, all in the slot cut
  // to that depth, as feed moves at the link feed (link_feed_mm_per_min).
  const double link_feed = link_feed_mm_per_min(job.machine);
  const bool stay_down = job.path.entry != EntryType::outside;
  int cycles = 0;
  double steady_length = 0;
  for (int level = 1; level <= levels; ++level) {
    Geometry gl = g;
    gl.zf = -depth * level / levels;
    const double z_top = level == 1 ? g.clearance : -depth * (level - 1) / levels + g.clearance;
    const double down = level > 1 && stay_down ? link_feed : 0.0;
    if (g.type == PathType::linear) {
      emit_curve_entry(out.path, gl, job.path, f0.p, f0.t, f0.p, mirror, z_top, down);
      ToolPath local;
      local.append(Segment::line(Vec3(0, 0, 0), Vec3(0, L, 0), Motion::feed, g.feed));
      out.path.mark_cycle();
      append_mapped(out.path, local, c, 0.0, gl.zf, tol);
      ++cycles;
      steady_length = L;
    } else {
      emit_curve_entry(out.path, gl, job.path, f0.p, f0.t, p0, mirror, z_top, down);
      // The start cap: a whole orbit circle about C(0) (with the tool it covers the round
      // end); it widens the entry's bore to the slot, so the cycles (the marks) start after it.
      append_mapped(out.path, local_cycle(g, 0, mirror, true), c, 0.0, gl.zf, tol);
      // Near the ends of an open centreline, cycles that would reach past the round ends
      // (elliptical with b > a, linear-elliptical's wall moves) give way to circular cycles,
      // whose circles about the centreline stay within a of it; equal steps up to the
      // family's first cycle and from its last.
      const auto [back, front] = c.closed() ? std::pair{0.0, 0.0} : end_overshoot_mm(g, mirror);
      double sigma_first = back, sigma_end = L - front;
      if (sigma_end < sigma_first) sigma_first = sigma_end = L;  // too short: circles only
      Geometry circles = g;
      circles.type = PathType::circular;
      circles.b = g.a;
      const auto step_at = [&](double sigma) {
        double s = g.s;
        for (double kappa : c.curvatures(sigma - reach, sigma + g.s + reach)) {
          s = std::min(s, rule->step(kappa));
        }
        return s;
      };
      const auto emit = [&](const Geometry& gc, double sigma, double s) {
        out.path.mark_cycle();
        const double before = out.path.length_mm();
        append_mapped(out.path, local_cycle(gc, s, mirror, false), c, sigma, gl.zf, tol);
        if (gc.type == g.type && std::abs(s - g.s) < 1e-12) {
          steady_length = out.path.length_mm() - before;
        }
        ++cycles;
        (void)checked_count(cycles);
      };
      const auto equal_circles = [&](double from, double to) {
        if (!(to - from > 1e-9)) return;
        const int n = checked_count(std::ceil((to - from) / step_at(from) - 1e-9));
        for (int k = 0; k < n; ++k) {
          emit(circles, from + (to - from) * k / n, (to - from) / n);
        }
      };
      equal_circles(0.0, sigma_first);
      double sigma = sigma_first;
      while (sigma < sigma_end - 1e-9) {
        const double s = std::min(step_at(sigma), sigma_end - sigma);
        emit(g, sigma, s);
        sigma += s;
      }
      equal_circles(sigma_end, L);
      if (!c.closed()) {
        // The end cap at C(L).
        out.path.mark_cycle();
        append_mapped(out.path, local_cycle(g, 0, mirror, true), c, L, gl.zf, tol);
        ++cycles;
      }
    }
    const Vec3 e = out.path.segments().back().end();
    if (level < levels && stay_down) {
      // In to the centreline's end (the end cap's orbit holds the tool), up to the next
      // level's feeding height there (clear of the walls by the orbit's radius), then back
      // along the centreline to its start (a ring: already there).
      const double z_next = gl.zf + g.clearance;
      const Centreline::Frame fe = c.at(L);
      const Vec3 in(fe.p.x(), fe.p.y(), e.z()), end_c(fe.p.x(), fe.p.y(), z_next);
      if ((in - e).norm() > 1e-12) out.path.append(Segment::line(e, in, Motion::feed, link_feed));
      out.path.append(Segment::line(in, end_c, Motion::feed, link_feed));
      if (!c.closed()) {
        ToolPath back;
        back.append(Segment::line(Vec3(0, L, 0), Vec3(0, 0, 0), Motion::feed, link_feed));
        append_mapped(out.path, back, c, 0.0, z_next, tol);
      }
      continue;
    }
    out.path.append(Segment::line(e, Vec3(e.x(), e.y(), g.safe_z), Motion::rapid, g.rapid));
  }
  if (job.slot.finish_pass && g.type != PathType::linear) {
    // Along the walls at full depth, a from the centreline: the right wall forward, round the
    // far end, back along the left wall and round the near end (a closed centreline: each wall
    // once), counter-clockwise, the walls on the tool's right: climb with a cw spindle, so
    // mirrored where the cycles are not (conventional or a ccw spindle).
    // Down at the centreline's start (cleared), out to the wall, the loop, up at safe z.
    std::vector<ToolPath> loops;
    const auto loop = [&](const auto& build) {
      ToolPath local;
      Builder bld(local, !mirror);
      build(bld);
      loops.push_back(std::move(local));
    };
    const double a = wall_a;
    if (c.closed()) {
      loop([&](Builder& b) {
        b.start_at(Vec3(a, 0, 0));
        b.line_to(Vec3(a, L, 0), Motion::feed, g.feed);
      });
      loop([&](Builder& b) {
        b.start_at(Vec3(-a, L, 0));
        b.line_to(Vec3(-a, 0, 0), Motion::feed, g.feed);
      });
    } else {
      loop([&](Builder& b) {
        b.start_at(Vec3(a, 0, 0));
        b.line_to(Vec3(a, L, 0), Motion::feed, g.feed);
        b.curve(Vec3(0, L, 0), Vec3(a, 0, 0), Vec3(0, a, 0), Vec3::Zero(), 0.0, kPi, g.feed);
        b.line_to(Vec3(-a, 0, 0), Motion::feed, g.feed);
        b.curve(Vec3(0, 0, 0), Vec3(a, 0, 0), Vec3(0, a, 0), Vec3::Zero(), kPi, kTwoPi, g.feed);
      });
    }
    for (const ToolPath& local : loops) {
      const Vec3 q = local.segments().front().start();  // local: x across, y along
      const Centreline::Frame fq = c.at(q.y());
      const Vec2 start = fq.p + q.x() * fq.n;
      const auto at = [](const Vec2& v, double z) { return Vec3(v.x(), v.y(), z); };
      const Vec3 here = out.path.segments().back().end();
      out.path.append(Segment::line(here, at(fq.p, g.safe_z), Motion::rapid, g.rapid));
      out.path.append(
          Segment::line(at(fq.p, g.safe_z), at(fq.p, g.clearance), Motion::rapid, g.rapid));
      out.path.append(
          Segment::line(at(fq.p, g.clearance), at(fq.p, g.zf), Motion::feed, g.entry_feed));
      out.path.append(Segment::line(at(fq.p, g.zf), at(start, g.zf), Motion::feed, g.entry_feed));
      out.path.mark_cycle();
      append_mapped(out.path, local, c, 0.0, g.zf, tol);
      const Vec3 e = out.path.segments().back().end();
      out.path.append(Segment::line(e, Vec3(e.x(), e.y(), g.safe_z), Motion::rapid, g.rapid));
    }
  }
  out.info.trochoid_radius_mm = g.a;
  out.info.semi_axis_feed_mm = g.b;
  out.info.first_cycle_y_mm = 0;
  out.info.cycles = cycles;
  out.info.cycle_length_mm = steady_length;
  out.info.closed_start = job.path.entry != EntryType::outside;
  out.info.levels = levels;
  return out;
}

}  // namespace trochomill::path_detail
