// Surface geometry: walls as envelopes of circles and of tip polylines, floor imprints,
// against closed forms.
#include "trochomill/surface.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "trochomill/error.hpp"

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

}  // namespace
}  // namespace trochomill
