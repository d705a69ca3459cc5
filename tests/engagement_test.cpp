// Engagement kernel: closed forms for straight full and partial immersion, and a
// brute-force reference (every earlier disc tested directly, no boundary structure) on
// trochoidal cases, for the engaged angle and h_max.
#include "trochomill/engagement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/job.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// Straight full-immersion slot (W = D): the engaged arc is the front half circle plus the
// slivers the previous disc leaves at the walls, pi + 2 asin(f_z / 2R) in the disc model
// (the continuous sweep gives pi; the difference is f_z / R), and h_max = f_z exactly
// (straight ahead the previous circle is f_z behind; the kernel's h_max is exact, so only
// rounding remains).
TEST(Engagement, StraightFullImmersion) {
  const Job job = test::straight_job(10.0);
  const double fz = job.cutting.feed_per_tooth_mm, R = 5.0;
  ToolPath p;
  p.append(Segment::line(Vec3(0, -10, -6), Vec3(0, 30, -6), Motion::feed, 600));
  const EngagementSeries e = compute_engagement(p, job);
  ASSERT_GT(e.samples.size(), 400u);
  int checked = 0;
  for (std::size_t i = 0; i < e.samples.size(); ++i) {
    const double y = e.samples.y_mm[i];
    if (y < 10 || y > 25) continue;  // steady state, away from the slot ends
    ++checked;
    EXPECT_NEAR(e.engagement_angle_rad[i], kPi + 2 * std::asin(fz / (2 * R)), 1e-9) << y;
    EXPECT_NEAR(e.h_max_mm[i], fz, 1e-12) << y;
    EXPECT_NEAR(e.h_max_angle_rad[i], kPi / 2, deg_to_rad(0.25));
    ASSERT_EQ(e.arcs[i].size(), 1u);
  }
  EXPECT_EQ(checked, 200);  // 15 mm at f_z = 0.075 mm
  // Teeth in cut: sampled 7 times per tooth pass (28 spindle phases per revolution, 12.86 deg
  // apart) the mean count over whole revolutions is Z psi / 2 pi to within the phases that
  // fall on the two arc ends: 2 * Z / 28 = 0.29 for Z = 4.
  EngagementOptions fine;
  fine.steps_per_tooth = 7;
  ToolPath shorter;  // 20 revolutions (6 mm) in steady state after entering the stock
  shorter.append(Segment::line(Vec3(0, -5.5, -6), Vec3(0, 12.5, -6), Motion::feed, 600));
  const EngagementSeries f = compute_engagement(shorter, job, fine);
  double teeth_sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < f.samples.size(); ++i) {
    if (f.samples.y_mm[i] < 6 || n >= 28 * 20) continue;  // 20 whole revolutions
    teeth_sum += f.teeth_in_cut[i];
    ++n;
  }
  EXPECT_NEAR(teeth_sum / n, 4 * (kPi + 2 * std::asin(fz / (2 * R))) / kTwoPi, 2.0 * 4 / 28);
  // Entering the stock at y = 0 from outside: no engagement before the tool reaches it.
  for (std::size_t i = 0; i < e.samples.size(); ++i) {
    if (e.samples.y_mm[i] < -R - 1e-9) {
      EXPECT_EQ(e.engagement_angle_rad[i], 0.0);
    }
  }
}

// Straight partial immersion a_e on one side: engagement angle acos(1 - a_e / R) (plus the
// wall sliver asin(f_z / 2R) of the disc model), h(phi) = f_z sin(phi) to within f_z^2 / R.
TEST(Engagement, StraightPartialImmersion) {
  for (const double ae : {0.5, 1.0, 2.5, 5.0}) {
    const Job job = test::straight_job(20.0);
    const double fz = job.cutting.feed_per_tooth_mm, R = 5.0;
    const double x0 = 10.0 + R - ae;  // the tool overlaps the stock |x| <= 10 by a_e
    ToolPath p;
    p.append(Segment::line(Vec3(x0, -10, -6), Vec3(x0, 30, -6), Motion::feed, 600));
    const EngagementSeries e = compute_engagement(p, job);
    const double psi = std::acos(1 - ae / R);
    for (std::size_t i = 0; i < e.samples.size(); ++i) {
      const double y = e.samples.y_mm[i];
      if (y < 10 || y > 25) continue;
      EXPECT_NEAR(e.engagement_angle_rad[i], psi + std::asin(fz / (2 * R)), 1e-9) << ae;
      // The chip is thickest where the arc starts (phi = pi - psi from +X, the feed-normal
      // angle psi): f_z sin(psi), with the disc model's second-order term below f_z^2 / R.
      EXPECT_NEAR(e.h_max_mm[i], fz * std::sin(std::min(psi, kPi / 2)), fz * fz / R) << ae;
    }
  }
}

// Brute force: the circle point at angle th is engaged iff it is in the slot rectangle and
// farther than R from every earlier centre (up to i - m) in the material. h at th: the ray
// from the centre leaves the last earlier disc at max(t + sq) below R.
struct Brute {
  double angle = 0, hmax = 0;
};
// The chip thickness at angle th of sample i's circle, or -1 where that point is not engaged.
double h_at(const PathSamples& s, std::size_t i, int m, double R, double hw, double L, double th) {
  const double cx = s.x_mm[i], cy = s.y_mm[i];
  const double px = cx + R * std::cos(th), py = cy + R * std::sin(th);
  if (std::abs(px) > hw || py < 0 || py > L) return -1;
  double rho = 0;
  const double ux = std::cos(th), uy = std::sin(th);
  for (std::size_t j = 0; j + m <= i; ++j) {
    if (s.z_mm[j] >= 0) continue;
    const double ox = s.x_mm[j] - cx, oy = s.y_mm[j] - cy;
    if (std::hypot(px - s.x_mm[j], py - s.y_mm[j]) <= R) return -1;
    const double t = ox * ux + oy * uy, q = R * R - (ox * ox + oy * oy - t * t);
    if (q >= 0 && t + std::sqrt(q) < R) rho = std::max(rho, t + std::sqrt(q));
  }
  return R - rho;
}

Brute brute(const PathSamples& s, std::size_t i, int m, double R, double hw, double L, int npts) {
  Brute b;
  int in = 0;
  for (int k = 0; k < npts; ++k) {
    const double h = h_at(s, i, m, R, hw, L, kTwoPi * (k + 0.5) / npts);
    if (h >= 0) {
      ++in;
      b.hmax = std::max(b.hmax, h);
    }
  }
  b.angle = kTwoPi * in / npts;
  return b;
}

TEST(Engagement, MatchesBruteForceOnTrochoids) {
  // circular: W = 2D puts every orbit's centre on all its discs' circles (a degenerate
  // vertex the kernel must survive), and its straight legs run along the walls.
  for (const std::string type : {"trochoidal", "circular", "elliptical", "linear-elliptical"}) {
    for (const int m : {1, 3}) {
      if (m == 3 && type != "elliptical") continue;  // brute force is O(n^2): keep it short
      const Job job = test::wagih_job(
          type, {parse_override("slot.length=4"), parse_override("path.linear_distance=1")});
      const PlannedPath pp = plan_path(job);
      EngagementOptions opt;
      opt.steps_per_tooth = m;
      const EngagementSeries e = compute_engagement(pp.path, job, opt);
      const int npts = 3600;  // 0.1 deg per point
      int compared = 0;
      for (std::size_t i = 0; i < e.samples.size(); i += 11) {
        if (e.samples.z_mm[i] >= 0) continue;
        const Brute b = brute(e.samples, i, m, 5.0, 10.0, 4.0, npts);
        if (b.angle == 0) {
          // No brute-force point is engaged: any arc the kernel finds is narrower than two
          // point spacings. Such an arc can nick the tip of a spike of material left where
          // two earlier discs meet at a small angle (the linear-elliptical passes leave one
          // on the centre line): a few um thick, a few nm wide, so points at any practical
          // spacing miss its top. There the kernel's h_max is checked where it says it is:
          // the brute force's own chip thickness at the kernel's angle (rounding only:
          // 1e-9 mm), and no point of a 20 times finer brute force (0.005 deg) is thicker.
          EXPECT_LE(e.engagement_angle_rad[i], 2 * kTwoPi / npts) << type << " sample " << i;
          if (e.h_max_mm[i] > 0) {
            EXPECT_NEAR(h_at(e.samples, i, m, 5.0, 10.0, 4.0, e.h_max_angle_rad[i]), e.h_max_mm[i],
                        1e-9)
                << type << " sample " << i;
            EXPECT_LE(brute(e.samples, i, m, 5.0, 10.0, 4.0, 20 * npts).hmax, e.h_max_mm[i] + 1e-9)
                << type << " sample " << i;
          }
          continue;
        }
        // Point sampling resolves each arc end to half a point: 2 ends per arc, a few arcs.
        EXPECT_NEAR(e.engagement_angle_rad[i], b.angle, 4 * kTwoPi / npts)
            << type << " m=" << m << " sample " << i;
        // h_max: the kernel's is exact; the brute force samples every 0.1 deg and misses
        // the maximum by up to half a spacing times the slope of h, which is about f_z per
        // radian (h ~ f_z sin phi) but steeper where the arc meets the previous cycle's
        // surface (Wagih's points B, D): 0.25 deg of f_z = 3.3e-4 mm covers both.
        EXPECT_NEAR(e.h_max_mm[i], b.hmax, 0.075 * deg_to_rad(0.25))
            << type << " m=" << m << " sample " << i;
        ++compared;
      }
      EXPECT_GT(compared, 30) << type;
    }
  }
}

TEST(Engagement, RejectsBadOptions) {
  const Job job = test::straight_job(10.0);
  ToolPath p;
  p.append(Segment::line(Vec3(0, -10, -6), Vec3(0, 30, -6), Motion::feed, 600));
  EngagementOptions o;
  o.steps_per_tooth = 0;
  EXPECT_THROW((void)compute_engagement(p, job, o), InputError);
}

// Climb milling with a clockwise (M3) spindle keeps the material on the tool's right: the tooth
// sweeps from the tool's left through its front to its right, so it enters material on the
// right at the thickest chip (down milling) and material on the left at zero (up milling).
// Measured here on what the kernel finds engaged, not on the planner's own frame: the share of
// each sample's engaged angle lying right of the motion (sin(phi - phi_v) < 0), over the
// program but its full-slot samples, for the families, a slot along a curve and a pocket;
// conventional mirrors it. Seen: 0.954 (linear) to 0.999 (the bend) for climb; the rest is
// where an arc reaches round the tool's front, at a cycle's first contact.
TEST(Engagement, ClimbPutsTheMaterialOnTheToolsRight) {
  const auto right_share = [](const Job& job) {
    const PlannedPath pp = plan_job(job);
    const EngagementSeries e = compute_engagement(pp.path, job);
    double right = 0, all = 0;
    for (std::size_t i = 0; i < e.samples.size(); ++i) {
      // A full slot (the entry, a linear slot's first pass) is cut on both sides alike.
      if (e.engagement_angle_rad[i] > 0.9 * kPi) continue;
      const double v = std::atan2(e.samples.ty[i], e.samples.tx[i]);
      for (const AngleArc& a : e.arcs[i]) {
        const int n = std::max(1, static_cast<int>(std::ceil(a.sweep_rad() / 0.01)));
        for (int k = 0; k < n; ++k) {
          const double phi = a.start_rad + a.sweep_rad() * (k + 0.5) / n;
          all += a.sweep_rad() / n;
          if (std::sin(phi - v) < 0) right += a.sweep_rad() / n;
        }
      }
    }
    return right / all;
  };
  const std::vector<std::pair<std::string, Job>> jobs = {
      {"trochoidal", test::wagih_job("trochoidal")},
      {"circular", test::wagih_job("circular")},
      {"linear", test::wagih_job("trochoidal", {parse_override("path.type=linear")})},
      {"bend", load_job(test::example("curves/bend.toml"))},
      {"pocket", parse_job("[geometry]\nfile = \"" +
                               (test::source_dir() / "tests/data/dxf/pockets.dxf").string() +
                               "\"\n[pocket]\nboundary = \"RECT\"\ndepth = 2.0\n"
                               "max_engagement = 50.0\n[tool]\ndiameter = 10.0\nteeth = 3\n"
                               "[cutting]\nfeed_rate = 1200.0\nspindle_speed = 8000.0\n",
                           "pocket.toml")},
  };
  for (const auto& [name, job] : jobs) {
    Job conv = job;
    conv.path.direction = Direction::conventional;
    const double climb = right_share(job), up = right_share(conv);
    EXPECT_GT(climb, 0.9) << name;
    EXPECT_LT(up, 0.1) << name;
  }
}

}  // namespace
}  // namespace trochomill
