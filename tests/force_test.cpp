// Cutting forces: the linear model's mean forces in full-immersion slotting against
// their closed form, Kienzle at a constant chip against its formula, Bergmann's model on a
// sharp edge against Kienzle, the fast chip source against the simulation, calibration round
// trips (nonlinear and mean-force), job keys and the materials library.
#include "trochomill/force.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

using test::straight_job;

// A full slot (width = D = 10 mm, 6 mm deep, 4 teeth, f_z 0.075 mm) with a 30 degree helix.
Job full_slot(const std::vector<Override>& extra = {}) {
  std::vector<Override> ov = {
      parse_override("tool.helix_angle=30"), parse_override("material.model=linear"),
      parse_override("material.k_tc=800"),   parse_override("material.k_rc=300"),
      parse_override("material.k_ac=120"),   parse_override("material.k_te=25"),
      parse_override("material.k_re=30"),    parse_override("material.k_ae=4")};
  ov.insert(ov.end(), extra.begin(), extra.end());
  return straight_job(10.0, 4, ov);
}

// A straight cut at half immersion: D 10 mm, 2 teeth, 1 mm deep, step 5 mm across a 15 mm
// slot, f_z 0.1 mm at 3000 rpm, no helix; the overrides add material and resolutions.
Job half_immersion(const std::vector<Override>& ov) {
  return parse_job(R"(
[tool]
diameter = 10.0
teeth = 2
flute_length = 3.0
[slot]
width = 15.0
length = 30.0
depth = 1.0
[path]
type = "linear"
step = 5.0
[cutting]
feed_per_tooth = 0.1
spindle_speed = 3000.0
)",
                   "half.toml", ov);
}

// Mean of a series over [t0, t1).
std::array<double, 3> mean_force(const ForceSeries& s, double t0, double t1) {
  std::array<double, 3> m{};
  int n = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s.t_s[i] < t0 || s.t_s[i] >= t1) continue;
    m[0] += s.fx_n[i], m[1] += s.fy_n[i], m[2] += s.fz_n[i];
    ++n;
  }
  for (double& v : m) v /= n;
  return m;
}

// Linear model, full immersion, Z teeth, depth a, feed per tooth f, cw spindle: averaging the
// tooth forces over a revolution (h = f sin theta on theta in (0, pi)) gives
//   F_x = Z a K_tc f / 4 + Z a K_te / pi,  F_y = Z a K_rc f / 4 + Z a K_re / pi,
//   F_z = Z a K_ac f / pi + Z a K_ae / 2   (docs/models.md section 12).
// The fast chip source is exact on a straight path (the circle translation is exact there),
// so the only error is the time sampling of the edge terms' jumps at entry and exit: at 3600
// steps per revolution at most one step in 3600 per jump, 0.1 % of the edge terms; the
// tolerance is 0.1 % of each mean.
TEST(Forces, LinearModelMeanForcesOfAFullSlotMatchTheClosedForm) {
  const Job job = full_slot({parse_override("forces.fast_steps_per_rev=3600")});
  const ToolPath path = plan_path(job).path;
  // 20 revolutions with the tool wholly in the slot (full engagement from ~2.5 s).
  const double rev = 60.0 / 2000.0, t0 = 3.0, t1 = t0 + 20 * rev;
  const JobForces jf = job_forces(job, path, t0 - rev, t1 + rev, true);
  const auto m = mean_force(jf.series, t0, t1 - 1e-9);
  const double Z = 4, a = 6, f = 0.075;
  const double fx = Z * a * 800 * f / 4 + Z * a * 25 / kPi;
  const double fy = Z * a * 300 * f / 4 + Z * a * 30 / kPi;
  const double fz = Z * a * 120 * f / kPi + Z * a * 4 / 2;
  EXPECT_NEAR(m[0], fx, 1e-3 * fx);
  EXPECT_NEAR(m[1], fy, 1e-3 * fy);
  EXPECT_NEAR(m[2], fz, 1e-3 * fz);
  // Power: the mean torque times omega; mean torque = R * Z a (K_tc f / 2 + K_te)... per
  // revolution the tangential force integrates to a (K_tc f * 2 + K_te pi) per tooth.
  const double torque = 5e-3 * Z * a * (800 * f * 2 + 25 * kPi) / kTwoPi;  // N m
  double tq = 0;
  int n = 0;
  for (std::size_t i = 0; i < jf.series.size(); ++i) {
    if (jf.series.t_s[i] >= t0 && jf.series.t_s[i] < t1 - 1e-9) tq += jf.series.torque_nm[i], ++n;
  }
  EXPECT_NEAR(tq / n, torque, 1e-3 * torque);
}

// The counter-clockwise spindle mirrors F_x (the cutting direction reverses), nothing else.
TEST(Forces, ACounterClockwiseSpindleMirrorsTheCrossForce) {
  const Job cw = full_slot({parse_override("forces.fast_steps_per_rev=720")});
  const Job ccw = full_slot({parse_override("forces.fast_steps_per_rev=720"),
                             parse_override("cutting.spindle_direction=ccw")});
  const double rev = 0.03, t0 = 3.0, t1 = t0 + 10 * rev;
  const auto a = mean_force(job_forces(cw, plan_path(cw).path, t0, t1, true).series, t0, t1);
  const auto b = mean_force(job_forces(ccw, plan_path(ccw).path, t0, t1, true).series, t0, t1);
  EXPECT_NEAR(a[0], -b[0], 1e-3 * std::abs(a[0]));  // the same sampling error bound as above
  EXPECT_NEAR(a[1], b[1], 1e-3 * a[1]);
  EXPECT_NEAR(a[2], b[2], 1e-3 * a[2]);
}

// Kienzle at constant h: F_c = w k_c h^(1 - m), F_n = w k_n h^(1 - m_n), F_a = w k_a h^(1 - m_a)
// exactly (a few roundings); on the corner the normal force follows the contour normal.
TEST(Forces, KienzleAtAConstantChipMatchesItsFormula) {
  SimTool tool;
  tool.radius_mm = 8, tool.corner_radius_mm = 0.8, tool.flute_length_mm = 2;
  tool.segment_mm = 0.1;
  const EdgeGrid grid = edge_grid(tool, 0.2);
  Material m;
  m.model = ForceModel::kienzle;
  m.k_c = 1800, m.m = 0.25, m.k_n = 600, m.m_n = 0.4, m.k_a = 150, m.m_a = 0.1;
  const SegmentForces sf(m, grid, deg_to_rad(80));
  const double h = 0.07, w = 0.1;
  const double fc = w * 1800 * std::pow(h, 0.75), fn = w * 600 * std::pow(h, 0.6),
               fa = w * 150 * std::pow(h, 0.9);
  for (int k : {0, 5, grid.segments - 1}) {
    const auto& n = grid.at(k, 0).normal;  // (radial, 0, axial)
    const auto f = sf.force(k, h, w);
    EXPECT_NEAR(f[1], fc, 1e-12 * fc);
    EXPECT_NEAR(f[0], fn * n[0] - fa * n[2], 1e-12 * fn);
    EXPECT_NEAR(f[2], fn * n[2] + fa * n[0], 1e-12 * fn);
  }
  // Through compute_forces: one chip on tooth 1 of a two-tooth cw tool at t = 0 on the
  // straight edge (the last segment), rotated to the workpiece frame at the edge's angle.
  tool.tooth_angle_rad = {0.3, 0.3 + kPi};
  tool.radial_offset_mm = {0, 0};
  tool.axial_offset_mm = {0, 0};
  tool.omega_rad_per_s = -100;
  tool.helix_rad = 0;
  SimResult chips;
  chips.segments_per_tooth = grid.segments;
  chips.steps.push_back(SimStep{});
  chips.steps[0].t_s = 0.002;
  ChipEntry e;
  e.step = 0;
  e.segment = static_cast<std::uint32_t>(grid.segments + grid.segments - 1);
  e.h_mm = static_cast<float>(h);
  e.w_mm = static_cast<float>(w);
  chips.chip_map.push_back(e);
  const ForceSeries s = compute_forces(chips, tool, grid, sf);
  const double th = 0.3 + kPi - 100 * 0.002;
  const double hf = static_cast<double>(static_cast<float>(h)),
               wf = static_cast<double>(static_cast<float>(w));
  const double Fc = wf * 1800 * std::pow(hf, 0.75), Fn = wf * 600 * std::pow(hf, 0.6),
               Fa = wf * 150 * std::pow(hf, 0.9);
  // cw: cutting direction (sin, -cos); radial (cos, sin); the straight edge's along = +z.
  EXPECT_NEAR(s.fx_n[0], Fn * std::cos(th) + Fc * std::sin(th), 1e-9);
  EXPECT_NEAR(s.fy_n[0], Fn * std::sin(th) - Fc * std::cos(th), 1e-9);
  EXPECT_NEAR(s.fz_n[0], Fa, 1e-9);
  EXPECT_NEAR(s.torque_nm[0], Fc * grid.at(grid.segments - 1, 0).r_mm * 1e-3, 1e-12);
  EXPECT_NEAR(s.power_w[0], s.torque_nm[0] * 100, 1e-12);
  EXPECT_DOUBLE_EQ(s.tooth_fx_n[1], s.fx_n[0]);
  EXPECT_DOUBLE_EQ(s.tooth_fx_n[0], 0.0);
}

// Bergmann's model on a sharp new edge (every facet the rake face, no ploughing) is Kienzle's
// with one exponent and no axial term: the same numbers to rounding.
TEST(Forces, BergmannOnASharpEdgeIsKienzle) {
  SimTool tool;
  tool.radius_mm = 8, tool.corner_radius_mm = 0.8, tool.flute_length_mm = 2;
  const EdgeGrid grid = edge_grid(tool, 0.2);
  Material b;
  b.model = ForceModel::bergmann;
  b.k_c = 1926.08, b.k_n = 502.64, b.m = 0.28;
  Material k = b;
  k.model = ForceModel::kienzle;
  const SegmentForces fb(b, grid, deg_to_rad(80)), fk(k, grid, deg_to_rad(80));
  for (int s = 0; s < grid.segments; s += 7) {
    for (const double h : {0.001, 0.03, 0.1, 0.3}) {
      const auto x = fb.force(s, h, 0.05), y = fk.force(s, h, 0.05);
      for (int q = 0; q < 3; ++q) EXPECT_NEAR(x[q], y[q], 1e-12 * (1 + std::abs(y[q])));
    }
  }
}

// The fast source's fused forces equal compute_forces on its chip record (the same chips, the
// edge angle's cosine and sine formed two ways: rounding only, 1e-9 N).
TEST(Forces, FusedFastForcesEqualTheChipRecordsForces) {
  const Job job = load_job(test::example("bergmann2021/trochoidal.toml"));
  const ToolPath path = plan_path(job).path;
  const auto [c0, c1] = cycle_window(path, 3, 4);
  const SimTool tool = sim_tool(job, job.simulation);
  const EdgeGrid grid = job_edge_grid(job, tool);
  const SegmentForces model(job.material, grid, deg_to_rad(80));
  const FastChipSource src(job, path, c0 + 8, c0 + 9, 240);
  const ForceSeries a = src.forces(tool, grid, model);
  const ForceSeries b = compute_forces(src.chips(tool), tool, grid, model);
  ASSERT_EQ(a.size(), b.size());
  double peak = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a.fx_n[i], b.fx_n[i], 1e-9);
    EXPECT_NEAR(a.fy_n[i], b.fy_n[i], 1e-9);
    EXPECT_NEAR(a.fz_n[i], b.fz_n[i], 1e-9);
    EXPECT_NEAR(a.torque_nm[i], b.torque_nm[i], 1e-12);
    peak = std::max(peak, a.resultant_n(i));
  }
  EXPECT_GT(peak, 50.0);  // the window cuts
}

// The force model refuses a job without a model, and names what to give.
TEST(Forces, NoMaterialModelIsAClearError) {
  const Job job = straight_job(10.0);
  try {
    (void)job_forces(job, plan_path(job).path, 0, 1, true);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("[material] model"), std::string::npos) << e.what();
  }
}

// The fast chip source against the simulation on a straight half-immersion cut (a_e = R,
// 1 mm deep, 2 teeth, no helix, f_z 0.1 mm, Bergmann's coefficients). Over four revolutions
// in steady cut the mean forces agree within 3 % and the peak resultant within 4 %: the
// simulation's engaged widths come from rays 0.01 mm apart on 0.05 mm segments (its mean
// width is below the segment's, sim_chip_test), and its chips are sampled per step at the
// chip-sampling resolution; the fast source is exact on a straight path.
TEST(Forces, FastChipsAgreeWithTheSimulationOnAStraightCut) {
  const Job job = half_immersion({parse_override("material.name=inconel718-bergmann2021"),
                                  parse_override("simulation.resolution=0.01"),
                                  parse_override("simulation.steps_per_rev=240"),
                                  parse_override("forces.fast_steps_per_rev=240")});
  const ToolPath path = plan_path(job).path;
  // Find a window of four revolutions with the tool wholly engaged in the first pass.
  const double rev = 0.02;
  const double t0 = 1.0, t1 = t0 + 4 * rev;
  const JobForces fast = job_forces(job, path, t0, t1, true);
  const JobForces sim = job_forces(job, path, t0, t1, false);
  ASSERT_EQ(fast.series.size(), sim.series.size());
  const auto mf = mean_force(fast.series, t0, t1), ms = mean_force(sim.series, t0, t1);
  const double scale = std::hypot(mf[0], mf[1], mf[2]);
  ASSERT_GT(scale, 10.0) << "the window is not in the cut";
  for (int q = 0; q < 3; ++q) EXPECT_NEAR(ms[q], mf[q], 0.03 * scale) << q;
  EXPECT_NEAR(sim.summary.f_resultant_max_n, fast.summary.f_resultant_max_n,
              0.04 * fast.summary.f_resultant_max_n);
}

// Mean-force regression: the closed-form means at three feeds give back the six coefficients
// (exact arithmetic up to rounding), and the fast source's means at three feeds give them
// within 0.2 % (twice the sampling bound of the closed-form test, for the fits' slopes).
TEST(Forces, MeanForceRegressionRecoversTheLinearCoefficients) {
  const Job job = full_slot({parse_override("forces.fast_steps_per_rev=3600")});
  const double Z = 4, a = 6;
  std::vector<MeanForcePoint> exact, sim;
  for (const double f : {0.05, 0.075, 0.1}) {
    exact.push_back({f, Z * a * 800 * f / 4 + Z * a * 25 / kPi,
                     Z * a * 300 * f / 4 + Z * a * 30 / kPi,
                     Z * a * 120 * f / kPi + Z * a * 4 / 2});
  }
  const MeanForceFit fe = fit_mean_forces(job, exact);
  EXPECT_NEAR(fe.material.k_tc, 800, 1e-9);
  EXPECT_NEAR(fe.material.k_rc, 300, 1e-9);
  EXPECT_NEAR(fe.material.k_ac, 120, 1e-9);
  EXPECT_NEAR(fe.material.k_te, 25, 1e-9);
  EXPECT_NEAR(fe.material.k_re, 30, 1e-9);
  EXPECT_NEAR(fe.material.k_ae, 4, 1e-9);
  for (const double v : fe.r2) EXPECT_NEAR(v, 1.0, 1e-12);
  // From simulated slot tests (fast chips) at three feeds, spindle fixed.
  for (const double fr : {400.0, 600.0, 800.0}) {
    const Job j = full_slot({parse_override("forces.fast_steps_per_rev=3600"),
                             parse_override("cutting.feed_rate=" + std::to_string(fr))});
    const double rev = 0.03, t0 = 3.0, t1 = t0 + 10 * rev;
    const auto m = mean_force(job_forces(j, plan_path(j).path, t0, t1, true).series, t0, t1);
    sim.push_back({fr / (2000.0 * 4), m[0], m[1], m[2]});
  }
  const MeanForceFit fs = fit_mean_forces(job, sim);
  // Any other job is refused: the closed form is for full-immersion straight slots.
  EXPECT_THROW((void)fit_mean_forces(test::wagih_job("trochoidal"), sim), InputError);
  EXPECT_NEAR(fs.material.k_tc, 800, 2e-3 * 800);
  EXPECT_NEAR(fs.material.k_rc, 300, 2e-3 * 300);
  EXPECT_NEAR(fs.material.k_ac, 120, 2e-3 * 120);
  EXPECT_NEAR(fs.material.k_te, 25, 2e-3 * 800 * 0.1);  // the offsets carry the slopes' error
  EXPECT_NEAR(fs.material.k_re, 30, 2e-3 * 300 * 0.1);
  EXPECT_NEAR(fs.material.k_ae, 4, 2e-3 * 120 * 0.1);
}

// Calibration round trip on Bergmann's case (fast chips, 1 s of the steady cycle's densest
// cut): forces generated with k_c 1926.08, k_n 502.64, m 0.28 and 0.013 mm radial runout at
// 1000 steps per revolution (the calibration's own rate for two teeth), interpolated to
// 20 kHz 7.3 ms late with 3 N of Gaussian noise, are fitted from k_c 1500, k_n 300, m 0.2,
// runout 0.005 mm. The noise is 1-2 % of the force amplitude and averages out over 20,000
// samples; what remains is the linear interpolation of the generated series (0.3 % on k_c
// when this was written); the fit must land within 1 % of each true value (the issue's bound).
TEST(Forces, CalibrationRoundTripRecoversCoefficientsAndRunout) {
#if defined(TROCHOMILL_SANITIZED)
  // 78 s under the sanitizers (the solver's iterations over a 20 kHz record): the Release
  // suite checks the recovered values; the sanitizers see the calibration's code in
  // Forces.CalibrationWithSimulatedChips, Forces.CalibrationRefusesAnUnidentifiableFit and
  // Cli.ForcesCalibrateAndMaterials.
  GTEST_SKIP() << "the recovered coefficients are checked in the Release suite";
#endif
  const std::vector<Override> fast = {parse_override("forces.fast_steps_per_rev=1000")};
  Job truth = load_job(test::example("bergmann2021/trochoidal.toml"), fast);
  const ToolPath path = plan_path(truth).path;
  const auto [c0, c1] = cycle_window(path, 3, 4);
  // The densest second of the cycle (found on the truth's own forces).
  const JobForces scan = job_forces(truth, path, c0, c1, true);
  const double tmax = scan.summary.t_resultant_max_s;
  const double t0 = std::max(c0, tmax - 0.5), t1 = t0 + 1.0;
  const JobForces gen = job_forces(truth, path, t0, t1, true);
  MeasuredForces meas;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 3.0);
  const double shift = 0.0073;
  const auto at = [&](const std::vector<double>& y, double t) {
    const auto& ts = gen.series.t_s;
    const auto it = std::upper_bound(ts.begin(), ts.end(), t);
    const auto j = static_cast<std::size_t>(it - ts.begin());
    const double f = (t - ts[j - 1]) / (ts[j] - ts[j - 1]);
    return y[j - 1] + f * (y[j] - y[j - 1]);
  };
  for (double t = gen.series.t_s.front(); t < gen.series.t_s.back(); t += 5e-5) {
    meas.t_s.push_back(t + shift);
    meas.fx_n.push_back(at(gen.series.fx_n, t) + noise(rng));
    meas.fy_n.push_back(at(gen.series.fy_n, t) + noise(rng));
    meas.fz_n.push_back(at(gen.series.fz_n, t) + noise(rng));
  }
  Job start =
      load_job(test::example("bergmann2021/trochoidal.toml"),
               {fast[0], parse_override("material.k_c=1500"), parse_override("material.k_n=300"),
                parse_override("material.m=0.2"), parse_override("tool.runout_radial=0.005")});
  CalibrationOptions o;
  o.model = ForceModel::bergmann;
  o.fit = {"k_c", "k_n", "m", "runout_radial"};
  o.fast = true;
  o.from_s = t0, o.to_s = t1;
  o.max_shift_s = 0.02;
  const CalibrationResult r = calibrate_forces(start, path, meas, o);
  EXPECT_NEAR(r.material.k_c, 1926.08, 0.01 * 1926.08);
  EXPECT_NEAR(r.material.k_n, 502.64, 0.01 * 502.64);
  EXPECT_NEAR(r.material.m, 0.28, 0.01 * 0.28);
  EXPECT_NEAR(r.tool.runout_radial_mm, 0.013, 0.01 * 0.013);
  EXPECT_NEAR(r.shift_s, shift, 1e-4);  // a third of a model step (1/240 rev = 0.31 ms)
  EXPECT_GT(r.r2, 0.99);
  EXPECT_LT(r.rmse_n, 3.0);         // the noise, partly filtered out
  EXPECT_TRUE(r.warnings.empty());  // 754 samples per tooth pass (20 kHz at 26.5 Hz)
  // The same record at 500 Hz: 18.8 samples per tooth pass, fewer than the 25 that keep ten
  // tooth-passing harmonics under 0.8 Nyquist: the fit says so.
  // The record taken every `stride` samples (20 kHz / stride).
  const auto every = [&](std::size_t stride) {
    MeasuredForces m;
    for (std::size_t i = 0; i < meas.t_s.size(); i += stride) {
      m.t_s.push_back(meas.t_s[i]);
      m.fx_n.push_back(meas.fx_n[i]);
      m.fy_n.push_back(meas.fy_n[i]);
      m.fz_n.push_back(meas.fz_n[i]);
    }
    return m;
  };
  const MeasuredForces coarse = every(40);
  CalibrationOptions oc = o;
  oc.fit = {"k_c"};
  const CalibrationResult rc = calibrate_forces(start, path, coarse, oc);
  ASSERT_EQ(rc.warnings.size(), 1u);
  EXPECT_NE(rc.warnings[0].find("measured record has 18.8 samples per tooth pass, fewer than "
                                "the 25"),
            std::string::npos)
      << rc.warnings[0];  // 500 Hz / (795.8 rpm / 60 x 2 teeth) = 18.85, printed to 0.1
  // The same record at 1250 Hz: 47 samples per tooth pass, enough for the harmonics, but taken
  // instant by instant (as `forces --csv` writes the model), so the force's jumps alias below
  // the cutoff; the fit says so and names a rate (it was silent, and k_c came out 3.4 % low
  // on such a record of the README's round trip).
  const CalibrationResult ra = calibrate_forces(start, path, every(16), oc);
  ASSERT_EQ(ra.warnings.size(), 1u);
  EXPECT_NE(ra.warnings[0].find("measured record (1250 Hz) is coarse for the force's jumps"),
            std::string::npos)
      << ra.warnings[0];
  EXPECT_NE(ra.warnings[0].find("record at 5000 Hz or more"), std::string::npos) << ra.warnings[0];
  for (const auto& p : r.parameters) {
    EXPECT_LT(p.ci95_lo, p.value);
    EXPECT_GT(p.ci95_hi, p.value);
    EXPECT_FALSE(p.at_bound) << p.name;
  }
  // The [material] block parses back as a job section.
  const std::string block = material_toml(r);
  const Job back = parse_job(R"(
[tool]
diameter = 16.0
teeth = 2
[slot]
width = 50.0
length = 65.0
depth = 1.0
[cutting]
feed_per_tooth = 0.1
cutting_speed = 40.0
[path]
type = "trochoidal"
step = 1.0
)" + block,
                             "calibrated.toml");
  EXPECT_NEAR(back.material.k_c, r.material.k_c, 1e-5 * r.material.k_c);
  EXPECT_EQ(*back.material.model, ForceModel::bergmann);
}

// Calibration with the simulation as chip source (coefficients only: one simulation), on the
// straight half-immersion cut: forces the simulation gives with Bergmann's coefficients, as
// measured at the model's own steps, come back within 0.5 % from k_c 1500, k_n 300, m 0.2
// (the same chips: only the filter's edges and the solver's tolerance remain).
TEST(Forces, CalibrationWithSimulatedChips) {
  const std::vector<Override> sim = {parse_override("simulation.resolution=0.02"),
                                     parse_override("simulation.steps_per_rev=240")};
  std::vector<Override> t = sim, st = sim;
  t.push_back(parse_override("material.name=inconel718-bergmann2021"));
  for (const char* o :
       {"material.model=bergmann", "material.k_c=1500", "material.k_n=300", "material.m=0.2"}) {
    st.push_back(parse_override(o));
  }
  const Job truth = half_immersion(t);
  const ToolPath path = plan_path(truth).path;
  const double t0 = 1.0, t1 = 1.2;  // ten revolutions in the cut
  const JobForces gen = job_forces(truth, path, t0, t1, false);
  MeasuredForces meas;
  meas.t_s = gen.series.t_s;
  meas.fx_n = gen.series.fx_n, meas.fy_n = gen.series.fy_n, meas.fz_n = gen.series.fz_n;
  const Job start = half_immersion(st);
  CalibrationOptions o;
  o.fast = false;
  o.from_s = t0, o.to_s = t1;
  const CalibrationResult r = calibrate_forces(start, path, meas, o);
  EXPECT_NEAR(r.material.k_c, 1926.08, 0.005 * 1926.08);
  EXPECT_NEAR(r.material.k_n, 502.64, 0.005 * 502.64);
  EXPECT_NEAR(r.material.m, 0.28, 0.005 * 0.28);
  EXPECT_NEAR(r.shift_s, 0.0, 1e-5);
}

// Runout phase is not identifiable with two teeth (only e cos(phase) enters): refused.
TEST(Forces, CalibrationRefusesAnUnidentifiableFit) {
  const Job job = load_job(test::example("bergmann2021/trochoidal.toml"));
  MeasuredForces m;
  for (int i = 0; i < 100; ++i) {
    m.t_s.push_back(i * 1e-3), m.fx_n.push_back(0), m.fy_n.push_back(0), m.fz_n.push_back(0);
  }
  CalibrationOptions o;
  o.fit = {"k_c", "runout_radial", "runout_phase"};
  o.fast = true;
  o.from_s = 0, o.to_s = 0.1;
  try {
    (void)calibrate_forces(job, plan_path(job).path, m, o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("runout_phase"), std::string::npos) << e.what();
  }
  o.fit = {"k_tc"};
  EXPECT_THROW((void)calibrate_forces(job, plan_path(job).path, m, o), InputError);
}

// [material] keys: the library by name, the job's keys over it, and clear errors.
// A trochoidal job ending in an open [material] section.
const char* const kMaterialJob = R"(
[tool]
diameter = 10.0
teeth = 4
[slot]
width = 20.0
length = 20.0
depth = 2.0
[path]
type = "trochoidal"
step = 1.0
[cutting]
feed_rate = 600.0
spindle_speed = 2000.0
[material]
)";

TEST(Forces, MaterialKeysAndTheLibrary) {
  const auto lib = material_library();
  ASSERT_GE(lib.size(), 3u);
  const Job j = parse_job(
      std::string(kMaterialJob) + "name = \"inconel718-bergmann2021\"\nk_n = 480.0\n", "m.toml");
  EXPECT_EQ(*j.material.model, ForceModel::bergmann);
  EXPECT_DOUBLE_EQ(j.material.k_c, 1926.08);
  EXPECT_DOUBLE_EQ(j.material.k_n, 480.0);  // the job's key over the library's
  EXPECT_DOUBLE_EQ(j.material.m, 0.28);
  const auto expect_error = [](const std::string& material, const std::string& needle) {
    try {
      (void)parse_job(std::string(kMaterialJob) + material, "bad.toml");
      ADD_FAILURE() << "no error for " << material;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_error("name = \"inconel718\"\n", "not in the materials library");
  expect_error("name = \"inconel718-bergman2021\"\n", "did you mean 'inconel718-bergmann2021'");
  expect_error("model = \"linear\"\nk_c = 100.0\nk_tc = 500.0\n",
               "belongs to the bergmann/kienzle");
  expect_error("model = \"bergmann\"\nk_n = 100.0\n", "needs k_c");
  expect_error("k_c = 100.0\n", "give [material] model");
  expect_error("model = \"kienzl\"\n", "did you mean 'kienzle'");
  expect_error("model = \"bergmann\"\nk_c = 100.0\nm = 1.5\n", "bad.toml:18:5: [material] m");
}

}  // namespace
}  // namespace trochomill

namespace trochomill {
namespace {

// Wagih 2023's performance index PI = MRR / (F_R,max Ra,max W_max) (Eq. 7) of the four
// example paths, every factor predicted (MRR by the model, F_R,max by the linear force model
// of an aluminium alloy over the steady cycle, Ra of the rougher wall by ISO 21920-2 on the
// tooth-level wall, W_max the tooth-level waviness): each PI is its factors' quotient (to
// rounding), and the ranking follows from them: the force differs by under 3 % and the
// removal rate by under 15 % between the paths, so Ra W decides, and the order is the
// ascending order of Ra W. The order that results, stated in docs/models.md section 14:
// linear-elliptical (its wall passes run straight along the walls: Ra and W of a few tenths
// of a micrometre), circular, trochoidal, elliptical.
TEST(Forces, PerformanceIndexRanksWagihsFourPaths) {
  struct Entry {
    std::string name;
    double pi, ra_w, force, mrr;
  };
  std::vector<Entry> e;
  for (const std::string name : {"trochoidal", "circular", "elliptical", "linear-elliptical"}) {
    const Job job = load_job(test::example("wagih2023/" + name + ".toml"),
                             {{"material.name", "al6082-t6-linear", ""}});
    const ProcessMetrics m = analyze_with_forces(job, plan_path(job).path);
    ASSERT_TRUE(m.performance_index && m.force_max_predicted_n && m.texture_left && m.texture_right)
        << name << ": " << m.performance_index_note;
    const double ra_um =
        1000 * std::max(m.texture_left->roughness.ra_mm, m.texture_right->roughness.ra_mm);
    const double w_um =
        1000 * std::max(m.walls_tooth.left.waviness_mm, m.walls_tooth.right.waviness_mm);
    const double pi = m.mrr_mm3_per_min / (*m.force_max_predicted_n * ra_um * w_um);
    EXPECT_NEAR(*m.performance_index / pi, 1.0, 1e-12) << name;
    e.push_back(
        {name, *m.performance_index, ra_um * w_um, *m.force_max_predicted_n, m.mrr_mm3_per_min});
  }
  auto spread = [&](double Entry::*f) {
    double lo = INFINITY, hi = 0;
    for (const Entry& x : e) lo = std::min(lo, x.*f), hi = std::max(hi, x.*f);
    return hi / lo - 1;
  };
  EXPECT_LT(spread(&Entry::force), 0.03);
  EXPECT_LT(spread(&Entry::mrr), 0.15);
  auto order = [&](auto better) {
    std::vector<Entry> s = e;
    std::sort(s.begin(), s.end(), better);
    std::vector<std::string> names;
    for (const Entry& x : s) names.push_back(x.name);
    return names;
  };
  const auto by_pi = order([](const Entry& a, const Entry& b) { return a.pi > b.pi; });
  EXPECT_EQ(by_pi, order([](const Entry& a, const Entry& b) { return a.ra_w < b.ra_w; }));
  EXPECT_EQ(by_pi, (std::vector<std::string>{"linear-elliptical", "circular", "trochoidal",
                                             "elliptical"}));
}

}  // namespace
}  // namespace trochomill
