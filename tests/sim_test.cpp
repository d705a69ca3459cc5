// Tri-dexel simulation (issue 5, first part): dexel arithmetic, removed volume of a straight
// slot against the swept volume (converging with the spacing, the three boards agreeing),
// the chip of a straight partial-immersion cut against f_z sin(phi).
#include "trochomill/sim.hpp"

#include <gtest/gtest.h>

#include <cmath>

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
    StockBox box{{-8, -10, -2}, {8, 30, 0}};
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

// Straight partial immersion (a_e = 1 mm on the right, feed along +y, cw spindle: down
// milling): while a tooth is engaged its chip at tooth angle a (from +x, the wedge's middle)
// is f_z sin(a)... measured from the feed direction: h = f_z cos(a - pi/2) = f_z sin(a) for
// the radius at angle a. Tolerance: f_z (Delta + 2 pi / steps) for the wedge's angular width
// (h_max is over the wedge) plus f_z^2 / (2 R) (a translated circle against the trochoidal
// tooth path) plus 2e-4 mm for the dexels' sampling across the wedge at d = 0.02 mm.
TEST(Sim, PartialImmersionChipIsFzSinPhi) {
  const double R = 5, ae = 1, fz = 0.1, d = 0.02;
  StockBox box{{R - ae, -2, -1}, {R + 2, 12, 0}};
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

}  // namespace
}  // namespace trochomill
