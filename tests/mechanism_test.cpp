// Cutting mechanism (issue 4): the exact chip model against the analysis kernel, K_re
// scaling, zone shares, the recommendation's monotonicity, h_m.
#include "trochomill/mechanism.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>

#include "test_util.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

Job mech_job(double width, double diameter, double step, double edge_radius = 0.01,
             const std::string& family = "trochoidal") {
  return load_job(
      test::example("wagih2023/" + family + ".toml"),
      {parse_override("slot.width=" + std::to_string(width)),
       parse_override("tool.diameter=" + std::to_string(diameter)),
       parse_override("path.step=" + std::to_string(step)), parse_override("slot.length=60"),
       parse_override("tool.edge_radius=" + std::to_string(edge_radius))});
}

// The exact model's h_e(theta) against the kernel's h_max on the planned path's steady state
// (an endless slot: stock open ahead, eight cycles of history), at every tooth pass of one
// cycle in the middle: within 2 % of f_z (issue 4), for three steps and two a/R ratios
// (a/R = 1: W = 20, D = 10; a/R = 1/3: W = 16, D = 12 as in Pivkin's experiment), and the
// elliptical family.
TEST(Mechanism, ExactModelMatchesKernel) {
  struct Case {
    double W, D, s;
    const char* family;
  };
  for (const Case cs : {Case{20, 10, 0.5, "trochoidal"}, Case{20, 10, 1.0, "trochoidal"},
                        Case{20, 10, 2.0, "trochoidal"}, Case{16, 12, 0.6, "trochoidal"},
                        Case{16, 12, 1.2, "trochoidal"}, Case{16, 12, 2.4, "trochoidal"},
                        Case{20, 10, 1.0, "elliptical"}}) {  // the example's r_e = 0.8 orbit
    const Job job = mech_job(cs.W, cs.D, cs.s, 0.01, cs.family);
    const MechanismSettings st = mechanism_settings(job);
    const double a = 0.5 * (cs.W - cs.D), fz = job.cutting.feed_per_tooth_mm;
    const double T = mechanism_curve(job, st).cycle_time_s;
    const PlannedPath pp = plan_path(job);
    const double tm = 0.5 * pp.path.duration_s();
    const double dt = 60.0 / (job.cutting.spindle_speed_rpm * job.tool.teeth);
    std::vector<double> times;
    for (double t = tm - 8 * T; t <= tm + T; t += dt) times.push_back(t);
    EngagementOptions o;
    o.open_ahead = true;
    const EngagementSeries e = compute_engagement(sample_at_times(pp.path, times), job, o);
    std::vector<double> th;
    std::vector<double> hk;
    for (std::size_t i = 0; i < e.samples.size(); ++i) {
      if (e.samples.t_s[i] < tm) continue;
      // theta from x = -a cos(theta), the branch from the direction of motion in x.
      const double ct = std::clamp(-e.samples.x_mm[i] / a, -1.0, 1.0);
      th.push_back(e.samples.tx[i] >= 0 ? std::acos(ct) : kTwoPi - std::acos(ct));
      hk.push_back(e.swept_rate_mm2_per_s[i] > 0 ? e.h_max_mm[i] : 0.0);
    }
    const MechanismCurve c = mechanism_curve_at(job, st, th);
    double worst = 0;
    int cutting = 0;
    for (std::size_t k = 0; k < th.size(); ++k) {
      worst = std::max(worst, std::abs(c.h_mm[k] - hk[k]));
      if (hk[k] > 0) ++cutting;
    }
    EXPECT_LT(worst, 0.02 * fz) << cs.family << " W " << cs.W << " D " << cs.D << " s " << cs.s;
    EXPECT_GT(cutting, 50) << "W " << cs.W << " s " << cs.s;
  }
}

// K_re = 100 h / r_e: halving r_e doubles it at every theta; zone shares sum to 1.
TEST(Mechanism, KreScalesInverselyWithEdgeRadius) {
  const Job j1 = mech_job(16, 12, 1.2, 0.01), j2 = mech_job(16, 12, 1.2, 0.02);
  MechanismSettings st = mechanism_settings(j1);
  st.points = 720;
  const MechanismCurve c1 = mechanism_curve(j1, st), c2 = mechanism_curve(j2, st);
  for (std::size_t i = 0; i < c1.k_re_pct.size(); ++i) {
    EXPECT_NEAR(c1.k_re_pct[i], 2 * c2.k_re_pct[i], 1e-9 * (1 + c1.k_re_pct[i]));
  }
  for (const auto* c : {&c1, &c2}) {
    const ZoneSummary z = summarize_zones(*c, st, false);
    EXPECT_NEAR(z.share[0] + z.share[1] + z.share[2], 1.0, 1e-12);
    EXPECT_GT(z.cutting_time_s, 0.0);
    EXPECT_LT(z.cutting_time_s, c->cycle_time_s);
  }
  // Kinematic rake angle: -asin((r_e - h) / r_e) below r_e, zero above.
  for (std::size_t i = 0; i < c2.h_mm.size(); ++i) {
    const double re = 0.02, h = c2.h_mm[i];
    EXPECT_NEAR(c2.gamma_k_rad[i], h < re ? -std::asin((re - h) / re) : 0.0, 1e-15);
  }
}

// The recommended step grows with the required CZIII share and with r_e; wear (kappa > 0
// thickens the effective chip) can only lower it.
TEST(Mechanism, RecommendationIsMonotonic) {
  const Job job = mech_job(16, 12, 1.2, 0.01);
  MechanismSettings st = mechanism_settings(job);
  st.points = 360;  // one point per degree: the shares move by < 1 % against 3600
  double prev = 0;
  for (const double share : {0.3, 0.5, 0.7}) {
    st.share = share;
    const Recommendation r = recommend(job, st, false, false);
    ASSERT_TRUE(r.found) << share;
    EXPECT_GE(r.zones.share[2], share);
    EXPECT_GT(r.value, prev) << share;
    prev = r.value;
  }
  st.share = 0.5;
  prev = 0;
  for (const double re : {0.005, 0.01, 0.02}) {
    const Job j = mech_job(16, 12, 1.2, re);
    const Recommendation r = recommend(j, st, false, false);
    ASSERT_TRUE(r.found) << re;
    EXPECT_GT(r.value, prev) << re;
    prev = r.value;
  }
  const Recommendation fresh = recommend(job, st, false, false);
  st.flank_wear_mm = 0.1;
  const Recommendation worn = recommend(job, st, true, false);
  ASSERT_TRUE(worn.found);
  EXPECT_LE(worn.value, fresh.value * 1.001);
  // The feed variant at the job's step.
  st.flank_wear_mm = 0;
  const Recommendation feed = recommend(job, st, false, true);
  ASSERT_TRUE(feed.found);
  EXPECT_GT(feed.value, 0.0);
}

// The curve is evaluated in parallel: the same numbers on one thread and on all.
TEST(Mechanism, SameResultWhateverTheThreadCount) {
  const Job job = mech_job(16, 12, 1.2, 0.01);
  MechanismSettings st = mechanism_settings(job);
  st.points = 720;
  const MechanismCurve all = mechanism_curve(job, st);
  MechanismCurve one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = mechanism_curve(job, st);
  }
  EXPECT_EQ(all.h_mm, one.h_mm);
  EXPECT_EQ(all.psi_rad, one.psi_rad);
  EXPECT_EQ(all.zone, one.zone);
}

// h_m = r_e (1 - cos theta_m) (Pivkin Eq. 1).
TEST(Mechanism, MinimumUndeformedChipThickness) {
  Job job = mech_job(16, 12, 1.2, 0.01);
  job.mechanism.friction_angle_deg = 40.0;
  MechanismSettings st = mechanism_settings(job);
  st.points = 360;
  const ZoneSummary z = summarize_zones(mechanism_curve(job, st), st, false);
  EXPECT_NEAR(z.h_m_mm, 0.01 * (1 - std::cos(deg_to_rad(40.0))), 1e-15);
}

TEST(Mechanism, RejectsWhatItCannotModel) {
  const Job circ = load_job(test::example("wagih2023/circular.toml"));
  MechanismSettings st = mechanism_settings(circ);
  EXPECT_THROW((void)mechanism_curve(circ, st), InputError);
  const Job no_edge =
      load_job(test::example("wagih2023/trochoidal.toml"), {parse_override("tool.edge_radius=0")});
  EXPECT_THROW((void)mechanism_curve(no_edge, mechanism_settings(no_edge)), InputError);
  EXPECT_THROW((void)parse_chip_model("magic"), InputError);
  EXPECT_THROW((void)load_job(test::example("wagih2023/trochoidal.toml"),
                              {parse_override("mechanism.czii_max=20")}),
               InputError);
}

}  // namespace
}  // namespace trochomill
