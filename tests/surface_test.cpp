// Surface geometry: walls as envelopes of circles and of tip polylines, floor imprints,
// against closed forms.
#include "trochomill/surface.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "surface/floor_look.hpp"
#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/job.hpp"
#include "trochomill/texture.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

PathSamples points(const std::vector<std::pair<double, double>>& xy, double z = -1) {
  PathSamples s;
  for (const auto& [x, y] : xy) {
    s.t_s.push_back(0);
    s.x_mm.push_back(x);
    s.y_mm.push_back(y);
    s.z_mm.push_back(z);
  }
  return s;
}

// Circles of radius R every s along x = -5: the classic scallop R - sqrt(R^2 - s^2/4) at
// y = s/2 (the grid of 2001 points puts a point exactly there, so only rounding remains).
TEST(Surface, CircleScallop) {
  const double R = 5, s = 1;
  std::vector<std::pair<double, double>> c;
  for (int k = -10; k <= 10; ++k) c.push_back({-5.0, k * s});
  const Walls w = walls_from_circles(points(c), R, 0.0, 0.0, s, 2001);
  EXPECT_NEAR(w.left.waviness_mm, R - std::sqrt(R * R - s * s / 4), 1e-12);
  EXPECT_NEAR(w.left.peak_y_mm, 0.5, 1e-12);
  EXPECT_NEAR(w.right.waviness_mm, R - std::sqrt(R * R - s * s / 4), 1e-12);
  // Circles above z_max do not cut.
  EXPECT_THROW((void)walls_from_circles(points(c, 1.0), R, 0.0, 0.0, s, 2001), InputError);
  EXPECT_THROW((void)walls_from_circles(points(c), R, 0.0, 1.0, 0.0, 2001), InputError);
}

// A polyline tip track: two V-shaped dips 1 mm apart give a profile with the V's depth.
TEST(Surface, TipPolylineEnvelope) {
  ToothTracks tr;
  tr.teeth = 1;
  tr.x_mm = {{0.0, -1.0, 0.0, -1.0, 0.0}};
  tr.y_mm = {{0.0, 0.5, 1.0, 1.5, 2.0}};
  tr.z_mm = {{-1.0, -1.0, -1.0, -1.0, -1.0}};
  const Walls w = walls_from_tips(tr, 0.0, 0.5, 1.5, 11);
  EXPECT_NEAR(w.left.waviness_mm, 1.0, 1e-12);
  EXPECT_NEAR(w.left.peak_y_mm, 1.0, 1e-12);
  EXPECT_NEAR(w.left.x_mm[5], 0.0, 1e-12);
  EXPECT_NEAR(w.left.x_mm[2], -0.6, 1e-12);
}

// Floor imprints: n circles centred at x = 0 over an advance A cross the line x = X twice
// each when |X| < R: 2 n / A per mm.
TEST(Surface, ImprintDensityClosedForm) {
  const ImprintDensity d = bottom_imprint_density(std::vector<double>(40, 0.0), 5.0, 10.0, 3.0, 5);
  ASSERT_EQ(d.x_mm.size(), 5u);
  EXPECT_DOUBLE_EQ(d.x_mm[0], -10.0);
  EXPECT_DOUBLE_EQ(d.crossings_per_mm[0], 0.0);
  EXPECT_DOUBLE_EQ(d.crossings_per_mm[1], 0.0);  // |X| = R: tangent, not a crossing pair
  EXPECT_DOUBLE_EQ(d.crossings_per_mm[2], 2 * 40 / 3.0);
  EXPECT_THROW((void)bottom_imprint_density({0.0}, 5.0, 10.0, 0.0, 5), InputError);
}

// ---- surface texture ---------------------------------------------------------------------

std::vector<double> sinusoid(double amplitude, double wavelength, double dx, std::size_t n) {
  std::vector<double> z(n);
  for (std::size_t i = 0; i < n; ++i) {
    z[i] = amplitude * std::sin(2 * std::numbers::pi * static_cast<double>(i) * dx / wavelength);
  }
  return z;
}

// A sinusoid of amplitude A over whole periods, sampled 4000 times a period from a zero (its
// peaks and valleys are samples): Ra = 2A/pi (the sampled mean of |sin| is cot(pi / 2N) / N,
// 2e-7 above it for N = 2000 samples a half period), Rq = A/sqrt 2 (exact on whole periods),
// Rp = Rv = A, Rz = Rt = 2A, Rsk = 0, Rku = 3/2, RSm = the wavelength; each to 1e-6 relative

// A straight cut along +y at x = 0 with a dished end face (no runout, sharp corner): a tooth's
// end edge passes a point (0, y) of the centre line when it points along +y (the point ahead,
// r = y - c_y) or -y (behind, r = c_y - y), at the closed-form times omega t + alpha_k =
// +-pi/2 (mod 2 pi); there the edge lies (R - r) tan(dish) above the tip. The floor is the
// least over those passes, computed here from the times alone. The profile finds the passes
// from samples 37 a revolution (interpolating in 5 degree steps): the crossing time's error
// is third order in the step, the height's below 1e-9 mm (tolerance 1e-9 mm).
TEST(Surface, FloorOfAStraightCutIsTheClosedForm) {
  Tool tool;
  tool.diameter_mm = 10;
  tool.teeth = 4;
  tool.tooth_angles_deg = {0, 90, 180, 270};
  tool.dish_angle_deg = 1.5;
  const double R = 5, omega = -2000 * 2 * std::numbers::pi / 60;  // cw, 2000 rpm
  const double v = 0.075 * 4 * 2000 / 60;                         // f_z 0.075 mm: 10 mm/s
  const double t_end = 3;
  PathSamples s;
  const int n = static_cast<int>(t_end * 2000 / 60 * 37);
  for (int i = 0; i <= n; ++i) {
    const double t = t_end * i / n;
    s.t_s.push_back(t);
    s.x_mm.push_back(0);
    s.y_mm.push_back(v * t);
    s.z_mm.push_back(-1);
  }
  // Off the lattice of pass centres (a point exactly at a corner's reach r = R is a tie of
  // rounding between the two).
  const double y0 = 10.0001234, dy = 0.0005;
  const std::size_t points = 4001;
  const FloorProfile f = floor_profile(s, tool, omega, 0.0, y0, dy, points);
  ASSERT_EQ(f.z_mm.size(), points);
  // The closed form: every pass's centre and direction.
  std::vector<std::pair<double, double>> passes;  // (centre y, +1 ahead / -1 behind)
  const double tan_dish = std::tan(1.5 * std::numbers::pi / 180);
  for (double alpha : tool.tooth_angles_deg) {
    alpha *= std::numbers::pi / 180;
    for (const double dir : {1.0, -1.0}) {
      // omega t + alpha = dir pi / 2 + 2 pi m, t in [0, t_end]
      for (int m = -200; m <= 200; ++m) {
        const double t = (dir * std::numbers::pi / 2 + 2 * std::numbers::pi * m - alpha) / omega;
        if (t >= 0 && t <= t_end) passes.push_back({v * t, dir});
      }
    }
  }
  ASSERT_GT(passes.size(), 700u);
  double lo = 1e9, hi = -1e9;
  for (std::size_t j = 0; j < points; ++j) {
    const double y = y0 + dy * static_cast<double>(j);
    double z = std::numeric_limits<double>::infinity();
    for (const auto& [c, dir] : passes) {
      const double r = dir * (y - c);
      if (r >= 0 && r <= R) z = std::min(z, -1 + (R - r) * tan_dish);
    }
    ASSERT_NEAR(f.z_mm[j], z, 1e-9) << y;
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
  // Marks, no deeper than a feed per tooth of dish (the next pass ahead or behind is at most
  // f_z away).
  EXPECT_GT(hi - lo, 0.1 * 0.075 * tan_dish);
  EXPECT_LE(hi - lo, 0.075 * tan_dish + 1e-12);
}

// Without a dish the end face is flat: on a trochoidal cut with a corner radius, radial and
// axial runout, the middle of the floor is the lowest tooth's tip height everywhere, exactly
// (the flat reaches R - rc from the axis; every point there is passed by every tooth).
TEST(Surface, FloorOfAFlatEndFaceIsFlatAtTheLowestTooth) {
  Job job =
      load_job(test::example("wagih2023/trochoidal.toml"),
               {parse_override("tool.dish_angle=0"), parse_override("tool.corner_radius=0.5"),
                parse_override("tool.runout_radial=0.01"),
                parse_override("tool.runout_axial=0.004"), parse_override("tool.runout_phase=30")});
  const ToolPath path = plan_path(job).path;
  const PathSamples s = sample_by_spindle_angle(path, 36, 2000);
  const double omega = -2000 * 2 * std::numbers::pi / 60;
  const FloorProfile f = floor_profile(s, job.tool, omega, 0.0, 4.0, 0.002, 5001);
  double lowest = 0;  // -e_ax cos(alpha_k - 30 deg) at its least: the tooth at 0 degrees
  for (const double a : job.tool.tooth_angles_deg) {
    lowest = std::min(lowest, -0.004 * std::cos((a - 30) * std::numbers::pi / 180));
  }
  for (const double z : f.z_mm) ASSERT_EQ(z, -6.0 + lowest);
}
// The floor's first look at its points four at a time (AVX2, where the processor has it) only
// spares the look point by point where that would pass over the point: the floor is the same
// doubles either way (no tolerance). On the Wagih trochoidal cut with the tools where the look
// differs most: a dished end with a corner radius (whose rise the vector look bounds from
// below), with radial and axial runout, a flat end with a corner, a sharp dished end; the three
// lines analyze takes (beside each wall and in the middle) and one across the corner's band.
TEST(Surface, TheFloorsVectorLookGivesTheSameFloor) {
  std::atomic<bool>& look = detail::floor_vector_look();
  if (!look.load()) GTEST_SKIP() << "the processor has no AVX2: the floor looks point by point";
  const std::vector<std::vector<std::string>> tools = {
      {"tool.dish_angle=2", "tool.corner_radius=0.8", "tool.runout_radial=0.01",
       "tool.runout_axial=0.004", "tool.runout_phase=30"},
      {"tool.dish_angle=0", "tool.corner_radius=0.5"},
      {"tool.dish_angle=1", "tool.corner_radius=0"}};
  for (const auto& sets : tools) {
    std::vector<Override> o;
    for (const std::string& kv : sets) o.push_back(parse_override(kv));
    const Job job = load_job(test::example("wagih2023/trochoidal.toml"), o);
    const PathSamples smp = sample_by_spindle_angle(plan_path(job).path, 36, 2000);
    const double omega = -2000 * 2 * std::numbers::pi / 60;
    const double beside = 0.5 * job.slot.width_mm - 0.5 * job.tool.radius_mm();
    long compared = 0;
    for (const double x : {-beside, 0.0, beside, 0.5 * job.slot.width_mm - 0.6}) {
      look.store(true);
      const FloorProfile a = floor_profile(smp, job.tool, omega, x, 4.0, 0.0005, 2001);
      look.store(false);
      const FloorProfile b = floor_profile(smp, job.tool, omega, x, 4.0, 0.0005, 2001);
      look.store(true);
      ASSERT_EQ(a.z_mm.size(), b.z_mm.size());
      for (std::size_t j = 0; j < a.z_mm.size(); ++j) {
        if (std::isnan(b.z_mm[j])) {
          ASSERT_TRUE(std::isnan(a.z_mm[j])) << sets.front() << " x " << x << " point " << j;
          continue;
        }
        ASSERT_EQ(a.z_mm[j], b.z_mm[j]) << sets.front() << " x " << x << " point " << j;
        ++compared;
      }
    }
    EXPECT_GT(compared, 4000) << sets.front();  // most points are cut
  }
}

// (Rsk to 1e-9 absolute: odd moments cancel to rounding).
TEST(Texture, SinusoidParametersMatchTheirClosedForms) {
  const double A = 0.002, lambda = 0.1, dx = lambda / 4000;
  const std::vector<double> z = sinusoid(A, lambda, dx, 40 * 4000);
  const ProfileParameters p = profile_parameters(z, dx);
  EXPECT_NEAR(p.ra_mm, 2 * A / std::numbers::pi, 1e-6 * A);
  EXPECT_NEAR(p.rq_mm, A / std::sqrt(2.0), 1e-6 * A);
  EXPECT_NEAR(p.rp_mm, A, 1e-6 * A);
  EXPECT_NEAR(p.rv_mm, A, 1e-6 * A);
  EXPECT_NEAR(p.rz_mm, 2 * A, 2e-6 * A);
  EXPECT_NEAR(p.rt_mm, 2 * A, 2e-6 * A);
  EXPECT_NEAR(p.rsk, 0.0, 1e-9);
  EXPECT_NEAR(p.rku, 1.5, 1e-6);
  EXPECT_NEAR(p.rsm_mm, lambda, 1e-6 * lambda);
  EXPECT_GE(p.elements, 38);  // 40 periods less the incomplete stretches at the ends
  EXPECT_EQ(p.sections, 5);
  EXPECT_NEAR(p.evaluation_length_mm, 4.0, 1e-12);
  // The material ratio: half the length lies above the mean line, all of it above the bottom.
  const MaterialRatioCurve c = material_ratio_curve(z, 3);
  EXPECT_NEAR(c.c_mm[0], A, 1e-12);
  EXPECT_NEAR(c.ratio_percent[1], 50.0, 0.01);  // the zeros themselves: 2 samples a period
  EXPECT_DOUBLE_EQ(c.ratio_percent[2], 100.0);
}

// Small bumps do not make elements: a sinusoid with a ripple of 5 % of its amplitude at 20
// times its frequency crosses the mean line near every zero several times, stretches lower
// than 10 % of Rz that merge into their neighbours; RSm stays the wavelength (1e-3 relative:
// the merged crossings move by the ripple's share of the slope).
TEST(Texture, SmallCrossingsMergeIntoTheirElements) {
  const double A = 0.002, lambda = 0.1, dx = lambda / 4000;
  std::vector<double> z = sinusoid(A, lambda, dx, 40 * 4000);
  // The ripple is at its crest where the sinusoid crosses zero, moving the crossing; 15 % of
  // A at 20 times the frequency is three times as steep, so it crosses back and forth.
  for (std::size_t i = 0; i < z.size(); ++i) {
    z[i] += 0.15 * A * std::cos(2 * std::numbers::pi * 20 * static_cast<double>(i) * dx / lambda);
  }
  std::size_t crossings = 0;
  for (std::size_t i = 1; i < z.size(); ++i) crossings += (z[i - 1] < 0) != (z[i] < 0) ? 1 : 0;
  EXPECT_GE(crossings, 3u * 80u - 2);  // three times at each zero of the sinusoid
  const ProfileParameters p = profile_parameters(z, dx);
  EXPECT_NEAR(p.rsm_mm, lambda, 1e-3 * lambda);
  EXPECT_LE(p.elements, 40);
}

// The filter's transmission: a sinusoid of wavelength lambda keeps exp(-pi (alpha lambda_c /
// lambda)^2) of its amplitude in the mean line (50 % at lambda = lambda_c), measured by
// projecting the mean line on sin and cos over whole periods, within 1e-4 over a sweep of
// wavelengths from lambda_c / 4 to 10 lambda_c. The truncation at +-lambda_c (6.5e-7 of the
// peak weight) and the 500 samples a cut-off leave far less than that.
TEST(Texture, GaussianFilterTransmitsAsTheStandardSays) {
  const double lc = 0.8, dx = lc / 500, A = 0.001;
  EXPECT_NEAR(gaussian_transmission(lc, lc), 0.5, 1e-15);
  for (const double ratio : {0.25, 0.5, 0.8, 1.0, 1.25, 2.0, 4.0, 10.0}) {
    const double lambda = ratio * lc;
    const std::size_t per = static_cast<std::size_t>(std::llround(lambda / dx));
    const double lam = static_cast<double>(per) * dx;  // whole samples a period
    const std::size_t periods = std::max<std::size_t>(4, static_cast<std::size_t>(12 * lc / lam));
    const std::vector<double> z = sinusoid(A, lam, dx, periods * per + 2 * 500 + 1);
    const FilteredProfile f = gaussian_filter(z, dx, lc);
    ASSERT_EQ(f.first, 500u);
    double s = 0, c = 0;
    const std::size_t m = (f.mean_mm.size() / per) * per;  // whole periods of the mean line
    for (std::size_t i = 0; i < m; ++i) {
      const double ph =
          2 * std::numbers::pi * static_cast<double>(f.first + i) / static_cast<double>(per);
      s += f.mean_mm[i] * std::sin(ph), c += f.mean_mm[i] * std::cos(ph);
    }
    const double amp = 2 * std::hypot(s, c) / static_cast<double>(m);
    EXPECT_NEAR(amp / A, gaussian_transmission(lam, lc), 1e-4) << ratio;
    // Mean line and residual add up to the profile.
    for (std::size_t i = 0; i < f.mean_mm.size(); i += 97) {
      EXPECT_NEAR(f.mean_mm[i] + f.residual_mm[i], z[f.first + i], 1e-15);
    }
  }
}

// End handling: with renormalised weights the mean line of a constant is that constant to the
// last sample, and away from the ends (one cut-off in) it equals the run-in/run-out filter's.
TEST(Texture, FilterEnds) {
  const double dx = 0.001, lc = 0.08;
  const std::vector<double> flat(1000, 0.0123);
  const FilteredProfile fn = gaussian_filter(flat, dx, lc, FilterEnds::normalize);
  ASSERT_EQ(fn.mean_mm.size(), flat.size());
  for (const double v : fn.residual_mm) EXPECT_NEAR(v, 0.0, 1e-15);
  const std::vector<double> z = sinusoid(0.001, 0.05, dx, 1000);
  const FilteredProfile a = gaussian_filter(z, dx, lc, FilterEnds::normalize),
                        b = gaussian_filter(z, dx, lc, FilterEnds::discard);
  ASSERT_EQ(b.first, 80u);
  for (std::size_t i = 0; i < b.mean_mm.size(); ++i) {
    EXPECT_NEAR(a.mean_mm[b.first + i], b.mean_mm[i], 1e-15);
  }
}

// The default cut-off fits the profile: a smooth wall (Ra 6 nm: the table's 0.08 mm) sampled
// every 0.05 mm (a coarse simulation's walls) resolves no 0.08 mm cut-off, so the nearest
// that fits, 0.25 mm, is taken and said (it was an error).
TEST(Texture, TheDefaultCutOffFitsTheProfile) {
  std::vector<double> z;
  for (int i = 0; i < 800; ++i) z.push_back(1e-5 * std::sin(2 * std::numbers::pi * i * 0.05 / 0.3));
  const ProfileTexture t = profile_texture(z, 0.05);
  EXPECT_EQ(t.cutoff_mm, 0.25);
  EXPECT_NE(t.cutoff_source.find("the nearest ISO 21920-3 cut-off this profile admits"),
            std::string::npos)
      << t.cutoff_source;
}

TEST(Texture, BadInputIsRefusedWithTheReason) {
  const std::vector<double> z(100, 0.0);
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { (void)gaussian_filter(z, 0.0, 0.1); }).find("sample spacing"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)gaussian_filter(z, 0.01, 0.015); }).find("two sample spacings"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)gaussian_filter(z, 0.01, 0.6); }).find("shorter than two cut-offs"),
            std::string::npos);
  std::vector<double> bad = z;
  bad[7] = std::nan("");
  EXPECT_NE(message([&] { (void)profile_parameters(bad, 0.01); }).find("(sample 7)"),
            std::string::npos);
  EXPECT_NE(message([&] {
              (void)profile_parameters(std::vector<double>(6, 0.0), 0.01);
            }).find("at least two per section"),
            std::string::npos);
  // Found by fuzzing the profile readers: a profile sampled every 4 mm cannot resolve the
  // default 0.8 mm cut-off (it divided by the cut-off's zero samples); a cut-off of 1e9
  // samples is refused before its weights are allocated (8 GB), with either end treatment.
  EXPECT_NE(message([&] { (void)profile_texture(z, 4.0); }).find("sampled too coarsely"),
            std::string::npos);
  EXPECT_NE(message([&] { (void)periodic_profile_texture(z, 4.0); }).find("sampled too coarsely"),
            std::string::npos);
  for (const FilterEnds ends : {FilterEnds::discard, FilterEnds::normalize}) {
    EXPECT_NE(message([&] { (void)gaussian_filter(z, 1e-9, 1.0, ends); }).find("(limit 5e+07)"),
              std::string::npos);
  }
  EXPECT_NE(message([&] { (void)profile_texture(z, 1e-9, 1.0); }).find("(limit 5e+07)"),
            std::string::npos);
}

// The robust Gaussian regression filter (ISO 16610-31) against scratches: a long wave (4 mm,
// 5 um) and a fine texture (0.05 mm, 1 um) with a 20 um deep, 0.02 mm wide scratch every
// 0.8 mm. The plain filter's mean line dips under each scratch by the scratch's area times
// the weighting function's peak, 4e-4 mm^2 / (alpha lambda_c) = 1.06 um (to 5 %: the long
// wave's slope and the texture under the scratch add a little); the robust one gives the
// scratches no weight and stays on the mean line of the profile without them to a tenth of
// that (0.09 um measured: around each scratch the fine texture is averaged over an uneven
// set of weights), so the scratches' full depth is in its R profile (Rv above 15 um).
TEST(Texture, RobustFilterIgnoresScratches) {
  const double dx = 0.0005, lc = 0.8;
  const std::size_t n = 16000;
  std::vector<double> clean(n), scratched(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(i) * dx;
    clean[i] = 0.005 * std::sin(2 * std::numbers::pi * x / 4) +
               0.001 * std::sin(2 * std::numbers::pi * x / 0.05);
    const double in_period = std::fmod(x, 0.8);
    scratched[i] = clean[i] - (in_period > 0.4 && in_period < 0.42 ? 0.02 : 0.0);
  }
  const FilteredProfile reference = gaussian_filter(clean, dx, lc);
  const FilteredProfile plain = gaussian_filter(scratched, dx, lc);
  const FilteredProfile robust = robust_gaussian_filter(scratched, dx, lc);
  ASSERT_EQ(robust.mean_mm.size(), reference.mean_mm.size());
  double plain_off = 0, robust_off = 0;
  for (std::size_t i = 0; i < reference.mean_mm.size(); ++i) {
    plain_off = std::max(plain_off, std::abs(plain.mean_mm[i] - reference.mean_mm[i]));
    robust_off = std::max(robust_off, std::abs(robust.mean_mm[i] - reference.mean_mm[i]));
  }
  const double alpha = std::sqrt(std::log(2.0) / std::numbers::pi);
  EXPECT_NEAR(plain_off / (4e-4 / (alpha * lc)), 1.0, 0.05);
  EXPECT_LT(robust_off, 0.1 * plain_off);
  ProfileFilterOptions o;
  o.robust = true;
  const ProfileTexture t = profile_texture(scratched, dx, lc, o);
  EXPECT_TRUE(t.robust);
  EXPECT_GT(t.roughness.rv_mm, 0.015);
  // lambda_s: a 2.5 um short-wave filter leaves the 0.05 mm texture (transmission
  // exp(-pi (alpha 0.0025 / 0.05)^2) = 0.998) and is stated.
  ProfileFilterOptions s;
  s.lambda_s_mm = 0.0025;
  const ProfileTexture ts = profile_texture(clean, dx, lc, s);
  const ProfileTexture t0 = profile_texture(clean, dx, lc);
  EXPECT_EQ(ts.lambda_s_mm, 0.0025);
  EXPECT_NEAR(ts.roughness.ra_mm / t0.roughness.ra_mm, gaussian_transmission(0.05, 0.0025), 1e-3);
  s.lambda_s_mm = 0.9;
  EXPECT_THROW((void)profile_texture(clean, dx, lc, s), InputError);
}

// One period of a periodic profile: a short wave (lambda_c / 16) keeps all of its amplitude
// in the R profile (the mean line takes exp(-pi 16^2 alpha^2) of it: nothing), so Ra = 2A/pi
// within 1e-4 and the W profile is flat; its Ra of 1.27 um takes the 0.8 mm default cut-off,
// one of 0.064 um the 0.25 mm one. A long wave of five cut-offs (4 mm) and amplitude B goes
// to the W profile at exp(-pi (alpha 0.8 / 4)^2) = 0.9727: Wt = 2 B times that, within 1e-3
// (the evaluation length holds one whole period of it, its crest and trough samples).
TEST(Texture, PeriodicProfileTextureChoosesTheCutOffAndSplitsRFromW) {
  const double A = 0.002, period = 4.0, dx = period / 16000;
  std::vector<double> z(16000);
  for (std::size_t i = 0; i < z.size(); ++i) {
    z[i] = A * std::sin(2 * std::numbers::pi * 80 * static_cast<double>(i) / 16000);  // 0.05 mm
  }
  ProfileTexture t = periodic_profile_texture(z, dx);
  EXPECT_EQ(t.cutoff_mm, 0.8);
  EXPECT_EQ(t.cutoff_source, "ISO 21920-3 default from Ra");
  EXPECT_NEAR(t.roughness.ra_mm, 2 * A / std::numbers::pi, 1e-4 * A);
  EXPECT_LT(t.wt_mm, 1e-6 * A);
  EXPECT_EQ(t.roughness.sections, 5);
  std::vector<double> small = z;
  for (double& v : small) v *= 0.05;  // Ra 0.064 um
  EXPECT_EQ(periodic_profile_texture(small, dx).cutoff_mm, 0.25);
  const double B = 0.01;
  for (std::size_t i = 0; i < z.size(); ++i) {
    z[i] += B * std::sin(2 * std::numbers::pi * static_cast<double>(i) / 16000);
  }
  t = periodic_profile_texture(z, dx, 0.8);
  EXPECT_EQ(t.cutoff_source, "given");
  EXPECT_NEAR(t.wt_mm, 2 * B * gaussian_transmission(4.0, 0.8), 1e-3 * 2 * B);
}

// Straight full-immersion slotting: the wall along the feed carries one cusp per tooth pass,
// f_z apart and f_z^2 / (8 R) high (the kinematic roughness of the tooth-tip circles). The
// tooth-level wall's Rz equals that within 5 % (the tips' trochoids are not quite circles:
// the feed adds f_z / (2 pi R) of curvature), Rsm the cusp spacing f_z within 1 %.
TEST(Texture, StraightSlotWallsGiveTheKinematicCusp) {
  const Job job = test::straight_job(10.0);
  const double fz = job.cutting.feed_per_tooth_mm, R = job.tool.radius_mm();
  ToolPath p;
  p.append(Segment::line(Vec3(0, 0, -6), Vec3(0, 3, -6), Motion::feed,
                         job.cutting.feed_rate_mm_per_min));
  const PathSamples s = sample_by_spindle_angle(p, 3600, job.cutting.spindle_speed_rpm);
  const ToothTracks tr = tooth_tracks(s, job.tool, job.cutting);
  // Only tips within 0.05 mm of the wall (the cusps are 0.14 um deep).
  // 200 points a cusp: the sharp crest is missed by at most its slope f_z / 2R times half a
  // spacing, 1 % of the cusp height.
  const Walls w = walls_from_tips(tr, 0.0, 1.5, 1.5 + fz, 201, 0.05);
  std::vector<double> z(w.left.x_mm.begin(), w.left.x_mm.end() - 1);
  const ProfileTexture t = periodic_profile_texture(z, fz / 200);
  EXPECT_NEAR(t.roughness.rz_mm, fz * fz / (8 * R), 0.05 * fz * fz / (8 * R));
  EXPECT_NEAR(t.roughness.rsm_mm, fz, 0.01 * fz);
}

// A simulation's walls.csv: the level nearest the z asked for (the middle one by default),
// sorted along y, each wall material side up; a gap in y is named by its line.
TEST(Texture, WallProfilesFromASimulationsWallsCsv) {
  const std::string csv =
      "y_mm,z_mm,left_x_mm,right_x_mm\n"
      "0.2,-1,-10.2,10.2\n0.0,-1,-10.0,10.0\n0.1,-1,-10.1,10.1\n"
      "0.0,-2,-9.0,9.0\n0.1,-2,-9.1,9.1\n0.2,-2,-9.2,9.2\n"
      "0.0,-3,-8.0,8.0\n0.1,-3,-8.1,8.1\n0.2,-3,-8.2,8.2\n";
  const MeasuredProfile mid = read_wall_profile_csv(csv, "walls.csv", true);
  EXPECT_EQ(mid.z_mm, (std::vector<double>{-9.0, -9.1, -9.2}));
  EXPECT_NEAR(mid.dx_mm, 0.1, 1e-15);
  const MeasuredProfile right = read_wall_profile_csv(csv, "walls.csv", false, -0.9);
  EXPECT_EQ(right.z_mm, (std::vector<double>{-10.0, -10.1, -10.2}));
  try {
    (void)read_wall_profile_csv(
        "y_mm,z_mm,left_x_mm,right_x_mm\n0,-1,1,1\n0.1,-1,1,1\n0.3,-1,1,1\n", "w.csv", true);
    ADD_FAILURE() << "a gap was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("w.csv:4:"), std::string::npos) << e.what();
  }
}

// A simulation stopped mid-slot: the walls (x = -+10 mm, a 2 um sine of 0.5 mm period) up to
// y = 8 mm, then the front arc of radius 10 mm about (0, 8). The machined part alone is
// measured (with the arc its waviness was the arc's, hundreds of um); a window whose walls
// are all front is refused.
TEST(Texture, WallProfilesOfASimulationLeaveOutTheFrontArc) {
  std::string csv = "y_mm,z_mm,left_x_mm,right_x_mm\n";
  const double amp = 0.002, period = 0.5;
  for (int i = 0; i <= 1800; ++i) {
    const double y = i * 0.01;
    const double x =
        y <= 8 ? 10 - amp * std::sin(2 * kPi * y / period) : std::sqrt(100 - (y - 8) * (y - 8));
    csv += fmt::format("{:.2f},-1,{:.9f},{:.9f}\n", y, -x, x);
  }
  const MeasuredProfile all = read_wall_profile_csv(csv, "walls.csv", true);
  EXPECT_EQ(all.z_mm.size(), 1801u);
  const MeasuredProfile left = read_wall_profile_csv(csv, "walls.csv", true, {}, true);
  // Kept: y up to 18 - 10.002 = 7.998 mm (the wall's distance from the centre line is its
  // deepest point's, 10 mm and the sine's 2 um), so the samples 0 to 7.99 mm.
  EXPECT_EQ(left.z_mm.size(), 800u);
  EXPECT_NE(left.description.find("the front arc, y 8 to 18 mm, left out"), std::string::npos)
      << left.description;
  for (const double z : left.z_mm) EXPECT_NEAR(z, -10.0, amp + 1e-9);
  const MeasuredProfile right = read_wall_profile_csv(csv, "walls.csv", false, {}, true);
  EXPECT_EQ(right.z_mm.size(), 800u);
  std::string front = "y_mm,z_mm,left_x_mm,right_x_mm\n";
  for (int i = 0; i <= 100; ++i) {
    const double y = i * 0.1, x = std::sqrt(100 - y * y);
    front += fmt::format("{:.1f},-1,{:.9f},{:.9f}\n", y, -x, x);
  }
  EXPECT_NE(test::message_of([&] {
              (void)read_wall_profile_csv(front, "w.csv", true, {}, true);
            }).find("is all front arc"),
            std::string::npos);
  // What is left of a short window (2.3 mm) holds no three cut-offs of 0.8 mm, where the
  // default's table starts: the default is the series' nearest that fits, 0.25 mm, with a
  // note (it was an error). The sine's 0.5 mm period is then waviness: Wa = 2 um x 2 / pi
  // times the Gaussian filter's transmission at 0.5 mm, within 5 % (the evaluation length,
  // 1.8 mm, holds 3.6 periods: the mean over it is not the whole periods' mean).
  const std::vector<double> short_wall(left.z_mm.begin(), left.z_mm.begin() + 231);
  const ProfileTexture t = profile_texture(short_wall, 0.01);
  EXPECT_EQ(t.cutoff_mm, 0.25);
  EXPECT_NE(t.cutoff_source.find("0.8 mm, where the default's table starts, does not fit"),
            std::string::npos)
      << t.cutoff_source;
  const double wa = amp * 2 / kPi * gaussian_transmission(0.5, 0.25);
  EXPECT_NEAR(t.wa_mm, wa, 0.05 * wa);
}

}  // namespace
}  // namespace trochomill
