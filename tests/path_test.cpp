// Path model and planner: primitive lengths against closed forms and independent
// quadrature, arc-length inversion, curvature, sampling, tooth tracks with runout, the
// acceleration-limited time against the trapezoid formula, and for every family: continuity,
// advance per cycle, the tool staying in the slot and cutting it whole.
#include "trochomill/path.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// Independent reference: composite Simpson's rule on |p'(u)| with n intervals.
double simpson_length(const Segment& s, int n) {
  const double h = (s.u1() - s.u0()) / n;
  double sum = 0;
  for (int i = 0; i <= n; ++i) {
    const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    sum += w * s.derivative_u(s.u0() + h * i).norm();
  }
  return std::abs(h) / 3.0 * sum;
}

TEST(Segment, CircleAndHelixLengthsAreClosedForm) {
  const Segment arc = Segment::arc_xy(1, 2, 5.0, 0.3, -2.5, -1, -1, Motion::feed, 600);
  EXPECT_NEAR(arc.length_mm(), 5.0 * 2.5, 1e-12);  // r |sweep|
  EXPECT_TRUE(arc.is_circular());
  EXPECT_NEAR(arc.curvature_at(3.0), 1.0 / 5.0, 1e-12);
  // Helix: 3 turns of radius 2 dropping 6 mm: length = sqrt((2 pi r N)^2 + h^2).
  const Segment helix = Segment::arc_xy(0, 0, 2.0, 0, -3 * kTwoPi, 0, -6, Motion::feed, 600);
  EXPECT_NEAR(helix.length_mm(), std::hypot(3 * kTwoPi * 2.0, 6.0), 1e-12);
  EXPECT_NEAR((helix.end() - Vec3(2, 0, -6)).norm(), 0.0, 1e-12);
}

TEST(Segment, EllipsePerimeterMatchesCompleteEllipticIntegral) {
  // Perimeter = 4 a E(e), e = sqrt(1 - b^2/a^2): an independent closed form (std::comp_ellint_2).
  for (double ratio : {0.2, 0.5, 0.8, 1.2}) {
    const double a = 5.0, b = ratio * a;
    const Segment e = Segment::curve(Vec3::Zero(), Vec3(-a, 0, 0), Vec3(0, b, 0), Vec3::Zero(), 0,
                                     kTwoPi, Motion::feed, 600);
    const double major = std::max(a, b), minor = std::min(a, b);
    const double exact =
        4 * major * std::comp_ellint_2(std::sqrt(1 - minor * minor / (major * major)));
    // 5-point Gauss-Legendre on spans of 1/16 rad: error ~1e-14 relative for these smooth
    // integrands; 1e-10 mm leaves room for the library's own elliptic-integral accuracy.
    EXPECT_NEAR(e.length_mm(), exact, 1e-10) << "ratio " << ratio;
  }
}

TEST(Segment, TrochoidLengthMatchesSimpsonAndInverts) {
  // One Wagih cycle: a = 5, b = 4, s = 1 mm.
  const Segment t = Segment::curve(Vec3(0, 0, -6), Vec3(-5, 0, 0), Vec3(0, 4, 0),
                                   Vec3(0, 1.0 / kTwoPi, 0), 0, kTwoPi, Motion::feed, 600);
  // Simpson with 200000 intervals: error ~h^4 ~ 1e-19, far below the 1e-10 asserted.
  EXPECT_NEAR(t.length_mm(), simpson_length(t, 200000), 1e-10);
  // Arc-length inversion: the length from u0 to u(s) (by Simpson) equals s.
  for (double s : {0.0, 0.37, 5.0, 12.345, t.length_mm()}) {
    const double u = t.u_at_length(s);
    const Segment part =
        Segment::curve(t.center(), t.axis_a(), t.axis_b(), t.drift(), 0, u, Motion::feed, 600);
    EXPECT_NEAR(part.length_mm(), s, 1e-9) << s;
  }
  // Curvature at u = pi/2 (front vertex: p' = (a, s/2pi), p'' = (0, -b)) against |p' x p''| /
  // |p'|^3.
  const Vec3 d1(5, 1.0 / kTwoPi, 0), d2(0, -4, 0);
  const double u = kPi / 2;
  const Segment upto =
      Segment::curve(t.center(), t.axis_a(), t.axis_b(), t.drift(), 0, u, Motion::feed, 600);
  EXPECT_NEAR(t.curvature_at(upto.length_mm()), d1.cross(d2).norm() / std::pow(d1.norm(), 3), 1e-9);
}

TEST(Sampling, CountsTimesAndTangents) {
  ToolPath p;
  p.append(Segment::line(Vec3(0, 0, 0), Vec3(0, 10, 0), Motion::feed, 600));  // 1 s
  p.append(Segment::arc_xy(5, 10, 5, kPi, -kPi, 0, 0, Motion::feed, 600));    // 5 pi mm
  EXPECT_NEAR(p.duration_s(), 1.0 + 5 * kPi / 10.0, 1e-12);
  const PathSamples s = sample_by_time(p, 0.01);
  EXPECT_EQ(s.size(), static_cast<std::size_t>(std::floor(p.duration_s() / 0.01)) + 2);
  EXPECT_NEAR(s.t_s.back(), p.duration_s(), 1e-12);
  EXPECT_NEAR(s.x_mm.back(), 10.0, 1e-12);
  for (std::size_t i = 0; i < s.size(); ++i) {
    EXPECT_NEAR(std::hypot(s.tx[i], s.ty[i]), 1.0, 1e-12);
    if (s.t_s[i] > 1.0 + 1e-9) {
      EXPECT_NEAR(s.curvature_per_mm[i], 0.2, 1e-12);
    }
  }
  // Tangent continuity at the junction: line +y, arc starting at (0,10) clockwise: +y.
  EXPECT_NEAR(p.segments()[1].tangent_at(0).y(), 1.0, 1e-12);
  const PathSamples by_len = sample_by_length(p, 0.5);
  for (std::size_t i = 1; i + 1 < by_len.size(); ++i) {
    EXPECT_NEAR(by_len.s_mm[i] - by_len.s_mm[i - 1], 0.5, 1e-12);
  }
  // By spindle angle: dt = 60 / (n N).
  const PathSamples sa = sample_by_spindle_angle(p, 60, 2000);
  EXPECT_NEAR(sa.t_s[1] - sa.t_s[0], 60.0 / (2000 * 60), 1e-15);
  EXPECT_THROW((void)sample_by_time(p, 0.0), InputError);
  EXPECT_THROW((void)sample_by_time(p, 1e-12), InputError);  // too many samples
  EXPECT_THROW((void)sample_by_spindle_angle(p, 0, 2000), InputError);
}

TEST(Sampling, ToothTracksWithRunout) {
  Job job = test::wagih_job("elliptical");
  ToolPath p;
  p.append(Segment::line(Vec3(0, 0, -6), Vec3(0, 10, -6), Motion::feed, 600));
  const PathSamples s = sample_by_spindle_angle(p, 360, 2000);
  // No runout: every tip at R from the centre, teeth 90 degrees apart, turning clockwise.
  ToothTracks tr = tooth_tracks(s, job.tool, job.cutting);
  for (std::size_t i = 0; i + 1 < s.size(); i += 97) {
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(std::hypot(tr.x_mm[k][i] - s.x_mm[i], tr.y_mm[k][i] - s.y_mm[i]), 5.0, 1e-12);
    }
    const double a0 = std::atan2(tr.y_mm[0][i] - s.y_mm[i], tr.x_mm[0][i] - s.x_mm[i]);
    const double a1 = std::atan2(tr.y_mm[1][i] - s.y_mm[i], tr.x_mm[1][i] - s.x_mm[i]);
    EXPECT_NEAR(std::remainder(a1 - a0 - kPi / 2, kTwoPi), 0.0, 1e-12);
    // Clockwise: the angle of tooth 0 decreases by 1 degree per sample.
    const double b0 =
        std::atan2(tr.y_mm[0][i + 1] - s.y_mm[i + 1], tr.x_mm[0][i + 1] - s.x_mm[i + 1]);
    EXPECT_NEAR(std::remainder(b0 - a0 + deg_to_rad(1.0), kTwoPi), 0.0, 1e-12);
  }
  // Radial runout e at phase lambda: tooth radius |R u(alpha) + e u(lambda)|, which is
  // R + e cos(alpha - lambda) to within e^2 / (2R).
  job.tool.runout_radial_mm = 0.013;
  job.tool.runout_phase_deg = 30;
  job.tool.runout_axial_mm = 0.005;
  tr = tooth_tracks(s, job.tool, job.cutting);
  for (int k = 0; k < 4; ++k) {
    const double rk = tooth_radius_mm(job.tool, k);
    EXPECT_NEAR(rk, 5.0 + 0.013 * std::cos(deg_to_rad(90.0 * k - 30)), 0.013 * 0.013 / 10 + 1e-15);
    EXPECT_NEAR(std::hypot(tr.x_mm[k][100] - s.x_mm[100] -
                               0.013 * std::cos(tr.spindle_angle_rad[100] + deg_to_rad(30)),
                           tr.y_mm[k][100] - s.y_mm[100] -
                               0.013 * std::sin(tr.spindle_angle_rad[100] + deg_to_rad(30))),
                5.0, 1e-12);
    // Tip distance from the spindle axis (the path centre) is the tooth radius.
    EXPECT_NEAR(std::hypot(tr.x_mm[k][100] - s.x_mm[100], tr.y_mm[k][100] - s.y_mm[100]), rk,
                1e-12);
    EXPECT_NEAR(tr.z_mm[k][0], -6 - 0.005 * std::cos(deg_to_rad(90.0 * k - 30)), 1e-15);
  }
}

TEST(Timing, AccelerationLimitMatchesTrapezoidFormula) {
  Machine m;
  m.max_acceleration_mm_per_s2 = 500;
  ToolPath p;
  p.append(Segment::line(Vec3(0, 0, 0), Vec3(100, 0, 0), Motion::feed, 3000));  // 50 mm/s
  // Trapezoid from rest to rest: t = L / v + v / a = 2 + 0.1 s. Each piece runs the exact
  // accelerate-cruise-brake profile, so only rounding remains.
  EXPECT_NEAR(estimate_time_s(p, m), 100.0 / 50 + 50.0 / 500, 1e-9);
  ToolPath q;
  q.append(Segment::line(Vec3(0, 0, 0), Vec3(1, 0, 0), Motion::feed, 3000));
  // Triangle: the top speed sqrt(a L) = 22.4 < 50 mm/s, t = 2 sqrt(L / a).
  EXPECT_NEAR(estimate_time_s(q, m), 2 * std::sqrt(1.0 / 500), 1e-9);
  m.max_acceleration_mm_per_s2 = 0;
  EXPECT_EQ(estimate_time_s(p, m), p.duration_s());
}

// Counts are checked before they are converted or used: a step tiny against a long slot is
// refused by its cycle count (it overflowed an int and printed -2147483647 cycles); a tiny
// step on a short slot plans, with about L / s cycles (the envelope's columns stay clear of
// its own sampling error, which had shown islands at the walls).
TEST(Planner, CycleCountsAreCheckedAndTinyStepsPlan) {
  try {
    (void)plan_path(
        test::wagih_job("trochoidal", {{"slot.length", "1e5", {}}, {"path.step", "0.001", {}}}));
    ADD_FAILURE() << "1e8 cycles were planned";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1e+08 cycles or passes (limit 1e+07)"), std::string::npos)
        << e.what();
  }
  const PlannedPath p = plan_path(test::wagih_job("trochoidal", {{"path.step", "0.01", {}}}));
  // The cycles advance over the slot's 20 mm, less the tool's own reach ahead (2R = 10 mm) at
  // the least, plus the orbit's reach before and after (2 (a + b + R) = 30 mm) at the most.
  EXPECT_GE(p.info.cycles * 0.01, 20.0 - 10.0);
  EXPECT_LE(p.info.cycles * 0.01, 20.0 + 30.0);
}

// Narrow ellipses plan, and their program cuts the whole slot: on the path sampled every
// 5 um (the sampled discs then fall short of the swept region by under ds^2 / 8 (kappa +
// 1 / R) = 3e-6 mm here, kappa <= 0.8 / mm), every column of the slot from the wall band
// inward is covered from y = 0 to L. The band is the scallop bound R - sqrt(R^2 - s^2 / 4)
// plus 1 um (a hundredfold the sampling shortfall). The planner's own check, on one cycle's
// centres spaced without regard to the orbit's curvature, had refused these with "uncut
// islands" at the walls, where the orbit turns on a radius of b^2 / a = 1.25 mm.
TEST(Planner, NarrowEllipsesPlanAndCutTheWholeSlot) {
  for (const char* aspect : {"0.5", "0.3"}) {
    for (const char* step : {"0.1", "0.3"}) {
      const Job job = test::wagih_job("elliptical",
                                      {{"path.aspect_ratio", aspect, {}}, {"path.step", step, {}}});
      const PlannedPath p = plan_path(job);
      const double R = job.tool.radius_mm(), W = job.slot.width_mm, L = job.slot.length_mm;
      const double s = std::stod(step);
      const double band = R - std::sqrt(R * R - 0.25 * s * s) + 1e-3;
      const PathSamples ps = sample_by_length(p.path, 0.005);
      const int nx = 200;
      std::vector<std::vector<std::pair<double, double>>> cols(nx + 1);
      const double x0 = -0.5 * W + band, dx = (W - 2 * band) / nx;
      for (std::size_t i = 0; i < ps.size(); ++i) {
        if (ps.z_mm[i] > -job.slot.depth_mm + 1e-9) continue;  // cutting at the slot's floor
        for (int j = 0; j <= nx; ++j) {
          const double x = x0 + dx * j, d = x - ps.x_mm[i];
          if (std::abs(d) >= R) continue;
          const double h = std::sqrt(R * R - d * d);
          auto& c = cols[static_cast<std::size_t>(j)];
          if (!c.empty() && ps.y_mm[i] - h <= c.back().second && ps.y_mm[i] + h >= c.back().first) {
            c.back().first = std::min(c.back().first, ps.y_mm[i] - h);
            c.back().second = std::max(c.back().second, ps.y_mm[i] + h);
          } else {
            c.emplace_back(ps.y_mm[i] - h, ps.y_mm[i] + h);
          }
        }
      }
      for (int j = 0; j <= nx; ++j) {
        auto& c = cols[static_cast<std::size_t>(j)];
        std::sort(c.begin(), c.end());
        double reach = 0;  // covered from y = 0 up to here
        for (const auto& [a, b] : c) {
          if (a > reach) break;
          reach = std::max(reach, b);
        }
        EXPECT_GE(reach, L) << "aspect " << aspect << ", step " << step << ": x = " << x0 + dx * j
                            << " is cut only up to y = " << reach;
      }
    }
  }
}

// A machine that accelerates without limit takes the programmed time: on a whole planned
// program (reversals, rapids, starts and stops) the limited time tends to it as a grows. The
// excess is the sum of v / a over the stops (about 1e-9 s at 1e12 mm/s^2).
TEST(Timing, UnboundedAccelerationGivesTheProgrammedTime) {
  const Job job = test::wagih_job("elliptical");
  const ToolPath p = plan_path(job).path;
  Machine m = job.machine;
  double previous = 1e300;
  for (const double a : {1e3, 1e6, 1e12}) {
    m.max_acceleration_mm_per_s2 = a;
    const double t = estimate_time_s(p, m);
    EXPECT_GE(t, p.duration_s() * (1 - 1e-12)) << a;
    EXPECT_LE(t, previous) << a;  // a faster machine is never slower
    previous = t;
  }
  EXPECT_NEAR(previous, p.duration_s(), 1e-6 * p.duration_s());
}

// ---- planned families -------------------------------------------------------------------

struct FamilyCase {
  std::string type;
  std::vector<std::string> sets;
};

std::vector<FamilyCase> family_cases() {
  std::vector<FamilyCase> out;
  for (const std::string dir : {"climb", "conventional"}) {
    for (const std::string entry : {"outside", "helix", "ramp", "plunge"}) {
      const std::vector<std::string> base = {"path.direction=" + dir, "path.entry=" + entry};
      out.push_back({"trochoidal", base});
      if (entry != "helix") out.push_back({"linear", base});
      // A wide slot (a = 17 > R = 8, Bergmann's geometry) exercises the interior of the
      // closed-start clean-up.
      auto wide = base;
      wide.insert(wide.end(), {"tool.diameter=16", "slot.width=50", "slot.length=30"});
      out.push_back({"trochoidal", wide});
      out.push_back({"circular", base});
      for (const std::string re : {"0.5", "0.8", "1.2"}) {
        auto s = base;
        s.push_back("path.aspect_ratio=" + re);
        out.push_back({"elliptical", s});
        for (const std::string d : {"0.5", "1", "1.25"}) {
          auto t = s;
          t.push_back("path.linear_distance=" + d);
          out.push_back({"linear-elliptical", t});
        }
      }
    }
  }
  return out;
}

Job make(const FamilyCase& c) {
  std::vector<Override> ov;
  for (const auto& s : c.sets) ov.push_back(parse_override(s));
  return test::wagih_job(c.type, ov);
}

std::string name(const FamilyCase& c) {
  std::string n = c.type;
  for (const auto& s : c.sets) n += " " + s;
  return n;
}

// All five families are tangent-continuous within their cycles; the linear family's passes
// are joined by retracts.
bool smooth_family(const std::string& type) { return type != "linear"; }

TEST(Planner, EveryFamilyIsContinuousAndAdvancesOneStepPerCycle) {
  for (const auto& c : family_cases()) {
    const Job job = make(c);
    const PlannedPath pp = plan_path(job);
    const auto& segs = pp.path.segments();
    ASSERT_GE(pp.path.cycles().size(), 2u) << name(c);
    // Position continuity at every junction (append enforces 1e-9; check it held).
    for (std::size_t i = 1; i < segs.size(); ++i) {
      ASSERT_LE((segs[i].start() - segs[i - 1].end()).norm(), 1e-9) << name(c) << " at " << i;
    }
    const auto& cyc = pp.path.cycles();
    if (c.type == "linear") {
      // Passes are evenly spaced in x (climb from +a to -a, conventional mirrored).
      for (std::size_t k = 2; k < cyc.size(); ++k) {
        const double d1 =
            segs[cyc[k].first_segment].start().x() - segs[cyc[k - 1].first_segment].start().x();
        const double d0 =
            segs[cyc[k - 1].first_segment].start().x() - segs[cyc[k - 2].first_segment].start().x();
        EXPECT_NEAR(d1, d0, 1e-12) << name(c);
      }
      continue;
    }
    // Tangent continuity inside the cycles: every cycle has as many segments as the one
    // before, so the last one ends where that count says.
    const std::size_t per_cycle = cyc[1].first_segment - cyc[0].first_segment;
    const std::size_t end = cyc.back().first_segment + per_cycle;
    ASSERT_LE(end, segs.size());
    for (std::size_t i = cyc.front().first_segment + 1; i < end; ++i) {
      const Vec3 t0 = segs[i - 1].tangent_at(segs[i - 1].length_mm()), t1 = segs[i].tangent_at(0);
      if (smooth_family(c.type)) {
        EXPECT_LE((t0 - t1).norm(), 1e-9) << name(c) << " tangent jump at segment " << i;
      }
    }
    // The entry arrives along the first cycle's start tangent (outside approach, helix).
    if (job.path.entry == EntryType::outside || job.path.entry == EntryType::helix) {
      const std::size_t f = cyc.front().first_segment;
      EXPECT_LE((segs[f - 1].tangent_at(segs[f - 1].length_mm()) - segs[f].tangent_at(0)).norm(),
                1e-9)
          << name(c);
    }
    // Advance per cycle: consecutive cycle starts differ by exactly (0, s, 0).
    for (std::size_t k = 1; k < cyc.size(); ++k) {
      const Vec3 d = segs[cyc[k].first_segment].start() - segs[cyc[k - 1].first_segment].start();
      EXPECT_NEAR(d.x(), 0.0, 1e-12) << name(c);
      EXPECT_NEAR(d.y(), job.path.step_mm, 1e-12) << name(c);
      EXPECT_NEAR(d.z(), 0.0, 1e-12) << name(c);
    }
  }
}

TEST(Planner, CycleLengthsAgreeBetweenFamilies) {
  // Circular: a circle of radius a plus the advance s, exactly.
  const PlannedPath circ = plan_path(test::wagih_job("circular"));
  EXPECT_NEAR(circ.info.cycle_length_mm, kTwoPi * 5 + 1.0, 1e-12);
  // Linear-elliptical = elliptical + 2 d (the half-ellipses are the same curves).
  const PlannedPath ell =
      plan_path(test::wagih_job("elliptical", {parse_override("path.aspect_ratio=0.8")}));
  const PlannedPath le =
      plan_path(test::wagih_job("linear-elliptical", {parse_override("path.aspect_ratio=0.8"),
                                                      parse_override("path.linear_distance=1")}));
  EXPECT_NEAR(le.info.cycle_length_mm, ell.info.cycle_length_mm + 2.0, 1e-9);
  // Trochoidal is elliptical with r_e = 1: the same points.
  const PlannedPath tro = plan_path(test::wagih_job("trochoidal"));
  const PlannedPath e1 =
      plan_path(test::wagih_job("elliptical", {parse_override("path.aspect_ratio=1")}));
  ASSERT_EQ(tro.path.segments().size(), e1.path.segments().size());
  EXPECT_NEAR(tro.path.length_mm(), e1.path.length_mm(), 1e-12);
  // Machining time at programmed feed = feed-move length / feed + rapid length / rapid rate.
  double t = 0;
  for (const auto& s : tro.path.segments()) t += s.length_mm() / (s.speed_mm_per_min() / 60);
  EXPECT_NEAR(tro.path.duration_s(), t, 1e-9);
}

TEST(Planner, ConventionalMirrorsClimbAndOrbitsTheOtherWay) {
  const PlannedPath climb = plan_path(test::wagih_job("elliptical"));
  const PlannedPath conv =
      plan_path(test::wagih_job("elliptical", {parse_override("path.direction=conventional")}));
  const PathSamples a = sample_by_length(climb.path, 0.5), b = sample_by_length(conv.path, 0.5);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a.x_mm[i], -b.x_mm[i], 1e-12);
    EXPECT_NEAR(a.y_mm[i], b.y_mm[i], 1e-12);
  }
  // Signed area swept by the centre over one cycle (shoelace): climb with a cw spindle orbits
  // counter-clockwise (> 0: the material outside the orbit on the tool's right, docs/models.md
  // section 2; Engagement.ClimbPutsTheMaterialOnTheToolsRight checks it on the kernel).
  auto area = [](const PlannedPath& p) {
    const auto& seg = p.path.segments()[p.path.cycles()[3].first_segment];
    double A = 0;
    const int n = 2000;
    for (int i = 0; i < n; ++i) {
      const Vec3 p0 = seg.point_u(seg.u0() + (seg.u1() - seg.u0()) * i / n);
      const Vec3 p1 = seg.point_u(seg.u0() + (seg.u1() - seg.u0()) * (i + 1) / n);
      A += 0.5 * (p0.x() * p1.y() - p1.x() * p0.y());
    }
    return A;
  };
  EXPECT_GT(area(climb), 0);
  EXPECT_LT(area(conv), 0);
  // A ccw spindle with climb milling mirrors too.
  const PlannedPath ccw =
      plan_path(test::wagih_job("elliptical", {parse_override("cutting.spindle_direction=ccw")}));
  EXPECT_LT(area(ccw), 0);
}

// The tool never leaves the slot: |x| + R <= W/2 and, with a closed start, y - R >= 0.
// The whole slot is cut: every point of |x| <= W/2 - delta, y_from <= y <= L lies within R of
// the tool centre at depth, delta = R - sqrt(R^2 - (s/2)^2) being the wall-scallop bound of
// tool circles (radius >= R) touching the wall every s. Samples every ds = 0.05 mm plus every
// segment end point.
TEST(Planner, ToolStaysInsideAndCutsTheWholeSlot) {
  for (const auto& c : family_cases()) {
    const Job job = make(c);
    const PlannedPath pp = plan_path(job);
    const double R = job.tool.radius_mm(), W = job.slot.width_mm, L = job.slot.length_mm;
    const double zf = -job.slot.depth_mm, s = job.path.step_mm;
    const double ds = 0.05;
    PathSamples smp = sample_by_length(pp.path, ds);
    // Path corners are not on the arc-length grid: add every segment's end points.
    for (const auto& seg : pp.path.segments()) {
      for (const Vec3& p : {seg.start(), seg.end()}) {
        smp.x_mm.push_back(p.x());
        smp.y_mm.push_back(p.y());
        smp.z_mm.push_back(p.z());
      }
    }
    std::map<long, std::vector<std::size_t>> bins;  // 1 mm bins in y of samples at depth
    for (std::size_t i = 0; i < smp.x_mm.size(); ++i) {
      ASSERT_LE(std::abs(smp.x_mm[i]) + R, W / 2 + 1e-9) << name(c) << " leaves the slot in x";
      if (pp.info.closed_start && smp.z_mm[i] < 0) {
        ASSERT_GE(smp.y_mm[i] - R, -1e-9) << name(c) << " cuts behind a closed start";
      }
      if (smp.z_mm[i] <= zf + 1e-9) bins[static_cast<long>(std::floor(smp.y_mm[i]))].push_back(i);
    }
    const double delta = R - std::sqrt(R * R - s * s / 4);
    // Sampled discs miss at most ds^2 / 8R of a continuous sweep; twice that keeps points
    // exactly on a straight sweep's edge (y = 0 under the end clean-up) from flickering.
    const double reach = R + ds * ds / (4 * R);
    // A closed start (helix/ramp/plunge inside the material) keeps only the corner fillets
    // of radius R a round tool cannot cut: points with y < R and |x| > W/2 - R farther than R
    // from the fillet centre (+-(W/2 - R), R) are not asserted.
    const double a_f = W / 2 - R;
    auto in_fillet = [&](double x, double y) {
      return pp.info.closed_start && y < R && std::abs(x) > a_f &&
             std::hypot(std::abs(x) - a_f, y - R) > R - 1e-9;
    };
    const double y_from = 0.0;
    int uncovered = 0;
    std::string first;
    const int nx = 81;
    for (int ix = 0; ix < nx; ++ix) {
      const double x = -W / 2 + delta + (W - 2 * delta) * ix / (nx - 1);
      for (double y = y_from; y <= L + 1e-9; y += 0.1) {
        bool hit = in_fillet(x, y);
        for (long b = static_cast<long>(std::floor(y - R)) - 1;
             b <= static_cast<long>(std::floor(y + R)) && !hit; ++b) {
          const auto it = bins.find(b);
          if (it == bins.end()) continue;
          for (std::size_t i : it->second) {
            if (std::hypot(smp.x_mm[i] - x, smp.y_mm[i] - y) <= reach) {
              hit = true;
              break;
            }
          }
        }
        if (!hit && uncovered++ == 0)
          first = "(" + std::to_string(x) + ", " + std::to_string(y) + ")";
      }
    }
    EXPECT_EQ(uncovered, 0) << name(c) << ": first uncovered point " << first;
  }
}

TEST(Planner, EntriesDescendAsSpecified) {
  // Helix: descends entry_pitch per turn.
  const Job hj = test::wagih_job(
      "elliptical", {parse_override("path.entry=helix"), parse_override("path.entry_pitch=0.5")});
  const PlannedPath hp = plan_path(hj);
  bool found = false;
  for (const auto& seg : hp.path.segments()) {
    if (seg.kind() == Segment::Kind::curve && seg.is_circular() && std::abs(seg.drift().z()) > 0) {
      // dz per radian = -pitch / 2 pi with the cw sweep (u decreasing): drift.z = pitch / 2 pi.
      EXPECT_NEAR(std::abs(seg.drift().z()) * kTwoPi, 0.5, 1e-12);
      found = true;
    }
  }
  EXPECT_TRUE(found);
  // Ramp: no leg steeper than the entry angle.
  const Job rj = test::wagih_job(
      "elliptical", {parse_override("path.entry=ramp"), parse_override("path.entry_angle=5")});
  const PlannedPath rp = plan_path(rj);
  int legs = 0;
  for (const auto& seg : rp.path.segments()) {
    if (seg.kind() != Segment::Kind::line || seg.motion() != Motion::feed) continue;
    const Vec3 d = seg.end() - seg.start();
    if (d.z() < 0 && std::hypot(d.x(), d.y()) > 0) {
      ++legs;
      EXPECT_LE(std::atan2(-d.z(), std::hypot(d.x(), d.y())), deg_to_rad(5.0) + 1e-12);
    }
  }
  // 7 mm drop (1 mm clearance + 6 mm) over legs of 2a = 10 mm at 5 deg: ceil(7 / 0.8749) = 9.
  EXPECT_EQ(legs, 9);
  // A helix that does not fit is refused with the largest radius that does.
  EXPECT_THROW(
      (void)plan_path(test::wagih_job("elliptical", {parse_override("path.entry=helix"),
                                                     parse_override("path.entry_radius=4.5")})),
      InputError);
}

TEST(Planner, LinearSlotPasses) {
  // Full-width slot (W = D): a single pass along x = 0 from outside to past the end.
  std::vector<Override> ov = {parse_override("slot.width=10")};
  const PlannedPath one = plan_path(test::wagih_job("linear", ov));
  EXPECT_EQ(one.info.cycles, 1);
  // Feed length: down 7 mm outside (1 mm clearance + 6) at entry feed, then y from -6 to
  // 20 + 5 + 1 = 26: 32 mm.
  EXPECT_NEAR(one.path.feed_length_mm(), 7 + 32, 1e-12);
  // W = 20, step 1 mm: ceil(10 / 1) + 1 = 11 passes from x = -5 to x = +5 (climb: each pass
  // along +y with the next one's material on its right).
  const PlannedPath wide = plan_path(test::wagih_job("linear"));
  EXPECT_EQ(wide.info.cycles, 11);
  const auto& segs = wide.path.segments();
  EXPECT_NEAR(segs[wide.path.cycles().front().first_segment].start().x(), -5.0, 1e-12);
  EXPECT_NEAR(segs[wide.path.cycles().back().first_segment].start().x(), 5.0, 1e-12);
}

}  // namespace
}  // namespace trochomill
