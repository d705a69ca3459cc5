// Time-stepped tri-dexel material removal by the cutting edges' swept wedges, with each
// removed piece assigned to the edge segment that removed it (include/trochomill/sim.hpp,
// docs/models.md section 11).
#include <fmt/format.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>

#include "sim/plane.hpp"
#include "sim/rows.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

using sim_detail::annulus_parts;
using sim_detail::contains_angle;
using sim_detail::kInf;
using sim_detail::rays_maybe;
using sim_detail::row_chords;
using sim_detail::RowChords;
using sim_detail::SectorSides;
using sim_detail::SectorSlicer;

// Steps whose path samples are taken at a time (simulate; 5.8 MB of samples).
constexpr std::size_t kSampleBlock = std::size_t{1} << 16;

// An angle range [a0, a1] with its cosines and sines and the axes it crosses, taken once:
// the bounding boxes of its annular sectors then cost no trigonometry.
struct AngleSpan {
  AngleSpan(double a0_, double a1_)
      : a0(a0_),
        a1(a1_),
        c0(std::cos(a0_)),
        s0(std::sin(a0_)),
        c1(std::cos(a1_)),
        s1(std::sin(a1_)) {
    for (int q = 0; q < 4; ++q)
      axis[q] = a1 - a0 >= kTwoPi || contains_angle(a0, a1, q * 0.5 * kPi);
  }
  // Bounding box of {t (cos a, sin a): r_in <= t <= r_out, a in [a0, a1]} (r_in 0: the
  // sector, with the centre): {x_lo, x_hi, y_lo, y_hi}.
  [[nodiscard]] std::array<double, 4> box(double r_in, double r_out) const {
    std::array<double, 4> b{kInf, -kInf, kInf, -kInf};
    auto add = [&](double x, double y) {
      b[0] = std::min(b[0], x), b[1] = std::max(b[1], x), b[2] = std::min(b[2], y),
      b[3] = std::max(b[3], y);
    };
    for (const double r : {r_in, r_out}) add(r * c0, r * s0), add(r * c1, r * s1);
    if (axis[0]) add(r_out, 0);
    if (axis[1]) add(0, r_out);
    if (axis[2]) add(-r_out, 0);
    if (axis[3]) add(0, -r_out);
    return b;
  }
  double a0, a1, c0, s0, c1, s1;
  bool axis[4]{};
};

std::array<double, 4> annular_box(double a0, double a1, double r_in, double r_out) {
  return AngleSpan(a0, a1).box(std::max(0.0, r_in), r_out);
}

// Whether a ray's intervals hold material in (lo, hi).
bool has_material(std::span<const Interval> ray, double lo, double hi) {
  for (const Interval& v : ray) {
    if (v.hi > lo && v.lo < hi) return true;
    if (v.lo >= hi) break;
  }
  return false;
}

// One tooth's wedge at one step, about one centre.
struct Wedge {
  double cx, cy, tip_z, a0, a1;  // a0 < a1: the wedge at height 0
  double H;                      // cutting height above the tip
  double r_off;                  // the tooth's radial runout offset
  double r_in_drop;  // material lies only beyond profile + r_off - r_in_drop (kInf: anywhere)
  // A closing wedge (about the previous centre, from the shared edge pa on; `run`) also takes
  // the strip between the shared edge about the two centres: the points within `move` of the
  // edge, on its far side, which lie within [a0, a1] only beyond the radius r_old. Ordinary
  // wedges have move 0.
  double move = 0;     // mm, the centre's move between the steps
  double pa = 0;       // rad, the shared edge at height 0
  bool up = true;      // the strip lies on the side of growing angles from pa
  double drop = kInf;  // the annulus's drop (as r_in_drop, also when the search is exhaustive)
  double r_old = 0;    // mm: at and beyond it [a0, a1] holds the strip
  // Along a direction u the drop is at most (dir_x, dir_y).u + dir_c (mm; dir_c infinite: no
  // such bound): see drop_toward.
  double dir_x = 0, dir_y = 0, dir_c = kInf;
};

// The largest (x, y).u over the unit vectors u at angles [a0, a1] (rad): |(x, y)| when the
// range holds its direction, else at an end (the dot product is unimodal around the circle).
double max_dot(double x, double y, double a0, double a1) {
  if (a1 - a0 >= kTwoPi || contains_angle(a0, a1, std::atan2(y, x))) return std::hypot(x, y);
  return std::max(x * std::cos(a0) + y * std::sin(a0), x * std::cos(a1) + y * std::sin(a1));
}

// The wedge's r_in_drop over the angles [a0, a1] (rad): within it, material lies only beyond
// the contour + r_off less this (mm; <= 0: nowhere within the contour).
double drop_toward(const Wedge& w, double a0, double a1, double d) {
  if (std::isinf(w.dir_c) || std::isinf(w.r_in_drop)) return w.r_in_drop;
  return std::min(w.r_in_drop, max_dot(w.dir_x, w.dir_y, a0, a1) + w.dir_c + d);
}

// Whether a closing wedge takes its strip on a layer whose edge lies at `radius` (mm) from its
// centre: where the layer's material (beyond radius - drop) may lie nearer than r_old.
bool needs_strip(const Wedge& w, double radius) {
  return w.move > 0 && std::max(0.0, radius - w.drop) < w.r_old;
}

// A closing wedge's angle range at distance r (mm) from its centre: [a0, a1], widened where the
// strip reaches beyond it (its points at r lie within asin(move / r) of the edge).
std::pair<double, double> closing_angles(const Wedge& w, double r) {
  if (!(w.move > 0) || r >= w.r_old) return {w.a0, w.a1};
  const double ext = std::max(w.a1 - w.a0, r > w.move ? std::asin(w.move / r) : 0.5 * kPi);
  return w.up ? std::pair{w.pa, w.pa + ext} : std::pair{w.pa - ext, w.pa};
}

// Accumulators of one board (merged in board order: the same numbers for any thread count).
struct BoardAcc {
  std::vector<double> seg_h, seg_lo, seg_hi, seg_v, removed_tooth;
  double removed_board = 0;
  std::uint64_t updates = 0;
  std::vector<Interval> removed;
  // The entries of the segments' arrays written since they were last reset, [q_lo, q_hi)
  // (empty when q_lo >= q_hi): the rest hold their defaults (a step engages a few of them).
  std::size_t q_lo = std::numeric_limits<std::size_t>::max(), q_hi = 0;
  void wrote(std::size_t q) { q_lo = std::min(q_lo, q), q_hi = std::max(q_hi, q + 1); }
  // The segments' arrays at their defaults for n entries (only the written ones reset).
  void reset_segments(std::size_t n) {
    if (seg_h.size() != n) {
      seg_h.assign(n, 0.0), seg_lo.assign(n, kInf), seg_hi.assign(n, -kInf), seg_v.assign(n, 0.0);
    } else if (q_lo < q_hi) {
      const auto a = static_cast<std::ptrdiff_t>(q_lo), b = static_cast<std::ptrdiff_t>(q_hi);
      std::fill(seg_h.begin() + a, seg_h.begin() + b, 0.0);
      std::fill(seg_lo.begin() + a, seg_lo.begin() + b, kInf);
      std::fill(seg_hi.begin() + a, seg_hi.begin() + b, -kInf);
      std::fill(seg_v.begin() + a, seg_v.begin() + b, 0.0);
    }
    q_lo = std::numeric_limits<std::size_t>::max(), q_hi = 0;
  }
};

// One step on its way through the pipeline (simulate): its wedges (per tooth, and centre),
// then each board's accumulators.
struct StepWork {
  std::size_t n = 0;          // the step (from 1 in the call)
  double tb = 0;              // s, its end
  std::array<double, 3> c{};  // mm, the centre at its end
  std::vector<Wedge> wedges;
  std::vector<std::size_t> tooth;  // each wedge's tooth
  std::array<BoardAcc, 3> acc;
};

// Steps through the pipeline together, and how many batches are in flight at most: enough
// that the boards' uneven work (one board's cuts heavy while another's are light, by turns
// along the cut) evens out before a stage waits (docs/PERFORMANCE.md: on the Bergmann arc, 6
// in flight left the two cores idle 12 % of the window, 24 about 2 %).
struct Batch {
  std::vector<StepWork> steps;
  std::size_t count = 0;  // the steps it holds (the first `count` of steps)
};
constexpr std::size_t kSimBatches = 24;
// The accumulators a batch holds at most (bytes): it has up to 32 steps, at least one.
constexpr std::size_t kSimBatchBytes = std::size_t{1} << 20;
// A step's bytes in flight (its wedges and three boards' accumulators), for `teeth` teeth of
// `segs` segments each.
std::size_t step_work_bytes(std::size_t teeth, std::size_t segs) {
  return 3 * (4 * teeth * segs + teeth) * sizeof(double) + 2 * teeth * sizeof(Wedge);
}
std::size_t batch_steps(std::size_t teeth, std::size_t segs) {
  return std::clamp<std::size_t>(kSimBatchBytes / step_work_bytes(teeth, segs), 1, 32);
}

class Stepper {
 public:
  Stepper(const SimTool& tool, const SimSettings& s, TriDexel& work)
      : tool_(tool),
        contour_(tool),
        s_(s),
        work_(work),
        d_(work.boards[0].spacing()),
        kappa_(std::tan(tool.helix_rad) / tool.radius_mm),
        segs_(tool.segments()),
        rc_(tool.corner_radius_mm),
        ht_(rc_ * (1 - std::cos(kPi - tool.lead_rad))),
        st_(rc_ * (kPi - tool.lead_rad)),
        inv_sin_(1 / std::sin(tool.lead_rad)) {
    for (int sg = 0; sg <= segs_; ++sg) {
      bounds_.push_back(tool.height_at_length(sg * tool.segment_mm));
    }
    // below_[c]: the inner bounds at or below the height c q (seg_of's start for heights in
    // cell c; the cells up to the top bound).
    cell_ = std::max(bounds_.back(), 1e-9) / kCells;
    below_.resize(kCells + 1);
    for (int c = 0; c <= kCells; ++c) {
      below_[static_cast<std::size_t>(c)] =
          static_cast<int>(std::upper_bound(bounds_.begin() + 1, bounds_.end() - 1, c * cell_) -
                           (bounds_.begin() + 1));
    }
    for (int sg = 0; sg < segs_; ++sg) seg_of_bottom_.push_back(seg_of(seg_bottom(sg)));
    for (const double b : bounds_) bound_length_.push_back(edge_length(b));
  }

  // The Z board for one wedge: columns over the x-extent of the wedge swept over all heights
  // (within the annulus where material can be), rows over that sector on each column's line;
  // then each ray exactly.
  void z_board(std::size_t k, const Wedge& w, BoardAcc& A) {
    DexelBoard& board = work_.boards[2];
    // The tiles the wedge searches, and whether any of their rays held material above its tip
    // (the first kSearched of them; a wedge spans a few).
    int n_searched = 0;
    SearchedTile spare;
    auto searched = [&](int i, int j) -> SearchedTile& {
      const int ti = i / DexelBoard::kTile, tj = j / DexelBoard::kTile;
      for (int q = 0; q < n_searched; ++q) {
        SearchedTile& st = searched_[static_cast<std::size_t>(q)];
        if (st.i / DexelBoard::kTile == ti && st.j / DexelBoard::kTile == tj) return st;
      }
      if (n_searched == kSearched) return spare;
      searched_[static_cast<std::size_t>(n_searched)] = {i, j, false};
      return searched_[static_cast<std::size_t>(n_searched++)];
    };
    const double rmax = tool_.radius_mm + std::max(0.0, w.r_off);
    // The contour's smallest radius over the cutting height (it is unimodal: at an end).
    const double flat = narrowest(w.H) + w.r_off;
    // A closing wedge's strip beyond [a0, a1] where material may lie (nearer than r_old): the
    // rays' angles then depend on their distance (closing_angles); searched within the sector
    // as wide as the strip is at r0, and the disc of radius r0 about the centre.
    const double r_mat = std::max(0.0, flat - w.drop);
    const bool strip = needs_strip(w, flat);
    // Rays nearer the centre than r_lo hold no material (annulus mode): the drop toward the
    // sector's angles at all heights (without a strip, whose angles are wider); none or less
    // than nothing, and the wedge has nothing to cut.
    const double drop = strip ? w.r_in_drop : span_drop(w);
    if (!(drop > 0)) return;
    const double r_lo = std::isinf(drop) ? 0.0 : std::max(0.0, flat - drop);
    const double r_hi = rmax;
    // r0 balances the disc's area (pi r0^2) against the widened sector's (about r_hi^2 move /
    // 2 r0): the rays searched, not the ones cut, which closing_angles decides.
    const double r0 =
        strip ? std::min(w.r_old,
                         std::max({r_mat, 4 * w.move, std::cbrt(r_hi * r_hi * w.move / (2 * kPi))}))
              : 0.0;
    const bool disc = strip && r_mat < r0;
    const auto [wa0, wa1] = strip ? closing_angles(w, r0) : std::pair{w.a0, w.a1};
    const double span_lo = kappa_ >= 0 ? wa0 : wa0 + w.H * kappa_;
    const double span_hi = kappa_ >= 0 ? wa1 + w.H * kappa_ : wa1;
    const bool wide = span_hi - span_lo >= kPi;
    auto bx = wide ? std::array<double, 4>{-r_hi, r_hi, -r_hi, r_hi}
                   : annular_box(span_lo, span_hi, r_lo, r_hi);
    if (disc) {
      bx[0] = std::min(bx[0], -r0), bx[1] = std::max(bx[1], r0);
      bx[2] = std::min(bx[2], -r0), bx[3] = std::max(bx[3], r0);
    }
    const auto [i0, i1] = board.index_range(true, w.cx + bx[0], w.cx + bx[1]);
    std::array<Interval, 2> parts{};
    const SectorSlicer slicer(span_lo - 0.5 * kPi, span_hi - 0.5 * kPi);
    // Without a helix or a strip every ray's angles are [a0, a1]: decided by its sides.
    const SectorSides sides(w.a0, w.a1, kappa_ == 0 && !strip);
    for (int i = i0; i <= i1; ++i) {
      const double dx = board.u_of(i) - w.cx;
      Interval chord{-kInf, kInf};
      if (!wide) {
        auto on = slicer.on_line(-dx, r_hi);
        if (disc && std::abs(dx) < r0) {  // the hull with the disc's chord
          const double c = std::sqrt(r0 * r0 - dx * dx);
          on = on ? Interval{std::min(on->lo, -c), std::max(on->hi, c)} : Interval{-c, c};
        }
        if (!on) continue;
        chord = *on;
      }
      const int np = annulus_parts(dx, chord.lo, chord.hi, r_lo, r_hi, parts);
      for (int q = 0; q < np; ++q) {
        const auto [j0, j1] = board.index_range(false, w.cy + parts[static_cast<std::size_t>(q)].lo,
                                                w.cy + parts[static_cast<std::size_t>(q)].hi);
        for (int jt = j0; jt <= j1;) {
          // A tile's rays at a time: none of them searched where the tile holds nothing above
          // the tip (most of those the wedge crosses: the floor behind the tool).
          const int jt1 = std::min(j1, (jt / DexelBoard::kTile + 1) * DexelBoard::kTile - 1);
          const int j_first = jt;
          jt = jt1 + 1;
          if (!board.may_hold_above(i, j_first, w.tip_z)) continue;
          SearchedTile& st = searched(i, j_first);
          for (int j = j_first; j <= jt1; ++j) {
            // Most rays the wedge crosses were emptied long ago: skip them first.
            if (!has_material(board.intervals(i, j), w.tip_z, w.tip_z + w.H)) continue;
            st.found = true;
            const double dy = board.v_of(j) - w.cy, rho = std::sqrt(dx * dx + dy * dy);
            if (rho > rmax) continue;
            // The contour reaches rho only between these heights (the corner from below, a
            // lead angle from above).
            const auto reach = contour_.heights_reaching(rho - w.r_off);
            if (!reach) continue;
            const double hmin = reach->lo, hmax = reach->hi;
            // (Plain variables, not a structured binding: the lambda below captures them.)
            const auto angles = strip ? closing_angles(w, rho) : std::pair{w.a0, w.a1};
            const double ra0 = angles.first, ra1 = angles.second;
            A.removed.clear();
            auto cut_h = [&](double h_lo, double h_hi) {
              h_lo = std::max(h_lo, hmin);
              h_hi = std::min({h_hi, w.H, hmax});
              if (!(h_hi > h_lo)) return;
              // The ray's material all below the contour at its distance (half the rays that
              // reach this far): the subtraction would find nothing, so it is not called.
              if (!has_material(board.intervals(i, j), w.tip_z + h_lo, w.tip_z + h_hi)) return;
              if (board.subtract(i, j, w.tip_z + h_lo, w.tip_z + h_hi, A.removed) > 0) {
                ++A.updates;
              }
            };
            if (kappa_ == 0) {
              if (sides.inside(dx, dy, rho,
                               [&] { return contains_angle(ra0, ra1, std::atan2(dy, dx)); })) {
                cut_h(0, w.H);
              }
            } else {
              const double th = std::atan2(dy, dx);
              // th + 2 pi m in [a0 + h kappa, a1 + h kappa]: h in [th' - a1, th' - a0] / kappa.
              const double m0 = std::ceil(((kappa_ >= 0 ? ra0 : ra0 + w.H * kappa_) - th) / kTwoPi);
              const double m1 =
                  std::floor(((kappa_ >= 0 ? ra1 + w.H * kappa_ : ra1) - th) / kTwoPi);
              for (double m = m0; m <= m1; m += 1) {
                const double tt = th + kTwoPi * m;
                const double ha = (tt - ra1) / kappa_, hb = (tt - ra0) / kappa_;
                cut_h(std::min(ha, hb), std::max(ha, hb));
              }
            }
            for (const Interval& p : A.removed) {
              A.removed_tooth[k] += (p.hi - p.lo) * d_ * d_;
              A.removed_board += (p.hi - p.lo) * d_ * d_;
              // The radial depth on a vertical ray is the contour radius less rho, largest where
              // the contour is widest: each segment the piece spans takes it there (exact: no
              // sampling needed), times the edge's sine for the thickness normal to the edge.
              const double h_lo = p.lo - w.tip_z, h_hi = p.hi - w.tip_z;
              for (int sg = seg_of(h_lo), sg1 = seg_of(h_hi); sg <= sg1; ++sg) {
                const double a = std::max(h_lo, seg_bottom(sg));
                const double h = tool_.widest_height(a, std::min(h_hi, seg_top(sg)));
                const double b = std::min(h_hi, seg_top(sg));
                if (!(b > a)) continue;  // the piece only touches this segment
                A.wrote(k * static_cast<std::size_t>(segs_) + static_cast<std::size_t>(sg));
                A.seg_v[k * static_cast<std::size_t>(segs_) + static_cast<std::size_t>(sg)] +=
                    (b - a) * d_ * d_;
                // (A piece's part that starts at the segment's bottom: seg_of of that bound,
                // taken once for the tool.)
                if (note_at(A, k,
                            a == seg_bottom(sg) ? seg_of_bottom_[static_cast<std::size_t>(sg)]
                                                : seg_of(a),
                            (contour_.profile_radius(h) + w.r_off - rho) * contour_.edge_sine(h))) {
                  // The engaged width: the pieces' extent along the segment.
                  extend(A, k, a, b);
                }
              }
            }
          }
        }
      }
    }
    // The tiles searched in vain: their bounds made exact (a cut since may have left them
    // nothing above the tip, and the next wedges then pass them by). A tile is read again only
    // after a cut in it.
    for (int q = 0; q < n_searched; ++q) {
      const SearchedTile& st = searched_[static_cast<std::size_t>(q)];
      if (!st.found) board.tighten_top(st.i, st.j);
    }
  }

  // The X (b = 0) or Y (b = 1) board for one wedge: per height level, the rows within the
  // wedge's extent at that height, then each ray's interval exactly. Board 0: rays along x at
  // (y, z) = (u, v); board 1: rays along y at (z, x) = (u, v).
  void xy_board(int b, std::size_t k, const Wedge& w, BoardAcc& A) {
    DexelBoard& board = work_.boards[static_cast<std::size_t>(b)];
    const bool z_first = b == 1;  // board 1's u is z; board 0's v is z
    const auto [z0, z1] = board.index_range(z_first, w.tip_z, w.tip_z + w.H);
    std::array<Interval, 2> parts{};
    // Without a helix every layer has the wedge's angles: their trigonometry once.
    std::optional<AngleSpan> flat_span;
    std::optional<SectorSlicer> flat_slicer;
    if (kappa_ == 0) {
      flat_span.emplace(w.a0, w.a1);
      flat_slicer.emplace(b == 0 ? SectorSlicer(w.a0, w.a1)
                                 : SectorSlicer(w.a0 - 0.5 * kPi, w.a1 - 0.5 * kPi));
    }
    // Layers in bundles of kBundle: the summaries are asked once for a bundle (the box of its
    // sector from the narrowest layer's annulus to the widest layer's radius, grown by a
    // spacing, holds each layer's box), and a bundle with nothing is skipped whole; the tooth
    // is out of the cut most of its turn. A bundle is thin enough that its annulus stays
    // about as narrow as a layer's (the whole wedge's would reach into the wall under the
    // corner, where every layer's radius differs).
    // The drop toward the wedge's angles: without a helix the same on every layer. An
    // ordinary wedge (no strip) with nothing beyond its contour on any layer is done.
    const double all_drop = span_drop(w);
    if (!(w.move > 0) && !(all_drop > 0)) return;
    for (int zl = z0; zl <= z1; ++zl) {
      if (!s_.exhaustive && (zl == z0 || zl % kBundle == 0)) {
        // Bundles aligned to kBundle layers: never across a tile (kTile is a multiple).
        const int end = std::min(z1, (zl / kBundle + 1) * kBundle - 1);
        if (!bundle_may_hold(b, board, w, zl, end, flat_span ? &*flat_span : nullptr)) {
          zl = end;
          continue;
        }
      }
      const double z = z_first ? board.u_of(zl) : board.v_of(zl);
      const double h = z - w.tip_z;
      if (h < 0 || h > w.H) continue;
      const double R_h = contour_.profile_radius(h) + w.r_off;
      if (!(R_h > 0)) continue;
      const double ah0 = w.a0 + h * kappa_, ah1 = w.a1 + h * kappa_;
      // A closing wedge's strip, where material may lie within it nearer than r_old; else the
      // drop toward this layer's angles (none or less: nothing on this layer).
      const bool strip = needs_strip(w, R_h);
      const double drop = strip         ? w.r_in_drop
                          : kappa_ == 0 ? all_drop
                                        : drop_toward(w, ah0, ah1, d_);
      if (!(drop > 0)) continue;
      const double r_in = std::isinf(drop) ? 0.0 : std::max(0.0, R_h - drop);
      const auto bx = flat_span ? flat_span->box(r_in, R_h) : annular_box(ah0, ah1, r_in, R_h);
      const SectorSlicer slicer = flat_slicer ? *flat_slicer
                                  : b == 0    ? SectorSlicer(ah0, ah1)
                                              : SectorSlicer(ah0 - 0.5 * kPi, ah1 - 0.5 * kPi);
      int sg_h = -1, sg_mid = -1;
      double sine = 0;
      // Cuts [lo, hi] (offsets along the row from along_c, the row at distance perp from the
      // centre) from ray (i, j) and records the chip.
      auto cut = [&](int i, int j, double along_c, double perp, double lo, double hi) {
        A.removed.clear();
        if (board.subtract(i, j, along_c + lo, along_c + hi, A.removed) > 0) ++A.updates;
        if (A.removed.empty()) return;
        if (sg_h < 0) {  // the layer's segments and edge sine, once a layer cuts
          sg_h = seg_of(h);
          sg_mid = seg_of(0.5 * ((h - 0.5 * d_) + (h + 0.5 * d_)));
          sine = contour_.edge_sine(h);
        }
        for (const Interval& p : A.removed) {
          A.removed_board += (p.hi - p.lo) * d_ * d_;
          // The piece's point nearest the centre: the perpendicular's foot, clamped.
          const double t = std::clamp(0.0, p.lo - along_c, p.hi - along_c);
          if (note_at(A, k, sg_h, (R_h - std::sqrt(perp * perp + t * t)) * sine)) {
            // One layer: a spacing of height.
            extend_at(A, k, sg_mid, h - 0.5 * d_, h + 0.5 * d_);
          }
        }
      };
      // The same when the ray's annulus part holds material (only there can it lie).
      auto cut_row = [&](int i, int j, double along_c, double perp, double lo, double hi) {
        const int np = annulus_parts(perp, lo, hi, r_in, R_h, parts);
        const std::span<const Interval> found = board.intervals(i, j);
        for (int q = 0; q < np; ++q) {
          if (has_material(found, along_c + parts[static_cast<std::size_t>(q)].lo,
                           along_c + parts[static_cast<std::size_t>(q)].hi)) {
            cut(i, j, along_c, perp, lo, hi);
            return;
          }
        }
      };
      if (strip) {
        strip_rows(b, board, w, zl, w.pa + h * kappa_, R_h, r_in, cut_row);
      }
      // Rows: board 0 over y (its u), board 1 over x (its v).
      const auto [r0, r1] = b == 0 ? board.index_range(true, w.cy + bx[2], w.cy + bx[3])
                                   : board.index_range(false, w.cx + bx[0], w.cx + bx[1]);
      // The tiles' summaries: nothing along these rows within the sector's extent, nothing to
      // do on this layer (the tooth is out of the cut most of its turn).
      if (!s_.exhaustive && r0 <= r1) {
        const bool hold = b == 0 ? board.may_hold(r0, r1, zl, zl, w.cx + bx[0], w.cx + bx[1])
                                 : board.may_hold(zl, zl, r0, r1, w.cy + bx[2], w.cy + bx[3]);
        if (!hold) continue;
      }
      if (r0 > r1) continue;
      // The rows' chords and annulus parts, all at once (vectorised; board 0's rows y = u
      // along x, board 1's x = v along y, turned by -90 degrees: (x, y) -> (y, -x)); then
      // whether each row's ray may hold material in its parts, the rays of a tile read a
      // vector at a time; then those rays checked and cut in row order.
      RowChords& rc = rows_[static_cast<std::size_t>(b)];
      const int n = r1 - r0 + 1;
      row_chords(slicer.coeffs(), b == 0 ? board.u0() : board.v0(), d_, r0, n, b == 0 ? w.cy : w.cx,
                 b == 1, R_h, r_in, rc);
      const double along_c = b == 0 ? w.cx : w.cy;
      for (int q = 0; q < n;) {
        const int r = r0 + q, run = std::min(n - q, DexelBoard::kTile - r % DexelBoard::kTile);
        if (const Dexel* rays = board.row_rays(b == 0 ? r : zl, b == 0 ? zl : r)) {
          rays_maybe(reinterpret_cast<const double*>(rays), run, q, along_c, rc);
        } else {  // an untouched tile: its rays hold the stock, the scalar check decides
          std::fill_n(rc.maybe.begin() + q, run, 1.0);
        }
        q += run;
      }
      for (int q = 0; q < n; ++q) {
        const auto u = static_cast<std::size_t>(q);
        if (rc.maybe[u] == 0) continue;
        const int i = b == 0 ? r0 + q : zl, j = b == 0 ? zl : r0 + q;
        const std::span<const Interval> found = board.intervals(i, j);
        if ((rc.a_lo[u] < rc.a_hi[u] &&
             has_material(found, along_c + rc.a_lo[u], along_c + rc.a_hi[u])) ||
            (rc.b_lo[u] < rc.b_hi[u] &&
             has_material(found, along_c + rc.b_lo[u], along_c + rc.b_hi[u]))) {
          cut(i, j, along_c, rc.perp[u], rc.lo[u], rc.hi[u]);
        }
      }
    }
  }

  // The rows of board b (0 or 1) at layer zl crossing a closing wedge's strip at that layer
  // (the shared edge at angle a, the contour radius R_h): the points w.c + t u + s v with
  // u = (cos a, sin a), v its normal on the strip's side, t >= 0, 0 <= s <= move, within R_h of
  // the centre. Each row's part of it, as cut_row(i, j, along_c, perp, lo, hi) wants it;
  // only where material may lie, at r_in or more from the centre (t >= sqrt(r_in^2 - move^2)).
  template <class CutRow>
  void strip_rows(int b, const DexelBoard& board, const Wedge& w, int zl, double a, double R_h,
                  double r_in, CutRow& cut_row) const {
    const double ux = std::cos(a), uy = std::sin(a);
    const double vx = w.up ? -uy : uy, vy = w.up ? ux : -ux;
    const double t_min = r_in > w.move ? std::sqrt(r_in * r_in - w.move * w.move) : 0.0;
    // The strip's extent across the rows: its corners, within the disc. (From t = 0: a row
    // along the strip's edge through the centre stays a row of it whatever the rounding.)
    double lo_r = kInf, hi_r = -kInf;
    for (const double t : {0.0, R_h}) {
      for (const double sv : {0.0, w.move}) {
        const double c = b == 0 ? t * uy + sv * vy : t * ux + sv * vx;
        lo_r = std::min(lo_r, c), hi_r = std::max(hi_r, c);
      }
    }
    lo_r = std::max(lo_r, -R_h), hi_r = std::min(hi_r, R_h);
    if (!(hi_r > lo_r)) return;
    const auto [r0, r1] = b == 0 ? board.index_range(true, w.cy + lo_r, w.cy + hi_r)
                                 : board.index_range(false, w.cx + lo_r, w.cx + hi_r);
    // Along the row (offset x from the centre's projection): f0 + f1 x within [lo, hi].
    auto clip = [](double f0, double f1, double lo, double hi, double& x0, double& x1) {
      if (std::abs(f1) < 1e-12) {
        if (f0 < lo || f0 > hi) x1 = x0 - 1;  // empty
        return;
      }
      const double p = (lo - f0) / f1, q = (hi - f0) / f1;
      x0 = std::max(x0, std::min(p, q)), x1 = std::min(x1, std::max(p, q));
    };
    for (int r = r0; r <= r1; ++r) {
      // Board 0: rows y = u along x; board 1: rows x = v along y.
      const double perp = b == 0 ? board.u_of(r) - w.cy : board.v_of(r) - w.cx;
      if (perp * perp >= R_h * R_h) continue;
      const double half = std::sqrt(R_h * R_h - perp * perp);
      double x0 = -half, x1 = half;
      // t = q.u + x e.u and s = q.v + x e.v, with q the row's offset and e its direction.
      const double qu = b == 0 ? perp * uy : perp * ux, eu = b == 0 ? ux : uy;
      const double qv = b == 0 ? perp * vy : perp * vx, ev = b == 0 ? vx : vy;
      clip(qu, eu, t_min, kInf, x0, x1);
      clip(qv, ev, 0.0, w.move, x0, x1);
      if (!(x1 > x0)) continue;
      const int i = b == 0 ? r : zl, j = b == 0 ? zl : r;
      cut_row(i, j, b == 0 ? w.cx : w.cy, perp, x0, x1);
    }
  }

  static constexpr int kBundle = 16;
  // The Z board's tiles one wedge searched (z_board).
  struct SearchedTile {
    int i = 0, j = 0;    // a ray of the tile
    bool found = false;  // a ray of it held material within the wedge's heights
  };
  static constexpr int kSearched = 16;
  std::array<SearchedTile, kSearched> searched_{};
  static_assert(DexelBoard::kTile % kBundle == 0);

  // Whether the layers [l0, l1] of board b (0 or 1) may hold material in wedge w's sectors
  // (false only when the summaries are sure they do not).
  // `flat`: the wedge's angles' span when they are the same on every layer (no helix).
  bool bundle_may_hold(int b, const DexelBoard& board, const Wedge& w, int l0, int l1,
                       const AngleSpan* flat) const {
    const bool z_first = b == 1;
    const double h0 = (z_first ? board.u_of(l0) : board.v_of(l0)) - w.tip_z;
    const double h1 = (z_first ? board.u_of(l1) : board.v_of(l1)) - w.tip_z;
    const double lo = std::max(0.0, h0), hi = std::min(w.H, h1);
    if (!(hi >= lo)) return false;  // no layer of the bundle is on the edge
    // The contour is unimodal: narrowest at an end of [lo, hi], widest at widest_height.
    const double narrowest =
        std::min(contour_.profile_radius(lo), contour_.profile_radius(hi)) + w.r_off;
    const double widest = contour_.profile_radius(tool_.widest_height(lo, hi)) + w.r_off;
    if (!(widest > 0)) return false;
    // A closing wedge's strip lies within its move of the shared edge (from the centre out):
    // the sector's box from the centre, grown by the move.
    const bool strip = needs_strip(w, narrowest);
    const double r_in =
        std::isinf(w.r_in_drop) || strip ? 0.0 : std::max(0.0, narrowest - w.r_in_drop - d_);
    const double span_lo = kappa_ >= 0 ? w.a0 + lo * kappa_ : w.a0 + hi * kappa_;
    const double span_hi = kappa_ >= 0 ? w.a1 + hi * kappa_ : w.a1 + lo * kappa_;
    const double r_out = widest + d_;
    const auto bx = span_hi - span_lo >= kPi ? std::array<double, 4>{-r_out, r_out, -r_out, r_out}
                    : flat                   ? flat->box(r_in, r_out)
                                             : annular_box(span_lo, span_hi, r_in, r_out);
    const double grow = d_ + (strip ? w.move : 0.0);
    const double x_lo = w.cx + bx[0] - grow, x_hi = w.cx + bx[1] + grow;
    const double y_lo = w.cy + bx[2] - grow, y_hi = w.cy + bx[3] + grow;
    if (b == 0) {
      const auto [r0, r1] = board.index_range(true, y_lo, y_hi);
      return r0 <= r1 && board.may_hold(r0, r1, l0, l1, x_lo, x_hi);
    }
    const auto [r0, r1] = board.index_range(false, x_lo, x_hi);
    return r0 <= r1 && board.may_hold(l0, l1, r0, r1, y_lo, y_hi);
  }

  // SimTool::edge_length_at with the constants taken once.
  [[nodiscard]] double edge_length(double h) const {
    h = std::max(0.0, h);
    if (h <= ht_ && rc_ > 0) return rc_ * std::acos(std::clamp(1 - h / rc_, -1.0, 1.0));
    return st_ + (h - ht_) * inv_sin_;
  }
  // edge_length(h) for a height h within segment sg, its bounds' taken once for the tool
  // (an engaged part of a segment often ends on one).
  [[nodiscard]] double edge_length_in(int sg, double h) const {
    const auto u = static_cast<std::size_t>(sg);
    if (h == bounds_[u]) return bound_length_[u];
    if (h == bounds_[u + 1]) return bound_length_[u + 1];
    return edge_length(h);
  }
  [[nodiscard]] int segs() const noexcept { return segs_; }
  // The contour's smallest radius over heights [0, H] (mm; unimodal: at an end).
  [[nodiscard]] double narrowest(double H) const {
    return std::max(0.0, std::min(contour_.profile_radius(0), contour_.profile_radius(H)));
  }
  // The wedge's drop toward its angles at all heights [0, H] (with a helix they turn).
  [[nodiscard]] double span_drop(const Wedge& w) const {
    return drop_toward(w, kappa_ >= 0 ? w.a0 : w.a0 + w.H * kappa_,
                       kappa_ >= 0 ? w.a1 + w.H * kappa_ : w.a1, d_);
  }

 private:
  // The segment holding height h: floor(edge length / segment length), clamped. Away from the
  // segments' bounds (their heights) the bounds decide it: the edge's length grows at least
  // as fast as the height (slope >= 1), so a height more than kBoundSlack from a bound lies on
  // the same side of it by length too, far beyond the length's rounding; nearer, the length
  // decides (an arc cosine on the corner).
  int seg_of(double h) const {
    if (h <= 0) return 0;  // the tip (a flat bottom's cut): the first segment, without the arc
    // The inner bounds at or below h (as std::upper_bound counts them): from those at or
    // below its cell's start on, one at a time (a cell holds a few bounds at most).
    int sg = segs_ - 1;
    if (h < kCells * cell_) {
      const auto c = static_cast<std::size_t>(h / cell_);
      sg = below_[std::min(c, below_.size() - 1)];
      // (h / cell_ may round up across a cell's start: then step back.)
      while (sg > 0 && bounds_[static_cast<std::size_t>(sg)] > h) --sg;
      while (sg < segs_ - 1 && bounds_[static_cast<std::size_t>(sg) + 1] <= h) ++sg;
    } else if (!(h >= kCells * cell_)) {  // NaN: as std::upper_bound takes it
      const auto inner0 = bounds_.begin() + 1, inner1 = bounds_.end() - 1;
      sg = static_cast<int>(std::upper_bound(inner0, inner1, h) - inner0);
    }  // (at or above the top bound every inner bound lies below: the last segment)
    if ((sg == 0 || h - seg_bottom(sg) > kBoundSlack) &&
        (sg == segs_ - 1 || seg_top(sg) - h > kBoundSlack)) {
      return sg;
    }
    return std::clamp(static_cast<int>(edge_length(h) / tool_.segment_mm), 0, segs_ - 1);
  }
  static constexpr double kBoundSlack = 1e-9;  // mm
  // The segment's height range.
  double seg_bottom(int sg) const { return bounds_[static_cast<std::size_t>(sg)]; }
  double seg_top(int sg) const { return bounds_[static_cast<std::size_t>(sg) + 1]; }
  // Records a chip (mm) of tooth k at height h above its tip. Chips thinner than
  // chip_sampling are slivers of the discretisation, not engagement: not recorded.
  bool note(BoardAcc& A, std::size_t k, double h, double chip) const {
    return note_at(A, k, seg_of(h), chip);
  }
  // The same in segment sg (seg_of(h)).
  bool note_at(BoardAcc& A, std::size_t k, int sg, double chip) const {
    if (chip < s_.chip_sampling_mm) return false;
    A.wrote(k * static_cast<std::size_t>(segs_) + static_cast<std::size_t>(sg));
    double& v = A.seg_h[k * static_cast<std::size_t>(segs_) + static_cast<std::size_t>(sg)];
    v = std::max(v, chip);
    return true;
  }
  // Extends the engaged part of tooth k's segment at the middle of [h0, h1] (heights above
  // the tip, clipped to the segment).
  void extend(BoardAcc& A, std::size_t k, double h0, double h1) const {
    extend_at(A, k, seg_of(0.5 * (h0 + h1)), h0, h1);
  }
  // The same in segment sg (seg_of of the middle).
  void extend_at(BoardAcc& A, std::size_t k, int sg, double h0, double h1) const {
    const std::size_t q = k * static_cast<std::size_t>(segs_) + static_cast<std::size_t>(sg);
    A.wrote(q);
    A.seg_lo[q] = std::min(A.seg_lo[q], std::max(h0, seg_bottom(sg)));
    A.seg_hi[q] = std::max(A.seg_hi[q], std::min(h1, seg_top(sg)));
  }

  const SimTool& tool_;
  const ToolContour contour_;  // the tool's contour, its constants taken once
  const SimSettings& s_;
  TriDexel& work_;
  double d_, kappa_;
  int segs_;
  double rc_, ht_, st_, inv_sin_;
  std::vector<double> bounds_;  // segment boundaries' heights
  // seg_of's table: the heights up to the top bound in kCells cells of cell_ mm.
  static constexpr int kCells = 4096;
  double cell_ = 1;
  std::vector<int> below_;
  std::vector<int> seg_of_bottom_;    // seg_of(seg_bottom(sg)) for each segment
  std::vector<double> bound_length_;  // edge_length of each bound
  // Per X/Y board (its stage runs one step at a time): a layer's rows.
  std::array<RowChords, 2> rows_;
  static_assert(sizeof(Dexel) == 4 * sizeof(double) && std::is_standard_layout_v<Dexel>,
                "rays_maybe reads a ray's inline words as four doubles");
};

}  // namespace

SimResult simulate(const ToolPath& path, const SimTool& tool, const SimSettings& s, TriDexel& work,
                   double t0_s, double t1_s, const SimControl& control) {
  sim_detail::require_rows();
  if (s.steps_per_rev < 8) {
    throw InputError(
        fmt::format("[simulation] steps_per_rev must be >= 8, got {}", s.steps_per_rev));
  }
  if (!(s.chip_sampling_mm > 0)) {
    throw InputError(
        fmt::format("[simulation] chip_sampling must be > 0 mm, got {}", s.chip_sampling_mm));
  }
  if (tool.tooth_angle_rad.empty() || !(tool.omega_rad_per_s != 0)) {
    throw InputError("simulate: the tool needs teeth and a spindle speed");
  }
  if (!(t1_s > t0_s))
    throw InputError(fmt::format("simulate: empty window {} to {} s", t0_s, t1_s));
  const double dt = kTwoPi / (std::abs(tool.omega_rad_per_s) * s.steps_per_rev);
  // Steps of dt from t0; the last one (shorter) ends exactly at t1, so that consecutive calls
  // (the pre-roll, then the window) sweep every angle once.
  const auto nsteps = static_cast<std::size_t>(std::ceil((t1_s - t0_s) / dt - 1e-9));
  auto time_at = [&](std::size_t q) {
    return q < nsteps ? t0_s + static_cast<double>(q) * dt : t1_s;
  };
  // The path sampled at the step times a block at a time (a whole program has tens of
  // millions of steps): samples [block0, block0 + kSampleBlock] while the steps' ends lie in
  // it; each step reads its own and the previous one.
  std::size_t block0 = 0;
  PathSamples ps;
  std::vector<double> block_times;
  auto sample_block = [&](std::size_t first) {
    block0 = first;
    block_times.clear();
    for (std::size_t q = first; q <= std::min(nsteps, first + kSampleBlock); ++q) {
      block_times.push_back(time_at(q));
    }
    ps = sample_at_times(path, block_times);
  };
  sample_block(0);
  const std::size_t nz = tool.tooth_angle_rad.size();
  const double d = work.boards[0].spacing();
  const double top = work.box.hi[2];
  Stepper stepper(tool, s, work);
  const int segs = stepper.segs();

  SimResult res;
  const bool keep = control.keep_records;
  if (keep && control.reserve_chip_entries > 0) {
    // One record per step, the chip map as estimated (estimate_simulation_memory): no
    // doubling of either on the way, so the memory used is what was estimated.
    res.steps.reserve(nsteps);
    res.chip_map.reserve(control.reserve_chip_entries);
  }
  res.segments_per_tooth = segs;
  // The last revolution: within it every tooth swept every angle, so (at constant depth)
  // nothing is left nearer a tooth's centre than its profile less the path length D since
  // (at least the largest move) and one spacing; the wedges then only look at that annulus.
  // In the first revolution of a call, or while the depth changes, the wedge is the whole
  // sector.
  //
  // Tighter, per tooth: the angles tooth k sweeps now were swept by tooth j (whose tip is no
  // higher) Delta_j = (its angular lag) / |omega| ago, about a centre at most D_j (the path
  // length since) away, so material lies beyond the contour + r_off_j - D_j: the annulus is
  // narrowed by the best such j (usually the previous tooth: about f_z instead of the feed
  // per revolution).
  //
  // A call continuing another (control.after) knows what that one knew: the steps are counted
  // over the chain (g), so the search is the annulus from the first step. The wedges' shapes
  // stay each call's own (the whole sectors of its first revolution): the results do not
  // depend on the carry, only the work does.
  const auto spr = static_cast<std::size_t>(s.steps_per_rev);
  const std::size_t ring_n = spr + 4 + kSimRingSlack;
  std::vector<double> cum(ring_n, 0.0);  // path length up to the last ring_n steps
  // The centre at the last ring_n steps (the chain's start at its step 0).
  std::vector<double> ring_x(ring_n, ps.x_mm[0]), ring_y(ring_n, ps.y_mm[0]);
  double cum_now = 0;
  std::size_t level_steps = 0;  // steps since the depth last changed
  std::size_t base = 0;         // the chain's steps before this call
  bool chain_enveloped = control.envelope_before;
  if (const SimCarry* c = control.after) {
    if (c->t_s != t0_s || c->steps_per_rev != s.steps_per_rev || c->cum_mm.size() != ring_n ||
        c->x_mm.size() != ring_n || c->y_mm.size() != ring_n) {
      throw Error(fmt::format(
          "simulate: the carry ended at {} s with {} steps per revolution; this call starts at "
          "{} s with {}",
          c->t_s, c->steps_per_rev, t0_s, s.steps_per_rev));
    }
    cum = c->cum_mm;
    ring_x = c->x_mm;
    ring_y = c->y_mm;
    cum_now = c->cum_now_mm;
    level_steps = c->level_steps;
    base = c->steps;
    chain_enveloped = c->envelope_before;
  }
  struct Lag {
    std::size_t steps;  // how many steps ago (rounded up, plus the wedge's span)
    double dr;          // r_off_k - r_off_j
  };
  std::vector<std::vector<Lag>> lags(nz);
  for (std::size_t k = 0; k < nz; ++k) {
    for (std::size_t j = 0; j < nz; ++j) {
      if (tool.axial_offset_mm[j] > tool.axial_offset_mm[k] + 1e-12) continue;
      double lag = tool.omega_rad_per_s < 0 ? tool.tooth_angle_rad[k] - tool.tooth_angle_rad[j]
                                            : tool.tooth_angle_rad[j] - tool.tooth_angle_rad[k];
      lag = std::fmod(lag, kTwoPi);
      if (lag < 0) lag += kTwoPi;
      if (lag < 1e-12) lag = kTwoPi;  // the tooth itself, a revolution ago
      const auto m = std::min(
          spr + 2,
          static_cast<std::size_t>(std::ceil(lag / kTwoPi * static_cast<double>(spr))) + 2);
      lags[k].push_back({m, tool.radial_offset_mm[k] - tool.radial_offset_mm[j]});
    }
  }
  const double min_core = 0.5 * tool.radius_mm;
  const double step_angle = kTwoPi / static_cast<double>(spr);  // rad swept per step
  const std::size_t every = std::max<std::size_t>(1, (nsteps + 1) / 200);
  std::size_t done = 0;               // the steps taken
  std::vector<ChipEntry> step_chips;  // this step's chip map entries
  // Step n's wedges (and its time and centre) into sw: in step order (the rings of path
  // lengths and centres move on).
  auto make_step = [&](std::size_t n, StepWork& sw) {
    const std::size_t g = base + n;  // the step over the chain
    sw.n = n;
    if (n > block0 + kSampleBlock) sample_block(n - 1);
    const std::size_t i = n - block0;  // this step's end in the block; i - 1 its start
    const std::array<double, 3> c{ps.x_mm[i], ps.y_mm[i], ps.z_mm[i]};
    const std::array<double, 2> prev{ps.x_mm[i - 1], ps.y_mm[i - 1]};
    const double moved = std::hypot(c[0] - prev[0], c[1] - prev[1]);
    cum_now += moved;
    cum[g % ring_n] = cum_now;
    ring_x[g % ring_n] = c[0], ring_y[g % ring_n] = c[1];
    level_steps = std::abs(c[2] - ps.z_mm[i - 1]) > 1e-9 ? 0 : level_steps + 1;
    // Settled: a revolution (and two steps) at this depth within the `steps` counted.
    auto settled_in = [&](std::size_t steps) { return steps > spr + 2 && level_steps >= spr + 2; };
    // Enveloped: the envelope swept up to the start of the `steps` counted (all at this depth)
    // left nothing within the contour of the centre there, so nothing nearer the present centre
    // than the contour less the path since.
    auto enveloped_in = [&](bool after_envelope, std::size_t steps) {
      return after_envelope && level_steps + 1 >= steps;
    };
    const bool settled = settled_in(g);
    const double D = settled                            ? cum_now - cum[(g - spr) % ring_n]
                     : enveloped_in(chain_enveloped, g) ? cum_now
                                                        : kInf;
    const bool annulus = D + d < min_core;
    // The shapes: this call's own first revolution takes whole sectors (as without a carry).
    const bool own = settled_in(n) || enveloped_in(control.envelope_before, n);
    const bool closing = annulus && own;  // a wedge and its closing wedge (else two sectors)
    res.annulus_steps += annulus ? 1 : 0;
    // Spindle angles from the step times (the path samples clamp at its end: a dwell there).
    const double ta = time_at(n - 1), tb = time_at(n);
    sw.tb = tb;
    sw.c = c;
    std::vector<Wedge>& wedges = sw.wedges;
    std::vector<std::size_t>& wedge_tooth = sw.tooth;
    wedges.clear();
    wedge_tooth.clear();
    for (std::size_t k = 0; k < nz; ++k) {
      Wedge w{};
      w.tip_z = c[2] + tool.axial_offset_mm[k];
      const double pa = tool.tooth_angle_rad[k] + tool.omega_rad_per_s * ta;
      const double pb = tool.tooth_angle_rad[k] + tool.omega_rad_per_s * tb;
      w.a0 = std::min(pa, pb);
      w.a1 = std::max(pa, pb);
      w.r_off = tool.radial_offset_mm[k];
      const double H = std::min(tool.flute_length_mm, top - w.tip_z);
      w.H = H > 0 ? H : 0.0;
      if (!(w.H > 0)) continue;
      double drop = D;
      const Lag* best = nullptr;  // the tooth giving the least drop
      if (annulus) {
        double best_drop = kInf;
        for (const Lag& l : lags[k]) {
          if (g < l.steps + 1) continue;
          const double dj = l.dr + cum_now - cum[(g - l.steps) % ring_n];
          drop = std::min(drop, dj);
          if (dj < best_drop) best_drop = dj, best = &l;
        }
      }
      // Along a direction: the tooth j that gives the least drop swept these angles
      // l.steps ago about the centre p_j then, so along u what it left lies beyond its contour
      // less (c - p_j).u (less than the path since where the path turns), up to |c - p_j|^2 /
      // R_j and the spread of the centres over the steps whose wedges swept a point near u
      // (kw either side; docs/models.md section 11).
      double dir_c = kInf, pj_x = 0, pj_y = 0;
      if (closing && !s.exhaustive) {
        if (best != nullptr) {
          const std::size_t gj = g - best->steps;
          pj_x = ring_x[gj % ring_n], pj_y = ring_y[gj % ring_n];
          const double dist = std::hypot(c[0] - pj_x, c[1] - pj_y) + moved;
          const double r_j = stepper.narrowest(w.H) + w.r_off - best->dr;
          const double kw = std::ceil(2 * dist / (r_j * step_angle)) + 5;
          if (r_j > 4 * dist && kw <= static_cast<double>(kSimRingSlack) &&
              static_cast<double>(gj) >= kw) {
            const auto kws = static_cast<std::size_t>(kw);
            const double spread = cum[std::min(g, gj + kws) % ring_n] - cum[(gj - kws) % ring_n];
            if (r_j > 4 * (dist + spread)) dir_c = best->dr + spread + 2 * dist * dist / r_j;
          }
        }
      }
      if (closing) {
        w.r_in_drop = s.exhaustive ? kInf : std::max(0.0, drop) + d;
        w.cx = c[0], w.cy = c[1];
        w.dir_x = c[0] - pj_x, w.dir_y = c[1] - pj_y, w.dir_c = dir_c;
        wedges.push_back(w), wedge_tooth.push_back(k);
        // The wedge is taken about this step's centre; the previous step's was about the
        // previous centre, so their shared edge (at pa) is offset by the move between steps
        // and would leave a sliver (width up to that move) that the next tooth finds with a
        // doubled chip. A thin sector about the previous centre from pa on, 2 move / R wide,
        // closes it at every radius above R / 2: all the annulus.
        const double ext = 2 * moved / tool.radius_mm;
        Wedge thin = w;
        thin.cx = prev[0], thin.cy = prev[1];
        thin.dir_x = prev[0] - pj_x, thin.dir_y = prev[1] - pj_y;
        thin.a0 = tool.omega_rad_per_s < 0 ? pa - ext : pa;
        thin.a1 = tool.omega_rad_per_s < 0 ? pa : pa + ext;
        // Below R / 2 (a layer narrower than the tool: a corner or ball, a lead angle) the
        // sector leaves part of the sliver where material may lie: the strip takes it (the
        // points within the move of the shared edge; closing_angles).
        thin.move = moved;
        thin.pa = pa;
        thin.up = tool.omega_rad_per_s >= 0;
        thin.drop = std::max(0.0, drop) + d;
        thin.r_old = ext < 0.5 * kPi ? moved / std::sin(ext) : moved;
        if (ext > 0) wedges.push_back(thin), wedge_tooth.push_back(k);
      } else {
        // The whole sector about both this step's centre and the previous one: consecutive
        // steps then share their edges exactly (no sliver at any radius).
        // The current centre first: its chips are the ones measured; the previous centre's
        // sector only takes the slivers in between. Continuing a chain, the search is still
        // the annulus: about the previous centre, material lies beyond the contour less the
        // drop and the move.
        const bool search = annulus && !s.exhaustive;
        w.r_in_drop = search ? std::max(0.0, drop) + d : kInf;
        w.cx = c[0], w.cy = c[1];
        wedges.push_back(w), wedge_tooth.push_back(k);
        w.r_in_drop = search ? std::max(0.0, drop) + moved + d : kInf;
        w.cx = prev[0], w.cy = prev[1];
        wedges.push_back(w), wedge_tooth.push_back(k);
      }
    }
  };
  // The records of a step whose boards are cut, in step order (one stage at a time: the
  // merged segments' buffers are reused).
  std::vector<double> seg_h, seg_lo, seg_hi;
  auto sg_of_q = [&](std::size_t q) {
    return static_cast<int>(q % static_cast<std::size_t>(segs));
  };
  auto finish_step = [&](StepWork& sw) {
    const std::array<BoardAcc, 3>& bacc = sw.acc;
    const double tb = sw.tb;
    const std::array<double, 3>& c = sw.c;
    // Merged where a board wrote (elsewhere every board's entries hold their defaults: no
    // chip).
    const std::size_t n_seg = nz * static_cast<std::size_t>(segs);
    std::size_t u_lo = n_seg, u_hi = 0;
    for (const BoardAcc& A : bacc) u_lo = std::min(u_lo, A.q_lo), u_hi = std::max(u_hi, A.q_hi);
    seg_h.resize(n_seg), seg_lo.resize(n_seg), seg_hi.resize(n_seg);
    for (std::size_t q = u_lo; q < u_hi; ++q) seg_h[q] = 0.0, seg_lo[q] = kInf, seg_hi[q] = -kInf;
    for (std::size_t b = 0; b < 3; ++b) {
      for (std::size_t q = u_lo; q < u_hi; ++q) {
        seg_h[q] = std::max(seg_h[q], bacc[b].seg_h[q]);
        seg_lo[q] = std::min(seg_lo[q], bacc[b].seg_lo[q]);
        seg_hi[q] = std::max(seg_hi[q], bacc[b].seg_hi[q]);
      }
      res.removed_by_board_mm3[b] += bacc[b].removed_board;
      res.dexel_updates += bacc[b].updates;
    }
    SimStep st;
    st.t_s = tb;
    st.tip_mm = Vec3(c[0], c[1], c[2]);
    st.removed_mm3 = bacc[2].removed_tooth;
    double sum = 0;
    step_chips.clear();
    for (std::size_t q = u_lo; q < u_hi; ++q) {
      const double h = seg_h[q];
      if (h > 0) {
        st.h_max_mm = std::max(st.h_max_mm, h);
        sum += h;
        ++st.engaged_segments;
        step_chips.push_back(
            {static_cast<std::uint32_t>(res.step_count), static_cast<std::uint32_t>(q),
             static_cast<float>(h),
             static_cast<float>(seg_hi[q] > seg_lo[q]
                                    ? stepper.edge_length_in(sg_of_q(q), seg_hi[q]) -
                                          stepper.edge_length_in(sg_of_q(q), seg_lo[q])
                                    : 0.0),
             static_cast<float>(bacc[2].seg_v[q])});
      }
    }
    st.h_mean_mm = st.engaged_segments > 0 ? sum / st.engaged_segments : 0.0;
    res.h_max_mm = std::max(res.h_max_mm, st.h_max_mm);
    ++res.step_count;
    if (control.sink) control.sink->take(st, step_chips);
    if (keep) {
      res.chip_map.insert(res.chip_map.end(), step_chips.begin(), step_chips.end());
      res.steps.push_back(std::move(st));
    }
    done = sw.n;
    if (control.hooks.progress && done % every == 0) control.hooks.progress(done, nsteps);
  };
  // Board b's cuts of a step: its wedges in order, into the board's own accumulators.
  auto cut_board = [&](int b, StepWork& sw) {
    BoardAcc& A = sw.acc[static_cast<std::size_t>(b)];
    A.reset_segments(nz * static_cast<std::size_t>(segs));
    A.removed_tooth.assign(nz, 0.0);
    A.removed_board = 0;
    A.updates = 0;
    for (std::size_t q = 0; q < sw.wedges.size(); ++q) {
      if (b == 2) {
        stepper.z_board(sw.tooth[q], sw.wedges[q], A);
      } else {
        stepper.xy_board(b, sw.tooth[q], sw.wedges[q], A);
      }
    }
  };
  // The steps go through a pipeline in batches: their wedges (in step order), then each
  // board's cuts (a stage per board, each in step order: the three boards are independent
  // pictures of the workpiece), then the records (in step order, each board's accumulators
  // merged in board order: the same numbers for any thread count). The boards of consecutive
  // batches overlap, so the cores have work without a barrier at every step. A batch's slot
  // is free again when it is taken: at most `kSimBatches` are in flight, and they finish in
  // order.
  const std::size_t per_batch = batch_steps(nz, static_cast<std::size_t>(segs));
  std::vector<Batch> batches(kSimBatches);
  for (Batch& bt : batches) bt.steps.resize(per_batch);
  std::size_t next = 1, produced = 0;
  // Each board packs its settled tiles (DexelBoard::pack_settled) once a revolution, in its
  // own stage: the machined region behind the tool then costs a few bytes a tile.
  const auto pack_every = static_cast<std::size_t>(s.steps_per_rev);
  auto board_stage = [&](int b) {
    return tbb::make_filter<Batch*, Batch*>(
        tbb::filter_mode::serial_in_order, [&cut_board, &work, b, pack_every](Batch* bt) {
          for (std::size_t q = 0; q < bt->count; ++q) cut_board(b, bt->steps[q]);
          const std::size_t n0 = bt->steps[0].n, n1 = bt->steps[bt->count - 1].n;
          if (n1 / pack_every != (n0 - 1) / pack_every) {
            (void)work.boards[static_cast<std::size_t>(b)].pack_settled();
          }
          return bt;
        });
  };
  tbb::parallel_pipeline(
      kSimBatches,
      tbb::make_filter<void, Batch*>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& fc) -> Batch* {
                                       Batch& bt = batches[produced % kSimBatches];
                                       bt.count = 0;
                                       while (bt.count < per_batch && next <= nsteps &&
                                              res.complete) {
                                         if (control.hooks.cancelled()) {
                                           res.complete = false;
                                           break;
                                         }
                                         make_step(next++, bt.steps[bt.count++]);
                                       }
                                       if (bt.count == 0) {
                                         fc.stop();
                                         return nullptr;
                                       }
                                       ++produced;
                                       return &bt;
                                     }) &
          board_stage(0) & board_stage(1) & board_stage(2) &
          tbb::make_filter<Batch*, void>(tbb::filter_mode::serial_in_order, [&](Batch* bt) {
            for (std::size_t q = 0; q < bt->count; ++q) finish_step(bt->steps[q]);
          }));
  res.removed_mm3 = res.removed_by_board_mm3[2];
  res.carry.t_s = time_at(done);
  res.carry.steps_per_rev = s.steps_per_rev;
  res.carry.steps = base + done;
  res.carry.level_steps = level_steps;
  res.carry.envelope_before = chain_enveloped;
  res.carry.cum_now_mm = cum_now;
  res.carry.cum_mm = std::move(cum);
  res.carry.x_mm = std::move(ring_x);
  res.carry.y_mm = std::move(ring_y);
  return res;
}

void tally_steps(SimResult& r) {
  r.step_count = r.steps.size();
  r.h_max_mm = 0;
  for (const SimStep& st : r.steps) r.h_max_mm = std::max(r.h_max_mm, st.h_max_mm);
}

Box3 job_stock(const Job& job) {
  Box3 b;
  if (job.stock_min_mm && job.stock_max_mm) {
    b.lo = *job.stock_min_mm;
    b.hi = *job.stock_max_mm;
    return b;
  }
  // The default stock (the slot runs through the workpiece from y = 0 to its length)
  // with a margin beside the walls and below the floor, where the wall and floor profiles are
  // read.
  const double m = 1.0;
  b.lo = {-0.5 * job.slot.width_mm - m, 0.0, -job.slot.depth_mm - 0.5};
  b.hi = {0.5 * job.slot.width_mm + m, job.slot.length_mm, 0.0};
  return b;
}

JobSimulation::JobSimulation() = default;
JobSimulation::~JobSimulation() = default;
JobSimulation::JobSimulation(JobSimulation&&) noexcept = default;
JobSimulation& JobSimulation::operator=(JobSimulation&&) noexcept = default;

JobSimulation simulate_job_in_arena(const Job& job, const ToolPath& path, double from_s,
                                    double to_s, const SimControl& control,
                                    const Mesh* stock_mesh) {
  if (!stock_mesh) stock_mesh = job.stock_mesh.get();  // the job's [stock] mesh, else the box
  const SimSettings& s = job.simulation;
  if (!(from_s >= 0) || !(to_s > from_s)) {
    throw InputError(
        fmt::format("simulation window {} to {} s: need 0 <= from < to", from_s, to_s));
  }
  sim_detail::require_rows();  // a missing plugin said now, before the pre-roll
  if (stock_mesh) control.hooks.begin("stock: the mesh's dexels");
  TriDexel work = stock_mesh ? stock_from_mesh(*stock_mesh, s.resolution_mm, control.hooks)
                             : TriDexel(job_stock(job), s.resolution_mm);
  if (!job.pocket.rest_of.empty()) {
    // Rest machining: the earlier program's flat end mill swept along it first (its envelope:
    // the workpiece it left, less the feed marks of its teeth).
    const RestStock* rest = job.pocket.rest.get();
    if (!rest) throw Error("simulate: [pocket] rest_of was not read (attach_rest_stock)");
    Job earlier = job;
    earlier.tool = Tool{};
    earlier.tool.diameter_mm = 2 * rest->tool_radius_mm;
    earlier.tool.teeth = job.tool.teeth;
    earlier.tool.tooth_angles_deg = job.tool.tooth_angles_deg;
    earlier.tool.flute_length_mm = job.tool.flute_length_mm;  // else the depth's (sim_tool)
    control.hooks.begin("stock: the earlier program's envelope (rest_of)");
    (void)sweep_envelope(rest->path, sim_tool(earlier, s), work, 0, rest->path.duration_s(),
                         control.hooks);
  }
  const SimTool tool = sim_tool(job, s);
  JobSimulation out;
  const auto clock = [] { return std::chrono::steady_clock::now(); };
  const auto since = [](auto t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  // The process's processor time (s, all threads), for each phase's utilisation.
  const auto cpu = [] { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; };
  out.threads = tbb::this_task_arena::max_concurrency();
  SimCarry carry;
  if (from_s > 0) {
    // The envelope up to one revolution before the window, then that revolution with the
    // teeth (not recorded): the window's first teeth meet the feed marks of the ones before.
    const auto t0 = clock();
    const double c0 = cpu();
    const double rev = kTwoPi / std::abs(tool.omega_rad_per_s);
    const double lead_from = std::max(0.0, from_s - rev);
    if (lead_from > 0) {
      control.hooks.begin("pre-roll: envelope");
      (void)sweep_envelope(path, tool, work, 0, lead_from, control.hooks);
    }
    SimControl lead;
    lead.keep_records = false;  // not recorded: only the workpiece it leaves and its carry
    lead.envelope_before = lead_from > 0;
    lead.hooks = control.hooks;
    lead.hooks.begin("pre-roll: last revolution");
    carry = simulate(path, tool, s, work, lead_from, from_s, lead).carry;
    out.pre_roll_s = from_s;
    out.pre_roll_wall_s = since(t0);
    out.pre_roll_cpu_s = cpu() - c0;
  }
  if (control.hooks.cancelled()) {  // stopped before the window
    out.result.complete = false;
    out.result.segments_per_tooth = tool.segments();
  } else {
    const auto t1 = clock();
    const double c1 = cpu();
    control.hooks.begin("window");
    // The window continues the lead revolution: its search is the annulus from the start.
    SimControl window = control;
    if (from_s > 0) window.after = &carry;
    out.result = simulate(path, tool, s, work, from_s, to_s, window);
    out.window_wall_s = since(t1);
    out.window_cpu_s = cpu() - c1;
  }
  for (const auto& b : work.boards) out.memory_bytes += b.memory_bytes();
  out.work = std::make_unique<TriDexel>(std::move(work));
  return out;
}

JobSimulation simulate_job(const Job& job, const ToolPath& path, double from_s, double to_s,
                           const SimControl& control, const Mesh* stock_mesh) {
  // [simulation] threads: 0 = all cores. The results do not depend on it.
  const int threads = job.simulation.threads;
  if (threads < 0) {
    throw InputError(
        fmt::format("[simulation] threads must be >= 0 (0: all cores), got {}", threads));
  }
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  return arena.execute(
      [&] { return simulate_job_in_arena(job, path, from_s, to_s, control, stock_mesh); });
}

MemoryEstimate estimate_simulation_memory(const Job& job, const ToolPath& path, double from_s,
                                          double to_s, const Mesh* stock_mesh) {
  if (!stock_mesh) stock_mesh = job.stock_mesh.get();  // as simulate_job
  const SimSettings& s = job.simulation;
  const Box3 box = stock_mesh ? mesh_box(*stock_mesh) : job_stock(job);
  const double d = s.resolution_mm;
  if (!(d > 0)) throw InputError(fmt::format("[simulation] resolution must be > 0 mm, got {}", d));
  // The region the tool visits up to the window's end: the path's box grown by the radius.
  const double R = job.tool.radius_mm() + job.tool.runout_radial_mm;
  double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  // The box of a path's positions up to `until` s (20,000 samples, at least 1 ms apart), its XY
  // grown by `grow` mm.
  auto visit = [&](const ToolPath& p, double until, double grow) {
    const double dt = std::max(1e-3, until / 20000.0);
    std::vector<double> times;
    for (double t = 0; t < until; t += dt) times.push_back(t);
    times.push_back(until);
    const PathSamples ps = sample_at_times(p, times);
    for (std::size_t n = 0; n < ps.size(); ++n) {
      const double q[3] = {ps.x_mm[n], ps.y_mm[n], ps.z_mm[n]};
      for (int k = 0; k < 3; ++k) {
        const double g = k < 2 ? grow : 0.0;
        lo[k] = std::min(lo[k], q[k] - g), hi[k] = std::max(hi[k], q[k] + g);
      }
    }
  };
  visit(path, to_s, 0.0);
  if (const RestStock* rest = job.pocket.rest.get(); rest && !rest->path.empty()) {
    // Rest machining: the earlier program's tool visits first (its reach beyond ours added).
    visit(rest->path, rest->path.duration_s(), std::max(0.0, rest->tool_radius_mm - R));
  }
  auto extent = [&](int k, double grow_lo, double grow_hi) {
    const double a = std::max(box.lo[static_cast<std::size_t>(k)], lo[k] - grow_lo);
    const double b = std::min(box.hi[static_cast<std::size_t>(k)], hi[k] + grow_hi);
    return b > a ? b - a : 0.0;
  };
  const double ex = extent(0, R, R), ey = extent(1, R, R), ez = extent(2, 0, kInf);
  const double tile = DexelBoard::kTile * d;
  auto tiles = [&](double a, double b) {
    return (std::ceil(a / tile) + 1) * (std::ceil(b / tile) + 1);
  };
  // A tile's rays (the X board's over y and z, the Y board's over z and x, the Z board's
  // over x and y).
  auto per_tile = [](int axis) {
    return static_cast<double>(DexelBoard::kTile * DexelBoard::kTile) *
           static_cast<double>(DexelBoard::ray_bytes(axis));
  };
  MemoryEstimate m;
  m.boards_bytes =
      tiles(ey, ez) * per_tile(0) + tiles(ez, ex) * per_tile(1) + tiles(ex, ey) * per_tile(2);
  if (stock_mesh) {
    // Every ray of the mesh's box is held, and while one board is cut to the mesh, the
    // crossings of a strip of rays (a vector each, two crossings).
    const double bx = box.hi[0] - box.lo[0], by = box.hi[1] - box.lo[1], bz = box.hi[2] - box.lo[2];
    m.boards_bytes = tiles(by, bz) * per_tile(0) + tiles(bz, bx) * per_tile(1) +
                     tiles(bx, by) * per_tile(2) +
                     DexelBoard::kTile * std::max({bx, by, bz}) / d * (24.0 + 32.0);
  }
  // The window's steps: one record each (its per-tooth removed volumes on the heap, a
  // malloc chunk of at least 32 bytes), and the time and path sample arrays of the run.
  const double steps = (to_s - from_s) * spindle_speed_rpm(job) / 60.0 * s.steps_per_rev;
  const SimTool tool = sim_tool(job, s);
  const double teeth = static_cast<double>(tool.tooth_angle_rad.size());
  const double heap_chunk = std::max(32.0, 16.0 * std::ceil((8.0 * teeth + 8.0) / 16.0));
  // The path sampled a block of steps at a time: the times and PathSamples' ten arrays; and
  // the batches of steps in flight.
  const auto segs = static_cast<std::size_t>(tool.segments());
  const auto nz = tool.tooth_angle_rad.size();
  m.stream_bytes =
      static_cast<double>(kSampleBlock + 1) * 8.0 * (1 + 10) +
      static_cast<double>(kSimBatches * batch_steps(nz, segs) * step_work_bytes(nz, segs));
  m.records_bytes = m.stream_bytes + steps * (static_cast<double>(sizeof(SimStep)) + heap_chunk);
  // The chip map: one entry per engaged segment and step. Teeth in the cut from the exact 2D
  // engagement of the path (per tooth pass, the slot's stock), times the segments along the
  // edge within the depth of cut (the stock's top down to the deepest tip in the window).
  double teeth_in_cut = 0, counted = 0, deepest = kInf;
  {
    const EngagementSeries es = compute_engagement(path, job);
    for (std::size_t i = 0; i < es.samples.size(); ++i) {
      const double t = es.samples.t_s[i];
      if (t < from_s || t > to_s) continue;
      teeth_in_cut += es.teeth_in_cut[i];
      counted += 1;
      deepest = std::min(deepest, es.samples.z_mm[i]);
    }
  }
  const double mean_in_cut = counted > 0 ? teeth_in_cut / counted : 0.0;
  const double depth = std::isfinite(deepest) ? std::max(0.0, box.hi[2] - deepest) : 0.0;
  const double segs_in_cut = std::min(static_cast<double>(tool.segments()),
                                      std::ceil(depth / std::max(tool.segment_mm, 1e-9)) + 1.0);
  m.chip_entries = steps * mean_in_cut * segs_in_cut;
  m.records_bytes += m.chip_entries * static_cast<double>(sizeof(ChipEntry));
  // The HDF5 chip map is dense: h, w and v as float per step and edge segment of every tooth.
  const double cols = teeth * static_cast<double>(tool.segments());
  m.dense_map_bytes = steps * (cols * 12.0 + 8.0 * (4 + teeth));
  // The HDF5 writer makes 1024 steps dense at a time; the deflate filter holds about as much
  // again while it compresses those rows' chunks.
  m.map_writer_bytes = 2.0 * std::min(steps, 1024.0) * (cols * 12.0 + 8.0 * (4 + teeth));
  // The outputs made from the workpiece at the end, one at a time: the floor as a height map
  // at the spacing over the region visited (floor.x3p), or the machined surface's mesh (at
  // most about 4 million triangles of 50 bytes, over a height field of half as many points).
  const double zb_cells =
      std::ceil((box.hi[0] - box.lo[0]) / d) * std::ceil((box.hi[1] - box.lo[1]) / d);
  m.outputs_bytes = std::max(std::ceil(ex / d) * std::ceil(ey / d) * 8.0,
                             std::min(4e6, 2.0 * zb_cells) * 50.0 + std::min(2e6, zb_cells) * 8.0);
  // What the process holds besides (its libraries, the job, the path; measured 20 MB).
  m.base_bytes = process_base_bytes() + static_cast<double>(path.segments().size()) * 400.0;
  return m;
}

}  // namespace trochomill
