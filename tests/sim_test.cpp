// Tri-dexel simulation: dexel arithmetic, removed volume of a straight
// slot against the swept volume (converging with the spacing, the three boards agreeing),
// the chip of a straight partial-immersion cut against f_z sin(phi).
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"

#include <gtest/gtest.h>
#include <hwy/targets.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "sim/plane.hpp"
#include "sim/rows.hpp"
#include "test_util.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

TEST(Sim, DexelSubtract) {
  Dexel d({0, 10});
  std::vector<Interval> removed;
  EXPECT_DOUBLE_EQ(d.subtract(2, 3, removed), 1.0);
  ASSERT_EQ(d.intervals().size(), 2u);
  EXPECT_EQ(d.intervals()[0].hi, 2);
  EXPECT_EQ(d.intervals()[1].lo, 3);
  EXPECT_DOUBLE_EQ(d.subtract(-1, 1, removed), 1.0);
  EXPECT_DOUBLE_EQ(d.subtract(2.5, 4, removed), 1.0);  // half in the gap
  EXPECT_DOUBLE_EQ(d.subtract(20, 30, removed), 0.0);
  EXPECT_DOUBLE_EQ(d.length(), 7.0);
  ASSERT_EQ(removed.size(), 3u);
  EXPECT_EQ(removed[2].lo, 3);
  EXPECT_EQ(removed[2].hi, 4);
  EXPECT_DOUBLE_EQ(d.subtract(0, 100, removed), 7.0);
  EXPECT_TRUE(d.intervals().empty());
  // A default dexel is empty (a spilled state with no block): no intervals, no length, and
  // nothing removed from it (clang's UBSan once caught an offset applied to its null block).
  const Dexel empty;
  EXPECT_TRUE(empty.intervals().empty());
  EXPECT_EQ(empty.length(), 0.0);
  EXPECT_EQ(Dexel().subtract(0, 1, removed), 0.0);
}

// A dexel split beyond its inline intervals moves to the heap, and back inline (its block
// freed) once cuts leave few enough: the intervals are the same either way.
TEST(Sim, DexelComesBackInlineWhenCutsJoinItAgain) {
  std::vector<Interval> removed;
  Dexel d({0, 10});
  (void)d.subtract(2, 3, removed);
  EXPECT_EQ(d.heap_bytes(), 0U);  // two intervals: inline
  (void)d.subtract(5, 6, removed);
  ASSERT_EQ(d.intervals().size(), 3U);
  EXPECT_GT(d.heap_bytes(), 0U);        // three: spilled
  (void)d.subtract(1.5, 5.5, removed);  // [0, 1.5] and [6, 10] left
  ASSERT_EQ(d.intervals().size(), 2U);
  EXPECT_EQ(d.heap_bytes(), 0U);
  EXPECT_EQ(d.intervals()[0].lo, 0);
  EXPECT_EQ(d.intervals()[0].hi, 1.5);
  EXPECT_EQ(d.intervals()[1].lo, 6);
  EXPECT_EQ(d.intervals()[1].hi, 10);
  // Inline again, it splits and spills again, and a spilled one emptied holds no block.
  (void)d.subtract(7, 8, removed);
  EXPECT_GT(d.heap_bytes(), 0U);
  (void)d.subtract(-1, 11, removed);
  EXPECT_TRUE(d.intervals().empty());
  EXPECT_EQ(d.heap_bytes(), 0U);
  // The Z board's dexel (one inline interval) likewise.
  BasicDexel<1> z({0, 10});
  (void)z.subtract(4, 5, removed);
  EXPECT_GT(z.heap_bytes(), 0U);
  (void)z.subtract(3, 10, removed);
  ASSERT_EQ(z.intervals().size(), 1U);
  EXPECT_EQ(z.heap_bytes(), 0U);
  EXPECT_EQ(z.intervals()[0].hi, 3);
}

// Random subtractions against a plain reference (intervals rebuilt in a fresh vector each
// time): the in-place, inline-first dexel holds exactly the same intervals (the arithmetic is
// the same min/max on the same doubles: exact equality) and reports the same removed pieces,
// with one inline interval (the Z board's) and two (the X and Y boards'), through copies and
// moves between inline and heap storage.
template <std::uint32_t N>
void dexel_matches_a_reference() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-1, 11), len(0, 3);
  std::size_t on_heap = 0;
  for (int trial = 0; trial < 200; ++trial) {
    BasicDexel<N> d({0, 10});
    std::vector<Interval> ref{{0, 10}};
    auto same = [&](const BasicDexel<N>& x) {
      const auto iv = x.intervals();
      return std::ranges::equal(iv, ref, [](const Interval& p, const Interval& q) {
        return p.lo == q.lo && p.hi == q.hi;
      });
    };
    for (int op = 0; op < 12; ++op) {
      const double a = pos(rng), b = a + len(rng);
      std::vector<Interval> got, want, next;
      const double cut = d.subtract(a, b, got);
      double want_cut = 0;
      for (const Interval& v : ref) {
        if (v.hi <= a || v.lo >= b) {
          next.push_back(v);
          continue;
        }
        const double lo = std::max(v.lo, a), hi = std::min(v.hi, b);
        want.push_back({lo, hi});
        want_cut += hi - lo;
        if (v.lo < lo) next.push_back({v.lo, lo});
        if (hi < v.hi) next.push_back({hi, v.hi});
      }
      ref = next;
      EXPECT_DOUBLE_EQ(cut, want_cut);
      ASSERT_EQ(got.size(), want.size());
      for (std::size_t k = 0; k < got.size(); ++k) {
        EXPECT_EQ(got[k].lo, want[k].lo);
        EXPECT_EQ(got[k].hi, want[k].hi);
      }
      ASSERT_TRUE(same(d)) << N << " " << trial << " " << op;
      on_heap += d.heap_bytes() > 0 ? 1 : 0;
      const BasicDexel<N> copy = d;  // copies keep the intervals
      ASSERT_TRUE(same(copy));
      BasicDexel<N> moved(std::move(d));  // so do moves, and assignments of either
      ASSERT_TRUE(same(moved));
      BasicDexel<N> other({-5, -4});
      other = copy;
      ASSERT_TRUE(same(other));
      d = std::move(moved);
      ASSERT_TRUE(same(d));
    }
  }
  EXPECT_GT(on_heap, 100u) << N;  // the heap's storage was exercised
}

TEST(Sim, DexelMatchesAReferenceUnderRandomCuts) {
  dexel_matches_a_reference<1>();
  dexel_matches_a_reference<2>();
  static_assert(sizeof(BasicDexel<1>) == 16 && sizeof(BasicDexel<2>) == 32);
}

// A square end mill (R 5 mm, two teeth) along a straight line through a box.
SimTool end_mill(double helix_deg, int teeth = 2, double rpm = 3000) {
  SimTool t;
  t.radius_mm = 5;
  t.flute_length_mm = 3;
  t.helix_rad = deg_to_rad(helix_deg);
  for (int k = 0; k < teeth; ++k) {
    t.tooth_angle_rad.push_back(kTwoPi * k / teeth);
    t.radial_offset_mm.push_back(0);
    t.axial_offset_mm.push_back(0);
  }
  t.omega_rad_per_s = -rpm_to_rad_per_s(rpm);  // cw
  t.segment_mm = 0.1;
  return t;
}

ToolPath line_path(double x, double y0, double y1, double z, double feed_mm_per_min) {
  ToolPath p;
  p.append(Segment::line(Vec3(x, y0, z), Vec3(x, y1, z), Motion::feed, feed_mm_per_min));
  return p;
}

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

// Straight partial immersion (a_e = 1 mm on the right, feed along +y, cw spindle: down
// milling): while a tooth is engaged its chip at tooth angle a (from +x, the wedge's middle)
// is f_z sin(a)... measured from the feed direction: h = f_z cos(a - pi/2) = f_z sin(a) for
// the radius at angle a. Tolerance: f_z (Delta + 2 pi / steps) for the wedge's angular width
// (h_max is over the wedge) plus f_z^2 / (2 R) (a translated circle against the trochoidal
// tooth path) plus 2e-4 mm for the dexels' sampling across the wedge at d = 0.02 mm.
TEST(Sim, PartialImmersionChipIsFzSinPhi) {
  const double R = 5, ae = 1, fz = 0.1, d = 0.02;
  Box3 box{{R - ae, -2, -1}, {R + 2, 12, 0}};
  TriDexel work(box, d);
  SimSettings s;
  s.steps_per_rev = 120;
  const SimTool tool = end_mill(0);
  const ToolPath p = line_path(0, -8, 10, -0.5, fz * 2 * 3000);
  const SimResult r = simulate(p, tool, s, work, 0, p.duration_s());
  const double delta = kTwoPi / s.steps_per_rev;
  const double phi_max = std::acos((R - ae) / R);
  int checked = 0;
  for (std::size_t n = 1; n < r.steps.size(); ++n) {
    const SimStep& st = r.steps[n];
    if (st.tip_mm[1] < 2 || st.tip_mm[1] > 8) continue;  // steady part of the cut
    for (std::size_t k = 0; k < 2; ++k) {
      // The tooth's angle at this step (mid-wedge), mod 2 pi into (-pi, pi].
      double a = tool.tooth_angle_rad[k] +
                 tool.omega_rad_per_s * (st.t_s - 0.5 * delta / std::abs(tool.omega_rad_per_s));
      a = std::remainder(a, kTwoPi);
      if (a < 0.05 || a > phi_max - 0.05) continue;  // inside the engagement, off its ends
      const double want = fz * std::sin(a);
      const double tol = fz * 2 * delta + fz * fz / (2 * R) + 2e-4;
      EXPECT_NEAR(st.h_max_mm, want, tol) << "step " << n << " angle " << a;
      ++checked;
    }
  }
  EXPECT_GT(checked, 50);
}

// Full slot with four teeth and a 35 degree helix: the chip never exceeds f_z plus the
// wedge's angular width times f_z plus f_z^2 / 2R, and reaches f_z (the tooth at 90
// degrees) within that tolerance. (A first version left slivers between consecutive wedges
// taken about different centres, which the next tooth met with a doubled chip.)
TEST(Sim, FullSlotChipPeaksAtFz) {
  const double fz = 0.075, R = 5, d = 0.04;
  Box3 box{{-6, -10, -1}, {6, -4, 0}};
  TriDexel work(box, d);
  SimSettings s;
  s.steps_per_rev = 120;
  SimTool tool = end_mill(35, 4, 2000);
  tool.flute_length_mm = 1.5;
  const ToolPath p = line_path(0, -16, -8, -0.5, fz * 4 * 2000);
  const SimResult r = simulate(p, tool, s, work, 0, p.duration_s());
  const double tol = fz * 2 * kTwoPi / s.steps_per_rev + fz * fz / (2 * R) + 4e-4;
  double hmax = 0;
  for (const SimStep& st : r.steps) {
    if (st.tip_mm[1] < -10) continue;  // steady (the front in the stock since y = -15)
    EXPECT_LT(st.h_max_mm, fz + tol) << st.t_s;
    hmax = std::max(hmax, st.h_max_mm);
  }
  EXPECT_NEAR(hmax, fz, tol);
  // The engaged width: the cut is 0.5 mm deep (tip at -0.5) and the segments 0.1 mm, so a
  // segment with a real chip is engaged over its whole length. Within one step the rays that
  // lose material see only part of it (the twisted wedge crosses a vertical ray over 0.37 mm
  // of height and the rays are 0.04 mm apart), so the measured extent is at most the segment
  // and, on average, most of it: mean above 80 %.
  int full = 0;
  double sum_w = 0;
  for (const ChipEntry& c : r.chip_map) {
    EXPECT_LE(c.w_mm, 0.1f + 1e-6f);
    if (c.h_mm > 0.5 * fz && r.steps[c.step].tip_mm[1] > -10) {
      sum_w += c.w_mm;
      ++full;
    }
  }
  EXPECT_GT(sum_w / full, 0.08);
  // The segments' volumes add up to the teeth's (Z board): the map loses only the pieces of
  // segments whose chip is below chip_sampling (slivers), bounded here by 1 %.
  double seg_v = 0, tooth_v = 0;
  for (const ChipEntry& c : r.chip_map) seg_v += c.v_mm3;
  for (const SimStep& st : r.steps) {
    for (const double v : st.removed_mm3) tooth_v += v;
  }
  EXPECT_NEAR(seg_v, tooth_v, 0.01 * tooth_v);
  EXPECT_LE(seg_v, tooth_v * (1 + 1e-6));
  EXPECT_GT(full, 100);
}

// A ball-nose end mill (R = rc = 5 mm, two teeth) in a full slot 1 mm deep: at height h above
// the tip the contour radius is r(h) = sqrt(2 R h - h^2) and the edge's sine r(h) / R, so the
// chip normal to the edge is at most f_z sin(phi) (the radial depth in a full slot is at most
// f_z, at the front), 0.075 mm at the top for f_z = 0.125 mm, and every segment's largest
// chip over the run reaches that of its lower end. The layers narrower than R / 2 are where the
// closing wedges' sector alone left slivers between consecutive steps (the next teeth then
// read 0.11-0.16 mm 0.1-0.2 mm above the tip); the strip closes them. Both spindle senses.
// Tolerance: the sampled wedges, as the flat end mill's (f_z 2 pi nz / steps_per_rev ... as
// below), plus a spacing's change of r(h) times the sine (the Z board reads a piece at its
// widest point within the segment, up to one ray's rounding of rho): d sin(phi) at most.
TEST(Sim, BallNoseChipIsFzTimesTheEdgeSine) {
  for (const double sense : {-1.0, 1.0}) {
    const double fz = 0.125, R = 5, d = 0.04, ap = 1;
    Box3 box{{-7, -10, -2}, {7, -2, 0}};
    TriDexel work(box, d);
    SimSettings s;
    s.steps_per_rev = 60;
    SimTool tool = end_mill(0, 2, 2000);
    tool.corner_radius_mm = R;
    tool.omega_rad_per_s *= sense;
    tool.segment_mm = 0.1;
    const ToolPath p = line_path(0, -16, -4, -ap, fz * 2 * 2000);
    const SimResult r = simulate(p, tool, s, work, 0, p.duration_s());
    const int segs = tool.segments();
    const double step_tol = fz * 2 * kTwoPi / s.steps_per_rev + fz * fz / (2 * R);
    std::vector<double> seg_max(static_cast<std::size_t>(segs), 0.0);
    int checked = 0;
    for (const ChipEntry& c : r.chip_map) {
      if (r.steps[c.step].tip_mm[1] < -8) continue;  // steady: the front in the stock since -15
      const int sg = static_cast<int>(c.segment % static_cast<std::uint32_t>(segs));
      const double top = std::min(ap, tool.height_at_length((sg + 1) * tool.segment_mm));
      const double sine = tool.profile_radius(top) / R;
      EXPECT_LT(c.h_mm, (fz + step_tol) * sine + d * sine + 1e-4)
          << "sense " << sense << " segment " << sg << " step " << c.step;
      seg_max[static_cast<std::size_t>(sg)] =
          std::max(seg_max[static_cast<std::size_t>(sg)], static_cast<double>(c.h_mm));
      ++checked;
    }
    EXPECT_GT(checked, 1000);
    double hmax = 0;
    for (int sg = 0; sg < segs; ++sg) {
      const double top = tool.height_at_length((sg + 1) * tool.segment_mm);
      if (top > ap) break;
      const double bottom = tool.height_at_length(sg * tool.segment_mm);
      const double sine = tool.profile_radius(bottom) / R;
      // The lowest segments' chips are below chip_sampling's resolution or a ray apart.
      if (bottom < 4 * d) continue;
      EXPECT_GT(seg_max[static_cast<std::size_t>(sg)], (fz - step_tol) * sine - d * sine - 1e-4)
          << "sense " << sense << " segment " << sg;
      hmax = std::max(hmax, seg_max[static_cast<std::size_t>(sg)]);
    }
    EXPECT_NEAR(hmax, fz * tool.profile_radius(ap) / R, (step_tol + d) * 0.6 + 1e-4);
    // With the strips nothing is left nearer the centre than the annulus: searching the whole
    // wedges finds nothing more, bit for bit (without the strips this differs).
    if (sense > 0) continue;
    SimSettings ex = s;
    ex.exhaustive = true;
    TriDexel work2(box, d);
    const SimResult e = simulate(p, tool, ex, work2, 0, p.duration_s());
    EXPECT_EQ(r.removed_by_board_mm3, e.removed_by_board_mm3);
    EXPECT_EQ(r.dexel_updates, e.dexel_updates);
    ASSERT_EQ(r.chip_map.size(), e.chip_map.size());
    for (std::size_t q = 0; q < r.chip_map.size(); ++q) {
      ASSERT_EQ(r.chip_map[q].segment, e.chip_map[q].segment) << q;
      ASSERT_EQ(r.chip_map[q].h_mm, e.chip_map[q].h_mm) << q;
    }
  }
}

// Radial runout e (tooth 0 on the offset's side): tooth 0 cuts at R + e, tooth 1 at R - e,
// so tooth 0's chip is the feed's f_z sin(a) plus 2e and tooth 1's minus 2e. Compared at
// the front (a near 90 degrees) in a full slot with two straight teeth: the two teeth's
// largest chips differ by 4e within 2e-4 mm (the wedges' sampling; both see the same feed).
TEST(Sim, RadialRunoutSplitsTheChips) {
  const double fz = 0.1, e = 0.01, d = 0.02;
  Box3 box{{-6, -10, -0.2}, {6, -4, 0}};
  TriDexel work(box, d);
  SimSettings s;
  s.steps_per_rev = 120;
  SimTool tool = end_mill(0, 2, 3000);
  tool.flute_length_mm = 0.5;
  tool.radial_offset_mm = {e, -e};
  const ToolPath p = line_path(0, -16, -8, -0.1, fz * 2 * 3000);
  const SimResult r = simulate(p, tool, s, work, 0, p.duration_s());
  double h[2] = {0, 0};
  for (const ChipEntry& c : r.chip_map) {
    if (r.steps[c.step].tip_mm[1] < -10) continue;
    const auto k =
        static_cast<std::size_t>(c.segment) / static_cast<std::size_t>(r.segments_per_tooth);
    h[k] = std::max(h[k], static_cast<double>(c.h_mm));
  }
  EXPECT_NEAR(h[0] - h[1], 4 * e, 2e-4);
  EXPECT_NEAR(0.5 * (h[0] + h[1]), fz, 0.01 * fz + 2e-4);
}

// Helix: the edge at height h trails the tip by h tan(helix) / R radians, so a segment at
// height h first cuts that much later in the spindle's turn. With a 30 degree helix and
// segments at 0.05 and 0.95 mm, the first steps with a chip differ by the lag (0.9 mm
// tan 30 / 5 mm = 0.104 rad) to within two steps.
TEST(Sim, HelixLagsEngagementAlongTheAxis) {
  const double d = 0.02, rpm = 3000;
  Box3 box{{4, -1, -1}, {6, 1, 0}};  // a block the stationary tool reaches on its +x side
  TriDexel work(box, d);
  SimSettings s;
  s.steps_per_rev = 360;
  SimTool tool = end_mill(30, 1, rpm);
  tool.segment_mm = 0.1;
  tool.tooth_angle_rad = {0.5 * kPi};  // turning clockwise into the block (|angle| < 37 deg)
  ToolPath p;
  p.append(Segment::line(Vec3(0, 0, -1), Vec3(0, 1e-6, -1), Motion::feed, 1e-6));
  const double rev = 60.0 / rpm;
  const SimResult r = simulate(p, tool, s, work, 0, rev);
  auto first_step = [&](int seg) {
    for (const ChipEntry& c : r.chip_map) {
      if (static_cast<int>(c.segment) == seg) return static_cast<int>(c.step);
    }
    return -1;
  };
  const int s0 = first_step(0), s9 = first_step(9);
  ASSERT_GE(s0, 0);
  ASSERT_GE(s9, 0);
  const double lag_steps = 0.9 * std::tan(deg_to_rad(30.0)) / 5.0 / (kTwoPi / s.steps_per_rev);
  EXPECT_NEAR(s9 - s0, lag_steps, 2.0);
}

// A trochoidal cut (Wagih's trochoidal example with a straight-fluted tool, 0.5 mm deep, f_z
// 0.225 mm, 0.05 mm dexels, 90 steps per revolution), its cycle 6 after a coarse pre-roll of
// the first six: each tooth's pass through the cut, its largest chip at the step t* where it
// meets it, against the analysis kernel's h_max at t* (the largest chip over the engaged
// arc, the removed region built from samples one tooth period apart, t* - k t_z: the previous
// tooth's pass). The kernel runs on 12 phases of that grid and the nearest is taken (within
// t_z / 24, where h_max moves by at most 0.001 mm here). Tolerance: the issue's 3 % of f_z
// (0.0068 mm; seen: 0.0047), wherever the kernel has a chip; the sim's own errors are the wedge's 4
// degree span around a flat maximum and the dexel spacing in the step direction (the X/Y rays
// measure the chip's radial depth exactly). Also: one thread and two give identical results.
TEST(Sim, TrochoidChipMatchesTheAnalysisKernel) {
  const Job job =
      load_job(test::example("wagih2023/trochoidal.toml"),
               {parse_override("slot.depth=0.5"), parse_override("slot.length=12"),
                parse_override("tool.helix_angle=0"), parse_override("cutting.feed_rate=1800"),
                parse_override("simulation.resolution=0.05"),
                parse_override("simulation.steps_per_rev=90")});
  const double fz = 1800.0 / (2000.0 * 4);  // 0.225 mm
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 6, 7);
  const JobSimulation js = simulate_job(job, path, from, to);
  const SimResult& r = js.result;
  ASSERT_GT(r.steps.size(), 100u);
  const double tz = 60.0 / (2000.0 * 4);
  constexpr int kPhases = 12;
  std::vector<std::vector<double>> grid(kPhases);
  std::vector<EngagementSeries> kernel;
  for (int p = 0; p < kPhases; ++p) {
    for (double t = p * tz / kPhases; t <= to + tz; t += tz) grid[p].push_back(t);
    kernel.push_back(compute_engagement(sample_at_times(path, grid[p]), job, EngagementOptions{}));
  }
  // Each tooth's passes through the cut (runs of steps where it has a chip; a gap of one
  // step does not split a pass), each pass's largest chip and its step.
  const int segs = r.segments_per_tooth;
  std::vector<std::vector<double>> tooth_h(4, std::vector<double>(r.steps.size(), 0.0));
  for (const ChipEntry& c : r.chip_map) {
    double& v = tooth_h[c.segment / static_cast<std::uint32_t>(segs)][c.step];
    v = std::max(v, static_cast<double>(c.h_mm));
  }
  struct Pass {
    std::size_t step;
    double h;
  };
  std::vector<Pass> passes;
  for (const auto& h : tooth_h) {
    std::optional<Pass> cur;
    std::size_t last = 0;
    for (std::size_t n = 0; n < h.size(); ++n) {
      if (!(h[n] > 0)) continue;
      if (cur && n > last + 2) passes.push_back(*cur), cur.reset();
      if (!cur || h[n] > cur->h) cur = Pass{n, h[n]};
      last = n;
    }
    if (cur) passes.push_back(*cur);
  }
  double worst = 0;
  int compared = 0;
  for (const Pass& pass : passes) {
    const double ts = r.steps[pass.step].t_s;
    // Whole passes only: not cut by the window's ends.
    if (ts < from + tz || ts > to - tz) continue;
    // The kernel sample nearest t*.
    double gap = 1e9, h_kernel = 0;
    for (int p = 0; p < kPhases; ++p) {
      const auto q = static_cast<std::size_t>(std::lround((ts - grid[p][0]) / tz));
      if (q < grid[p].size() && std::abs(grid[p][q] - ts) < gap) {
        gap = std::abs(grid[p][q] - ts);
        h_kernel = kernel[p].h_max_mm[q];
      }
    }
    ASSERT_LE(gap, tz / (2 * kPhases) + 1e-9);
    if (!(h_kernel > 0.05 * fz) && !(pass.h > 0.05 * fz)) continue;
    worst = std::max(worst, std::abs(pass.h - h_kernel));
    ++compared;
  }
  EXPECT_GT(compared, 20);
  EXPECT_LT(worst, 0.03 * fz);

  // Deterministic whatever the thread count.
  JobSimulation one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = simulate_job(job, path, from, from + 0.2);
  }
  const JobSimulation two = simulate_job(job, path, from, from + 0.2);
  ASSERT_EQ(one.result.steps.size(), two.result.steps.size());
  EXPECT_EQ(one.result.removed_by_board_mm3, two.result.removed_by_board_mm3);
  EXPECT_EQ(one.result.dexel_updates, two.result.dexel_updates);
  ASSERT_EQ(one.result.chip_map.size(), two.result.chip_map.size());
  for (std::size_t i = 0; i < one.result.chip_map.size(); ++i) {
    EXPECT_EQ(one.result.chip_map[i].h_mm, two.result.chip_map[i].h_mm);
  }
}

// A straight full slot (a_p 1 mm, R 5 mm, f_z 0.2 mm) read off each board: the X board's walls
// lie at x = +-R less at most the feed marks' depth f_z^2 / 8R (1e-3 mm) on the rows the tool
// passed; the Z and Y boards place the wall between their last cut ray and their first uncut
// one, so within one spacing of it; the Z board's floor is the tip height z = -1 (exact: the
// ray is cut from the tip up) and the X board is cut at every level above it and at none below.
TEST(Sim, TheThreeBoardsAgreeOnTheMachinedSlot) {
  const double d = 0.05, R = 5, fz = 0.2;
  const Box3 box{{-8, -10, -2}, {8, 10, 0}};
  TriDexel work(box, d);
  SimSettings s;
  s.steps_per_rev = 60;
  const SimTool tool = end_mill(0);
  const ToolPath p = line_path(0, -16, 16, -1, fz * 2 * 3000);
  (void)simulate(p, tool, s, work, 0, p.duration_s());
  const auto walls = wall_profiles(work, 0.0, 20);
  int rows = 0;
  for (const WallPoint& w : walls) {
    if (w.y_mm < -9 || w.y_mm > 9) continue;
    EXPECT_GT(w.z_mm, -1.0) << "cut below the tip";
    EXPECT_NEAR(w.left_x_mm, -R, fz * fz / (8 * R) + 1e-9) << w.y_mm << " " << w.z_mm;
    EXPECT_NEAR(w.right_x_mm, R, fz * fz / (8 * R) + 1e-9) << w.y_mm << " " << w.z_mm;
    ++rows;
  }
  EXPECT_GT(rows, 1000);
  // Z board: the floor profile across the slot at y = 0.
  const auto floor = floor_profiles(work, 400);
  int checked = 0;
  for (const FloorPoint& f : floor) {
    if (std::abs(f.y_mm - 0.025) > 1e-9) continue;
    if (std::abs(f.x_mm) < R - d) {
      EXPECT_DOUBLE_EQ(f.z_mm, -1.0) << f.x_mm;
    }
    if (std::abs(f.x_mm) > R + d) {
      EXPECT_DOUBLE_EQ(f.z_mm, 0.0) << f.x_mm;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 320);
  // Y board (rays along y at (z, x)): at mid-depth, cut within the walls, whole outside.
  const DexelBoard& yb = work.boards[1];
  const int zl = static_cast<int>((-0.5 - box.lo[2]) / d);
  for (int j = 0; j < yb.count_v(); ++j) {
    const double x = yb.v_of(j);
    double len = 0;
    for (const Interval& v : yb.intervals(zl, j)) len += v.hi - v.lo;
    if (std::abs(x) < R - d) {
      EXPECT_NEAR(len, 0.0, 1e-9) << x;
    }
    if (std::abs(x) > R + d) {
      EXPECT_NEAR(len, 20.0, 1e-9) << x;
    }
  }
}

// The chip map through HDF5 and back: every value identical (float32 stored as float32).
TEST(Sim, ChipMapHdf5RoundTrip) {
  const Box3 box{{-8, -10, -2}, {8, 10, 0}};
  TriDexel work(box, 0.1);
  SimSettings s;
  s.steps_per_rev = 60;
  const SimTool tool = end_mill(30);
  const ToolPath p = line_path(0, -14, -6, -1, 0.1 * 2 * 3000);
  const SimResult r = simulate(p, tool, s, work, 0, p.duration_s());
  const ChipMapData m = chip_map_data(r, tool, s);
  ASSERT_EQ(m.h_mm.size(), r.steps.size() * 2 * static_cast<std::size_t>(r.segments_per_tooth));
  std::size_t nonzero = 0;
  for (const float v : m.h_mm) nonzero += v > 0 ? 1 : 0;
  EXPECT_EQ(nonzero, r.chip_map.size());
  const auto file = std::filesystem::temp_directory_path() / "trochomill_chips_test.h5";
  write_chip_map_h5(file, m);
  // The same map writes the same bytes (no time stamps in the file), a second later too.
  const auto file2 = std::filesystem::temp_directory_path() / "trochomill_chips_test2.h5";
  sleep(1);
  write_chip_map_h5(file2, m);
  EXPECT_EQ(test::read_file(file), test::read_file(file2));
  // Written from the result itself, made dense a block of 1024 steps at a time (the run has
  // more than two blocks): the same bytes as from the whole dense map.
  ASSERT_GT(r.steps.size(), 2048u);
  write_chip_map_h5(file2, r, tool, s);
  EXPECT_EQ(test::read_file(file), test::read_file(file2));
  std::filesystem::remove(file2);
  const ChipMapData back = read_chip_map_h5(file);
  std::filesystem::remove(file);
  EXPECT_EQ(back.teeth, 2u);
  EXPECT_EQ(back.segments_per_tooth, m.segments_per_tooth);
  EXPECT_EQ(back.steps_per_rev, 60);
  EXPECT_TRUE(back.complete);
  EXPECT_EQ(back.t_s, m.t_s);
  EXPECT_EQ(back.tip_mm, m.tip_mm);
  EXPECT_EQ(back.removed_mm3, m.removed_mm3);
  EXPECT_EQ(back.h_mm, m.h_mm);
  EXPECT_EQ(back.w_mm, m.w_mm);
  EXPECT_EQ(back.v_mm3, m.v_mm3);
  EXPECT_EQ(back.segment_height_mm, m.segment_height_mm);
  EXPECT_THROW((void)read_chip_map_h5(file), Error);  // gone: a clear error, no crash
}

// The machined surface's STL is a closed solid: every edge is shared by exactly two
// triangles, and its volume by the divergence theorem equals the height field's integral
// (trapezoidal over the grid cells, which the two triangles per cell integrate exactly) to
// float precision (1e-6 relative: the STL stores float32).
TEST(Sim, SurfaceStlIsAClosedSolidOfTheHeightFieldsVolume) {
  const Box3 box{{-8, -10, -2}, {8, 10, 0}};
  TriDexel work(box, 0.1);
  SimSettings s;
  s.steps_per_rev = 60;
  SimTool tool = end_mill(0);
  tool.corner_radius_mm = 1;
  const ToolPath p = line_path(0, -16, 4, -1, 0.2 * 2 * 3000);
  (void)simulate(p, tool, s, work, 0, p.duration_s());
  const HeightField f = surface_height_field(work, 0.2);
  const std::string stl = height_field_stl(f);
  std::uint32_t n = 0;
  std::memcpy(&n, stl.data() + 80, 4);
  ASSERT_EQ(stl.size(), 84u + 50u * n);
  std::map<std::array<float, 6>, int> edges;
  double vol = 0;
  for (std::uint32_t t = 0; t < n; ++t) {
    float v[12];
    std::memcpy(v, stl.data() + 84 + 50 * t, 48);
    const float* a = v + 3;
    const float* b = v + 6;
    const float* c = v + 9;
    vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
            a[2] * (b[0] * c[1] - b[1] * c[0])) /
           6.0;
    for (const auto& [p0, p1] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
      std::array<float, 6> key{p0[0], p0[1], p0[2], p1[0], p1[1], p1[2]};
      std::array<float, 6> rev{p1[0], p1[1], p1[2], p0[0], p0[1], p0[2]};
      ++edges[std::min(key, rev)];
    }
  }
  for (const auto& [e, k] : edges) ASSERT_EQ(k, 2);
  const std::size_t nc = f.x_mm_of_column.size(), nr = f.y_mm_of_row.size();
  double want = 0;
  for (std::size_t a = 0; a + 1 < nc; ++a) {
    for (std::size_t b = 0; b + 1 < nr; ++b) {
      const double dx = f.x_mm_of_column[a + 1] - f.x_mm_of_column[a];
      const double dy = f.y_mm_of_row[b + 1] - f.y_mm_of_row[b];
      // Two triangles on the diagonal (a, b)-(a+1, b+1): their integral.
      const double z0 = f.z_mm[a * nr + b], z2 = f.z_mm[(a + 1) * nr + b + 1];
      const double z1 = f.z_mm[(a + 1) * nr + b], z3 = f.z_mm[a * nr + b + 1];
      want += dx * dy * ((z0 + z1 + z2) / 6 + (z0 + z2 + z3) / 6 - f.bottom_mm);
    }
  }
  EXPECT_NEAR(vol, want, 1e-6 * std::abs(want) + 1e-3);
  // And the slot is in it: the machined volume (stock less the solid) is near the slot's.
  EXPECT_GT(box.volume_mm3() - want, 100.0);
}

// An insert mill with a 45 degree lead (R 8 mm at the tip, no corner radius, two inserts)
// slotting straight through a 10 mm block 1 mm deep: the slot's section is the contour's,
// 2 (R a_p - a_p^2 / 2) = 15 mm^2 (the edge runs in by a_p cot 45), so 150 mm^3 (bound: the
// removed region's boundary, 168 mm^2 cut plus its 150 mm^2 opening in the top face, times
// d / 2: the boards' layers do not fall on the faces at this spacing); the chip normal to the edge
// peaks at f_z sin 45 (tolerance as for the end mill: the wedge's width and f_z^2 / 2R); a
// per-insert seating offset of 0.02 mm raises that insert's chip by 0.02 sin 45 and lowers the
// other's.
TEST(Sim, InsertMillWithALeadAngle) {
  const double fz = 0.1, R = 8, d = 0.03;
  const std::string job_text = R"(
[tool]
type = "insert_mill"
diameter = 16.0
teeth = 2
lead_angle = 45.0
flute_length = 5.0
[slot]
width = 20.0
length = 20.0
depth = 1.0
[cutting]
feed_per_tooth = 0.1
spindle_speed = 1000.0
[path]
type = "linear"
step = 5.0
)";
  const Job job = parse_job(job_text, "insert.toml", {});
  SimSettings s;
  s.steps_per_rev = 60;
  const SimTool tool = sim_tool(job, s);
  EXPECT_NEAR(tool.profile_radius(0.0), R, 1e-12);
  EXPECT_NEAR(tool.profile_radius(1.0), R - 1.0, 1e-12);
  EXPECT_NEAR(tool.edge_sine(0.5), std::sqrt(0.5), 1e-12);
  const Box3 box{{-10, -5, -2}, {10, 5, 0}};
  TriDexel work(box, d);
  const ToolPath p = line_path(0, -20, 20, -1, fz * 2 * 1000);
  const SimResult r = simulate(p, tool, s, work, 0, p.duration_s());
  const double want = 10 * 2 * (R * 1.0 - 0.5);
  for (int b = 0; b < 3; ++b) {
    EXPECT_NEAR(r.removed_by_board_mm3[static_cast<std::size_t>(b)], want, (168 + 150) * d / 2)
        << b;
  }
  const double tol = fz * 2 * kTwoPi / s.steps_per_rev + fz * fz / (2 * R) + 4e-4;
  double hmax = 0;
  for (const SimStep& st : r.steps) {
    if (st.tip_mm[1] < -11 || st.tip_mm[1] > -4) continue;  // the front in the block
    hmax = std::max(hmax, st.h_max_mm);
  }
  EXPECT_NEAR(hmax, fz * std::sqrt(0.5), tol);

  // Seating: insert 0 sits 0.02 mm further out.
  Job seated = job;
  seated.tool.insert_radial_mm = {0.02, 0.0};
  const SimTool t2 = sim_tool(seated, s);
  TriDexel w2(box, d);
  const SimResult r2 = simulate(p, t2, s, w2, 0, p.duration_s());
  double h0 = 0, h1 = 0;
  for (const ChipEntry& c : r2.chip_map) {
    const SimStep& st = r2.steps[c.step];
    if (st.tip_mm[1] < -11 || st.tip_mm[1] > -4) continue;
    (c.segment / static_cast<std::uint32_t>(r2.segments_per_tooth) == 0 ? h0 : h1) =
        std::max(c.segment / static_cast<std::uint32_t>(r2.segments_per_tooth) == 0 ? h0 : h1,
                 static_cast<double>(c.h_mm));
  }
  EXPECT_NEAR(h0 - h1, 2 * 0.02 * std::sqrt(0.5), 2 * tol);
  EXPECT_NEAR(h0, (fz + 0.02) * std::sqrt(0.5), tol);
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

// Two chip map entries equal in every field, bit for bit.
bool same_entry(const ChipEntry& a, const ChipEntry& b) {
  return a.step == b.step && a.segment == b.segment && a.h_mm == b.h_mm && a.w_mm == b.w_mm &&
         a.v_mm3 == b.v_mm3;
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

// The edge's structured grid: segments equidistant along the edge (the corner arc's quarter
// circle, pi rc / 2, then the flank), their widths summing to the edge's length, heights
// rising, the contour radius and its outward normal (unit; (sin phi, 0, -cos phi) on the
// arc, radial on the flank) at each segment's middle; tau sub-segments across the band.
TEST(Sim, EdgeGridFollowsTheContour) {
  SimTool t;
  t.radius_mm = 8;
  t.corner_radius_mm = 0.8;
  t.flute_length_mm = 2;
  t.segment_mm = 0.1;
  t.sub_segments = 4;
  const double arc = 0.5 * kPi * 0.8, total = arc + (2 - 0.8);
  EXPECT_NEAR(t.edge_length_at(2), total, 1e-12);
  EXPECT_NEAR(t.height_at_length(arc), 0.8, 1e-12);
  EXPECT_NEAR(t.height_at_length(t.edge_length_at(0.3)), 0.3, 1e-12);
  const EdgeGrid g = edge_grid(t, 0.2);
  EXPECT_EQ(g.segments, static_cast<int>(std::ceil(total / 0.1)));
  ASSERT_EQ(g.cells.size(), static_cast<std::size_t>(g.segments * 4));
  double sum = 0, prev_h = -1;
  for (int k = 0; k < g.segments; ++k) {
    const EdgeCell& c = g.at(k, 0);
    sum += c.width_mm;
    EXPECT_GT(c.h_mm, prev_h);
    prev_h = c.h_mm;
    EXPECT_NEAR(c.r_mm, t.profile_radius(c.h_mm), 1e-12);
    EXPECT_NEAR(std::hypot(c.normal[0], c.normal[2]), 1.0, 1e-12);
    if (c.s_mm < arc) {
      const double phi = c.s_mm / 0.8;
      EXPECT_NEAR(c.normal[0], std::sin(phi), 1e-12);
      EXPECT_NEAR(c.normal[2], -std::cos(phi), 1e-12);
      EXPECT_NEAR(c.h_mm, 0.8 * (1 - std::cos(phi)), 1e-12);
    } else {
      EXPECT_NEAR(c.normal[0], 1.0, 1e-12);
      EXPECT_NEAR(c.r_mm, 8.0, 1e-12);
    }
    if (k + 1 < g.segments) {
      EXPECT_NEAR(c.width_mm, 0.1, 1e-12);
    }
    for (int q = 0; q < 4; ++q) EXPECT_NEAR(g.at(k, q).depth_mm, (q + 0.5) * 0.05, 1e-12);
  }
  EXPECT_NEAR(sum, total, 1e-12);
  // The simulation's segment at a height is the grid's.
  for (const double h : {0.0, 0.05, 0.4, 0.79, 0.81, 1.5}) {
    const int k = t.segment_at(h);
    EXPECT_LE(t.height_at_length(k * 0.1), h + 1e-12);
    EXPECT_GT(t.height_at_length((k + 1) * 0.1), h);
  }
}

// Wagih's job made small for a quick simulation: 0.5 mm deep, 6 mm long, 0.1 mm dexels, 60
// steps a revolution.
Job small_wagih_job() {
  return load_job(
      test::example("wagih2023/trochoidal.toml"),
      {parse_override("slot.depth=0.5"), parse_override("slot.length=6"),
       parse_override("simulation.resolution=0.1"), parse_override("simulation.steps_per_rev=60")});
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

// simulate's --out is written as one set: cancelled between files, the folder holds none of
// this run's files (an earlier run's stay as they were) and no staging folder; not cancelled,
// all six replace the earlier ones.
TEST(Sim, OutputsAreWrittenAsOneSet) {
  const Job job = small_wagih_job();
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 2, 3);
  const JobSimulation js = simulate_job(job, path, from, to);
  const auto dir =
      std::filesystem::temp_directory_path() / ("trochomill_outputs_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  write_file_atomic(dir / "series.csv", "an earlier run\n");
  const auto entries = [&] {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      names.push_back(e.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  };
  std::atomic<bool> stop{false};
  RunHooks hooks;
  hooks.cancel = &stop;
  std::vector<std::string> phases;
  hooks.phase = [&](std::string_view name) { phases.emplace_back(name); };
  // The floor: cut across the slot in this window (floor.x3p is then the sixth file).
  const double half =
      0.5 * job.slot.width_mm - job.tool.corner_radius_mm - job.simulation.resolution_mm;
  const HeightMap floor = floor_height_map(*js.work, -half, half, -0.5 * job.slot.depth_mm);
  EXPECT_GE(floor.nx, 2u);
  hooks.progress = [&](std::size_t done, std::size_t total) {
    EXPECT_EQ(total, 6u);
    if (done == 3) stop = true;  // after three of the six files
  };
  EXPECT_THROW((void)write_simulation_outputs(dir, job, js, std::nullopt, hooks), Interrupted);
  EXPECT_EQ(phases, std::vector<std::string>{"writing outputs"});
  EXPECT_EQ(entries(), std::vector<std::string>{"series.csv"});
  EXPECT_EQ(read_file(dir / "series.csv"), "an earlier run\n");

  stop = false;
  hooks.progress = {};
  EXPECT_EQ(write_simulation_outputs(dir, job, js, std::nullopt, hooks), "");
  EXPECT_EQ(entries(), (std::vector<std::string>{"chips.h5", "floor.csv", "floor.x3p", "series.csv",
                                                 "surface.stl", "walls.csv"}));
  // floor.x3p holds the floor: the same heights (to one rounding, mm to m and back).
  const HeightMap back = read_x3p(dir / "floor.x3p");
  ASSERT_EQ(back.z_mm.size(), floor.z_mm.size());
  for (std::size_t i = 0; i < floor.z_mm.size(); ++i) {
    ASSERT_NEAR(back.z_mm[i], floor.z_mm[i], 2.3e-16 * std::abs(floor.z_mm[i]));
  }
  EXPECT_NE(read_file(dir / "series.csv"), "an earlier run\n");
  std::filesystem::remove_all(dir);
}

// A simulation whose records go to a sink and are not kept hands the sink exactly the records a
// kept run holds (every field bit for bit, each step's chip entries in order), keeps none, and
// counts the same steps and h_max. The outputs streamed into SimulationOutputs as the steps come
// are the bytes write_simulation_outputs writes from the kept run.
TEST(Sim, StreamedRecordsAreTheKeptOnes) {
  const Job job = small_wagih_job();
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 2, 3);
  const JobSimulation kept = simulate_job(job, path, from, to);
  struct Collect final : SimSink {
    void take(const SimStep& st, std::span<const ChipEntry> chips) override {
      for (const ChipEntry& c : chips) EXPECT_EQ(c.step, steps.size());
      steps.push_back(st);
      entries.insert(entries.end(), chips.begin(), chips.end());
    }
    std::vector<SimStep> steps;
    std::vector<ChipEntry> entries;
  } got;
  SimControl c;
  c.keep_records = false;
  c.sink = &got;
  const JobSimulation streamed = simulate_job(job, path, from, to, c);
  const SimResult &k = kept.result, &r = streamed.result;
  EXPECT_TRUE(r.steps.empty());
  EXPECT_TRUE(r.chip_map.empty());
  ASSERT_GT(k.steps.size(), 1000u);
  ASSERT_GT(k.chip_map.size(), 1000u);
  EXPECT_EQ(k.step_count, k.steps.size());
  EXPECT_EQ(r.step_count, k.steps.size());
  double h_max = 0;
  for (const SimStep& st : k.steps) h_max = std::max(h_max, st.h_max_mm);
  EXPECT_GT(h_max, 0.0);
  EXPECT_EQ(k.h_max_mm, h_max);
  EXPECT_EQ(r.h_max_mm, h_max);
  EXPECT_EQ(r.removed_by_board_mm3, k.removed_by_board_mm3);
  EXPECT_EQ(r.dexel_updates, k.dexel_updates);
  ASSERT_EQ(got.steps.size(), k.steps.size());
  for (std::size_t n = 0; n < k.steps.size(); ++n) {
    const SimStep &a = got.steps[n], &b = k.steps[n];
    ASSERT_EQ(a.t_s, b.t_s) << n;
    ASSERT_EQ(a.tip_mm, b.tip_mm) << n;
    ASSERT_EQ(a.removed_mm3, b.removed_mm3) << n;
    ASSERT_EQ(a.h_max_mm, b.h_max_mm) << n;
    ASSERT_EQ(a.h_mean_mm, b.h_mean_mm) << n;
    ASSERT_EQ(a.engaged_segments, b.engaged_segments) << n;
  }
  ASSERT_EQ(got.entries.size(), k.chip_map.size());
  for (std::size_t q = 0; q < k.chip_map.size(); ++q) {
    ASSERT_TRUE(same_entry(got.entries[q], k.chip_map[q])) << q;
  }

  const auto base =
      std::filesystem::temp_directory_path() / ("trochomill_stream_" + std::to_string(::getpid()));
  std::filesystem::remove_all(base);
  std::filesystem::create_directory(base);  // the outputs make only their own folder
  const std::string note = write_simulation_outputs(base / "kept", job, kept, std::nullopt);
  SimulationOutputs out(base / "streamed", job);
  c.sink = &out;
  const JobSimulation js = simulate_job(job, path, from, to, c);
  EXPECT_EQ(out.finish(js, std::nullopt), note);
  for (const char* f : {"series.csv", "chips.h5", "walls.csv", "floor.csv", "surface.stl"}) {
    const std::string a = test::read_file(base / "kept" / f);
    EXPECT_GT(a.size(), 1000u) << f;
    EXPECT_TRUE(a == test::read_file(base / "streamed" / f)) << f;
  }
  const ChipMapData m = read_chip_map_h5(base / "streamed" / "chips.h5");
  EXPECT_EQ(m.t_s.size(), k.steps.size());
  EXPECT_TRUE(m.complete);
  std::filesystem::remove_all(base);
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

// The boards' material summaries: after random cuts, whenever a query says a stretch of rays
// holds no material in a range, none of them does (checked ray by ray); and a range that
// covers a ray's remaining material is always reported.
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

TEST(Sim, BoardSummaryNeverHidesMaterial) {
  const Box3 box{{0, 0, 0}, {10, 7, 3}};
  DexelBoard board(0, box, 0.05);  // rays along x, 140 x 60 of them
  board.enable_summary();
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> ri(0, board.count_u() - 1), rj(0, board.count_v() - 1);
  std::uniform_real_distribution<double> x(-0.5, 10.5), len(0, 4);
  std::vector<Interval> removed;
  for (int k = 0; k < 20000; ++k) {
    const double a = x(rng);
    (void)board.subtract(ri(rng), rj(rng), a, a + len(rng), removed);
  }
  // Cuts ending on the bins' edges (the stock's 10 mm in 256 bins) or a few ulps either side:
  // where a bin rule that is not monotone in x, or an edge rule unlike the query's, would
  // hide material (queries below end there too).
  std::uniform_int_distribution<int> edge(0, DexelBoard::kBins), ulps(-3, 3);
  auto near_edge = [&] {
    double v = 10.0 * edge(rng) / DexelBoard::kBins;
    const int n = ulps(rng);
    for (int q = 0; q < std::abs(n); ++q) v = std::nextafter(v, n > 0 ? 11.0 : -1.0);
    return v;
  };
  for (int k = 0; k < 20000; ++k) {
    const double a = near_edge(), b = near_edge();
    (void)board.subtract(ri(rng), rj(rng), std::min(a, b), std::max(a, b), removed);
  }
  // Half the cuts with the upkeep paused, then rebuilt: the same guarantee.
  board.pause_summary();
  for (int k = 0; k < 10000; ++k) {
    const double a = x(rng);
    (void)board.subtract(ri(rng), rj(rng), a, a + len(rng), removed);
  }
  board.resume_summary();
  int empty = 0;
  for (int q = 0; q < 8000; ++q) {
    const int i0 = ri(rng), j0 = rj(rng);
    const int i1 = std::min(board.count_u() - 1, i0 + 5),
              j1 = std::min(board.count_v() - 1, j0 + 2);
    double lo = x(rng), hi = lo + 0.3 * len(rng);
    if (q % 2 == 1) {  // a stretch between two bins' edges (give or take ulps)
      lo = near_edge(), hi = near_edge();
      if (lo > hi) std::swap(lo, hi);
    }
    bool any = false;
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        // Untouched rays: the whole stock, [0, 10].
        for (const Interval& v : board.intervals(i, j)) any = any || (v.hi > lo && v.lo < hi);
      }
    }
    const bool may = board.may_hold(i0, i1, j0, j1, lo, hi);
    if (any) {
      EXPECT_TRUE(may) << i0 << " " << j0 << " " << lo << " " << hi;
    }
    if (!may) ++empty;
  }
  EXPECT_GT(empty, 100);  // the summary does find empty stretches
}

// Packed tiles (DexelBoard::pack_settled) hold what their rays held. Two boards take the same
// cuts; one packs after each period, the other never. Tiles cut to one level all over (a
// floor), emptied (rays across a slot) or left uneven, on the board's inner and edge tiles
// (140 x 75 rays: tiles of 64, 64 and 12 rays by 64 and 11): every ray the same bit for bit, the
// same touched rays, the summary's answers the same (kept through packing, rebuilt from the
// packed interval after a pause); a cut that removes nothing leaves a tile packed, one that
// removes something brings it back; the arrays' bytes are what packing reports freed.
TEST(Sim, PackedTilesHoldWhatTheirRaysHeld) {
  for (const int axis : {2, 0}) {
    // 140 x 75 rays on either board (u along x and v along y on the Z board; y and z on X).
    const Box3 box = axis == 2 ? Box3{{0, 0, 0}, {7, 3.75, 3}} : Box3{{0, 0, 0}, {3, 7, 3.75}};
    DexelBoard packed(axis, box, 0.05), plain(axis, box, 0.05);
    if (axis == 0) packed.enable_summary(), plain.enable_summary();
    ASSERT_EQ(packed.count_u(), 140);
    ASSERT_EQ(packed.count_v(), 75);
    const Interval full = packed.full();
    std::vector<Interval> removed;
    auto cut = [&](int i, int j, double a, double b) {
      removed.clear();
      const double r1 = packed.subtract(i, j, a, b, removed);
      removed.clear();
      const double r2 = plain.subtract(i, j, a, b, removed);
      ASSERT_EQ(r1, r2) << i << " " << j;
    };
    auto same = [&] {
      for (int i = 0; i < packed.count_u(); ++i) {
        for (int j = 0; j < packed.count_v(); ++j) {
          ASSERT_EQ(packed.touched(i, j), plain.touched(i, j)) << i << " " << j;
          ASSERT_TRUE(std::ranges::equal(
              packed.intervals(i, j), plain.intervals(i, j),
              [](const Interval& p, const Interval& q) { return p.lo == q.lo && p.hi == q.hi; }))
              << axis << " " << i << " " << j;
        }
      }
      // Volumes summed in another order (a packed tile's rays as one product): to 1e-12
      // relative, far below a ray's d^2 times a spacing.
      EXPECT_NEAR(packed.volume_mm3(), plain.volume_mm3(), 1e-12 * plain.volume_mm3());
    };
    const double mid = 0.5 * (full.lo + full.hi);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> x(full.lo, full.hi);
    for (int i = 0; i < packed.count_u(); ++i) {
      for (int j = 0; j < packed.count_v(); ++j) {
        if (i < 64) {
          cut(i, j, mid, full.hi + 1);  // a floor at mid: uniform tiles
        } else if (i < 128 && j < 64) {
          cut(i, j, full.lo - 1, full.hi + 1);  // emptied
        } else if (i >= 128) {
          cut(i, j, mid, full.hi + 1);  // the edge tiles (12 rays across), a floor
          if (i == 130 && j == 70) cut(i, j, mid - 0.1, mid);  // one ray lower, same start
        } else {
          const double a = x(rng);
          cut(i, j, a, a + 0.5);  // uneven
        }
      }
    }
    const std::size_t bytes = packed.memory_bytes();
    EXPECT_EQ(packed.pack_settled(), 0U);  // cut in this period: nothing settled yet
    const std::size_t freed = packed.pack_settled();
    EXPECT_EQ(packed.memory_bytes(), bytes - freed);
    // Packed: the floor's two tiles, the emptied one and the edge's (2, 0) (its tile (2, 1)
    // holds the ray apart); not the uneven tile (1, 1).
    EXPECT_EQ(packed.packed_tiles(), 4U);
    EXPECT_EQ(freed, 4 * packed.ray_bytes(axis) * DexelBoard::kTile * DexelBoard::kTile);
    same();
    // The summary's answers (X board) over random stretches: the same on both boards.
    auto same_summary = [&] {
      if (axis != 0) return;
      std::uniform_int_distribution<int> ri(0, packed.count_u() - 1), rj(0, packed.count_v() - 1);
      int empty = 0;
      for (int q = 0; q < 4000; ++q) {
        const int i0 = ri(rng), j0 = rj(rng);
        const double lo = x(rng), hi = lo + 0.2;
        const bool m = packed.may_hold(i0, i0 + 3, j0, j0 + 3, lo, hi);
        ASSERT_EQ(m, plain.may_hold(i0, i0 + 3, j0, j0 + 3, lo, hi)) << i0 << " " << j0;
        empty += m ? 0 : 1;
      }
      EXPECT_GT(empty, 100);
    };
    same_summary();
    packed.pause_summary(), plain.pause_summary();
    packed.resume_summary(), plain.resume_summary();
    same_summary();
    // Cuts that remove nothing keep the tiles packed; one that removes brings its tile back.
    cut(10, 10, mid + 0.1, full.hi);  // above the floor
    cut(70, 10, full.lo, full.hi);    // an emptied ray
    EXPECT_EQ(packed.packed_tiles(), 4U);
    cut(10, 10, mid - 0.2, mid - 0.1);
    EXPECT_EQ(packed.packed_tiles(), 3U);
    same();
    same_summary();
  }
}

}  // namespace
}  // namespace trochomill

namespace trochomill {
namespace {

// A box given as a mesh is the box: every ray of the three boards holds the same interval as
// the box stock's (bit for bit: faces square to the rays are met at their exact height, and a
// diagonal through a ray centre is taken by one of its two triangles, not both or neither).
TEST(Sim, AMeshStockOfABoxIsTheBox) {
  const Box3 box{{-1.0, 0.0, -0.5}, {1.0, 2.0, 0.5}};
  const double d = 0.05;
  const TriDexel from_mesh = stock_from_mesh(test::box_mesh(box.lo, box.hi), d);
  const TriDexel plain(box, d);
  for (std::size_t b = 0; b < 3; ++b) {
    const DexelBoard& m = from_mesh.boards[b];
    const DexelBoard& p = plain.boards[b];
    ASSERT_EQ(m.count_u(), p.count_u());
    ASSERT_EQ(m.count_v(), p.count_v());
    EXPECT_EQ(m.volume_mm3(), p.volume_mm3()) << b;
    for (int i = 0; i < m.count_u(); ++i) {
      for (int j = 0; j < m.count_v(); ++j) {
        ASSERT_TRUE(m.touched(i, j));  // every ray is held
        const auto r = m.intervals(i, j);
        ASSERT_EQ(r.size(), 1u) << b << " " << i << " " << j;
        EXPECT_EQ(r[0].lo, p.full().lo);
        EXPECT_EQ(r[0].hi, p.full().hi);
      }
    }
  }
}

// Two closed solids in one mesh: an octahedron |x| + |y| + |z| <= 1 (volume 4/3) and, apart
// from it, a box with a box-shaped hole through it (its inner walls face inward): every board's
// volume is the solids' (the midpoint rule over the rays: the octahedron's section lengths
// are piecewise linear across the rays, its error under 2e-4 of the volume at 0.01 mm,
// measured 1.8e-5 on each board), and rays through the hole are empty. A mesh with one triangle
// missing is refused, naming a ray.
TEST(Sim, AMeshStockHoldsWhatTheMeshEncloses) {
  Mesh m;
  const std::array<std::array<double, 3>, 6> v = {
      {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}};
  for (const auto& p : v) m.vertices.emplace_back(p[0], p[1], p[2]);
  for (const std::uint32_t x : {0u, 1u}) {
    for (const std::uint32_t y : {2u, 3u}) {
      for (const std::uint32_t z : {4u, 5u}) m.triangles.push_back({x, y, z});
    }
  }
  auto add = [&m](const Mesh& o, bool inward) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (const auto& p : o.vertices) m.vertices.push_back(p);
    for (auto t : o.triangles) {
      if (inward) std::swap(t[1], t[2]);
      m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
  };
  add(test::box_mesh({2.0, -1.0, -1.0}, {4.0, 1.0, 1.0}), false);
  add(test::box_mesh({2.5, -0.5, -1.0}, {3.5, 0.5, 1.0}), true);  // the hole, through along z
  // Measured as a Z-board hole along z: its faces at z = -1, 1 coincide with the outer box's
  // (the rays there cross four faces at two heights: in, in, out, out: no material).
  const double volume = 4.0 / 3.0 + 2 * 2 * 2 - 1 * 1 * 2;
  const TriDexel w = stock_from_mesh(m, 0.01);
  for (std::size_t b = 0; b < 3; ++b) {
    EXPECT_NEAR(w.boards[b].volume_mm3(), volume, 2e-4 * volume) << b;
  }
  const DexelBoard& z = w.boards[2];
  const auto [i0, i1] = z.index_range(true, 2.6, 3.4);
  const auto [j0, j1] = z.index_range(false, -0.4, 0.4);
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j)
      EXPECT_TRUE(z.touched(i, j) && z.intervals(i, j).empty()) << i << " " << j;
  }
  Mesh open = m;
  open.triangles.erase(open.triangles.begin());
  try {
    (void)stock_from_mesh(open, 0.01);
    ADD_FAILURE() << "an open mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace trochomill

namespace trochomill {

// The X and Y boards' row check done for a layer's rows at once with Highway's vectors
// (sim_detail::row_chords) against the scalar pieces it replaces (SectorSlicer::on_line and
// annulus_parts), row by row, on every vector target this processor runs: the same bits, or
// the simulation's results would depend on the processor. Sectors of every kind (about the
// axes, across 0 and pi, ending on multiples of pi), rows through the centre, inner radii
// from none to beyond the outer.
TEST(Sim, RowChordsAreTheScalarRowsOnEveryTarget) {
  using sim_detail::annulus_parts;
  using sim_detail::RowChords;
  using sim_detail::SectorSlicer;
  std::mt19937_64 rng(20261203);
  std::uniform_real_distribution<double> U(0, 1);
  const auto bits = [](double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
  };
  std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets();
  ASSERT_FALSE(targets.empty());
  std::size_t rows = 0, chords = 0, split = 0;
  for (const int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    for (int c = 0; c < 2000; ++c) {
      // Ends on the multiples of pi / 2 a fifth of the time each.
      auto angle = [&] {
        return U(rng) < 0.2 ? std::floor(U(rng) * 8 - 4) * 0.5 * kPi : (U(rng) * 4 - 2) * kPi;
      };
      const double a0 = angle();
      const double a1 = a0 + (U(rng) < 0.2 ? 0.5 * kPi : U(rng) * 0.99 * kPi);
      const SectorSlicer slicer(a0, a1);
      const double d = 0.005 * (1 + std::floor(U(rng) * 4));
      const double origin = -5 + 10 * U(rng), R = 8 * U(rng) + 0.01;
      const double r_in = U(rng) < 0.2 ? 0.0 : R * 1.1 * U(rng);
      const int r0 = static_cast<int>(U(rng) * 100);
      const int n = 1 + static_cast<int>(U(rng) * 2.5 * R / d);
      // A row through the centre in half the cases.
      const int mid = r0 + static_cast<int>(U(rng) * n);
      const double centre = U(rng) < 0.5 ? origin + (mid + 0.5) * d : origin + U(rng) * n * d;
      const bool negate = U(rng) < 0.5;
      RowChords out;
      sim_detail::row_chords(slicer.coeffs(), origin, d, r0, n, centre, negate, R, r_in, out);
      for (int k = 0; k < n; ++k) {
        const auto q = static_cast<std::size_t>(k);
        const double perp = (origin + (r0 + k + 0.5) * d) - centre;
        ASSERT_EQ(bits(out.perp[q]), bits(perp));
        const auto on = slicer.on_line(negate ? -perp : perp, R);
        std::array<Interval, 2> parts{};
        const int np = on ? annulus_parts(perp, on->lo, on->hi, r_in, R, parts) : 0;
        // The vectors keep the near part and the far one apart (the scalar code packs them);
        // an empty part is (inf, -inf).
        std::vector<Interval> got;
        if (out.a_lo[q] < out.a_hi[q]) got.push_back({out.a_lo[q], out.a_hi[q]});
        if (out.b_lo[q] < out.b_hi[q]) got.push_back({out.b_lo[q], out.b_hi[q]});
        ASSERT_EQ(static_cast<int>(got.size()), np) << "target " << hwy::TargetName(target);
        for (int p = 0; p < np; ++p) {
          ASSERT_EQ(bits(got[static_cast<std::size_t>(p)].lo), bits(parts[p].lo));
          ASSERT_EQ(bits(got[static_cast<std::size_t>(p)].hi), bits(parts[p].hi));
        }
        if (np > 0) {  // the chord itself is only read where a part holds material
          ASSERT_EQ(bits(out.lo[q]), bits(on->lo));
          ASSERT_EQ(bits(out.hi[q]), bits(on->hi));
        }
        ++rows, chords += on ? 1 : 0, split += np == 2 ? 1 : 0;
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  // The cases reached what they are for: many rows, most with a chord, some split in two.
  EXPECT_GT(rows, 100'000U);
  EXPECT_GT(chords, rows / 4);
  EXPECT_GT(split, 1000U);
}

// The row check's vectorised look at the rays (sim_detail::rays_maybe) never passes over a
// ray with material in a row's parts, and finds material exactly where the intervals have it
// for the rays it reads (one or two inline intervals; spilled and emptied rays are left to
// the caller, flagged): rays of both X and Y boards cut at random into 0-4 intervals, parts
// at random (some empty, some touching a ray's ends), runs of every length up to a tile's
// edge, on every vector target.
TEST(Sim, RaysMaybeIsTheIntervalsOnEveryTarget) {
  using sim_detail::kInf;
  using sim_detail::RowChords;
  std::mt19937_64 rng(3122026);
  std::uniform_real_distribution<double> U(0, 1);
  const Box3 box{{0, 0, 0}, {10, 6.4, 6.4}};
  std::size_t inline_rays = 0, flagged = 0, with_material = 0;
  for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    for (int axis = 0; axis < 2; ++axis) {
      DexelBoard board(axis, box, 0.1);  // 64 x 64 rays: one tile
      std::vector<Interval> removed;
      for (int i = 0; i < 64; ++i) {
        for (int j = 0; j < 64; ++j) {
          const int cuts = static_cast<int>(U(rng) * 4);
          for (int c = 0; c < cuts; ++c) {
            const double a = U(rng) * 10;
            (void)board.subtract(i, j, a, a + U(rng) * 3, removed);
          }
          if (U(rng) < 0.05) (void)board.subtract(i, j, -1, 11, removed);  // emptied
        }
      }
      for (int t = 0; t < 400; ++t) {
        const int layer = static_cast<int>(U(rng) * 64), r0 = static_cast<int>(U(rng) * 64);
        const int count = 1 + static_cast<int>(U(rng) * (64 - r0));
        RowChords rc;
        rc.reserve_rows(static_cast<std::size_t>(count) + 64);
        const double along = U(rng) * 4;
        for (int k = 0; k < count; ++k) {
          const auto u = static_cast<std::size_t>(k);
          auto part = [&](double& lo, double& hi) {
            lo = U(rng) * 8 - along, hi = lo + U(rng) * 2;
            if (U(rng) < 0.3) lo = kInf, hi = -kInf;  // no part
          };
          part(rc.a_lo[u], rc.a_hi[u]);
          part(rc.b_lo[u], rc.b_hi[u]);
        }
        const int i = axis == 0 ? r0 : layer, j = axis == 0 ? layer : r0;
        const Dexel* rays = board.row_rays(i, j);
        ASSERT_NE(rays, nullptr);
        sim_detail::rays_maybe(reinterpret_cast<const double*>(rays), count, 0, along, rc);
        for (int k = 0; k < count; ++k) {
          const auto u = static_cast<std::size_t>(k);
          const auto found =
              board.intervals(axis == 0 ? r0 + k : layer, axis == 0 ? layer : r0 + k);
          bool any = false;
          for (const Interval& v : found) {
            for (const auto& [lo, hi] :
                 {std::pair{rc.a_lo[u], rc.a_hi[u]}, std::pair{rc.b_lo[u], rc.b_hi[u]}}) {
              any = any || (lo < hi && v.hi > along + lo && v.lo < along + hi);
            }
          }
          ASSERT_TRUE(rc.maybe[u] == 0.0 || rc.maybe[u] == 1.0);
          if (any) {
            ASSERT_EQ(rc.maybe[u], 1.0) << hwy::TargetName(target);
          }
          // Inline rays (one or two intervals, not spilled): the answer is exact.
          if (!found.empty() && found.size() <= 2 &&
              static_cast<const void*>(found.data()) == static_cast<const void*>(&rays[k])) {
            ++inline_rays;
            ASSERT_EQ(rc.maybe[u] == 1.0, any) << hwy::TargetName(target);
          }
          flagged += rc.maybe[u] == 1.0 ? 1 : 0, with_material += any ? 1 : 0;
        }
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GT(inline_rays, 10'000U);
  EXPECT_GT(with_material, inline_rays / 10);
  EXPECT_LT(with_material, flagged + 1);
}

}  // namespace trochomill
