// Time-stepped tri-dexel material removal by the cutting edges' swept wedges, with each
// removed piece assigned to the edge segment that removed it (include/trochomill/sim.hpp,
// docs/models.md section 11).
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

double SimTool::profile_radius(double h) const {
  if (h < 0) return -1;
  if (h >= corner_radius_mm) return radius_mm;
  const double r = corner_radius_mm, dz = r - h;
  return radius_mm - r + std::sqrt(std::max(0.0, r * r - dz * dz));
}

int SimTool::segments() const {
  return std::max(1, static_cast<int>(std::ceil(flute_length_mm / segment_mm - 1e-9)));
}

SimTool sim_tool(const Job& job, const SimSettings& s) {
  SimTool t;
  t.radius_mm = job.tool.radius_mm();
  t.corner_radius_mm = job.tool.corner_radius_mm;
  // Without a flute length the edges reach the top of the slot (depth plus 1 mm).
  t.flute_length_mm =
      job.tool.flute_length_mm > 0 ? job.tool.flute_length_mm : job.slot.depth_mm + 1.0;
  t.helix_rad = deg_to_rad(job.tool.helix_angle_deg);
  const double phase = deg_to_rad(job.tool.runout_phase_deg);
  for (const double a : job.tool.tooth_angles_deg) {
    const double ar = deg_to_rad(a);
    t.tooth_angle_rad.push_back(ar);
    // Runout as an axis offset e at `phase` from tooth 0: tooth k's cutting radius grows by
    // e cos(angle_k - phase) (first order in e / R); axial runout tilts likewise.
    t.radial_offset_mm.push_back(job.tool.runout_radial_mm * std::cos(ar - phase));
    t.axial_offset_mm.push_back(job.tool.runout_axial_mm * std::cos(ar - phase));
  }
  const double w = rpm_to_rad_per_s(spindle_speed_rpm(job));
  t.omega_rad_per_s = job.cutting.spindle_direction == SpindleDirection::cw ? -w : w;
  t.segment_mm = s.segment_mm;
  return t;
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Whether the angle range [a0, a1] contains alpha modulo 2 pi.
bool contains_angle(double a0, double a1, double alpha) {
  const double m = std::ceil((a0 - alpha) / kTwoPi);
  return alpha + m * kTwoPi <= a1;
}

// The offsets x (along the line) of the points of the thin sector {t (cos a, sin a): 0 <= t
// <= r, a in [a0, a1]} (a1 - a0 < pi) on the line at signed distance dy from the centre,
// parallel to the first axis. x = dy cot a where sin a has the sign of dy, clipped to the
// disc's chord.
std::optional<Interval> sector_on_line(double dy, double a0, double a1, double r) {
  if (dy * dy >= r * r) return std::nullopt;
  const double w = std::sqrt(r * r - dy * dy);
  if (dy == 0) {
    double lo = kInf, hi = -kInf;
    if (contains_angle(a0, a1, 0.0)) lo = std::min(lo, 0.0), hi = std::max(hi, w);
    if (contains_angle(a0, a1, kPi)) lo = std::min(lo, -w), hi = std::max(hi, 0.0);
    if (lo < hi) return Interval{lo, hi};
    return std::nullopt;
  }
  // Split at the multiples of pi (sin a = 0) and keep the part where sin a has dy's sign.
  const double k = std::floor(a0 / kPi);
  const double cut = (k + 1) * kPi;
  double lo = kInf, hi = -kInf;
  auto piece = [&](double p0, double p1) {
    if (!(p1 > p0)) return;
    const double s = std::sin(0.5 * (p0 + p1));
    if (s * dy <= 0) return;
    auto x_at = [&](double a) {
      const double sa = std::sin(a);
      if (std::abs(sa) < 1e-300 || sa * dy <= 0) {  // at a split: the line runs off to infinity
        return (std::cos(a) * dy * s > 0) ? kInf : -kInf;
      }
      return dy * std::cos(a) / sa;
    };
    const double x0 = x_at(p0), x1 = x_at(p1);
    lo = std::min({lo, x0, x1});
    hi = std::max({hi, x0, x1});
  };
  piece(a0, std::min(a1, cut));
  piece(cut, a1);
  lo = std::max(lo, -w);
  hi = std::min(hi, w);
  if (lo < hi) return Interval{lo, hi};
  return std::nullopt;
}

// Bounding box of the sector {t (cos a, sin a): 0 <= t <= r, a in [a0, a1]} about the
// origin: {x_lo, x_hi, y_lo, y_hi}.
std::array<double, 4> sector_box(double a0, double a1, double r) {
  std::array<double, 4> b{0, 0, 0, 0};
  auto add = [&](double a) {
    const double x = r * std::cos(a), y = r * std::sin(a);
    b[0] = std::min(b[0], x), b[1] = std::max(b[1], x), b[2] = std::min(b[2], y),
    b[3] = std::max(b[3], y);
  };
  add(a0);
  add(a1);
  for (int q = 0; q < 4; ++q) {
    if (a1 - a0 >= kTwoPi || contains_angle(a0, a1, q * 0.5 * kPi)) add(q * 0.5 * kPi);
  }
  return b;
}

// Whether a ray (nullptr: untouched, the full stock interval `full`) holds material in
// (lo, hi).
bool has_material(const Dexel* ray, Interval full, double lo, double hi) {
  if (ray == nullptr) return full.hi > lo && full.lo < hi;
  for (const Interval& v : ray->intervals()) {
    if (v.hi > lo && v.lo < hi) return true;
    if (v.lo >= hi) break;
  }
  return false;
}

struct ToothPose {
  double cx, cy, tip_z, a0, a1, r_off;  // a0 < a1: the wedge at height 0
};

}  // namespace

SimResult simulate(const ToolPath& path, const SimTool& tool, const SimSettings& s, TriDexel& work,
                   double t0_s, double t1_s) {
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
  std::vector<double> times;
  for (double t = t0_s; t <= t1_s + 1e-12; t += dt) times.push_back(t);
  const PathSamples ps = sample_at_times(path, times);
  const std::size_t nz = tool.tooth_angle_rad.size();
  const int segs = tool.segments();
  const double kappa = std::tan(tool.helix_rad) / tool.radius_mm;  // edge angle per mm of height
  const double d = work.boards[0].spacing();
  const double d2 = d * d;
  const double top = work.box.hi[2];

  SimResult res;
  res.segments_per_tooth = segs;
  // Each board is an independent picture of the workpiece: the three are updated in parallel,
  // each with its own accumulators, merged in board order (the same numbers whatever the
  // thread count: maxima, and sums kept per board).
  struct BoardAcc {
    std::vector<double> seg_h, removed_tooth;
    double removed_board = 0;
    std::uint64_t updates = 0;
    std::vector<Interval> removed;
  };
  std::array<BoardAcc, 3> bacc;
  std::vector<ToothPose> poses(nz);
  std::vector<double> heights(nz);
  for (std::size_t n = 1; n < ps.size(); ++n) {
    // Spindle angles from the step times (the path samples clamp at its end: a dwell there).
    const double ta = times[n - 1], tb = times[n];
    for (std::size_t k = 0; k < nz; ++k) {
      ToothPose tp{};
      tp.cx = ps.x_mm[n];
      tp.cy = ps.y_mm[n];
      tp.tip_z = ps.z_mm[n] + tool.axial_offset_mm[k];
      const double pa = tool.tooth_angle_rad[k] + tool.omega_rad_per_s * ta;
      const double pb = tool.tooth_angle_rad[k] + tool.omega_rad_per_s * tb;
      tp.a0 = std::min(pa, pb);
      tp.a1 = std::max(pa, pb);
      // The wedge is taken about this step's centre; the previous step's was about the
      // previous centre, so their shared edge is offset by the move delta between steps and
      // would leave a sliver (width up to delta) that the next tooth finds with a doubled
      // chip. Extending the wedge backwards over the shared edge by 2 delta / R closes it
      // for radii above R / 2 (double coverage is harmless: material goes once).
      const double moved = std::hypot(ps.x_mm[n] - ps.x_mm[n - 1], ps.y_mm[n] - ps.y_mm[n - 1]);
      const double ext = 2 * moved / tool.radius_mm;
      if (tool.omega_rad_per_s < 0) {
        tp.a1 += ext;  // turning clockwise: the older edge is the larger angle
      } else {
        tp.a0 -= ext;
      }
      tp.r_off = tool.radial_offset_mm[k];
      const double H = std::min(tool.flute_length_mm, top - tp.tip_z);
      poses[k] = tp;
      heights[k] = H > 0 ? H : 0.0;
    }
    tbb::parallel_for(0, 3, [&](int bsel) {
      BoardAcc& A = bacc[static_cast<std::size_t>(bsel)];
      A.seg_h.assign(nz * static_cast<std::size_t>(segs), 0.0);
      A.removed_tooth.assign(nz, 0.0);
      A.removed_board = 0;
      A.updates = 0;
      std::vector<Interval>& removed = A.removed;
      for (std::size_t k = 0; k < nz; ++k) {
        const ToothPose& tp = poses[k];
        const double H = heights[k];
        if (!(H > 0)) continue;
        const double rmax = tool.radius_mm + std::max(0.0, tp.r_off);
        auto seg_of = [&](double h) {
          return std::clamp(static_cast<int>(h / tool.segment_mm), 0, segs - 1);
        };
        auto note = [&](double h, double chip) {
          if (chip <= 0) return;
          double& v =
              A.seg_h[k * static_cast<std::size_t>(segs) + static_cast<std::size_t>(seg_of(h))];
          v = std::max(v, chip);
        };
        // Grid index range covering [lo, hi] along a board axis.
        auto idx = [&](const DexelBoard& board, bool first, double lo, double hi) {
          const int ax = first ? (board.axis() + 1) % 3 : (board.axis() + 2) % 3;
          const double o = work.box.lo[static_cast<std::size_t>(ax)];
          const int count = first ? board.count_u() : board.count_v();
          const int i0 = std::max(0, static_cast<int>(std::ceil((lo - o) / d - 0.5)));
          const int i1 = std::min(count - 1, static_cast<int>(std::floor((hi - o) / d - 0.5)));
          return std::pair<int, int>{i0, i1};
        };
        auto account = [&](int, const std::vector<Interval>& pieces) {
          double v = 0;
          for (const Interval& p : pieces) v += (p.hi - p.lo) * d2;
          A.removed_board += v;
        };
        // Z board: columns over the x-extent of the wedge swept over all heights, rows over the
        // y-extent of that sector on each column's line; then each ray exactly.
        if (bsel == 2) {
          DexelBoard& board = work.boards[2];
          const double span_lo = kappa >= 0 ? tp.a0 : tp.a0 + H * kappa;
          const double span_hi = kappa >= 0 ? tp.a1 + H * kappa : tp.a1;
          const bool wide = span_hi - span_lo >= kPi;
          const auto bx = sector_box(span_lo, span_hi, rmax);
          const auto [i0, i1] = wide ? idx(board, true, tp.cx - rmax, tp.cx + rmax)
                                     : idx(board, true, tp.cx + bx[0], tp.cx + bx[1]);
          for (int i = i0; i <= i1; ++i) {
            const double x = board.u_of(i), dx = x - tp.cx;
            double ylo = 0, yhi = 0;
            if (wide) {
              if (dx * dx >= rmax * rmax) continue;
              const double w = std::sqrt(rmax * rmax - dx * dx);
              ylo = -w, yhi = w;
            } else {
              const auto on = sector_on_line(-dx, span_lo - 0.5 * kPi, span_hi - 0.5 * kPi, rmax);
              if (!on) continue;
              ylo = on->lo, yhi = on->hi;
            }
            const auto [j0, j1] = idx(board, false, tp.cy + ylo, tp.cy + yhi);
            for (int j = j0; j <= j1; ++j) {
              // Most rays the wedge crosses were emptied long ago: skip them first.
              if (!has_material(board.find(i, j), board.full(), tp.tip_z, tp.tip_z + H)) continue;
              const double dy = board.v_of(j) - tp.cy, rho = std::hypot(dx, dy);
              if (rho > rmax) continue;
              // Corner: the profile reaches rho only from h_min up.
              double hmin = 0;
              const double flat = tool.radius_mm - tool.corner_radius_mm + tp.r_off;
              if (rho > flat) {
                const double r = tool.corner_radius_mm, q = rho - flat;
                if (q > r) continue;
                hmin = r - std::sqrt(r * r - q * q);
              }
              const double th = std::atan2(dy, dx);
              removed.clear();
              auto cut_h = [&](double h_lo, double h_hi) {
                h_lo = std::max(h_lo, hmin);
                h_hi = std::min(h_hi, H);
                if (!(h_hi > h_lo)) return;
                if (board.ray(i, j).subtract(tp.tip_z + h_lo, tp.tip_z + h_hi, removed) > 0) {
                  ++A.updates;
                }
              };
              if (kappa == 0) {
                if (contains_angle(tp.a0, tp.a1, th)) cut_h(0, H);
              } else {
                // th + 2 pi m in [a0 + h kappa, a1 + h kappa]: h in [th' - a1, th' - a0] / kappa.
                const double m0 = std::ceil((span_lo - th) / kTwoPi);
                const double m1 = std::floor((span_hi - th) / kTwoPi);
                for (double m = m0; m <= m1; m += 1) {
                  const double tt = th + kTwoPi * m;
                  const double ha = (tt - tp.a1) / kappa, hb = (tt - tp.a0) / kappa;
                  cut_h(std::min(ha, hb), std::max(ha, hb));
                }
              }
              for (const Interval& p : removed) {
                A.removed_tooth[k] += (p.hi - p.lo) * d2;
                // Along the corner arc the chip varies with the height: points every
                // chip_sampling; along the flank (profile radius R) it is R - rho on every
                // segment the piece spans.
                const double h_lo = p.lo - tp.tip_z, h_hi = p.hi - tp.tip_z;
                const double rc = tool.corner_radius_mm;
                if (h_lo < rc) {
                  const double c_hi = std::min(h_hi, rc), len = c_hi - h_lo;
                  const int np =
                      std::max(2, static_cast<int>(std::ceil(len / s.chip_sampling_mm)) + 1);
                  for (int q = 0; q < np; ++q) {
                    const double h = h_lo + len * q / (np - 1);
                    note(h, tool.profile_radius(h) + tp.r_off - rho);
                  }
                }
                if (h_hi > rc) {
                  const double chip = tool.radius_mm + tp.r_off - rho;
                  for (int sg = seg_of(std::max(h_lo, rc)); sg <= seg_of(h_hi); ++sg) {
                    note((sg + 0.5) * tool.segment_mm, chip);
                  }
                }
              }
              account(2, removed);
            }
          }
        }
        // X and Y boards: per height level, the rows within the wedge's extent at that height,
        // then each ray's interval exactly. Board 0: rays along x at (y, z) = (u, v); board 1:
        // rays along y at (z, x) = (u, v).
        if (bsel < 2) {
          const int b = bsel;
          DexelBoard& board = work.boards[static_cast<std::size_t>(b)];
          const bool z_first = b == 1;  // board 1's u is z; board 0's v is z
          const auto [z0, z1] = idx(board, z_first, tp.tip_z, tp.tip_z + H);
          for (int zl = z0; zl <= z1; ++zl) {
            const double z = z_first ? board.u_of(zl) : board.v_of(zl);
            const double h = z - tp.tip_z;
            if (h < 0 || h > H) continue;
            const double R_h = tool.profile_radius(h) + tp.r_off;
            if (!(R_h > 0)) continue;
            const double ah0 = tp.a0 + h * kappa, ah1 = tp.a1 + h * kappa;
            const auto bx = sector_box(ah0, ah1, R_h);
            // Rows: board 0 over y (its u), board 1 over x (its v).
            const auto [r0, r1] = b == 0 ? idx(board, true, tp.cy + bx[2], tp.cy + bx[3])
                                         : idx(board, false, tp.cx + bx[0], tp.cx + bx[1]);
            for (int r = r0; r <= r1; ++r) {
              const int i = b == 0 ? r : zl, j = b == 0 ? zl : r;
              const double reach_c = b == 0 ? tp.cx : tp.cy;
              if (!has_material(board.find(i, j), board.full(), reach_c - R_h, reach_c + R_h)) {
                continue;
              }
              std::optional<Interval> off;
              double along_c = 0, perp = 0;
              if (b == 0) {  // line y = u: offsets along x
                perp = board.u_of(i) - tp.cy;
                off = sector_on_line(perp, ah0, ah1, R_h);
                along_c = tp.cx;
              } else {  // line x = v: rotate by -90 degrees, (x, y) -> (y, -x)
                perp = board.v_of(j) - tp.cx;
                off = sector_on_line(-perp, ah0 - 0.5 * kPi, ah1 - 0.5 * kPi, R_h);
                along_c = tp.cy;
              }
              if (!off) continue;
              removed.clear();
              if (board.ray(i, j).subtract(along_c + off->lo, along_c + off->hi, removed) > 0) {
                ++A.updates;
              }
              for (const Interval& p : removed) {
                // The piece's point nearest the centre: the perpendicular's foot, clamped.
                const double t = std::clamp(0.0, p.lo - along_c, p.hi - along_c);
                note(h, R_h - std::hypot(perp, t));
              }
              account(b, removed);
            }
          }
        }
      }
    });
    std::vector<double> seg_h(nz * static_cast<std::size_t>(segs), 0.0);
    for (std::size_t b = 0; b < 3; ++b) {
      for (std::size_t q = 0; q < seg_h.size(); ++q)
        seg_h[q] = std::max(seg_h[q], bacc[b].seg_h[q]);
      res.removed_by_board_mm3[b] += bacc[b].removed_board;
      res.dexel_updates += bacc[b].updates;
    }
    SimStep st;
    st.t_s = tb;
    st.tip_mm = {ps.x_mm[n], ps.y_mm[n], ps.z_mm[n]};
    st.removed_mm3 = bacc[2].removed_tooth;
    double sum = 0;
    for (std::size_t q = 0; q < seg_h.size(); ++q) {
      const double h = seg_h[q];
      if (h > 0) {
        st.h_max_mm = std::max(st.h_max_mm, h);
        sum += h;
        ++st.engaged_segments;
        res.chip_map.push_back({static_cast<std::uint32_t>(res.steps.size()),
                                static_cast<std::uint32_t>(q), static_cast<float>(h)});
      }
    }
    st.h_mean_mm = st.engaged_segments > 0 ? sum / st.engaged_segments : 0.0;
    res.steps.push_back(std::move(st));
  }
  res.removed_mm3 = res.removed_by_board_mm3[2];
  return res;
}

StockBox job_stock(const Job& job) {
  StockBox b;
  if (job.stock_min_mm && job.stock_max_mm) {
    b.lo = *job.stock_min_mm;
    b.hi = *job.stock_max_mm;
    return b;
  }
  // The domain notes' stock (the slot runs through the workpiece from y = 0 to its length)
  // with a margin beside the walls and below the floor, where the wall and floor profiles are
  // read.
  const double m = 1.0;
  b.lo = {-0.5 * job.slot.width_mm - m, 0.0, -job.slot.depth_mm - 0.5};
  b.hi = {0.5 * job.slot.width_mm + m, job.slot.length_mm, 0.0};
  return b;
}

std::pair<double, double> cycle_window(const ToolPath& path, int a, int b) {
  const auto& marks = path.cycles();
  const int n = static_cast<int>(marks.size());
  if (n == 0) throw InputError("--cycles: the path has no cycle marks (a planned trochoid has)");
  if (a < 0 || b <= a || b > n) {
    throw InputError(
        fmt::format("--cycles {}:{}: need 0 <= A < B <= {} (the path's cycles)", a, b, n));
  }
  const double t0 = marks[static_cast<std::size_t>(a)].start_time_s;
  const double t1 = b < n ? marks[static_cast<std::size_t>(b)].start_time_s : path.duration_s();
  return {t0, t1};
}

JobSimulation simulate_job(const Job& job, const ToolPath& path, double from_s, double to_s) {
  const SimSettings& s = job.simulation;
  if (!(from_s >= 0) || !(to_s > from_s)) {
    throw InputError(
        fmt::format("simulation window {} to {} s: need 0 <= from < to", from_s, to_s));
  }
  TriDexel work(job_stock(job), s.resolution_mm);
  const SimTool tool = sim_tool(job, s);
  JobSimulation out;
  if (from_s > 0) {
    SimSettings coarse = s;
    coarse.steps_per_rev = std::max(8, s.steps_per_rev / 25);
    (void)simulate(path, tool, coarse, work, 0, from_s);
    out.pre_roll_s = from_s;
  }
  out.result = simulate(path, tool, s, work, from_s, to_s);
  for (const auto& b : work.boards) out.memory_bytes += b.memory_bytes();
  return out;
}

}  // namespace trochomill
