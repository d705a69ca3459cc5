// Shared helpers for the simulation's tests (sim_*_test.cpp): a simple end mill, a straight
// path, Wagih's job made small, and chip map entries compared bit for bit.
#pragma once

#include <string>
#include <vector>

#include "test_util.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/units.hpp"

namespace trochomill::test {

// A square end mill (R 5 mm, two teeth) along a straight line through a box.
inline SimTool end_mill(double helix_deg, int teeth = 2, double rpm = 3000) {
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

inline ToolPath line_path(double x, double y0, double y1, double z, double feed_mm_per_min) {
  ToolPath p;
  p.append(Segment::line(Vec3(x, y0, z), Vec3(x, y1, z), Motion::feed, feed_mm_per_min));
  return p;
}

// Two chip map entries equal in every field, bit for bit.
inline bool same_entry(const ChipEntry& a, const ChipEntry& b) {
  return a.step == b.step && a.segment == b.segment && a.h_mm == b.h_mm && a.w_mm == b.w_mm &&
         a.v_mm3 == b.v_mm3;
}

// Wagih's job made small for a quick simulation: 0.5 mm deep, 6 mm long, 0.1 mm dexels, 60
// steps a revolution.
inline Job small_wagih_job() {
  return load_job(
      test::example("wagih2023/trochoidal.toml"),
      {parse_override("slot.depth=0.5"), parse_override("slot.length=6"),
       parse_override("simulation.resolution=0.1"), parse_override("simulation.steps_per_rev=60")});
}

}  // namespace trochomill::test
