// The tool's envelope swept along a path, removed from the tri-dexel workpiece without teeth
// or time steps (include/trochomill/sim.hpp, docs/models.md section 11): the fast way to bring
// the workpiece to the state the earlier part of a cut leaves.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "sim/plane.hpp"
#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"

namespace trochomill {
namespace {

using sim_detail::kInf;

// A piece of the path in plan view at one tip height (the lower of its ends): a chord from
// (ax, ay) to (bx, by), or a circular arc about (cx, cy) of radius rho over the angles
// [th0, th1] (counter-clockwise, at most a quarter turn) whose ends are (ax, ay), (bx, by).
struct Piece {
  double ax, ay, bx, by, z;
  bool arc = false;
  double cx = 0, cy = 0, rho = 0, th0 = 0, th1 = 0;
  // A chord's length and unit direction in the plan frame and in the swapped one ((y, x)),
  // taken once (set by with_direction).
  std::array<double, 3> dir{}, dir_swapped{};
};

// The length and unit direction of the segment (ax, ay)-(bx, by): {L, ux / L, uy / L}.
std::array<double, 3> direction(double ax, double ay, double bx, double by) {
  const double ux = bx - ax, uy = by - ay, L = std::hypot(ux, uy);
  return L > 0 ? std::array<double, 3>{L, ux / L, uy / L} : std::array<double, 3>{0, 0, 0};
}

Piece with_direction(Piece p) {
  p.dir = direction(p.ax, p.ay, p.bx, p.by);
  p.dir_swapped = direction(p.ay, p.ax, p.by, p.bx);
  return p;
}

// The offsets along a line of the points within r of the segment A-B (a capsule), in the
// line's frame: the line is {(t, yl)}, the segment from (ax, ay) to (bx, by). Convex: one
// interval, the hull of the two end discs' chords and the band's.
std::optional<Interval> capsule_on_line(double ax, double ay, double bx, double by,
                                        const std::array<double, 3>& dir, double r, double yl) {
  double lo = kInf, hi = -kInf;
  auto disc = [&](double cx, double cy) {
    const double dy = yl - cy;
    if (dy * dy >= r * r) return;
    const double w = std::sqrt(r * r - dy * dy);
    lo = std::min(lo, cx - w), hi = std::max(hi, cx + w);
  };
  disc(ax, ay);
  disc(bx, by);
  const double L = dir[0];
  if (L > 0) {
    // 0 <= (X - A).u <= L and |(X - A).n| <= r with X = (t, yl): linear in t.
    const double ex = dir[1], ey = dir[2];
    double t0 = -kInf, t1 = kInf;
    auto band = [&](double coef, double rest, double lo_v, double hi_v) {
      // lo_v <= coef t + rest <= hi_v
      if (std::abs(coef) < 1e-15) {
        if (rest < lo_v || rest > hi_v) t0 = kInf, t1 = -kInf;
        return;
      }
      double a = (lo_v - rest) / coef, b = (hi_v - rest) / coef;
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a), t1 = std::min(t1, b);
    };
    band(ex, -ax * ex + (yl - ay) * ey, 0.0, L);
    band(-ey, ax * ey + (yl - ay) * ex, -r, r);
    if (t0 < t1) lo = std::min(lo, t0), hi = std::max(hi, t1);
  }
  if (lo < hi) return Interval{lo, hi};
  return std::nullopt;
}

double dist_to_segment(double px, double py, const Piece& p) {
  const double ux = p.bx - p.ax, uy = p.by - p.ay, l2 = ux * ux + uy * uy;
  double t = l2 > 0 ? ((px - p.ax) * ux + (py - p.ay) * uy) / l2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const double ex = px - p.ax - t * ux, ey = py - p.ay - t * uy;
  return std::sqrt(ex * ex + ey * ey);
}

// Chords of the path between lengths s0 and s1 within `tol` of it (greedy over points `step`
// apart), appended to `out`.
void chords(const ToolPath& path, double s0, double s1, double step, double tol,
            std::vector<Piece>& out) {
  std::vector<Vec3> pts;
  const auto n = static_cast<std::size_t>(std::ceil((s1 - s0) / step));
  for (std::size_t k = 0; k <= n; ++k) {
    pts.push_back(path.point_at_length(std::min(s1, s0 + static_cast<double>(k) * step)));
  }
  std::size_t i = 0;
  while (i + 1 < pts.size()) {
    std::size_t j = i + 1;
    while (j + 1 < pts.size()) {
      // Would the chord i -> j + 1 stay within tol of every point between (and keep z)?
      const Vec3& a = pts[i];
      const Vec3& b = pts[j + 1];
      bool ok = std::abs(b.z() - a.z()) <= tol;
      const Piece trial{a.x(), a.y(), b.x(), b.y(), 0};
      for (std::size_t q = i + 1; ok && q <= j; ++q) {
        ok = dist_to_segment(pts[q].x(), pts[q].y(), trial) <= tol &&
             std::abs(pts[q].z() - a.z()) <= tol;
      }
      if (!ok) break;
      ++j;
    }
    out.push_back(
        {pts[i].x(), pts[i].y(), pts[j].x(), pts[j].y(), std::min(pts[i].z(), pts[j].z())});
    i = j;
  }
}

// The path between t0 and t1 as pieces: its circular arcs in the XY plane exactly (split into
// quarter turns at most), everything else as chords.
std::vector<Piece> pieces_of(const ToolPath& path, double t0_s, double t1_s, double step,
                             double tol) {
  const PathSamples ends = sample_at_times(path, {t0_s, t1_s});
  const double s0 = ends.s_mm[0], s1 = ends.s_mm[1];
  std::vector<Piece> out;
  double pending = s0;  // start of a stretch still to be cut into chords
  for (std::size_t k = path.segment_at_length(s0); k < path.segments().size(); ++k) {
    const Segment& seg = path.segments()[k];
    const double a = std::max(s0, path.segment_start_length_mm(k));
    const double b = std::min(s1, path.segment_start_length_mm(k) + seg.length_mm());
    if (a >= s1) break;
    if (!(b > a) || !seg.is_circular() || !seg.is_flat_xy()) continue;
    if (a > pending) chords(path, pending, a, step, tol, out);
    pending = b;
    const Vec3 c = seg.center();
    const double rho = seg.axis_a().norm();
    const Vec3 pa = path.point_at_length(a);
    const double ta = std::atan2(pa.y() - c.y(), pa.x() - c.x());
    const double span = (b - a) / rho;
    // Counter-clockwise when a x b points up and u increases (or both reversed).
    const bool ccw = (seg.axis_a().x() * seg.axis_b().y() - seg.axis_a().y() * seg.axis_b().x() >
                      0) == (seg.u1() >= seg.u0());
    const double lo = ccw ? ta : ta - span;
    const int parts = std::max(1, static_cast<int>(std::ceil(span / (0.5 * kPi) - 1e-12)));
    for (int q = 0; q < parts; ++q) {
      Piece p{};
      p.arc = true;
      p.cx = c.x(), p.cy = c.y(), p.rho = rho, p.z = pa.z();
      p.th0 = lo + span * q / parts;
      p.th1 = lo + span * (q + 1) / parts;
      p.ax = c.x() + rho * std::cos(p.th0), p.ay = c.y() + rho * std::sin(p.th0);
      p.bx = c.x() + rho * std::cos(p.th1), p.by = c.y() + rho * std::sin(p.th1);
      out.push_back(p);
    }
  }
  if (s1 > pending) chords(path, pending, s1, step, tol, out);
  return out;
}

// The piece's bounding box in plan: {x_lo, x_hi, y_lo, y_hi}.
std::array<double, 4> bbox(const Piece& p) {
  std::array<double, 4> b{std::min(p.ax, p.bx), std::max(p.ax, p.bx), std::min(p.ay, p.by),
                          std::max(p.ay, p.by)};
  if (p.arc) {
    if (sim_detail::contains_angle(p.th0, p.th1, 0)) b[1] = p.cx + p.rho;
    if (sim_detail::contains_angle(p.th0, p.th1, 0.5 * kPi)) b[3] = p.cy + p.rho;
    if (sim_detail::contains_angle(p.th0, p.th1, kPi)) b[0] = p.cx - p.rho;
    if (sim_detail::contains_angle(p.th0, p.th1, 1.5 * kPi)) b[2] = p.cy - p.rho;
  }
  return b;
}

// The points within r of an arc piece on the line {(t, yl)}: up to four intervals (the
// annular sector's, up to two, and the end discs' chords; they may overlap).
int arc_on_line(double cx, double cy, double rho, double th0, double th1, double r, double yl,
                Interval out[4]) {
  int n = 0;
  const double p = yl - cy;
  const double r_out = rho + r, r_in = std::max(0.0, rho - r);
  if (const auto chord = sim_detail::SectorSlicer(th0, th1).on_line(p, r_out)) {
    std::array<Interval, 2> parts{};
    const int np = sim_detail::annulus_parts(p, chord->lo, chord->hi, r_in, r_out, parts);
    for (int k = 0; k < np; ++k) {
      out[n++] = {cx + parts[static_cast<std::size_t>(k)].lo,
                  cx + parts[static_cast<std::size_t>(k)].hi};
    }
  }
  for (const double th : {th0, th1}) {
    const double ex = cx + rho * std::cos(th), ey = cy + rho * std::sin(th);
    const double dy = yl - ey;
    if (dy * dy < r * r) {
      const double w = std::sqrt(r * r - dy * dy);
      out[n++] = {ex - w, ex + w};
    }
  }
  return n;
}

// The piece's points within r on the line {(t, yl)} in the plan frame (swap: the line
// {(yl, t)} instead, t along y).
int piece_on_line(const Piece& p, double r, double yl, bool swap, Interval out[4]) {
  if (p.arc) {
    return swap ? arc_on_line(p.cy, p.cx, p.rho, 0.5 * kPi - p.th1, 0.5 * kPi - p.th0, r, yl, out)
                : arc_on_line(p.cx, p.cy, p.rho, p.th0, p.th1, r, yl, out);
  }
  const auto cap = swap ? capsule_on_line(p.ay, p.ax, p.by, p.bx, p.dir_swapped, r, yl)
                        : capsule_on_line(p.ax, p.ay, p.bx, p.by, p.dir, r, yl);
  if (!cap) return 0;
  out[0] = *cap;
  return 1;
}

double dist_to_piece(double px, double py, const Piece& p) {
  if (!p.arc) return dist_to_segment(px, py, p);
  const double dx = px - p.cx, dy = py - p.cy;
  if (sim_detail::contains_angle(p.th0, p.th1, std::atan2(dy, dx))) {
    return std::abs(std::sqrt(dx * dx + dy * dy) - p.rho);
  }
  const double ax = px - p.ax, ay = py - p.ay, bx = px - p.bx, by = py - p.by;
  return std::sqrt(std::min(ax * ax + ay * ay, bx * bx + by * by));
}

// Pieces in runs of this many consecutive ones: a run's box bounds its pieces' reach on a
// row, so that a row skips whole runs already inside what it removes.
constexpr std::size_t kRun = 8;

// The boxes (in plan) and tip heights of a run of pieces.
struct Run {
  std::size_t first = 0, last = 0;  // pieces [first, last)
  std::array<double, 4> box{kInf, -kInf, kInf, -kInf};
};

// The union of a row's intervals, sorted and disjoint (intervals that touch are merged: a
// dexel subtraction leaves nothing between them either way).
class RowUnion {
 public:
  void clear() { v_.clear(); }
  [[nodiscard]] bool covers(double lo, double hi) const {
    for (const Interval& u : v_) {
      if (u.lo <= lo && hi <= u.hi) return true;
    }
    return false;
  }
  void add(Interval a) {
    std::size_t k = 0;
    while (k < v_.size() && v_[k].hi < a.lo) ++k;
    std::size_t e = k;
    while (e < v_.size() && v_[e].lo <= a.hi) {
      a.lo = std::min(a.lo, v_[e].lo), a.hi = std::max(a.hi, v_[e].hi);
      ++e;
    }
    v_.erase(v_.begin() + static_cast<std::ptrdiff_t>(k),
             v_.begin() + static_cast<std::ptrdiff_t>(e));
    v_.insert(v_.begin() + static_cast<std::ptrdiff_t>(k), a);
  }
  [[nodiscard]] const std::vector<Interval>& intervals() const noexcept { return v_; }

 private:
  std::vector<Interval> v_;
};

// A box's reach within r on the line at `across` (its extent along the line grown by the
// chord at its distance; a margin keeps it above the rounding of the exact pieces'): empty
// when lo > hi.
Interval box_on_line(double a_lo, double a_hi, double c_lo, double c_hi, double r, double across) {
  const double dc = std::max({0.0, c_lo - across, across - c_hi});
  if (!(r > dc)) return {kInf, -kInf};
  const double w = std::sqrt(r * r - dc * dc) + 1e-9;
  return {a_lo - w - 1e-9, a_hi + w + 1e-9};
}

// The distance from (x, y) to a box {x_lo, x_hi, y_lo, y_hi}: a lower bound of the distance to
// anything inside it.
double box_distance(const std::array<double, 4>& b, double x, double y) {
  const double dx = std::max({0.0, b[0] - x, x - b[1]}), dy = std::max({0.0, b[2] - y, y - b[3]});
  return std::sqrt(dx * dx + dy * dy);
}

}  // namespace

double sweep_envelope(const ToolPath& path, const SimTool& tool, TriDexel& work, double t0_s,
                      double t1_s, const RunHooks& hooks) {
  if (!(t1_s > t0_s)) return 0.0;
  const double d = work.boards[0].spacing();
  const double r_off = tool.radial_offset_mm.empty()
                           ? 0.0
                           : std::max(0.0, *std::max_element(tool.radial_offset_mm.begin(),
                                                             tool.radial_offset_mm.end()));
  const double a_off =
      tool.axial_offset_mm.empty()
          ? 0.0
          : *std::min_element(tool.axial_offset_mm.begin(), tool.axial_offset_mm.end());
  const double R = tool.radius_mm + r_off;
  const double top = work.box.hi[2];
  const ToolContour contour(tool);
  // Within this distance of a piece its end face is flat and its flank reaches every height
  // (cylindrical tools: the corner's centre circle; 0 otherwise: no shortcut).
  const double flat_r = tool.lead_rad >= 0.5 * kPi - 1e-12
                            ? std::max(0.0, tool.radius_mm - tool.corner_radius_mm) + r_off
                            : -1.0;
  // Chords within a quarter spacing of the path and at most 1 um: a chord of a curved path
  // falls short of the arc's outer side by its deviation, material the next cut would meet
  // as extra chip.
  std::vector<Piece> pieces =
      pieces_of(path, t0_s, t1_s, std::min(0.05, d), std::min(0.25 * d, 0.001));
  for (Piece& p : pieces) p = with_direction(p);
  const std::size_t np_all = pieces.size();
  std::vector<std::array<double, 4>> boxes(np_all);
  std::vector<double> tips(np_all), heights(np_all);
  double tip_lo = kInf, tip_hi = -kInf;
  for (std::size_t q = 0; q < np_all; ++q) {
    boxes[q] = bbox(pieces[q]);
    tips[q] = pieces[q].z + a_off;
    heights[q] = std::min(tool.flute_length_mm, top - tips[q]);
    if (heights[q] > 0) {
      tip_lo = std::min(tip_lo, tips[q]);
      tip_hi = std::max(tip_hi, tips[q] + heights[q]);
    }
  }
  // Runs of up to kRun pieces at one tip height (a run never spans a change of depth), and the
  // groups of runs at one tip height (the Z board's cut depends on the tip).
  std::vector<Run> runs;
  std::vector<std::size_t> group_start{0};  // runs [group_start[g], group_start[g + 1])
  for (std::size_t q = 0; q < np_all;) {
    Run r;
    r.first = q;
    while (q < np_all && q - r.first < kRun && tips[q] == tips[r.first]) {
      r.box[0] = std::min(r.box[0], boxes[q][0]), r.box[1] = std::max(r.box[1], boxes[q][1]);
      r.box[2] = std::min(r.box[2], boxes[q][2]), r.box[3] = std::max(r.box[3], boxes[q][3]);
      ++q;
    }
    r.last = q;
    if (!runs.empty() && tips[r.first] != tips[runs.back().first]) {
      group_start.push_back(runs.size());
    }
    runs.push_back(r);
  }
  group_start.push_back(runs.size());
  // The groups by tip height (ties in path order), each group's tip and cutting height, and
  // each run's and piece's group: a layer's cutting groups are then found by a search, not a pass
  // over every piece (a plunge's pieces each have their own tip).
  const std::size_t n_groups = group_start.size() - 1;
  std::vector<double> group_tip(n_groups), group_height(n_groups);
  std::vector<std::size_t> by_tip(n_groups), run_group(runs.size()), piece_group(np_all);
  for (std::size_t g = 0; g < n_groups; ++g) {
    group_tip[g] = tips[runs[group_start[g]].first];
    group_height[g] = heights[runs[group_start[g]].first];
    by_tip[g] = g;
    for (std::size_t k = group_start[g]; k < group_start[g + 1]; ++k) {
      run_group[k] = g;
      for (std::size_t q = runs[k].first; q < runs[k].last; ++q) piece_group[q] = g;
    }
  }
  std::stable_sort(by_tip.begin(), by_tip.end(),
                   [&](std::size_t a, std::size_t c) { return group_tip[a] < group_tip[c]; });
  // The work, in strips of whole tiles (each tile is only ever touched by one task: no two
  // threads create or cut the same rays): the Z board's strips of columns along x, the X
  // board's strips of rows along y, the Y board's along x.
  struct Task {
    int board, first, last;  // rows (X, Y boards) or columns (Z board) [first, last]
  };
  std::vector<Task> tasks;
  if (tip_lo < tip_hi) {
    for (int b = 0; b < 3; ++b) {
      const DexelBoard& board = work.boards[static_cast<std::size_t>(b)];
      const int n = b == 1 ? board.count_v() : board.count_u();
      for (int a = 0; a < n; a += DexelBoard::kTile) {
        tasks.push_back({b, a, std::min(n, a + DexelBoard::kTile) - 1});
      }
    }
  }
  // The volume each task removed from the Z board, summed in task order: the same number for
  // any thread count.
  std::vector<double> volumes(tasks.size(), 0.0);
  for (auto& b : work.boards) b.pause_summary();
  SharedProgress progress(hooks, tasks.size());
  tbb::parallel_for(std::size_t{0}, tasks.size(), [&](std::size_t t) {
    if (hooks.cancelled()) return;
    const Task task = tasks[t];
    std::vector<Interval> removed;
    if (task.board == 2) {
      // Z board: rays along z at (x, y) = (u, v). A piece cuts a ray from its tip up to where
      // the contour reaches the ray's distance from it; those height ranges are nested (the
      // nearer, the larger), so the pieces at one tip cut what the nearest one cuts. Per
      // column and tip: the union of the pieces' reach (radius R) on the column; within it,
      // where a piece passes within the flat part of the end face (cylindrical tools: the
      // contour reaches every height there), the whole height; elsewhere (the corner's ring)
      // the nearest piece's distance, runs of pieces farther than the best found skipped.
      DexelBoard& board = work.boards[2];
      double volume = 0;
      RowUnion reach_all, reach_flat;
      Interval segs[6];
      std::size_t hint = 0;
      for (int i = task.first; i <= task.last; ++i) {
        const double x = board.u_of(i);
        for (std::size_t g = 0; g + 1 < group_start.size(); ++g) {
          const std::size_t g0 = group_start[g], g1 = group_start[g + 1];
          const double tip = tips[runs[g0].first], H = heights[runs[g0].first];
          if (!(H > 0)) continue;
          reach_all.clear(), reach_flat.clear();
          for (std::size_t k = g0; k < g1; ++k) {
            const auto& rb = runs[k].box;
            const Interval ra = box_on_line(rb[2], rb[3], rb[0], rb[1], R, x);
            if (ra.lo > ra.hi) continue;
            const bool need_all = !reach_all.covers(ra.lo, ra.hi);
            const Interval rf = box_on_line(rb[2], rb[3], rb[0], rb[1], flat_r, x);
            const bool need_flat = rf.lo <= rf.hi && !reach_flat.covers(rf.lo, rf.hi);
            if (!need_all && !need_flat) continue;
            for (std::size_t q = runs[k].first; q < runs[k].last; ++q) {
              const auto& pb = boxes[q];
              if (need_all) {
                const Interval pr = box_on_line(pb[2], pb[3], pb[0], pb[1], R, x);
                if (pr.lo <= pr.hi && !reach_all.covers(pr.lo, pr.hi)) {
                  const int n = piece_on_line(pieces[q], R, x, true, segs);
                  for (int e = 0; e < n; ++e) reach_all.add(segs[e]);
                }
              }
              if (need_flat) {
                const Interval pr = box_on_line(pb[2], pb[3], pb[0], pb[1], flat_r, x);
                if (pr.lo <= pr.hi && !reach_flat.covers(pr.lo, pr.hi)) {
                  const int n = piece_on_line(pieces[q], flat_r, x, true, segs);
                  for (int e = 0; e < n; ++e) reach_flat.add(segs[e]);
                }
              }
            }
          }
          const auto& flats = reach_flat.intervals();
          std::size_t f = 0;
          for (const Interval& v : reach_all.intervals()) {
            const auto [j0, j1] = board.index_range(false, v.lo, v.hi);
            for (int j = j0; j <= j1; ++j) {
              const double y = board.v_of(j);
              while (f < flats.size() && flats[f].hi < y) ++f;
              removed.clear();
              if (f < flats.size() && flats[f].lo <= y) {
                board.subtract(i, j, tip, tip + H, removed);
              } else {
                // The nearest piece: the last ray's first, then every run not surely farther.
                double best = kInf;
                if (hint >= runs[g0].first && hint < runs[g1 - 1].last) {
                  best = dist_to_piece(x, y, pieces[hint]);
                }
                for (std::size_t k = g0; k < g1; ++k) {
                  if (box_distance(runs[k].box, x, y) > best + 1e-9) continue;
                  for (std::size_t q = runs[k].first; q < runs[k].last; ++q) {
                    if (box_distance(boxes[q], x, y) > best + 1e-9) continue;
                    const double rho = dist_to_piece(x, y, pieces[q]);
                    if (rho < best) best = rho, hint = q;
                  }
                }
                const auto reach = contour.heights_reaching(best - r_off);
                if (!reach) continue;
                board.subtract(i, j, tip + reach->lo, tip + std::min(H, reach->hi), removed);
              }
              for (const Interval& p : removed) volume += (p.hi - p.lo) * d * d;
            }
          }
        }
      }
      volumes[t] = volume;
    } else {
      // X board (rays along x at (y, z) = (u, v)) and Y board (rays along y at (z, x) = (u, v)):
      // per layer and row, the union of the pieces' regions of that height's radius on the row
      // (each piece's exactly, as one subtraction each would remove), then one subtraction per
      // interval of the union. Runs of pieces whose box's reach the union already covers are
      // skipped whole.
      const int b = task.board;
      DexelBoard& board = work.boards[static_cast<std::size_t>(b)];
      const bool z_first = b == 1;
      const bool swap = b == 1;
      const auto [z0, z1] = board.index_range(z_first, tip_lo, tip_hi);
      // Each group's radius on the layer (-1: not cutting there), and the layer's cutting groups
      // with their radii (in tip order) and the last layer's.
      std::vector<double> gr(n_groups, -1.0);
      std::vector<std::pair<std::size_t, double>> cutting, prev_cutting;
      RowUnion row;
      Interval segs[6];
      // The strip's rows' unions (kept while the layers' radii stay the same: above the
      // corner every layer has the same), the runs that reach the strip on this layer, and a
      // few pieces whose intervals covered the last row's union (tried first on the next:
      // neighbouring rows have nearly the same union, and the runs it covers are then skipped
      // at once; next_seeds).
      std::vector<std::vector<Interval>> unions(
          static_cast<std::size_t>(task.last - task.first + 1));
      std::vector<std::size_t> active, seed;
      // The pieces' intervals that grew the row's union (their union is the row's).
      struct Grown {
        double lo, hi;
        std::size_t q;
      };
      std::vector<Grown> grown;
      const double strip_lo = b == 0 ? board.u_of(task.first) : board.v_of(task.first);
      const double strip_hi = b == 0 ? board.u_of(task.last) : board.v_of(task.last);
      bool have_prev = false;
      auto try_piece = [&](std::size_t q, double rq, double line) {
        const auto& pb = boxes[q];
        const Interval pr = swap ? box_on_line(pb[2], pb[3], pb[0], pb[1], rq, line)
                                 : box_on_line(pb[0], pb[1], pb[2], pb[3], rq, line);
        if (pr.lo > pr.hi || row.covers(pr.lo, pr.hi)) return;
        const int np = piece_on_line(pieces[q], rq, line, swap, segs);
        for (int k = 0; k < np; ++k) {
          if (!row.covers(segs[k].lo, segs[k].hi)) {
            row.add(segs[k]);
            grown.push_back({segs[k].lo, segs[k].hi, q});
          }
        }
      };
      // The next row's seeds: few pieces whose intervals cover the row's union (greedy: from
      // each part's start, the grown interval reaching farthest), so that on the next row,
      // nearly the same, they build most of the union at once and the runs inside it are
      // skipped whole.
      auto next_seeds = [&]() {
        seed.clear();
        for (const Interval& u : row.intervals()) {
          double at = u.lo;
          for (;;) {
            const Grown* best = nullptr;
            for (const Grown& g : grown) {
              if (g.lo <= at && g.hi > at && (!best || g.hi > best->hi)) best = &g;
            }
            if (!best) break;
            if (std::find(seed.begin(), seed.end(), best->q) == seed.end()) seed.push_back(best->q);
            at = best->hi;
            if (at >= u.hi) break;
          }
        }
      };
      for (int zl = z0; zl <= z1; ++zl) {
        const double z = z_first ? board.u_of(zl) : board.v_of(zl);
        // The groups cutting on this layer (tips within a flute length below it) and their
        // radii.
        for (const auto& [g, r] : cutting) gr[g] = -1;
        cutting.clear();
        const auto first =
            std::lower_bound(by_tip.begin(), by_tip.end(), z - tool.flute_length_mm - 1e-9,
                             [&](std::size_t g, double tip) { return group_tip[g] < tip; });
        for (auto it = first; it != by_tip.end() && group_tip[*it] <= z; ++it) {
          const std::size_t g = *it;
          const double h = z - group_tip[g];
          if (!(group_height[g] > 0) || h < 0 || h > group_height[g]) continue;
          const double Rh = contour.profile_radius(h) + r_off;
          if (Rh > 0) gr[g] = Rh, cutting.emplace_back(g, Rh);
        }
        if (cutting.empty()) {
          have_prev = false;
          continue;
        }
        if (!have_prev || cutting != prev_cutting) {
          active.clear();
          for (const auto& [g, r] : cutting) {
            for (std::size_t k = group_start[g]; k < group_start[g + 1]; ++k) {
              const auto& rb = runs[k].box;
              const double c_lo = swap ? rb[0] : rb[2], c_hi = swap ? rb[1] : rb[3];
              if (c_lo - r <= strip_hi + 1e-9 && c_hi + r >= strip_lo - 1e-9) active.push_back(k);
            }
          }
          for (int r = task.first; r <= task.last; ++r) {
            const int i = b == 0 ? r : zl, j = b == 0 ? zl : r;
            const double line = b == 0 ? board.u_of(i) : board.v_of(j);
            row.clear();
            grown.clear();
            for (const std::size_t q : seed) {
              if (const double rq = gr[piece_group[q]]; rq > 0) try_piece(q, rq, line);
            }
            for (const std::size_t k : active) {
              const auto& rb = runs[k].box;
              const double rk = gr[run_group[k]];
              const Interval reach = swap ? box_on_line(rb[2], rb[3], rb[0], rb[1], rk, line)
                                          : box_on_line(rb[0], rb[1], rb[2], rb[3], rk, line);
              if (reach.lo > reach.hi || row.covers(reach.lo, reach.hi)) continue;
              for (std::size_t q = runs[k].first; q < runs[k].last; ++q) try_piece(q, rk, line);
            }
            unions[static_cast<std::size_t>(r - task.first)] = row.intervals();
            next_seeds();
          }
          prev_cutting = cutting;
          have_prev = true;
        }
        for (int r = task.first; r <= task.last; ++r) {
          const int i = b == 0 ? r : zl, j = b == 0 ? zl : r;
          for (const Interval& v : unions[static_cast<std::size_t>(r - task.first)]) {
            if (!board.touched(i, j) && !(board.full().hi > v.lo && board.full().lo < v.hi)) {
              continue;
            }
            removed.clear();
            board.subtract(i, j, v.lo, v.hi, removed);
          }
        }
      }
    }
    progress.add(1);
  });
  for (auto& b : work.boards) b.resume_summary();
  double volume = 0;
  for (const double v : volumes) volume += v;
  return volume;
}

}  // namespace trochomill
