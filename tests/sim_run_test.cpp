// The simulation's run: removed volume against the swept volume (time-stepped and the envelope
// pre-roll), the annulus search and windows that continue one another, cancellation and a
// sink's errors, the path's sampling across blocks, and the envelope's rows against an
// independent reference.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "sim_util.hpp"
#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

using test::end_mill;
using test::line_path;
using test::same_entry;
using test::small_wagih_job;

// Full-immersion slot, a_p = 1 mm, the tool entering from outside the stock and dwelling two
// revolutions at the end: the removed volume is the swept area (the slot 10 mm wide from the
// stock's edge at y = -10 to y = 20, plus the half disc at the end) times a_p = 339.27 mm^3.
// A board's volume error is bounded by the boundary's length (80 mm) times a_p times d / 2
// (rays whose centre falls on the wrong side of a boundary); it shrinks with the spacing.
// The three boards agree within the same bound.
TEST(Sim, StraightSlotRemovesTheSweptVolume) {
  const double want = 10.0 * 30.0 + 0.5 * kPi * 25.0;
  double prev_err = 1e9;
  for (const double d : {0.1, 0.05}) {
    Box3 box{{-8, -10, -2}, {8, 30, 0}};
    TriDexel work(box, d);
    SimSettings s;
    s.steps_per_rev = 60;
    const SimTool tool = end_mill(0);
    const double feed = 0.2 * 2 * 3000;  // f_z 0.2 mm
    const ToolPath p = line_path(0, -16, 20, -1, feed);
    const double t_end = p.duration_s() + 2 * 60.0 / 3000;
    const SimResult r = simulate(p, tool, s, work, 0, t_end);
    const double bound = 80 * 1.0 * d / 2;
    for (int b = 0; b < 3; ++b) {
      EXPECT_NEAR(r.removed_by_board_mm3[static_cast<std::size_t>(b)], want, bound)
          << d << " " << b;
      // The board's own bookkeeping: stock minus what remains.
      EXPECT_NEAR(box.volume_mm3() - work.boards[static_cast<std::size_t>(b)].volume_mm3(),
                  r.removed_by_board_mm3[static_cast<std::size_t>(b)], 1e-6 * want);
    }
    const double err = std::abs(r.removed_mm3 - want);
    EXPECT_LT(err, prev_err + 1e-9) << d;
    prev_err = err;
    EXPECT_GT(r.dexel_updates, 0u);
  }
}

// The envelope sweep (the fast pre-roll) along a half circle of radius 6 mm from (6, 0) to
// (-6, 0) (a 5 mm end mill, flat and with a 1 mm corner radius, 1 mm deep) in a stock above
// y = 0: the swept volume there is the annular sector from 1 to 11 mm, 60 pi mm^2, times a_p,
// less the corners (the end discs' outer halves lie below y = 0). Bound per board: the boundary's
// length (58 mm) times a_p times d / 2, plus the chords' 1 um over that length. The three boards
// agree with each other within the same bound, and the time-stepped simulation of the same path (60
// steps per revolution, dwelling a revolution at the end; its feed marks f_z^2 / 8R = 1e-3 mm over
// the 35 mm of outer wall are below the bound) leaves the same volume.
TEST(Sim, EnvelopeSweepRemovesTheSweptVolume) {
  for (const double rc : {0.0, 1.0}) {
    // Pappus: the tool's axial section (2R a_p less two corners of rc^2 (1 - pi / 4)) along the
    // path's 6 pi mm.
    const double want = (10.0 * 1.0 - 2 * rc * rc * (1 - kPi / 4)) * 6 * kPi;
    const double d = 0.05;
    const double bound = 58 * 1.0 * d / 2 + 58 * 1.0 * 0.001;
    const Box3 box{{-12, 0, -2}, {12, 12, 0}};
    ToolPath p;
    p.append(Segment::arc_xy(0, 0, 6, 0, kPi, -1, -1, Motion::feed, 1200));
    SimTool tool = end_mill(0);
    tool.corner_radius_mm = rc;
    TriDexel env(box, d);
    const double v = sweep_envelope(p, tool, env, 0, p.duration_s());
    EXPECT_NEAR(v, want, bound) << rc;
    double vb[3];
    for (int b = 0; b < 3; ++b) {
      vb[b] = box.volume_mm3() - env.boards[static_cast<std::size_t>(b)].volume_mm3();
      EXPECT_NEAR(vb[b], want, bound) << b;
    }
    EXPECT_NEAR(vb[2], v, 1e-9 * want);
    // The same half circle as 720 straight moves (the chord path of the sweep): the same
    // volume on every board within the bound.
    ToolPath poly;
    for (int q = 0; q < 720; ++q) {
      const double a0 = kPi * q / 720, a1 = kPi * (q + 1) / 720;
      poly.append(Segment::line(Vec3(6 * std::cos(a0), 6 * std::sin(a0), -1),
                                Vec3(6 * std::cos(a1), 6 * std::sin(a1), -1), Motion::feed, 1200));
    }
    TriDexel env2(box, d);
    (void)sweep_envelope(poly, tool, env2, 0, poly.duration_s());
    for (int b = 0; b < 3; ++b) {
      EXPECT_NEAR(box.volume_mm3() - env2.boards[static_cast<std::size_t>(b)].volume_mm3(), vb[b],
                  bound)
          << b;
    }
    // The same path time-stepped with the teeth, dwelling a revolution at the end.
    TriDexel work(box, d);
    SimSettings s;
    s.steps_per_rev = 60;
    const SimResult r = simulate(p, tool, s, work, 0, p.duration_s() + 60.0 / 3000);
    for (int b = 0; b < 3; ++b) {
      EXPECT_NEAR(r.removed_by_board_mm3[static_cast<std::size_t>(b)], vb[b], bound) << b;
    }
  }
}

// The annulus argument (docs/models.md section 11): after a revolution, searching only the
// annulus beyond each tooth's contour less the path since an earlier tooth (no higher) swept
// the same angles finds all the material. Against the same wedges searched whole, on a
// trochoidal cut with radial and axial runout, a helix and three unequally pitched teeth,
// starting from the envelope swept up to the window (so the annulus applies from the first
// step, bounded by the path since): bit-identical removed volumes, chip maps and update
// counts (the rays left out hold no material, so nothing else changes).
// Wagih's trochoid 0.5 mm deep with three unequally pitched teeth, radial and axial runout,
// 0.05 mm dexels and 72 steps per revolution.
Job runout_trochoid_job() {
  return load_job(
      test::example("wagih2023/trochoidal.toml"),
      {parse_override("slot.depth=0.5"), parse_override("slot.length=8"),
       parse_override("tool.teeth=3"), parse_override("tool.tooth_angles=[0, 110, 235]"),
       parse_override("tool.runout_radial=0.01"), parse_override("tool.runout_axial=0.005"),
       parse_override("tool.runout_phase=30"), parse_override("cutting.feed_rate=1200"),
       parse_override("simulation.resolution=0.05"),
       parse_override("simulation.steps_per_rev=72")});
}

// The annulus's bounds only leave out rays without material: the same window searched whole
// (SimSettings::exhaustive) gives the same volumes, updates and chips. At 72 steps per
// revolution the directional bound's margins (the centres' spread over the steps either side)
// are wide; at 600 they are a few microns and the bound is about the chip's crescent (the
// second window, a part of the same cycle). Narrowing the directional bound to 0.3 of its
// dot product without the spacing fails the second window and not the first.
void annulus_search_finds_all_the_material(const Job& job, double part) {
  const ToolPath path = plan_path(job).path;
  auto [from, to] = cycle_window(path, 3, 4);
  to = from + part * (to - from);
  const SimTool tool = sim_tool(job, job.simulation);
  SimSettings ex = job.simulation;
  ex.exhaustive = true;
  TriDexel w1(job_stock(job), 0.05), w2(job_stock(job), 0.05);
  (void)sweep_envelope(path, tool, w1, 0, from);
  (void)sweep_envelope(path, tool, w2, 0, from);
  // Both from the envelope: the annulus from the first step.
  SimControl after;
  after.envelope_before = true;
  const SimResult a = simulate(path, tool, job.simulation, w1, from, to, after);
  const SimResult b = simulate(path, tool, ex, w2, from, to, after);
  ASSERT_EQ(a.steps.size(), b.steps.size());
  EXPECT_EQ(a.removed_by_board_mm3, b.removed_by_board_mm3);
  EXPECT_EQ(a.dexel_updates, b.dexel_updates);
  ASSERT_EQ(a.chip_map.size(), b.chip_map.size());
  for (std::size_t q = 0; q < a.chip_map.size(); ++q) {
    ASSERT_EQ(a.chip_map[q].step, b.chip_map[q].step);
    ASSERT_EQ(a.chip_map[q].segment, b.chip_map[q].segment);
    ASSERT_EQ(a.chip_map[q].h_mm, b.chip_map[q].h_mm);
  }
  EXPECT_GT(a.removed_mm3, part * 1.0);
}

TEST(Sim, AnnulusSearchFindsAllTheMaterial) {
  annulus_search_finds_all_the_material(runout_trochoid_job(), 1.0);
  Job fine = runout_trochoid_job();
  fine.simulation.steps_per_rev = 600;
  annulus_search_finds_all_the_material(fine, 0.25);
}

// A window continuing the call before it (SimControl::after, its SimCarry) searches only the
// annulus from its first step; alone, its first revolution (and two steps) searches whole
// sectors. The wedges' shapes are each call's own, so the results are the same bit for bit
// (volumes, update counts, the chip map's h, w and v) with or without the carry: the rays the
// carry leaves out hold no material. A carry from another time is refused.
TEST(Sim, AWindowContinuesTheCallBeforeIt) {
  const Job job = runout_trochoid_job();
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 3, 4);
  const SimTool tool = sim_tool(job, job.simulation);
  const double rev = kTwoPi / std::abs(tool.omega_rad_per_s);
  SimResult lead[2], win[2];
  for (int k = 0; k < 2; ++k) {
    TriDexel w(job_stock(job), 0.05);
    (void)sweep_envelope(path, tool, w, 0, from);
    SimControl c;
    c.envelope_before = true;
    lead[k] = simulate(path, tool, job.simulation, w, from, from + rev, c);
    SimControl cw;
    if (k == 1) cw.after = &lead[k].carry;
    win[k] = simulate(path, tool, job.simulation, w, from + rev, to, cw);
  }
  const std::size_t n = win[0].steps.size(), spr = 72;
  ASSERT_GT(n, 3 * spr);
  EXPECT_EQ(lead[1].carry.t_s, from + rev);
  EXPECT_EQ(lead[1].carry.steps, lead[1].steps.size());
  EXPECT_EQ(win[0].annulus_steps, n - (spr + 2));  // settled after a revolution and two steps
  EXPECT_EQ(win[1].annulus_steps, n);
  EXPECT_EQ(win[1].carry.steps, lead[1].steps.size() + n);
  EXPECT_EQ(win[0].removed_by_board_mm3, win[1].removed_by_board_mm3);
  EXPECT_EQ(win[0].dexel_updates, win[1].dexel_updates);
  ASSERT_EQ(win[0].chip_map.size(), win[1].chip_map.size());
  for (std::size_t q = 0; q < win[0].chip_map.size(); ++q) {
    ASSERT_TRUE(same_entry(win[0].chip_map[q], win[1].chip_map[q])) << q;
  }
  EXPECT_GT(win[0].removed_mm3, 1.0);
  // A carry that ended elsewhere.
  TriDexel w(job_stock(job), 0.05);
  SimControl wrong;
  wrong.after = &lead[1].carry;
  EXPECT_THROW((void)simulate(path, tool, job.simulation, w, from + 2 * rev, to, wrong), Error);
}

// Cancellation (Ctrl-C in the CLI): a flag raised before the run stops it in the pre-roll,
// with no steps and `complete` false; raised from the progress callback after some steps, the
// window keeps the steps computed so far (fewer than the whole) and is marked incomplete.
TEST(Sim, CancelKeepsWhatWasComputed) {
  const Job job = small_wagih_job();
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 2, 3);
  std::atomic<bool> stop{true};
  SimControl c;
  c.hooks.cancel = &stop;
  const JobSimulation early = simulate_job(job, path, from, to, c);
  EXPECT_FALSE(early.result.complete);
  EXPECT_TRUE(early.result.steps.empty());
  ASSERT_NE(early.work, nullptr);

  stop = false;
  std::size_t calls = 0;
  std::vector<std::string> phases;
  c.hooks.phase = [&](std::string_view name) { phases.emplace_back(name); };
  c.hooks.progress = [&](std::size_t done, std::size_t total) {
    // Stopped in the window, after its third report.
    if (phases.back() == "window" && ++calls == 3) stop = true;
    EXPECT_LE(done, total);
  };
  const JobSimulation part = simulate_job(job, path, from, to, c);
  EXPECT_EQ(phases, (std::vector<std::string>{"pre-roll: envelope", "pre-roll: last revolution",
                                              "window"}));
  EXPECT_FALSE(part.result.complete);
  EXPECT_GT(part.result.steps.size(), 0u);
  const JobSimulation whole = simulate_job(job, path, from, to);
  EXPECT_TRUE(whole.result.complete);
  EXPECT_LT(part.result.steps.size(), whole.result.steps.size());
  // What was computed is what the whole run computed up to there.
  for (std::size_t n = 0; n < part.result.steps.size(); ++n) {
    ASSERT_EQ(part.result.steps[n].h_max_mm, whole.result.steps[n].h_max_mm);
  }
}

// What a sink throws stops the simulation and comes out of it, the sink called no more: the
// steps go through a pipeline in batches (several in flight), and none is taken after the
// throw.
TEST(Sim, WhatTheSinkThrowsStopsTheSimulation) {
  const Job job = small_wagih_job();
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 2, 3);
  struct Full final : SimSink {
    void take(const SimStep&, std::span<const ChipEntry>) override {
      if (++calls == 500) throw std::runtime_error("the sink is full");
    }
    std::size_t calls = 0;
  } full;
  SimControl c;
  c.keep_records = false;
  c.sink = &full;
  try {
    (void)simulate_job(job, path, from, to, c);
    ADD_FAILURE() << "simulate did not throw";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "the sink is full");
  }
  EXPECT_EQ(full.calls, 500u);
}

// The path is sampled a block of 65,536 steps at a time: over more than two blocks every step's
// tip is where the path is at the step's time (the path sampled at all those times at once).
TEST(Sim, StepsFollowThePathAcrossSampleBlocks) {
  const Box3 box{{-8, -10, -2}, {8, 30, 0}};
  SimSettings s;
  s.steps_per_rev = 4000;  // 200,000 steps per second at 3000 rpm
  const SimTool tool = end_mill(0);
  const ToolPath p = line_path(0, -16, 20, -1, 0.1 * 2 * 3000);
  TriDexel work(box, 0.5);
  const SimResult r = simulate(p, tool, s, work, 0, 0.7);
  ASSERT_GT(r.steps.size(), 2u * 65536u + 1000u);
  std::vector<double> times;
  for (const SimStep& st : r.steps) times.push_back(st.t_s);
  const PathSamples at = sample_at_times(p, times);
  for (std::size_t n = 0; n < r.steps.size(); ++n) {
    ASSERT_EQ(r.steps[n].tip_mm[0], at.x_mm[n]) << n;
    ASSERT_EQ(r.steps[n].tip_mm[1], at.y_mm[n]) << n;
    ASSERT_EQ(r.steps[n].tip_mm[2], at.z_mm[n]) << n;
  }
  EXPECT_GT(r.removed_mm3, 0.0);
}

// The envelope's boards against an independent reference: a polygon of 90 moves,
// each 0.5 mm long and turned 10.5 degrees from the one before (two and a half loops, each
// over the last, like a trochoid's), swept by an end mill with a 1 mm corner. Every corner lies on
// one of the sweep's sample points, so its pieces are the moves themselves. On each ray the
// material left must be the stock less the union, over the moves, of the points within the
// contour's radius at the ray's height of the move: each such set on a line is an interval
// (the distance to a segment is convex along the line), found here by golden section and bisection
// (to 1e-16 mm). The sweep merges the moves' intervals row by row and skips moves its union already
// covers: it must agree to 1e-9 mm (the pieces' closed forms round at about 1e-15 mm), the boards
// must be the same bit for bit on one thread and on all, and the volume the same.
TEST(Sim, EnvelopeRowsAreTheUnionOfTheMoves) {
  const Box3 box{{-6, -4, -2}, {8, 12, 0}};
  const double d = 0.05, z = -1.0;
  ToolPath path;
  std::vector<std::array<double, 4>> moves;  // (ax, ay, bx, by)
  double x = 0, y = 0;
  for (int k = 0; k < 90; ++k) {
    const double a = deg_to_rad(10.5 * k);
    const double nx = x + 0.5 * std::cos(a), ny = y + 0.5 * std::sin(a);
    path.append(Segment::line(Vec3(x, y, z), Vec3(nx, ny, z), Motion::feed, 1200));
    moves.push_back({x, y, nx, ny});
    x = nx, y = ny;
  }
  SimTool tool = end_mill(0);
  tool.radius_mm = 3;
  tool.corner_radius_mm = 1;
  TriDexel one(box, d), all(box, d);
  double v_one = 0;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    v_one = sweep_envelope(path, tool, one, 0, path.duration_s());
  }
  const double v_all = sweep_envelope(path, tool, all, 0, path.duration_s());
  EXPECT_EQ(v_one, v_all);
  EXPECT_GT(v_all, 10.0);
  // The points of the line {(t, across)} within r of segment A-B: [lo, hi] or nothing.
  auto on_line = [](double ax, double ay, double bx, double by, double r,
                    double across) -> std::optional<Interval> {
    auto dist = [&](double t) {
      const double ux = bx - ax, uy = by - ay, l2 = ux * ux + uy * uy;
      const double s = std::clamp(((t - ax) * ux + (across - ay) * uy) / l2, 0.0, 1.0);
      return std::hypot(t - ax - s * ux, across - ay - s * uy);
    };
    if (across < std::min(ay, by) - r || across > std::max(ay, by) + r) return std::nullopt;
    double lo = std::min(ax, bx) - r - 1, hi = std::max(ax, bx) + r + 1;
    for (int it = 0; it < 90; ++it) {  // 0.618^90 of 9 mm: below 1e-17 mm  // the convex distance's
                                       // minimum (golden section)
      const double m1 = lo + 0.382 * (hi - lo), m2 = lo + 0.618 * (hi - lo);
      (dist(m1) < dist(m2) ? hi : lo) = dist(m1) < dist(m2) ? m2 : m1;
    }
    const double tm = 0.5 * (lo + hi);
    if (dist(tm) > r) return std::nullopt;
    auto root = [&](double in, double out) {
      for (int it = 0; it < 64; ++it) {  // 2^-64 of 4 mm
        const double m = 0.5 * (in + out);
        (dist(m) <= r ? in : out) = m;
      }
      return 0.5 * (in + out);
    };
    return Interval{root(tm, tm - r - 1), root(tm, tm + r + 1)};
  };
  std::size_t rays = 0;
  for (int b = 0; b < 2; ++b) {
    const DexelBoard& board = all.boards[static_cast<std::size_t>(b)];
    const DexelBoard& single = one.boards[static_cast<std::size_t>(b)];
    for (int i = 0; i < board.count_u(); ++i) {
      for (int j = 0; j < board.count_v(); ++j) {
        const auto got = board.intervals(i, j);
        ASSERT_EQ(board.touched(i, j), single.touched(i, j));
        ASSERT_TRUE(std::ranges::equal(
            got, single.intervals(i, j),
            [](const Interval& p, const Interval& q) { return p.lo == q.lo && p.hi == q.hi; }))
            << b << " " << i << " " << j;
        if ((i + j) % 3 != 0) continue;  // a third of the rays against the reference
        // Board 0: rays along x at (y, z) = (u, v); board 1: along y at (z, x) = (u, v).
        const double h = (b == 0 ? board.v_of(j) : board.u_of(i)) - z;
        const double across = b == 0 ? board.u_of(i) : board.v_of(j);
        std::vector<Interval> cut;
        const double r = tool.profile_radius(h);
        if (h >= 0 && r > 0) {
          for (const auto& m : moves) {
            const auto iv = b == 0 ? on_line(m[0], m[1], m[2], m[3], r, across)
                                   : on_line(m[1], m[0], m[3], m[2], r, across);
            if (iv) cut.push_back(*iv);
          }
        }
        std::sort(cut.begin(), cut.end(), [](auto& p, auto& q) { return p.lo < q.lo; });
        std::vector<Interval> want;  // the stock along the ray less the union
        double from = board.full().lo;
        for (const Interval& c : cut) {
          if (c.lo > from) want.push_back({from, std::min(c.lo, board.full().hi)});
          from = std::max(from, c.hi);
        }
        if (from < board.full().hi) want.push_back({from, board.full().hi});
        std::erase_if(want, [](const Interval& v) { return !(v.hi > v.lo); });
        const std::vector<Interval> have(got.begin(), got.end());
        ASSERT_EQ(have.size(), want.size()) << b << " " << i << " " << j;
        for (std::size_t q = 0; q < have.size(); ++q) {
          EXPECT_NEAR(have[q].lo, want[q].lo, 1e-9) << b << " " << i << " " << j;
          EXPECT_NEAR(have[q].hi, want[q].hi, 1e-9) << b << " " << i << " " << j;
        }
        ++rays;
      }
    }
  }
  EXPECT_GT(rays, 8000u);
  // The Z board: each ray cut from the tip up to where the contour reaches its distance from
  // the nearest move (the nearer moves' height ranges hold the farther ones').
  const DexelBoard& zb = all.boards[2];
  std::size_t zrays = 0, corner = 0;
  const double top = box.hi[2];
  for (int i = 0; i < zb.count_u(); i += 2) {
    for (int j = 0; j < zb.count_v(); j += 2) {
      const double px = zb.u_of(i), py = zb.v_of(j);
      double rho = 1e300;
      for (const auto& m : moves) {
        const double ux = m[2] - m[0], uy = m[3] - m[1];
        const double s =
            std::clamp(((px - m[0]) * ux + (py - m[1]) * uy) / (ux * ux + uy * uy), 0.0, 1.0);
        rho = std::min(rho, std::hypot(px - m[0] - s * ux, py - m[1] - s * uy));
      }
      std::vector<Interval> want{zb.full()};
      if (const auto reach = tool.heights_reaching(rho)) {
        const double lo = z + reach->lo, hi = std::min(top, z + reach->hi);
        if (hi > lo) {
          want.clear();
          if (lo > zb.full().lo) want.push_back({zb.full().lo, lo});
          if (hi < zb.full().hi) want.push_back({hi, zb.full().hi});
          corner += reach->lo > 0 ? 1 : 0;
        }
      }
      const auto got = zb.intervals(i, j);
      const std::vector<Interval> have(got.begin(), got.end());
      ASSERT_EQ(have.size(), want.size()) << i << " " << j << " " << rho;
      for (std::size_t q = 0; q < have.size(); ++q) {
        EXPECT_NEAR(have[q].lo, want[q].lo, 1e-9) << i << " " << j;
        EXPECT_NEAR(have[q].hi, want[q].hi, 1e-9) << i << " " << j;
      }
      ++zrays;
    }
  }
  EXPECT_GT(zrays, 10000u);
  EXPECT_GT(corner, 1000u);  // rays under the corner's ring, cut part of the way only
  for (int i = 0; i < zb.count_u(); ++i) {
    for (int j = 0; j < zb.count_v(); ++j) {
      ASSERT_EQ(zb.touched(i, j), one.boards[2].touched(i, j));
      ASSERT_TRUE(
          std::ranges::equal(zb.intervals(i, j), one.boards[2].intervals(i, j),
                             [](auto& p, auto& q) { return p.lo == q.lo && p.hi == q.hi; }));
    }
  }
}

}  // namespace
}  // namespace trochomill
