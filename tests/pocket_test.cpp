// Pockets: the region helpers (Clipper booleans, even-odd containment, parts), the polyline
// fit, the removed region against its closed form, the planner's invariants and the job's
// refusals. The peers (LinuxCNC's reading, shapely's cut area) are tests/pockets/peer.py.
#include "trochomill/pocket.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <string>

#include "test_util.hpp"
#include "trochomill/analysis.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/job.hpp"
#include "trochomill/report/path.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"
#include "trochomill/units.hpp"

using namespace trochomill;

namespace {

std::string pocket_job(const std::string& pocket_keys, const std::string& extra = "") {
  return "[geometry]\nfile = \"" + (test::source_dir() / "tests/data/dxf/pockets.dxf").string() +
         "\"\n[pocket]\n" + pocket_keys +
         "\n[tool]\ndiameter = 10.0\nteeth = 3\n[cutting]\nfeed_rate = 1200.0\n"
         "spindle_speed = 8000.0\n" +
         extra;
}

bool has(const std::string& m, const std::string& part) {
  return m.find(part) != std::string::npos;
}

}  // namespace

TEST(Pocket, RegionHelpersAgreeWithClosedForms) {
  const Contour square = Contour::polyline({{0, 0}, {10, 0}, {10, 10}, {0, 10}}, true);
  const Contour hole = Contour::circle({5, 5}, 2);
  // Even-odd: the circle inside the square is a hole; arcs exact at the boundary's sides.
  EXPECT_TRUE(region_contains({square, hole}, {1, 1}));
  EXPECT_FALSE(region_contains({square, hole}, {5, 5}));
  EXPECT_TRUE(region_contains({hole}, {5, 6.999}));
  EXPECT_FALSE(region_contains({hole}, {5, 7.001}));
  EXPECT_FALSE(region_contains({square}, {10.001, 5}));
  // Difference and intersection: areas to Clipper's chords (1e-3 mm tolerance: the circle's
  // chords of sagitta 5e-4 mm lose about 2 pi r * 2/3 * 5e-4 = 4e-3 mm^2).
  const double tol = 1e-3;
  EXPECT_NEAR(region_area_mm2(region_difference({square}, {hole}, tol)), 100 - kPi * 4, 1e-2);
  EXPECT_NEAR(region_area_mm2(region_intersection({square}, {hole}, tol)), kPi * 4, 1e-2);
  // Parts: the square with its hole and a second square apart.
  const Contour far = Contour::polyline({{20, 0}, {25, 0}, {25, 5}, {20, 5}}, true);
  const auto region = offset_region({square, hole, far}, 0, tol);
  const auto parts = region_parts(region);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].size(), 2u);  // the larger square with the hole
  EXPECT_EQ(parts[1].size(), 1u);
  EXPECT_NEAR(region_area_mm2(parts[0]), 100 - kPi * 4, 1e-2);
}

TEST(Pocket, PolylineFitKeepsPointsAndChordsWithinTheTolerance) {
  // 90 points on a quarter circle of radius 10 mm: one arc through them.
  std::vector<Vec2> pts;
  for (int k = 0; k <= 90; ++k)
    pts.emplace_back(10 * std::cos(k * kPi / 180), 10 * std::sin(k * kPi / 180));
  auto fit = fit_polyline(pts, 1e-3);
  ASSERT_EQ(fit.size(), 1u);
  EXPECT_TRUE(fit[0].is_arc());
  EXPECT_NEAR(fit[0].radius_mm(), 10, 1e-9);
  EXPECT_NEAR(fit[0].sweep_rad(), 0.5 * kPi, 1e-9);
  // A square's corner: two lines, joined exactly at the corner.
  fit = fit_polyline({{0, 0}, {1, 0}, {2, 0}, {2, 1}, {2, 2}}, 1e-3);
  ASSERT_EQ(fit.size(), 2u);
  EXPECT_FALSE(fit[0].is_arc());
  EXPECT_EQ(fit[0].end, Vec2(2, 0));
  // Points that turn back do not make a loop the long way round: each piece's length stays
  // that of the points it stands for.
  fit = fit_polyline({{0, 0}, {1, 0}, {1.0001, 0.0001}, {0.5, 0.0002}}, 1e-2);
  double len = 0;
  for (const auto& p : fit) len += p.length_mm();
  EXPECT_LT(len, 2.0);
  // Every piece within the tolerance of every point and chord middle it stands for.
  pts.clear();
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.05 * k;
    pts.emplace_back(t, std::sin(t) + 0.002 * ((k % 3) - 1));
  }
  const double tol = 0.01;
  fit = fit_polyline(pts, tol);
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    double d = 1e9, dm = 1e9;
    for (const auto& p : fit) {
      d = std::min(d, p.distance_mm(pts[k]));
      dm = std::min(dm, p.distance_mm(0.5 * (pts[k] + pts[k + 1])));
    }
    EXPECT_LE(d, tol + 1e-12);
    EXPECT_LE(dm, tol + 1e-12);
  }
  // A quarter circle of radius 5 mm in 0.5 mm chords: their middles lie d^2 / 8r = 6.25 um
  // inside the circle. Held within 2 um, no arc spans two chords (lines a chord each); an arc
  // turning the way allowed to bulge 7 um spans them all, one turning the other way does not.
  pts.clear();
  const double step = 2 * std::asin(0.5 / 10);  // a 0.5 mm chord of radius 5
  for (int k = 0; k * step <= 0.5 * kPi + 1e-12; ++k) {
    pts.emplace_back(5 * std::cos(k * step), 5 * std::sin(k * step));
  }
  EXPECT_EQ(fit_polyline(pts, 0.002).size(), pts.size() - 1);
  fit = fit_polyline(pts, 0.002, 0.007, true);  // counter-clockwise, as the points turn
  ASSERT_EQ(fit.size(), 1u);
  EXPECT_NEAR(fit[0].radius_mm(), 5, 1e-9);
  EXPECT_TRUE(fit[0].ccw);
  EXPECT_EQ(fit_polyline(pts, 0.002, 0.007, false).size(), pts.size() - 1);
  EXPECT_EQ(fit_polyline(pts, 0.002, 0.006, true).size(), pts.size() - 1);  // 6 < 6.25 um
}

TEST(Pocket, RemovedRegionGivesTheUncutArcInClosedForm) {
  // One disc of radius R at the origin: the circle at distance d keeps 2 pi - 2 acos(d / 2R).
  const double R = 5;
  RemovedRegion removed(R, {-20, -20}, {20, 20});
  removed.cut({0, 0});
  for (const double d : {0.1, 1.0, 4.0, 9.0}) {
    double total = 0;
    for (const AngleArc& a : removed.uncut_arcs({d, 0})) total += a.sweep_rad();
    // 1e-9 rad: the kernel's crossings are exact to rounding.
    EXPECT_NEAR(total, kTwoPi - 2 * std::acos(d / (2 * R)), 1e-9) << d;
  }
  EXPECT_TRUE(removed.contains({4.9, 0}));
  EXPECT_FALSE(removed.contains({5.1, 0}));
  EXPECT_TRUE(removed.uncut_arcs({11, 0}).size() == 1);  // untouched: the whole circle
}

TEST(Pocket, PlanHoldsTheTargetAndKeepsOffTheWalls) {
  const Job job = parse_job(pocket_job("boundary = \"RECT\"\ndepth = 4.0\nmax_step_down = 2.0\n"
                                       "stock_to_leave = 0.2\nmax_engagement = 50.0\n"),
                            "rect.toml");
  // max_chip follows: f_z sin(50 degrees), f_z = 1200 / (3 8000) = 0.05 mm.
  EXPECT_NEAR(job.pocket.max_chip_mm, 0.05 * std::sin(deg_to_rad(50)), 1e-12);
  // The stock: the boundary's box, 0.5 mm below the floor.
  ASSERT_TRUE(job.stock_min_mm && job.stock_max_mm);
  EXPECT_EQ(*job.stock_min_mm, Vec3(0, 0, -4.5));
  EXPECT_EQ(*job.stock_max_mm, Vec3(60, 40, 0));
  const PlannedPocket p = plan_pocket(job);
  EXPECT_TRUE(p.info.proven);
  EXPECT_EQ(p.info.replans, 0);
  EXPECT_EQ(p.info.aim_margin_deg, 1.2);
  EXPECT_EQ(p.info.parts, 1);
  EXPECT_EQ(p.info.levels, 2);
  EXPECT_GT(p.info.passes, 0);
  EXPECT_LE(p.info.planned_max_engagement_deg, 48.8 + 1e-9);  // the aim: 1.2 degrees below
  // One plan for both levels: the same passes at each.
  EXPECT_EQ(p.info.passes_by_level, std::vector<int>(2, p.info.passes));
  EXPECT_TRUE(p.info.unreachable.empty());
  // The four corners' cusps: (1 - pi/4) (R + stock + max(fit, 0.005 mm of the arcs bulge) +
  // 3e-3)^2 each, to Clipper's chords.
  EXPECT_NEAR(p.info.cusps_mm2, 4 * (1 - kPi / 4) * std::pow(5.208, 2), 0.05);
  // Starts and ends above the safe plane; every rapid that moves across is there.
  const auto& segs = p.path.segments();
  EXPECT_GE(segs.front().start().z(), job.machine.safe_z_mm);
  EXPECT_GE(segs.back().end().z(), job.machine.safe_z_mm);
  for (const Segment& s : segs) {
    if (s.motion() != Motion::rapid) continue;
    const bool across = (s.end() - s.start()).head<2>().norm() > 1e-9;
    if (across) {
      EXPECT_GE(std::min(s.start().z(), s.end().z()), job.machine.safe_z_mm - 1e-12);
    }
  }
  // No centre at a cutting level closer than R + stock to the walls before the finishing
  // pass, nor than R in it (1e-6 mm: the path's own geometry, not the program's decimals).
  const Contour walls = job.pocket.boundary_contours->front().contour;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const Segment& s = segs[i];
    if (s.motion() != Motion::feed || s.start().z() >= 0 || s.end().z() >= 0) continue;
    const double limit = i < p.info.finish_first_segment ? 5.2 : 5.0;
    const int n = std::max(2, static_cast<int>(s.length_mm() / 0.05));
    for (int k = 0; k <= n; ++k) {
      const Vec3 q = s.point_at(s.length_mm() * k / n);
      ASSERT_GE(walls.distance_mm(q.head<2>()), limit - 1e-6) << i << " at " << q.transpose();
    }
  }
  // The kernel's proof: the clearing within the target + 2 %, the finishing pass reported.
  const PocketProof proof = p.proof;
  EXPECT_LE(proof.clearing_max_engagement_deg, 50 * 1.02);
  EXPECT_GT(proof.clearing_max_engagement_deg, 40);  // it does cut near the target
  EXPECT_GT(proof.finish_max_engagement_deg, 0);
  // The runs through cleared area and the links that stay down go at the link feed (no
  // air_feed or max_feed: the rapid rate, 10000 mm/min, 0.417 mm a tooth): they are a good
  // part of the program, and they cut nothing but the feed marks such moves leave, whose
  // depth f^2 / 8R is 4.3 um, and grazes below f_z^2 / 8R (0.06 um): their chip is a mark's
  // depth, within a quarter of f_z (0.0125 mm).
  ASSERT_FALSE(p.info.air_segments.empty());
  EXPECT_GT(p.info.air_length_mm, 0.2 * p.info.clearing_length_mm);
  EXPECT_TRUE(std::is_sorted(p.info.air_segments.begin(), p.info.air_segments.end()));
  for (const std::size_t k : p.info.air_segments) {
    ASSERT_LT(k, p.info.finish_first_segment);
    EXPECT_EQ(segs[k].speed_mm_per_min(), job.machine.rapid_rate_mm_per_min) << k;
    EXPECT_EQ(segs[k].start().z(), segs[k].end().z()) << k;  // at the level
  }
  EXPECT_LE(proof.air_max_chip_mm, 0.25 * 0.05);
  // What they remove in all: less than a band a mark deep along every such move over the
  // pocket's depth (length x 4 mm x f^2 / 8R, f = 0.417 mm: about 10 mm^3 here); measured
  // 0.22 mm^3 here, 0.08 to 0.7 mm^3 on the other test pockets, so the bound leaves room and
  // still fails on a link through uncut stock (4 mm x 2 mm of section a millimetre of it).
  const double f = job.machine.rapid_rate_mm_per_min / (job.cutting.spindle_speed_rpm * 3);
  double air_mm = 0;
  for (const std::size_t k : p.info.air_segments) air_mm += segs[k].length_mm();
  EXPECT_GT(proof.air_removed_mm3, 0);  // the marks are there, and counted
  EXPECT_LE(proof.air_removed_mm3, air_mm * 4.0 * f * f / (8 * 5.0));
  // `analyze` proves it from its own series: the same figures (one sample per tooth pass).
  const PocketProof again = prove_pocket(p.info, analyze_process(job, p.path).series);
  EXPECT_EQ(again.clearing_max_engagement_deg, proof.clearing_max_engagement_deg);
  EXPECT_EQ(again.finish_max_engagement_deg, proof.finish_max_engagement_deg);
  EXPECT_EQ(again.air_max_chip_mm, proof.air_max_chip_mm);
  EXPECT_EQ(again.air_removed_mm3, proof.air_removed_mm3);
}

// Channels: the parts narrower than [pocket] channel_width (2 D = 20 mm here) are cleared by
// trochoidal loops about points of their medial axis, each loop as wide as the channel there
// (the peers' checks of these pockets, the cut area and LinuxCNC's reading, are in
// tests/pockets/peer.py).
// The plate's pocket at a tenth (10 x 6 mm about a 1 mm boss), a 1 mm tool at the 10 mm
// tool's f_z / R (0.005 mm): the engagement is a matter of angles, so the plan holds the target
// as at full size. With the fitted arcs' bulge off the steps' chords a fixed 0.005 mm (a share
// of R ten times the 10 mm tool's), the kernel found 57.1 degrees for 53 on every replan.
TEST(Pocket, ASmallToolHoldsTheTargetAsALargeOne) {
  std::string text = pocket_job(
      "boundary = \"SMALL\"\nislands = \"SMALLI\"\ndepth = 1.0\nmax_step_down = 1.0\n"
      "stock_to_leave = 0.02\nmax_engagement = 53.0\n");
  text.replace(text.find("diameter = 10.0"), 15, "diameter = 1.0");
  text.replace(text.find("feed_rate = 1200.0"), 18, "feed_rate = 120.0");
  const Job job = parse_job(text, "small.toml");
  ASSERT_NEAR(job.cutting.feed_per_tooth_mm, 0.005, 1e-15);
  const PlannedPocket p = plan_pocket(job);
  EXPECT_TRUE(p.info.proven);
  // The target + 2 %: the kernel's teeth fall at their own phases (as every pocket's test).
  EXPECT_LE(p.proof.clearing_max_engagement_deg, 53 * 1.02);
  EXPECT_GT(p.proof.clearing_max_engagement_deg, 45);  // it cuts at the target, not far below
}

TEST(Pocket, ChannelsAreClearedByTrochoidalLoopsAlongTheirAxis) {
  const auto job_of = [](const std::string& layer, const std::string& more = "") {
    return parse_job(pocket_job("boundary = \"" + layer +
                                "\"\ndepth = 4.0\nmax_step_down = 2.0\nstock_to_leave = 0.2\n"
                                "max_engagement = 50.0\n" +
                                more),
                     layer + ".toml");
  };
  // A 60 x 14 mm channel: the tool centre's region 1.792 mm either side of its axis (7 mm
  // less R + stock and the fit's margins, 0.008 mm).
  const Job chan = job_of("CHAN");
  const PlannedPocket p = plan_pocket(chan);
  EXPECT_TRUE(p.info.proven);
  EXPECT_EQ(p.info.channels, 1);
  EXPECT_EQ(p.info.channel_width_mm, 20);
  EXPECT_EQ(p.info.channels_left_mm2, 0);
  EXPECT_LE(p.proof.clearing_max_engagement_deg, 50 * 1.02);
  EXPECT_GT(p.proof.clearing_max_engagement_deg, 40);  // it does cut near the target
  // The loops: arcs of that radius about points of the axis, y = 7 (1e-3 mm: the radius is the
  // clearance to Clipper's chords, within its tolerance of the exact offset).
  int loops = 0;
  for (std::size_t i = 0; i < p.info.finish_first_segment; ++i) {
    const Segment& s = p.path.segments()[i];
    if (!s.is_circular() || s.start().z() != -2.0) continue;
    const double r = (s.start() - s.center()).head<2>().norm();
    if (std::abs(r - 1.792) < 1e-3) {
      ++loops;
      EXPECT_NEAR(s.center().y(), 7, 1e-6);
      EXPECT_GE(s.center().x(), 507 - 1e-3);
      EXPECT_LE(s.center().x(), 553 + 1e-3);
    }
  }
  EXPECT_GT(loops, 40);
  // The same channel by the clearing passes alone (no part narrower than 1 mm). Since a pass's
  // tail through cleared area is written only where the next pass goes on from it, the passes
  // take as long as the loops here (measured: loops 103.75 s, passes 104.00 s; 127.3 s with
  // every tail), but their program has more than twice the moves (1701 lines against 4094): a
  // pass a step-over wide at a time, each with its link. The time within 5 % either way (the
  // two plans' difference is 0.24 %).
  const Job passes = job_of("CHAN", "channel_width = 1.0\n");
  const PlannedPocket q = plan_pocket(passes);
  EXPECT_EQ(q.info.channels, 0);
  EXPECT_LE(q.proof.clearing_max_engagement_deg, 50 * 1.02);
  EXPECT_LT(p.path.duration_s(), 1.05 * q.path.duration_s())
      << p.path.duration_s() << " s against " << q.path.duration_s() << " s";
  EXPECT_GT(p.path.duration_s(), 0.95 * q.path.duration_s())
      << p.path.duration_s() << " s against " << q.path.duration_s() << " s";
  EXPECT_LT(2 * p.path.segments().size(), q.path.segments().size())
      << p.path.segments().size() << " segments against " << q.path.segments().size();

  // A ring all round an island: one closed channel, opened where the helix comes down and
  // cleared both ways from there.
  const PlannedPocket ring = plan_pocket(job_of("RING", "islands = \"RINGI\"\n"));
  EXPECT_TRUE(ring.info.proven);
  EXPECT_EQ(ring.info.channels, 2);
  EXPECT_EQ(ring.info.channels_left_mm2, 0);
  EXPECT_LE(ring.proof.clearing_max_engagement_deg, 50 * 1.02);

  // A room with a channel 11.2 mm wide: narrower than D + 2 stock + R / 2, where the clearing
  // passes do not go (the rounding of their region's corners closes it). Its loops, 0.392 mm
  // wide, clear it within the target (without them, the finishing pass cut it as a slot at
  // 180 degrees).
  const PlannedPocket thin = plan_pocket(job_of("THIN"));
  EXPECT_TRUE(thin.info.proven);
  EXPECT_EQ(thin.info.channels, 1);
  EXPECT_LE(thin.proof.clearing_max_engagement_deg, 50 * 1.02);
  EXPECT_LT(thin.proof.finish_max_engagement_deg, 135) << thin.proof.finish_max_engagement_deg;
  // Two rooms joined by a bar 10.45 mm wide: its tool centre region is 0.034 mm wide, too
  // narrow for loops (R / 20 = 0.25 mm of clearance at least). Each room is a part with its
  // own entry; the bar is reported as the finishing pass's slot (some 30 x 10.45 mm), and the
  // finishing pass comes down in a room, not in the bar's stock.
  const PlannedPocket bar = plan_pocket(job_of("BAR"));
  EXPECT_EQ(bar.info.parts, 2);
  EXPECT_EQ(bar.info.helix_entries, 2);
  ASSERT_EQ(bar.info.slotted.size(), 1u);
  EXPECT_NEAR(bar.info.slotted[0].at_mm.x(), 845, 1);
  EXPECT_GT(bar.info.slotted[0].area_mm2, 30 * 10.4);
  EXPECT_LT(bar.info.slotted[0].area_mm2, 1.2 * 30 * 10.45);  // perimeter / 2: its ends too
  const Vec3 down = bar.path.segments()[bar.info.finish_first_segment].end();  // over it
  EXPECT_TRUE(down.x() < 830 || down.x() > 860) << down.transpose();
  // The finishing pass slots the bar level by level (max_step_down 2 of the 4 mm), not at full
  // depth alone: its feed moves through the bar (830 < x < 860) at both levels, -2 and -4 mm.
  std::set<double> bar_levels;
  for (std::size_t i = bar.info.finish_first_segment; i < bar.path.segments().size(); ++i) {
    const Segment& g = bar.path.segments()[i];
    if (g.motion() == Motion::feed && g.start().z() == g.end().z() && g.start().z() < 0 &&
        std::min(g.start().x(), g.end().x()) < 845 && std::max(g.start().x(), g.end().x()) > 845) {
      bar_levels.insert(g.start().z());
    }
  }
  EXPECT_EQ(bar_levels, (std::set<double>{-4.0, -2.0}));
  // However small channel_width is.
  const PlannedPocket small = plan_pocket(job_of("THIN", "channel_width = 1.0\n"));
  EXPECT_EQ(small.info.channels, 1);
  EXPECT_LT(small.proof.finish_max_engagement_deg, 135);
}

// [path] type in a pocket's job: the channels cleared by the straight slot's family. In the
// straight 60 x 14 mm channel each cycle is the family's closed form (docs/models.md section 2:
// Wagih 2023 Eq. 1 with a = the orbit's half-width, b = r_e a, the step s between the cycle's
// starts on its wall, d the wall moves), checked on every planned piece of the steady middle,
// and every plan holds the target by the kernel.
TEST(Pocket, ChannelsTakeEveryFamilyOfTheStraightSlot) {
  struct Case {
    const char* type;
    double aspect, d;
  };
  for (const Case& c : {Case{"trochoidal", 1, 0}, Case{"circular", 1, 0},
                        Case{"elliptical", 0.6, 0}, Case{"linear-elliptical", 0.8, 0.3}}) {
    SCOPED_TRACE(c.type);
    std::string more = std::string("[path]\ntype = \"") + c.type + "\"\n";
    if (c.aspect != 1) more += "aspect_ratio = " + std::to_string(c.aspect) + "\n";
    if (c.d > 0) more += "linear_distance = " + std::to_string(c.d) + "\n";
    const Job job = parse_job(pocket_job("boundary = \"CHAN\"\ndepth = 4.0\nmax_step_down = 2.0\n"
                                         "stock_to_leave = 0.2\nmax_engagement = 50.0\n",
                                         more),
                              "CHAN.toml");
    ASSERT_TRUE(job.pocket.channel_family.has_value());
    const PlannedPocket p = plan_pocket(job);
    EXPECT_TRUE(p.info.proven);
    EXPECT_EQ(p.info.channels, 1);
    EXPECT_EQ(p.info.channel_family, c.type);
    EXPECT_LE(p.proof.clearing_max_engagement_deg, 50 * 1.02);
    // The family takes the axis but for its ends (a cycle reaching past them is a circle's).
    EXPECT_GT(p.info.channel_family_mm, 30) << p.info.channel_loops_mm;

    // The first level's pieces at the feed, and where they start on the orbit's wall: the
    // axis is y = 7; the cycles start on the wall right of their travel (climb).
    std::vector<const Segment*> pieces;
    for (std::size_t i = 0; i < p.info.finish_first_segment; ++i) {
      const Segment& s = p.path.segments()[i];
      if (s.motion() == Motion::feed && s.start().z() == -2.0 && s.end().z() == -2.0)
        pieces.push_back(&s);
    }
    double a = 0;  // the orbit's half-width: the pieces' furthest from the axis
    for (const Segment* s : pieces) {
      if (s->start().x() > 515 && s->start().x() < 545)
        a = std::max(a, std::abs(s->start().y() - 7));
    }
    // The clearance 1.792 mm less half the axis samples' spacing (0.025 mm) and 1e-4 mm.
    EXPECT_GT(a, 1.792 - 0.03);
    EXPECT_LT(a, 1.792 + 1e-3);
    // The cycles' starts: on the wall right of their travel (climb), so x increases along the
    // starts below the axis (travel +x) and decreases along those above (travel -x). The
    // pieces starting on either wall, the distinct x in order on each (with the first piece).
    // For linear-elliptical, a wall move's end (d after a start) is not a start.
    struct Start {
      double x;
      std::size_t piece;
      double travel;
    };
    std::vector<Start> starts;
    for (const double side : {-1.0, 1.0}) {
      std::vector<Start> wall;
      for (std::size_t i = 0; i < pieces.size(); ++i) {
        const Vec3 q = pieces[i]->start();
        if (std::abs(q.y() - 7 - side * a) > 1e-7) continue;
        if (!wall.empty() && std::abs(wall.back().x - q.x()) < 1e-9) continue;
        wall.push_back({q.x(), i, -side});
      }
      for (std::size_t w = 0; w < wall.size(); ++w) {
        if (c.d > 0 && w > 0 && std::abs(-side * (wall[w].x - wall[w - 1].x) - c.d) < 1e-6)
          continue;
        starts.push_back(wall[w]);
      }
    }
    std::sort(starts.begin(), starts.end(),
              [](const Start& u, const Start& v) { return u.piece < v.piece; });
    ASSERT_GT(starts.size(), 6u);
    const double b = c.aspect * a;
    int cycles = 0;
    double worst = 0;
    for (std::size_t k = 0; k + 1 < starts.size(); ++k) {
      const double travel = starts[k].travel, y0 = starts[k].x;
      const double x0 = -travel * a;  // the start wall, across (y - 7)
      // The next start on the same wall; consecutive starts of one trochoid are a step apart
      // (at most R) in its travel (on the other wall, the same test runs backwards).
      std::size_t k1 = k + 1;
      while (k1 < starts.size() && starts[k1].travel != travel) ++k1;
      if (k1 == starts.size()) continue;
      const double s = travel * (starts[k1].x - y0);
      if (!(s > 0) || s > 5 || y0 < 512 || y0 > 548) continue;
      // The closed form, densely (its distance to a point within 1e-5 mm: chords of 1e-3 rad).
      std::vector<Vec2> form;  // (across, along from the cycle's start)
      const auto curve = [&](double yc, double t0, double t1) {
        for (int j = 0; j <= 6000; ++j) {
          const double t = t0 + (t1 - t0) * j / 6000;
          form.emplace_back(x0 * std::cos(t), yc + b * std::sin(t) + s * t / (2 * kPi));
        }
      };
      const auto line = [&](const Vec2& u, const Vec2& v) {
        for (int j = 0; j <= 1000; ++j) form.push_back(u + (v - u) * (j / 1000.0));
      };
      const std::string type = c.type;
      if (type == "circular") {
        for (int j = 0; j <= 6000; ++j) {
          const double t = 2 * kPi * j / 6000;
          form.emplace_back(x0 * std::cos(t), a * std::sin(t));
        }
        line({x0, 0}, {x0, s});
      } else if (type == "linear-elliptical") {
        line({x0, 0}, {x0, c.d});
        curve(c.d, 0, kPi);
        line({-x0, c.d + s / 2}, {-x0, s / 2});
        curve(0, kPi, 2 * kPi);
      } else {
        curve(0, 0, 2 * kPi);
      }
      for (std::size_t i = starts[k].piece; i < starts[k1].piece; ++i) {
        for (int j = 0; j <= 8; ++j) {
          const Segment& g = *pieces[i];
          const Vec3 q = g.point_u(g.u0() + (g.u1() - g.u0()) * j / 8);
          const Vec2 local(q.y() - 7, travel * (q.x() - y0));
          double best = 1e9;
          for (const Vec2& f : form) best = std::min(best, (f - local).norm());
          worst = std::max(worst, best);
        }
      }
      ++cycles;
    }
    EXPECT_GE(cycles, 5);
    // [pocket] fit_tolerance (0.002 mm: the biarcs' within 0.8 of it at their samples) and the
    // closed form's chords.
    EXPECT_LT(worst, 0.002 + 1e-5) << cycles << " cycles";
  }
  // Wall moves of 1.2 mm in a 14 mm channel: no linear-elliptical cycle holds 50 degrees, the
  // loops clear it and the plan says where.
  const Job far = parse_job(pocket_job("boundary = \"CHAN\"\ndepth = 4.0\nmax_step_down = 2.0\n"
                                       "stock_to_leave = 0.2\nmax_engagement = 50.0\n",
                                       "[path]\ntype = \"linear-elliptical\"\n"
                                       "linear_distance = 1.2\n"),
                            "CHAN.toml");
  const PlannedPocket p = plan_pocket(far);
  EXPECT_TRUE(p.info.proven);
  EXPECT_LT(p.info.channel_family_mm, 0.1 * p.info.channel_unheld_mm);
  EXPECT_GT(p.info.channel_unheld_mm, 30);
  EXPECT_TRUE(
      has(pocket_summary(p.info, p.proof), "where no linear-elliptical cycle held the target"));
}

// The planner's margin below the target is measured, not a bound: the example plate with a
// [stock] box from x = 26.5 mm planned at 1.2 degrees below its 53 degree target reaches 54.65
// degrees by the kernel. The proof sends that plan back; the next, 0.5 degrees lower, holds.
// (Should a planner change make the first plan hold here, this case no longer sends one back:
// find another by sweeping the box's edge, as docs/models.md describes; the sweep from x = 10
// to 30 mm in 0.5 mm steps found this one alone.)
TEST(Pocket, TheProofSendsAPlanBackThatPassesTheTarget) {
  const Job job = JobDocument::load(test::source_dir() / "examples/pockets/plate.toml")
                      .build({parse_override("stock.min=[26.5, -10, -10]"),
                              parse_override("stock.max=[100, 60, 0]")});
  const PlannedPocket p = plan_pocket(job);
  EXPECT_GT(p.info.first_proof_max_deg, 53 * (1 + kProofTolerance));
  EXPECT_GE(p.info.replans, 1);
  EXPECT_EQ(p.info.aim_margin_deg, 1.2 + 0.5 * p.info.replans);
  EXPECT_TRUE(p.info.proven);
  EXPECT_LE(p.proof.clearing_max_engagement_deg, 53 * (1 + kProofTolerance));
  // The same proof from the program's own kernel run (not the planner's record of it).
  EXPECT_EQ(prove_pocket(job, p).clearing_max_engagement_deg, p.proof.clearing_max_engagement_deg);
}

// A pocket no clearing can enter (40 x 10.5 mm for a 10 mm tool and 0.2 mm of stock: 0.1 mm of
// room) is cut by the finishing pass alone. Nothing cleared reaches its contour, so the pass
// must not feed straight down into the stock (it once went down 4 mm at the entry feed, then
// slotted at full depth): it goes level by level (max_step_down), down along the contour no
// steeper than the helix entry.
TEST(Pocket, AContourNothingClearedReachesIsRampedDownLevelByLevel) {
  const Job job = parse_job(pocket_job("boundary = \"SLIT\"\ndepth = 4.0\nmax_step_down = 2.0\n"
                                       "stock_to_leave = 0.2\nmax_engagement = 50.0\n"),
                            "slit.toml");
  const PlannedPocket p = plan_pocket(job);
  EXPECT_EQ(p.info.passes, 0);
  const double R = job.tool.radius_mm();
  const double slope = job.path.entry_pitch_mm / (kPi * R);  // the helix's, at radius R / 2
  int ramps = 0;
  std::vector<double> flat_levels;
  for (const Segment& g : p.path.segments()) {
    if (g.motion() != Motion::feed) continue;
    const double dz = g.start().z() - g.end().z();
    const double xy = (g.end() - g.start()).head<2>().norm();
    if (dz > 1e-9 && g.end().z() < 0) {
      // Below the top, every descent runs along the contour: at most the helix's slope
      // (1e-9: the descent is spread over the loop's length, in rounding).
      ASSERT_GT(xy, 0) << g.start().transpose() << " -> " << g.end().transpose();
      EXPECT_LE(dz / g.length_mm(), slope + 1e-9);
      ++ramps;
    } else if (std::abs(dz) <= 1e-12 && xy > 1 && g.start().z() < 0 &&
               (flat_levels.empty() || flat_levels.back() != g.start().z())) {
      flat_levels.push_back(g.start().z());
    }
  }
  EXPECT_GT(ramps, 0);
  // Once round at each level, from the top: -2, then -4 mm.
  EXPECT_EQ(flat_levels, (std::vector<double>{-2.0, -4.0}));
  // The round at each level cuts what the ramp's slope left above the level (the ramps are
  // entries; measured 80.3 degrees at most).
  EXPECT_GT(p.proof.finish_max_engagement_deg, 45);
}

TEST(Pocket, AHelixInANarrowPartIsNoSteeperThanOneOfHalfTheToolsRadius) {
  // The 60 x 14 mm channel leaves the helix a radius of 1.61 mm for a 10 mm tool (0.9 of the
  // room): at entry_pitch a turn it descended at 0.099, where a helix of radius R / 2 (and
  // the finishing pass's ramps) descend at pitch / (pi R) = 0.064.
  const Job job = parse_job(pocket_job("boundary = \"CHAN\"\ndepth = 4.0\nmax_step_down = 2.0\n"
                                       "stock_to_leave = 0.2\nmax_engagement = 50.0\n"),
                            "chan.toml");
  const PlannedPocket p = plan_pocket(job);
  const double R = job.tool.radius_mm();
  const double slope = job.path.entry_pitch_mm / (kPi * R);
  int descents = 0;
  double smallest_radius = R;
  for (const Segment& g : p.path.segments()) {
    const double dz = g.start().z() - g.end().z();
    const double xy = (g.end() - g.start()).head<2>().norm();
    if (g.motion() != Motion::feed || !(dz > 1e-9)) continue;
    const bool arc = g.kind() == Segment::Kind::curve;
    if (arc) smallest_radius = std::min(smallest_radius, g.axis_a().head<2>().norm());
    if (xy <= 1e-9 && !arc) continue;  // straight down into what a level above cleared
    // (1e-9: the drop is spread over whole turns, in rounding.)
    EXPECT_LE(dz / g.length_mm(), slope + 1e-9) << g.start().transpose();
    ++descents;
  }
  EXPECT_GT(descents, 0);
  EXPECT_LT(smallest_radius, 0.5 * R);  // the case itself: a helix narrower than R / 2
}

TEST(Pocket, AnOutlineAndItsHolesOnOneLayerAreAPocketAndItsIslands) {
  // Shops draw a part's outline and its holes on one layer: the pocket is what lies inside an
  // odd number of the boundary layer's contours, so NEST (a rectangle and a circle in it) plans
  // as NESTO with the island NESTI: the same program, move for move.
  const auto plan = [](const std::string& keys) {
    return plan_pocket(
        parse_job(pocket_job(keys + "depth = 2.0\nstock_to_leave = 0.2\nmax_engagement = 50.0\n"),
                  "nest.toml"));
  };
  const PlannedPocket one = plan("boundary = \"NEST\"\n");
  const PlannedPocket two = plan("boundary = \"NESTO\"\nislands = \"NESTI\"\n");
  ASSERT_EQ(one.path.segments().size(), two.path.segments().size());
  EXPECT_EQ(one.path.length_mm(), two.path.length_mm());
  EXPECT_EQ(one.info.passes, two.info.passes);
  // No tool centre at the floor nearer the hole's wall than R + stock (1e-6 mm).
  const Contour hole = Contour::circle({1215, 15}, 6);
  for (const Segment& g : one.path.segments()) {
    if (g.motion() != Motion::feed || g.end().z() > -2 + 1e-9) continue;
    EXPECT_GE(hole.distance_mm(g.end().head<2>()), 5.0 - 1e-6) << g.end().transpose();
    EXPECT_FALSE(region_contains({hole}, g.end().head<2>())) << g.end().transpose();
  }
  // Walls that cross are refused, and an island inside a hole of the boundary layer stands in
  // the stock, not in the pocket.
  std::string m = test::message_of([&] { (void)plan("boundary = \"CROSS\"\n"); });
  EXPECT_TRUE(has(m, "on layer 'CROSS' cross (300 mm^2 of the smaller lies outside the other)"))
      << m;
  m = test::message_of([&] { (void)plan("boundary = \"NEST\"\nislands = \"NESTX\"\n"); });
  EXPECT_TRUE(has(m, "is not inside a boundary")) << m;
  // A pre-drilled hole in the outline's hole is in an island, not outside the boundary.
  m = test::message_of(
      [&] { (void)plan("boundary = \"NEST\"\nentry_holes = [[1215.0, 15.0]]\n"); });
  EXPECT_TRUE(has(m, "in a hole of the boundary (a contour of layer 'NEST' nested in another"))
      << m;
}

TEST(Pocket, BadPocketsAreRefusedWithTheirReason) {
  const auto message = [](const std::string& keys, const std::string& extra = "") {
    return test::message_of([&] { (void)parse_job(pocket_job(keys, extra), "bad.toml"); });
  };
  const std::string ok = "boundary = \"RECT\"\ndepth = 4.0\n";
  std::string m = message("boundary = \"OPEN\"\ndepth = 4.0\nmax_engagement = 50.0\n");
  EXPECT_TRUE(has(m, "layer 'OPEN' has an open contour")) << m;
  m = message(ok + "islands = \"OUT\"\nmax_engagement = 50.0\n");
  EXPECT_TRUE(has(m, "is not inside a boundary")) << m;
  m = message(ok + "islands = \"OVER\"\nmax_engagement = 50.0\n");
  EXPECT_TRUE(has(m, "overlap or nest")) << m;
  m = message(ok + "max_engagement = 0.0\n");
  EXPECT_TRUE(has(m, "[pocket] max_engagement: must be in (0, 180]")) << m;
  m = message(ok + "max_engagement = 181.0\n");
  EXPECT_TRUE(has(m, "[pocket] max_engagement: must be in (0, 180]")) << m;
  m = message(ok);
  EXPECT_TRUE(has(m, "missing [pocket] max_engagement (degrees) or max_chip (mm)")) << m;
  m = message(ok + "max_engagement = 50.0\nmax_chip = 0.02\n");
  EXPECT_TRUE(has(m, "not both")) << m;
  m = message(ok + "max_chip = 0.06\n");
  EXPECT_TRUE(has(m, "must be below the feed per tooth f_z = 0.05 mm")) << m;
  m = message(ok + "max_engagement = 50.0\nchannel_width = -1.0\n");
  EXPECT_TRUE(has(m, "[pocket] channel_width: must be in [0, 10000]")) << m;
  m = message(ok + "max_engagement = 50.0\n", "[slot]\nwidth = 12.0\ndepth = 3.0\nlength = 20.0\n");
  EXPECT_TRUE(has(m, "[slot] and [pocket]")) << m;
  m = message(ok + "max_engagement = 50.0\n", "[path]\nstep = 1.0\n");
  EXPECT_TRUE(has(m, "[path] step: is for slots")) << m;
  // [path] type chooses the channels' family: not the linear one; its shape keys need it.
  m = message(ok + "max_engagement = 50.0\n", "[path]\ntype = \"linear\"\n");
  EXPECT_TRUE(has(m, "[path] type: a pocket's channels are cleared by the trochoidal families"))
      << m;
  m = message(ok + "max_engagement = 50.0\n", "[path]\naspect_ratio = 0.8\n");
  EXPECT_TRUE(
      has(m, "[path] aspect_ratio: shapes the family of a pocket's channels: give [path] type"))
      << m;
  EXPECT_FALSE(has(m, "type = \"trochoidal\" is the elliptical family")) << m;  // none given
  m = message(ok + "max_engagement = 50.0\n",
              "[path]\ntype = \"trochoidal\"\naspect_ratio = 0.8\n");
  EXPECT_TRUE(has(m, "use type = \"elliptical\"")) << m;
  m = message(ok + "max_engagement = 50.0\n", "[path]\ntype = \"elliptic\"\n");
  EXPECT_TRUE(has(m, "[path] type")) << m;
  m = message("depth = 4.0\nmax_engagement = 50.0\n");
  EXPECT_TRUE(has(m, "missing required key [pocket] boundary")) << m;
  m = message("boundary = \"NOPE\"\ndepth = 4.0\nmax_engagement = 50.0\n");
  EXPECT_TRUE(has(m, "'NOPE'")) << m;
  // A tool wider than the pocket: refused when planning, with the tool and the layer.
  std::string text = pocket_job(ok + "max_engagement = 50.0\n");
  text.replace(text.find("diameter = 10.0"), 15, "diameter = 45.0");
  const Job wide = parse_job(text, "wide.toml");
  m = test::message_of([&] { (void)plan_pocket(wide); });
  EXPECT_TRUE(has(m,
                  "the tool (D = 45 mm) with stock_to_leave = 0 mm fits nowhere in layer "
                  "'RECT'"))
      << m;
  // A pocket whose every part is too narrow for the clearing (CHAN, 14 mm, with a 13.4 mm tool
  // and 0.2 mm of stock: less than R / 10 wider) and no finishing pass: nothing to cut, said
  // (it crashed on the empty program).
  text = pocket_job(
      "boundary = \"CHAN\"\ndepth = 4.0\nstock_to_leave = 0.2\nfinish_pass = false\n"
      "max_engagement = 50.0\n");
  text.replace(text.find("diameter = 10.0"), 15, "diameter = 13.4");
  const Job narrow = parse_job(text, "narrow.toml");
  m = test::message_of([&] { (void)plan_pocket(narrow); });
  EXPECT_TRUE(has(m, "[pocket] finish_pass = false: nothing to cut in layer 'CHAN'")) << m;
  // A job with [pocket] is not a slot: the slot models say so.
  const Job pocket = parse_job(pocket_job(ok + "max_engagement = 50.0\n"), "p.toml");
  m = test::message_of([&] { (void)plan_slot(pocket); });
  EXPECT_TRUE(has(m, "the job plans a pocket")) << m;
}

TEST(Pocket, RestMachiningCutsWhatTheLargerToolLeft) {
  // A 20 mm tool's program on the 60 x 40 mm rectangle (one level 2 mm deep, its finishing
  // pass at full depth), then a 6 mm tool's program after it ([pocket] rest_of).
  const std::string keys = "boundary = \"RECT\"\ndepth = 2.0\nmax_engagement = 50.0\n";
  const Job rough = JobDocument::parse(pocket_job(keys), "rough.toml")
                        .build({parse_override("tool.diameter=20")});
  const PlannedPocket first = plan_pocket(rough);
  const auto ngc = test::scratch_dir("rest") / "rough.ngc";
  {
    std::ofstream out(ngc);
    out << write_gcode(rough, first.path, gcode_options(rough.machine).write);
  }
  Job rest =
      JobDocument::parse(pocket_job(keys + "rest_of = \"" + ngc.string() + "\"\n"), "rest.toml")
          .build({parse_override("tool.diameter=6"), parse_override("simulation.resolution=0.2"),
                  parse_override("simulation.steps_per_rev=24")});
  attach_rest_stock(rest);
  ASSERT_TRUE(rest.pocket.rest);
  EXPECT_EQ(rest.pocket.rest->tool_radius_mm, 10.0);  // from the program's header
  const PlannedPocket second = plan_pocket(rest);
  EXPECT_EQ(second.info.rest_tool_diameter_mm, 20.0);
  EXPECT_GT(second.info.rest_cleared_mm2, 0.9 * 2400 - 1);
  // The kernel against the stock the first program left: the target within 2 % (the
  // issue's allowance; the same margin as every pocket), entries excepted.
  const PocketProof proof = second.proof;
  EXPECT_LE(proof.clearing_max_engagement_deg, 50 * 1.02);
  EXPECT_GT(proof.clearing_max_engagement_deg, 30);  // it does cut: the corners

  // The simulation (tri-dexel, independent of the planner's discs): the first tool's sweep,
  // then the second program. Each tool leaves at each of the four corners the cusp
  // (1 - pi/4) r^2 of its finishing pass's radius r = R + 0.002 mm (the pass keeps that off
  // the walls): the second removes the difference, the pair the pocket less the second's.
  const JobSimulation sim = simulate_job(rest, second.path, 0, second.path.duration_s());
  const double depth = 2, cusp = 1 - kPi / 4;
  const double r1 = 10.002, r2 = 3.002;
  const double left_by_first = 4 * cusp * (r1 * r1 - r2 * r2) * depth;  // 156.3 mm^3
  // 1 %: 0.2 mm dexels along the corners' arcs (measured 0.05 % at 4 mm deep).
  EXPECT_NEAR(sim.result.removed_mm3, left_by_first, 0.01 * left_by_first);
  const double before = TriDexel(job_stock(rest), 0.2).boards[2].volume_mm3();
  const double pair = before - sim.work->boards[2].volume_mm3();
  const double pocket = 2400 * depth - 4 * cusp * r2 * r2 * depth;
  // 1 % of the pocket, the issue's: the first program alone would be 3.3 % short.
  EXPECT_NEAR(pair, pocket, 0.01 * pocket);
}

TEST(Pocket, RestMachiningRefusesWhatItCannotUse) {
  const std::string keys = "boundary = \"RECT\"\ndepth = 2.0\nmax_engagement = 50.0\n";
  auto message = [&](const std::string& more, const std::string& set = "") {
    try {
      Job job = JobDocument::parse(pocket_job(keys + more), "rest.toml")
                    .build(set.empty() ? std::vector<Override>{}
                                       : std::vector<Override>{parse_override(set)});
      attach_rest_stock(job);
      (void)plan_pocket(job);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const auto dir = test::scratch_dir("rest-bad");
  // A program that is not there: the key and the file.
  std::string m = message("rest_of = \"" + (dir / "none.ngc").string() + "\"\n");
  EXPECT_TRUE(has(m, "[pocket] rest_of")) << m;
  EXPECT_TRUE(has(m, "none.ngc")) << m;
  // A program without a trochomill header and no rest_tool_diameter: the key to give.
  { std::ofstream(dir / "plain.ngc") << "G21 G90\nG0 X30 Y20 Z5\nG1 Z-2 F100\nG1 X40 F500\nM2\n"; }
  m = message("rest_of = \"" + (dir / "plain.ngc").string() + "\"\n");
  EXPECT_TRUE(has(m, "[pocket] rest_tool_diameter: give the diameter")) << m;
  // Its tool smaller than this job's (10 mm).
  m = message("rest_of = \"" + (dir / "plain.ngc").string() + "\"\nrest_tool_diameter = 6\n");
  EXPECT_TRUE(has(m, "smaller than this job's")) << m;
  // A program that never cuts below the top at a constant height.
  { std::ofstream(dir / "above.ngc") << "G21 G90\nG0 X30 Y20 Z5\nG1 X40 F500\nM2\n"; }
  m = message("rest_of = \"" + (dir / "above.ngc").string() + "\"\nrest_tool_diameter = 20\n");
  EXPECT_TRUE(has(m, "removed nothing")) << m;
  // A program of two tools.
  {
    std::ofstream(dir / "two.ngc") << "G21 G90\nT1 M6\nG0 X30 Y20 Z5\nG1 Z-2 F100\nG1 X40 F500\n"
                                      "G0 Z5\nT2 M6\nG0 X20 Y20\nG1 Z-2\nG1 X25\nM2\n";
  }
  m = message("rest_of = \"" + (dir / "two.ngc").string() + "\"\nrest_tool_diameter = 20\n");
  EXPECT_TRUE(has(m, "changes tools (T1 at")) << m;
  EXPECT_TRUE(has(m, "two.ngc:7")) << m;
  // rest_tool_diameter without rest_of.
  m = message("rest_tool_diameter = 20\n");
  EXPECT_TRUE(has(m, "give [pocket] rest_of too")) << m;
  // A plain program with its diameter given: read, and the plan cuts what it left.
  Job job = JobDocument::parse(pocket_job(keys + "rest_of = \"" + (dir / "plain.ngc").string() +
                                          "\"\nrest_tool_diameter = 20\n"),
                               "rest.toml")
                .build();
  attach_rest_stock(job);
  ASSERT_TRUE(job.pocket.rest);
  ASSERT_EQ(job.pocket.rest->levels.size(), 1u);
  EXPECT_EQ(job.pocket.rest->levels[0].z_mm, -2.0);
  // The slot it cut (10 mm long, 20 wide, round ends: 200 + 100 pi mm^2), on the coverage's
  // grid of 0.25 mm: 2 %, half a cell along its 83 mm outline (measured 0.02 %).
  const PlannedPocket p = plan_pocket(job);
  EXPECT_NEAR(p.info.rest_cleared_mm2, 200 + 100 * kPi, 0.02 * (200 + 100 * kPi));
}

TEST(Pocket, RestDiscsMakeTheLargerToolsSweep) {
  // An earlier 16 mm tool along a line and a half circle at z = -2, and a pass at z = -1 that
  // a level at -2 does not count: the discs of a 6 mm tool cover every point within 8 mm of
  // the moves at or below the height (less the scallops, spacing^2 / 8R = 0.1 um), and none
  // beyond 8 mm.
  RestStock rest;
  rest.name = "earlier.ngc";
  rest.tool_radius_mm = 8;
  Contour chain;
  chain.pieces.push_back(ContourPiece::line({0, 0}, {30, 0}));
  chain.pieces.push_back(ContourPiece::arc({30, 0}, {30, 20}, {30, 10}, true));
  Contour high;
  high.pieces.push_back(ContourPiece::line({0, 40}, {30, 40}));
  rest.levels = {{-2.0, {chain}}, {-1.0, {high}}};
  const double R = 3, spacing = 0.05;
  const std::vector<Vec2> c = rest_disc_centres(rest, -2.0, R, spacing);
  ASSERT_FALSE(c.empty());
  auto covered = [&](const Vec2& p) {
    for (const Vec2& q : c) {
      if ((q - p).norm() <= R) return true;
    }
    return false;
  };
  auto to_moves = [&](const Vec2& p) {
    return std::min(chain.distance_mm(p), 1e9);  // the level at -1 is above -2
  };
  int inside = 0;
  for (double y = -10; y <= 45; y += 0.37) {
    for (double x = -10; x <= 50; x += 0.41) {
      const Vec2 p(x, y);
      const double d = to_moves(p);
      // 2e-3 mm: room over the scallops of the outline's discs (0.1 um) and of the discs of
      // radius 5 mm along the moves (0.01 um).
      if (d < 8 - 2e-3) {
        EXPECT_TRUE(covered(p)) << x << " " << y;
        ++inside;
      } else if (d > 8 + 1e-9) {
        EXPECT_FALSE(covered(p)) << x << " " << y;
      }
    }
  }
  EXPECT_GT(inside, 1000);
  // At -1 both levels count: the pass along y = 40 too.
  const std::vector<Vec2> both = rest_disc_centres(rest, -1.0, R, spacing);
  EXPECT_GT(both.size(), c.size());
  // A smaller earlier tool is refused.
  rest.tool_radius_mm = 2;
  EXPECT_THROW((void)rest_disc_centres(rest, -2.0, R, spacing), InputError);
}

namespace {

// A 6 mm tool's pocket job (`keys`, target 50 degrees) after `program`, a 20 mm tool's
// (written to a scratch folder `name`), its rest stock attached.
Job rest_job(const std::string& name, const std::string& keys, const std::string& program) {
  const auto file = test::scratch_dir(name) / "earlier.ngc";
  std::ofstream(file) << program;
  Job job = JobDocument::parse(pocket_job(keys + "max_engagement = 50.0\nrest_of = \"" +
                                          file.string() + "\"\nrest_tool_diameter = 20\n"),
                               name + ".toml")
                .build({parse_override("tool.diameter=6")});
  attach_rest_stock(job);
  return job;
}

}  // namespace

TEST(Pocket, RestStockCountsOnlyBelowTheEarlierCut) {
  // The 40 mm circle, 2 mm deep in two levels, after a 20 mm tool's slot 1 mm deep (10 mm
  // long across the centre): the first level starts where the slot is, the second has nothing
  // cleared (its plan its own). The kernel's removal counts the slot's region from 1 mm down
  // only: pi 20^2 2 - (200 + 100 pi) 1 mm^3 in all.
  const Job job = rest_job("rest-levels", "boundary = \"CIRC\"\ndepth = 2.0\nmax_step_down = 1.0\n",
                           "G21 G90\nG0 X445 Y20 Z5\nG1 Z-1 F100\nG1 X455 F500\nG0 Z5\nM2\n");
  const PlannedPocket p = plan_pocket(job);
  EXPECT_EQ(p.info.rest_cleared_mm2, 0.0);  // the deepest level's
  // Level by level: the slot's region at the first (the coverage cells within the earlier
  // tool's sweep, 10 x 20 mm and its round ends, 200 + 100 pi mm^2, to the cells' 2 %), none
  // below.
  ASSERT_EQ(p.info.rest_cleared_by_level_mm2.size(), 2u);
  EXPECT_NEAR(p.info.rest_cleared_by_level_mm2[0], 200 + 100 * kPi, 0.02 * (200 + 100 * kPi));
  EXPECT_EQ(p.info.rest_cleared_by_level_mm2[1], 0.0);
  EXPECT_TRUE(has(pocket_summary(p.info, p.proof), "at the levels from the top"));
  const EngagementSeries e = compute_engagement(p.path, job);
  double removed = 0;
  for (std::size_t i = 1; i < e.samples.size(); ++i) {
    removed += e.removal_rate_mm3_per_s[i] * (e.samples.t_s[i] - e.samples.t_s[i - 1]);
  }
  const double expected = kPi * 400 * 2 - (200 + 100 * kPi);  // 1999.1 mm^3
  // 2 %: the kernel's removal is 1.2 % short of the closed form on this pocket (the
  // simulation: 0.02 %); counting the slot's region to the top, as before the earlier
  // program's levels counted above a position, gave 3.7 % too much.
  EXPECT_NEAR(removed, expected, 0.02 * expected);
  const PocketProof proof = p.proof;
  EXPECT_LE(proof.clearing_max_engagement_deg, 50 * 1.02);
}

TEST(Pocket, RestMachiningComesDownOnlyWhereTheDiscIsCleared) {
  // An earlier 20 mm tool's full circle of radius 12 about (30, 20), 2 mm deep, leaves a
  // pillar of radius 2 at its centre, the stock nearest the rectangle's widest place: a 6 mm
  // tool's circle about that centre lies in the cleared ring, its disc does not. No rapid may
  // go below the top within 2 + 3 mm of the pillar's axis (it came down on it before).
  const Job job = rest_job("rest-pillar", "boundary = \"RECT\"\ndepth = 2.0\n",
                           "G21 G90\nG0 X42 Y20 Z5\nG1 Z-2 F100\nG3 X42 Y20 I-12 J0 F500\n"
                           "G0 Z5\nM2\n");
  const PlannedPocket p = plan_pocket(job);
  int descents = 0;
  for (const Segment& g : p.path.segments()) {
    if (g.motion() != Motion::rapid || !(g.end().z() < 0)) continue;
    ++descents;
    const double d = std::hypot(g.end().x() - 30, g.end().y() - 20);
    EXPECT_GE(d, 5.0 - 1e-9) << g.end().transpose();  // the disc clear of the pillar
  }
  EXPECT_GT(descents, 0);  // it does come down from above
}

TEST(Pocket, TheSimulationRemovesThePocket) {
  // The 40 mm circle 2 mm deep with a 10 mm tool (a circle has no corners' cusps): the
  // tri-dexel simulation of the whole program removes pi 20^2 2 mm^3. (Its tool's flutes
  // reach the pocket's depth without a flute length: 1 mm, the slot's default, left half.)
  const Job job = JobDocument::parse(pocket_job("boundary = \"CIRC\"\ndepth = 2.0\n"
                                                "max_engagement = 50.0\n"),
                                     "circle.toml")
                      .build({parse_override("simulation.resolution=0.25"),
                              parse_override("simulation.steps_per_rev=16")});
  const PlannedPocket p = plan_pocket(job);
  const JobSimulation sim = simulate_job(job, p.path, 0, p.path.duration_s());
  const double expected = kPi * 400 * 2;  // 2513.3 mm^3
  // 1 % (the issue's): 0.25 mm dexels along the 126 mm wall (measured 0.01 %).
  EXPECT_NEAR(sim.result.removed_mm3, expected, 0.01 * expected);
}

TEST(Pocket, AnOpenPocketIsEnteredFromBesideTheStock) {
  // The 60 x 40 rectangle 2 mm deep, the [stock] box from x = 20 on: its left third is air.
  // The tool comes down there (no helix), its disc clear of the box, and the clearing holds
  // the target where it meets the box's edge (where the tool's circle leaves the edge from
  // inside, the sliver between them joins the arc in the stock: the planner takes a band two
  // teeth's advances wide beyond the edge as stock).
  const Job job =
      JobDocument::parse(pocket_job("boundary = \"RECT\"\ndepth = 2.0\n"
                                    "max_engagement = 50.0\n"),
                         "open.toml")
          .build({parse_override("stock.min=[20, -5, -3]"), parse_override("stock.max=[80, 45, 0]"),
                  parse_override("simulation.resolution=0.25"),
                  parse_override("simulation.steps_per_rev=16")});
  const PlannedPocket p = plan_pocket(job);
  EXPECT_EQ(p.info.open_entries, 1);
  EXPECT_EQ(p.info.helix_entries, 0);
  // The air the clearing covers: the tool centre's region (R + 0.008 mm in from the walls, its
  // convex corners rounded by R / 4) grown by R, left of the edge less the band (0.1 mm): 19.892
  // x 39.984 mm less two corners' cusps of radius 6.258; counted in the planner's cells of
  // 0.5 mm, of which those on the strip's outline (100 mm long: 25 mm^2, 3.2 %) fall either
  // way (measured 764.5 mm^2).
  const double air = 19.892 * 39.984 - 2 * (1 - kPi / 4) * std::pow(6.258, 2);
  EXPECT_NEAR(p.info.open_mm2, air, 0.04 * air);
  // The first descent below the top is in the air, the tool's disc clear of the box (the
  // others go down where the tool passed at that level: the relinks).
  const auto& segs = p.path.segments();
  const auto first =
      std::find_if(segs.begin(), segs.end(), [](const Segment& g) { return g.end().z() < 0; });
  ASSERT_NE(first, segs.end());
  EXPECT_LE(first->end().x(), 20 - 5 + 1e-9) << first->end().transpose();
  for (const Segment& g : segs) {
    // No helix: no arc that descends.
    EXPECT_FALSE(g.kind() != Segment::Kind::line && g.end().z() != g.start().z())
        << g.start().transpose();
  }
  const PocketProof proof = p.proof;
  EXPECT_LE(proof.clearing_max_engagement_deg, 50 * 1.02);
  EXPECT_GT(proof.clearing_max_engagement_deg, 40);
  // The simulation removes the rectangle's part in the box, 2 mm deep, less the two corners'
  // cusps of radius R + 0.002 (the finishing pass's): 1 % (the issue's; 0.25 mm dexels).
  const JobSimulation sim = simulate_job(job, p.path, 0, p.path.duration_s());
  const double expected = 2 * (40 * 40 - 2 * (1 - kPi / 4) * 5.002 * 5.002);
  EXPECT_NEAR(sim.result.removed_mm3, expected, 0.01 * expected);
  // A box beside the pocket (here, the drawing's frame mistaken): nothing to cut, refused with
  // both boxes named; the planner would have written a finishing pass through the air.
  const std::string m = test::message_of([&] {
    (void)plan_pocket(JobDocument::parse(pocket_job("boundary = \"RECT\"\ndepth = 2.0\n"
                                                    "max_engagement = 50.0\n"),
                                         "away.toml")
                          .build({parse_override("stock.min=[100, -5, -3]"),
                                  parse_override("stock.max=[180, 45, 0]")}));
  });
  EXPECT_TRUE(has(m,
                  "[stock] min, max: the box (100, -5) .. (180, 45) mm leaves none of the "
                  "pocket of layer 'RECT' (x 0 .. 60, y 0 .. 40 mm, less its islands)"))
      << m;
  // A box over nothing of the pocket but what the islands hold (the test pockets' rectangle
  // has none: the islands pocket's round boss), and one below the floor: refused too.
  const auto refused = [&](const std::string& boundary, const std::string& lo,
                           const std::string& hi) {
    return test::message_of([&] {
      (void)plan_pocket(
          JobDocument::parse(pocket_job(boundary + "depth = 2.0\n"
                                                   "max_engagement = 50.0\n"),
                             "box.toml")
              .build({parse_override("stock.min=" + lo), parse_override("stock.max=" + hi)}));
    });
  };
  std::string u = refused("boundary = \"ISLB\"\nislands = \"ISL\"\n", "[217, 14, -5]",
                          "[225, 18, 0]");  // inside the 12 x 8 mm block island
  EXPECT_TRUE(has(u,
                  "[stock] min, max: the box (217, 14) .. (225, 18) mm leaves none of the "
                  "pocket of layer 'ISLB'"))
      << u;
  u = refused("boundary = \"RECT\"\n", "[0, 0, -30]", "[60, 40, -2]");
  EXPECT_TRUE(has(u,
                  "[stock] max: the box's top z = -2 mm is at or below the pocket's floor "
                  "z = -2 mm: nothing to cut"))
      << u;
  // A stock whose top is above the top face z = 0 the program is planned from: the rapids
  // come down to the clearance 1 mm above z = 0, inside it. Refused, for a pocket and a slot.
  const std::string expect_top =
      "[stock] max: the stock's top z = 2 mm is above the top face z = 0 the program is planned "
      "from: its depths and levels are measured from z = 0 and its rapids come down to [path] "
      "clearance = 1 mm above z = 0";
  std::string t = test::message_of([&] {
    (void)plan_pocket(JobDocument::parse(pocket_job("boundary = \"RECT\"\ndepth = 2.0\n"
                                                    "max_engagement = 50.0\n"),
                                         "top.toml")
                          .build({parse_override("stock.min=[-5, -5, -3]"),
                                  parse_override("stock.max=[80, 45, 2]")}));
  });
  EXPECT_TRUE(has(t, expect_top)) << t;
  t = test::message_of([&] {
    (void)plan_slot(test::straight_job(
        10.0, 4,
        {parse_override("stock.min=[-20, -5, -10]"), parse_override("stock.max=[20, 60, 2]")}));
  });
  EXPECT_TRUE(has(t, expect_top)) << t;
}

TEST(Pocket, APreDrilledHoleIsTheEntry) {
  // A hole at (45, 20) in the 60 x 40 rectangle, two levels: each level is entered by feeding
  // straight down it (no helix) from the clearance above the top (then above the level
  // above), and out to a flat circle about it.
  const Job job = parse_job(pocket_job("boundary = \"RECT\"\ndepth = 4.0\nmax_step_down = 2.0\n"
                                       "max_engagement = 50.0\nentry_holes = [[45, 20]]\n"),
                            "hole.toml");
  ASSERT_EQ(job.pocket.entry_holes_mm.size(), 1u);
  const PlannedPocket p = plan_pocket(job);
  EXPECT_EQ(p.info.hole_entries, 1);
  EXPECT_EQ(p.info.helix_entries, 0);
  // The first move below the top feeds down the hole; the deepest point of each level's
  // descents there is the level.
  const auto& segs = p.path.segments();
  const auto first =
      std::find_if(segs.begin(), segs.end(), [](const Segment& g) { return g.end().z() < 0; });
  ASSERT_NE(first, segs.end());
  EXPECT_EQ(first->motion(), Motion::feed);
  EXPECT_EQ(first->start().head<2>(), Vec2(45, 20));
  EXPECT_EQ(first->end(), Vec3(45, 20, -2));
  std::vector<double> plunged_to;
  for (const Segment& g : segs) {
    EXPECT_FALSE(g.kind() != Segment::Kind::line && g.end().z() != g.start().z())
        << g.start().transpose();
    if (g.motion() == Motion::feed && g.end().z() < g.start().z() &&
        g.end().head<2>() == Vec2(45, 20) && g.start().head<2>() == Vec2(45, 20)) {
      if (plunged_to.empty() || plunged_to.back() != g.end().z()) plunged_to.push_back(g.end().z());
    }
  }
  EXPECT_EQ(plunged_to, (std::vector<double>{-2, -4}));
  // The program says what it needs before anything moves (else the tool plunges into the stock).
  const std::string program = write_gcode(job, p.path, gcode_options(job.machine).write);
  EXPECT_TRUE(
      has(program, "(NEEDS PRE-DRILLED HOLES at least 10 mm wide and 4 mm deep at X45 Y20)"))
      << program.substr(0, 400);
  EXPECT_LT(program.find("NEEDS PRE-DRILLED"), program.find("G0 "));
  // A second hole in the same part is not gone down (the first listed is the part's entry):
  // the header does not ask for it.
  Job two = job;
  two.pocket.entry_holes_mm.emplace_back(20, 20);
  two.pocket.entry_holes_mm.emplace_back(45, 20);  // the same hole again: listed once
  const std::string program2 = write_gcode(two, p.path, gcode_options(two.machine).write);
  EXPECT_TRUE(
      has(program2, "(NEEDS PRE-DRILLED HOLES at least 10 mm wide and 4 mm deep at X45 Y20)"))
      << program2.substr(0, 400);
  // Out of a hole of the tool's width no move keeps within the target: the flat circle about
  // it opens the way, as the helix's does, and the clearing covers the pocket (it gave up
  // nothing; with the helix at the widest place 0.06 mm^2, an inside corner's last cell).
  EXPECT_LE(p.info.left_for_finish_mm2, 0.5);
  EXPECT_GT(p.info.passes, 100);
  const PocketProof proof = p.proof;
  EXPECT_LE(proof.clearing_max_engagement_deg, 50 * 1.02);
  // Refused: a hole where the tool centre may not go (3 mm from the wall), a malformed list.
  const auto message = [](const std::string& holes) {
    return test::message_of([&] {
      (void)plan_pocket(parse_job(pocket_job("boundary = \"RECT\"\ndepth = 4.0\n"
                                             "max_engagement = 50.0\nentry_holes = " +
                                             holes + "\n"),
                                  "bad.toml"));
    });
  };
  // Each message gives the reason that applies: near a wall (3 mm from it, within R + 0 +
  // 0.008 mm of the fit and Clipper's chords), outside the boundary, in a rounded corner ((5.3,
  // 5.3) is 5.3 mm from both walls, but 1.355 mm from the centre (6.258, 6.258) of the corner
  // the clearing rounds by R / 4 = 1.25 mm).
  std::string m = message("[[45, 20], [3, 20]]");
  EXPECT_TRUE(has(
      m,
      "[pocket] entry_holes: hole 2 (counting from 1) at (3, 20) mm is where the tool centre may "
      "not go: 3 mm from a wall or island, within R + stock_to_leave + 0.008 = 5.008 mm (the "
      "tool would cut the wall going down it)"))
      << m;
  m = message("[[70, 20]]");
  EXPECT_TRUE(has(m,
                  "hole 1 (counting from 1) at (70, 20) mm is where the tool centre may not "
                  "go: outside the boundary (layer 'RECT')"))
      << m;
  m = message("[[5.3, 5.3]]");
  EXPECT_TRUE(has(m,
                  "hole 1 (counting from 1) at (5.3, 5.3) mm is where the tool centre may not "
                  "go: in a corner the clearing rounds off (by R / 4 = 1.25 mm"))
      << m;
  m = message("[45, 20]");
  EXPECT_TRUE(has(m, "[pocket] entry_holes: hole 1 (counting from 1) must be a point [x, y]")) << m;
  m = message("[[45, 20, 1]]");
  EXPECT_TRUE(has(m, "hole 1 (counting from 1) must be a point [x, y]")) << m;
}

TEST(Pocket, AStockMeshIsClearedOnlyWhereItStands) {
  // The 60 x 40 rectangle 6 mm deep in three levels, its stock a block (70 x 70 mm, 10 deep)
  // with a drafted core about the pocket's centre (30, 20): 32 sides, radius 12 mm at the top,
  // 8 mm at its floor 5 mm down. At the first two levels (z = -2, -4) the core is air: the
  // tool comes down into it from above (no helix) where its disc is clear of the core's wall
  // at that level and above; the third level (z = -6, below the core) is entered by a helix.
  // (A core whose floor were at a level would be stock there: the tool's tip meets it.)
  const std::filesystem::path dir = test::scratch_dir("pocket-mesh");
  Mesh core = test::cored_block_mesh(35, -10, 12, 8, -5, 32);
  for (Vec3& v : core.vertices) v += Vec3(30, 20, 0);
  write_mesh(dir / "cored.stl", core);
  const std::string keys =
      "boundary = \"RECT\"\ndepth = 6.0\nmax_step_down = 2.0\nmax_engagement = 50.0\n";
  const std::vector<Override> sim = {parse_override("simulation.resolution=0.25"),
                                     parse_override("simulation.steps_per_rev=16")};
  const Job job = JobDocument::parse(pocket_job(keys, "[stock]\nmesh = \"cored.stl\"\n"),
                                     (dir / "cored.toml").string())
                      .build(sim);
  ASSERT_TRUE(job.stock_mesh);
  EXPECT_EQ(*job.stock_max_mm, Vec3(65, 55, 0));  // the mesh's box
  const PlannedPocket p = plan_pocket(job);
  // The first descent below the top is in the core: at z = -2 + clearance, its tool disc
  // within the core's radius there and above, 10.4 mm at z = -2.
  const auto& segs = p.path.segments();
  const auto first =
      std::find_if(segs.begin(), segs.end(), [](const Segment& g) { return g.end().z() < 0; });
  ASSERT_NE(first, segs.end());
  const double off = (first->end().head<2>() - Vec2(30, 20)).norm();
  EXPECT_LE(off + 5, 10.4 * std::cos(kPi / 32))
      << first->end().transpose();  // the n-gon's inradius
  // Helices only at the third level: from the clearance above the second level down.
  int helix_turns = 0;
  for (const Segment& g : segs) {
    if (g.kind() == Segment::Kind::line || g.end().z() == g.start().z()) continue;
    ++helix_turns;
    EXPECT_LE(g.start().z(), -4 + job.path.clearance_mm + 1e-9) << g.start().transpose();
    EXPECT_GE(g.end().z(), -6 - 1e-9);
  }
  EXPECT_GT(helix_turns, 0);
  // The proof, by the kernel on the same mesh stock: the target holds.
  EXPECT_LE(p.proof.clearing_max_engagement_deg, 50 * 1.02);
  EXPECT_GT(p.proof.clearing_max_engagement_deg, 40);
  // The simulation on the mesh removes the pocket (less the four corners' cusps of radius R +
  // 0.002, the finishing pass's) less the core's frustum: 1 % (the issue's; 0.25 mm dexels).
  auto ngon = [](double r) { return 16 * r * r * std::sin(2 * kPi / 32); };
  const double frustum = 5.0 / 3 * (ngon(12) + ngon(8) + std::sqrt(ngon(12) * ngon(8)));
  const double expected = 6 * (60 * 40 - 4 * (1 - kPi / 4) * 5.002 * 5.002) - frustum;
  const JobSimulation js = simulate_job(job, p.path, 0, p.path.duration_s());
  EXPECT_NEAR(js.result.removed_mm3, expected, 0.01 * expected);
  // The same pocket in the mesh's box takes longer: the core's air is not cut.
  const Job boxed = JobDocument::parse(pocket_job(keys), "boxed.toml")
                        .build({parse_override("stock.min=[-5, -15, -10]"),
                                parse_override("stock.max=[65, 55, 0]")});
  EXPECT_LT(p.path.duration_s(), plan_pocket(boxed).path.duration_s());

  // Refused, naming the key: a mesh above the top face, one beside the pocket, one below its
  // floor, a missing file, a mesh with a box, a mesh for a slot.
  auto refused = [&](const Mesh& m, const std::string& name, const std::string& extra = "") {
    write_mesh(dir / name, m);
    return test::message_of([&] {
      (void)plan_pocket(
          JobDocument::parse(pocket_job(keys, "[stock]\nmesh = \"" + name + "\"\n" + extra),
                             (dir / "bad.toml").string())
              .build());
    });
  };
  std::string m = refused(test::box_mesh({-5, -5, -10}, {65, 45, 1}), "high.stl");
  EXPECT_TRUE(has(m, "[stock] mesh: the stock's top z = 1 mm is above the top face z = 0")) << m;
  m = refused(test::box_mesh({100, -5, -10}, {165, 45, 0}), "beside.stl");
  EXPECT_TRUE(has(m,
                  "[stock] mesh: the mesh 'beside.stl' (x 100 .. 165, y -5 .. 45 mm, above "
                  "the floor z = -6 mm) leaves none of the pocket of layer 'RECT'"))
      << m;
  m = refused(test::box_mesh({-5, -5, -20}, {65, 45, -6}), "low.stl");
  EXPECT_TRUE(has(m, "[stock] mesh: the mesh's top z = -6 mm is at or below the pocket's floor"))
      << m;
  // Not a closed solid: a triangle missing (a hole in the surface), or every one turned
  // inwards. The planner's plan view and the kernel need a solid: refused when the job is read.
  Mesh holed = core;
  holed.triangles.pop_back();
  m = refused(holed, "holed.stl");
  EXPECT_TRUE(has(m, "[stock] mesh") && has(m, "holed.stl: the stock mesh is not a closed solid") &&
              has(m, "belongs to one triangle only"))
      << m;
  Mesh inside_out = core;
  for (auto& t : inside_out.triangles) std::swap(t[1], t[2]);
  m = refused(inside_out, "inside-out.stl");
  EXPECT_TRUE(has(m, "the stock mesh's triangles face inwards")) << m;
  m = refused(core, "core.stl", "min = [0, 0, -3]\nmax = [1, 1, 0]\n");
  EXPECT_TRUE(has(m, "[stock] mesh: give the stock as a box (min and max) or as a mesh, not both"))
      << m;
  m = test::message_of([&] {
    (void)JobDocument::parse(pocket_job(keys, "[stock]\nmesh = \"missing.stl\"\n"),
                             (dir / "missing.toml").string())
        .build();
  });
  EXPECT_TRUE(has(m, "[stock] mesh") && has(m, "missing.stl")) << m;
  m = test::message_of(
      [&] { (void)test::straight_job(10.0, 4, {parse_override("stock.mesh=\"cored.stl\"")}); });
  EXPECT_TRUE(has(m, "stock.mesh: is read by pocket jobs")) << m;
}

TEST(Pocket, TheCoredBlankExampleComesDownIntoItsCore) {
  // examples/pockets/cored.toml: the plate's pocket cut from a blank FreeCAD meshed
  // (make-blank.py: OpenCASCADE's solid, its own tessellation, 3 levels of its triangles
  // meeting at the core's rim) with a drafted round core at (36, 33), radius 10 mm at the top
  // face and 8 mm at its floor 4.5 mm down. The first level (z = -3) comes down into the core,
  // where the core's radius is 8 + 2 (4.5 - 3) / 4.5 = 8.667 mm: the tool's disc within it.
  const Job job = JobDocument::load(test::source_dir() / "examples/pockets/cored.toml").build();
  ASSERT_TRUE(job.stock_mesh);
  const PlannedPocket p = plan_pocket(job);
  const double r3 = 8 + 2 * (4.5 - 3) / 4.5;
  const auto& segs = p.path.segments();
  const auto first =
      std::find_if(segs.begin(), segs.end(), [](const Segment& g) { return g.end().z() < 0; });
  ASSERT_NE(first, segs.end());
  EXPECT_LE((first->end().head<2>() - Vec2(36, 33)).norm() + 5, r3) << first->end().transpose();
  EXPECT_EQ(p.info.plans, 2);
  // The air the first level's clearing covers: the disc of the core's radius at z = -3 less the
  // band of two teeth's advances (0.1 mm) the planner keeps as stock, on its 0.25 mm cells (the
  // 54 mm outline's cells fall either way: 3 %). Below the core, none.
  ASSERT_EQ(p.info.open_mm2_by_level.size(), 2u);
  const double air = kPi * std::pow(r3 - 0.1, 2);
  EXPECT_NEAR(p.info.open_mm2_by_level[0], air, 0.03 * air);
  EXPECT_EQ(p.info.open_mm2_by_level[1], 0);
  // Each level's own passes: the first sets out from the core, the second is the block's plan.
  // The figures of a level are the deepest's; the summary gives the passes level by level.
  ASSERT_EQ(p.info.passes_by_level.size(), 2u);
  ASSERT_EQ(p.info.clearing_length_by_level_mm.size(), 2u);
  EXPECT_EQ(p.info.passes_by_level[1], p.info.passes);
  EXPECT_EQ(p.info.clearing_length_by_level_mm[1], p.info.clearing_length_mm);
  EXPECT_NE(p.info.passes_by_level[0], p.info.passes_by_level[1]);
  // The core is air at the first level: its clearing is shorter.
  EXPECT_LT(p.info.clearing_length_by_level_mm[0], p.info.clearing_length_by_level_mm[1]);
  EXPECT_TRUE(has(pocket_summary(p.info, p.proof),
                  fmt::format("by level from the top {}, {} clearing passes",
                              p.info.passes_by_level[0], p.info.passes_by_level[1])));
  // The proof on the blank itself (the kernel's plan view of FreeCAD's triangles).
  EXPECT_LE(p.proof.clearing_max_engagement_deg, 53 * 1.02);
  EXPECT_GT(p.proof.clearing_max_engagement_deg, 45);
}

TEST(Pocket, NoRapidEntersTheStockOfAStepMesh) {
  // The example plate's pocket in a blank with a step: its top at z = 0 for x < 46 mm and at
  // -4 beyond (an L-shaped profile in x z, extruded along y). The levels' plans differ (the
  // first has air beyond the step), so a descent at a level comes down fast only where every
  // level above cleared the tool's disc (a helix start the first level left stock at once
  // came down 2 mm into it: 0.42 mm axial chips at a G0). The engagement kernel on the program,
  // on the same mesh: no sample of a rapid going down engages the stock.
  const std::filesystem::path dir = test::scratch_dir("pocket-step");
  const std::vector<std::array<double, 2>> xz = {{-5, -12}, {85, -12}, {85, -4},
                                                 {46, -4},  {46, 0},   {-5, 0}};
  Mesh m;
  for (const double y : {-5.0, 55.0}) {
    for (const auto& q : xz) m.vertices.push_back({q[0], y, q[1]});
  }
  const auto n = static_cast<std::uint32_t>(xz.size());
  // The two ends fanned from the profile's first corner, the sides joining them; turned
  // outwards (a positive volume).
  for (std::uint32_t k = 1; k + 1 < n; ++k) {
    m.triangles.push_back({0, k, k + 1});          // y = -5, facing -y
    m.triangles.push_back({n, n + k + 1, n + k});  // y = 55, facing +y
  }
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t a = k, b = (k + 1) % n;
    m.triangles.push_back({a, n + b, b});
    m.triangles.push_back({a, n + a, n + b});
  }
  ASSERT_NO_THROW(check_closed_mesh(m));
  write_mesh(dir / "step.stl", m);
  const Job job =
      JobDocument::load(test::source_dir() / "examples/pockets/plate.toml")
          .build({parse_override("stock.mesh=\"" + (dir / "step.stl").string() + "\"")});
  const PlannedPocket p = plan_pocket(job);
  EXPECT_GE(p.info.plans, 2);
  const EngagementSeries e = compute_engagement(p.path, job, EngagementOptions{});
  std::size_t rapid = 0;
  for (std::size_t i = 0; i < e.samples.size(); ++i) {
    // A rapid going down (a rapid up from a level leaves the frontier beside the tool, which
    // the kernel reads as an arc in the stock: not cut).
    if (p.path.segments()[e.samples.segment[i]].motion() != Motion::rapid ||
        !(e.samples.tz[i] < 0)) {
      continue;
    }
    ++rapid;
    EXPECT_EQ(e.engagement_angle_rad[i], 0.0)
        << e.samples.x_mm[i] << " " << e.samples.y_mm[i] << " " << e.samples.z_mm[i] << " seg "
        << e.samples.segment[i];
    EXPECT_EQ(e.axial_chip_mm[i], 0.0)
        << e.samples.x_mm[i] << " " << e.samples.y_mm[i] << " " << e.samples.z_mm[i];
  }
  EXPECT_GT(rapid, 50u);
}
