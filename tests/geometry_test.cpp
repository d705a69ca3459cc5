// Geometry: boxes, planar contours (lengths, exact areas and distances against sampled ones) and
// offsets through Clipper against closed forms and the exact distance to the input.
#include "trochomill/geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "trochomill/error.hpp"
#include "trochomill/units.hpp"

using namespace trochomill;

namespace {

// The distance from p to the piece by dense sampling: an independent check of the exact
// distance (the sampled point nearest p is within half a sample spacing of the true nearest).
double sampled_distance(const ContourPiece& k, const Vec2& p, int n) {
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= n; ++i) d = std::min(d, (k.point_at(double(i) / n) - p).norm());
  return d;
}

// Every vertex of the offset lies between d - tol and d + tol from the input (the offset's
// definition); returns the largest deviation seen.
double largest_deviation(const std::vector<Contour>& out, const std::vector<Contour>& in,
                         double d) {
  double worst = 0;
  for (const Contour& c : out) {
    for (const ContourPiece& k : c.pieces) {
      double dist = std::numeric_limits<double>::infinity();
      for (const Contour& i : in) dist = std::min(dist, i.distance_mm(k.start));
      worst = std::max(worst, std::abs(dist - d));
    }
  }
  return worst;
}

double perimeter(const std::vector<Contour>& cs) {
  double s = 0;
  for (const Contour& c : cs) s += c.length_mm();
  return s;
}

}  // namespace

TEST(Geometry, BoxStartsEmptyAndGrowsByPoints) {
  Box3 b;
  EXPECT_TRUE(b.empty());
  EXPECT_EQ(b.volume_mm3(), 0.0);
  b.extend(Vec3(1, 2, 3));
  EXPECT_FALSE(b.empty());
  EXPECT_EQ(b.volume_mm3(), 0.0);
  b.extend(Vec3(-1, 4, 0));
  EXPECT_EQ(b.lo, Vec3(-1, 2, 0));
  EXPECT_EQ(b.hi, Vec3(1, 4, 3));
  EXPECT_DOUBLE_EQ(b.volume_mm3(), 2.0 * 2.0 * 3.0);
  EXPECT_TRUE(b.contains(Vec3(0, 3, 1)));
  EXPECT_FALSE(b.contains(Vec3(0, 5, 1)));
}

// An arc's length, sweep, points and tangent against its closed forms, both ways round; its
// exact distance against dense sampling at random points inside, outside and beyond its ends.
TEST(Geometry, ArcsAndLinesMeasureExactly) {
  const Vec2 c(1.0, -2.0);
  const double r = 5.0;
  const auto at = [&](double deg) {
    return Vec2(c + r * Vec2(std::cos(deg_to_rad(deg)), std::sin(deg_to_rad(deg))));
  };
  const ContourPiece a = ContourPiece::arc(at(30), at(150), c, true);
  EXPECT_NEAR(a.sweep_rad(), deg_to_rad(120), 1e-14);
  EXPECT_NEAR(a.length_mm(), r * deg_to_rad(120), 1e-12);
  EXPECT_NEAR((a.point_at(0.5) - at(90)).norm(), 0, 1e-12);
  EXPECT_NEAR((a.tangent_at(0.5) - Vec2(-1, 0)).norm(), 0, 1e-12);
  const ContourPiece b = a.reversed();  // clockwise, 120 degrees back
  EXPECT_NEAR(b.sweep_rad(), -deg_to_rad(120), 1e-14);
  EXPECT_NEAR((b.tangent_at(0.5) - Vec2(1, 0)).norm(), 0, 1e-12);
  const ContourPiece big = ContourPiece::arc(at(150), at(30), c, true);  // the other 240
  EXPECT_NEAR(big.sweep_rad(), deg_to_rad(240), 1e-14);
  const ContourPiece full = ContourPiece::arc(at(10), at(10), c, false);
  EXPECT_NEAR(full.sweep_rad(), -kTwoPi, 1e-15);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-12.0, 12.0);
  // 100,000 samples on a 5 mm arc of 240 degrees (the longest piece, 21 mm): spacing 2.1e-4 mm,
  // so the sampled distance exceeds the exact one by at most 1.05e-4 mm, never falls below it.
  for (const ContourPiece& k : {a, b, big, full, ContourPiece::line(at(0), at(200))}) {
    for (int i = 0; i < 40; ++i) {
      const Vec2 p(u(rng), u(rng));
      const double exact = k.distance_mm(p), sampled = sampled_distance(k, p, 100000);
      EXPECT_LE(exact, sampled + 1e-12);
      EXPECT_GE(exact, sampled - 1.1e-4);
    }
  }
}

// Signed areas with arcs exact: a circle, a slot outline (stadium), a square with a
// semicircular notch; against the shoelace of a polyline within 1e-7 mm of the contour
// (its area error is below perimeter x 1e-7).
TEST(Geometry, SignedAreaIsExactWithArcs) {
  const Contour circle = Contour::circle(Vec2(3, 4), 2.5);
  EXPECT_NEAR(circle.signed_area_mm2(), kPi * 2.5 * 2.5, 1e-12);
  EXPECT_NEAR(circle.reversed().signed_area_mm2(), -kPi * 2.5 * 2.5, 1e-12);
  EXPECT_TRUE(circle.counter_clockwise());
  EXPECT_NEAR(circle.length_mm(), kTwoPi * 2.5, 1e-12);

  Contour stadium;  // a 20 mm slot of width 6: two lines, two half circles
  stadium.closed = true;
  stadium.pieces = {
      ContourPiece::line({0, -3}, {20, -3}), ContourPiece::arc({20, -3}, {20, 3}, {20, 0}, true),
      ContourPiece::line({20, 3}, {0, 3}), ContourPiece::arc({0, 3}, {0, -3}, {0, 0}, true)};
  EXPECT_NEAR(stadium.signed_area_mm2(), 20 * 6 + kPi * 9, 1e-12);

  Contour notch;  // a 10 mm square with a half disc of radius 2 cut from its top edge
  notch.closed = true;
  notch.pieces = {
      ContourPiece::line({0, 0}, {10, 0}),   ContourPiece::line({10, 0}, {10, 10}),
      ContourPiece::line({10, 10}, {7, 10}), ContourPiece::arc({7, 10}, {3, 10}, {5, 10}, false),
      ContourPiece::line({3, 10}, {0, 10}),  ContourPiece::line({0, 10}, {0, 0})};
  EXPECT_NEAR(notch.signed_area_mm2(), 100 - kPi * 2, 1e-12);
  for (const Contour* c : std::vector<const Contour*>{&circle, &stadium, &notch}) {
    const std::vector<Vec2> p = c->points(1e-7);
    double shoelace = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec2& a = p[i];
      const Vec2& b = p[(i + 1) % p.size()];
      shoelace += 0.5 * (a.x() * b.y() - b.x() * a.y());
    }
    EXPECT_NEAR(shoelace, c->signed_area_mm2(), c->length_mm() * 1e-7);
    for (const Vec2& q : p) EXPECT_LT(c->distance_mm(q), 1e-12);
  }
  EXPECT_THROW((void)Contour::polyline({{0, 0}, {1, 0}}, false).signed_area_mm2(),
               std::logic_error);
}

// A region grown and shrunk: a square's offsets against their closed forms (the grown square
// has quarter circles at its corners), every vertex at the offset distance from the square
// (exact distance) within the tolerance, outer boundaries counter-clockwise, the same result
// whichever way the input runs.
TEST(Geometry, OffsetsOfASquareMatchTheirClosedForms) {
  const double s = 20, d = 2, tol = 0.001;
  const std::vector<Contour> square = {Contour::polyline({{0, 0}, {s, 0}, {s, s}, {0, s}}, true)};
  const std::vector<Contour> grown = offset_region(square, d, tol);
  ASSERT_EQ(grown.size(), 1u);
  EXPECT_TRUE(grown[0].counter_clockwise());
  // Chords inside the corner arcs lose at most perimeter x tol of area; the 1 nm grid less.
  EXPECT_NEAR(region_area_mm2(grown), s * s + 4 * s * d + kPi * d * d, perimeter(grown) * tol);
  EXPECT_LE(largest_deviation(grown, square, d), tol);
  const std::vector<Contour> shrunk = offset_region(square, -d, tol);
  ASSERT_EQ(shrunk.size(), 1u);
  EXPECT_NEAR(region_area_mm2(shrunk), (s - 2 * d) * (s - 2 * d), 1e-9 * s * s);
  EXPECT_LE(largest_deviation(shrunk, square, d), 1e-6);  // straight sides: the grid only
  // The same region drawn clockwise gives the same offset, vertex for vertex.
  const std::vector<Contour> again = offset_region({square[0].reversed()}, d, tol);
  ASSERT_EQ(again.size(), 1u);
  ASSERT_EQ(again[0].pieces.size(), grown[0].pieces.size());
  for (std::size_t i = 0; i < again[0].pieces.size(); ++i) {
    EXPECT_EQ(again[0].pieces[i].start, grown[0].pieces[i].start);
  }
  // Shrunk past its half width the region vanishes.
  EXPECT_TRUE(offset_region(square, -10.5, tol).empty());
}

// A pocket with an island (a disc of radius 10 around one of radius 4, 0.5 off centre, even-odd:
// the island is a hole whichever way it runs): offset outward by 1, the boundary grows to 11 and
// the island shrinks to 3; inward by 2.5 the ring keeps 7.5 and 6.5. Orientations: outer
// counter-clockwise, hole clockwise. Arcs in, chords out: each vertex within tol.
TEST(Geometry, OffsetsOfARegionWithAnIsland) {
  const double tol = 0.002;
  const std::vector<Contour> ring = {Contour::circle({0, 0}, 10), Contour::circle({0.5, 0}, 4)};
  for (const double d : {1.0, -2.5}) {
    const std::vector<Contour> out = offset_region(ring, d, tol);
    ASSERT_EQ(out.size(), 2u) << d;
    EXPECT_TRUE(out[0].counter_clockwise());
    EXPECT_FALSE(out[1].counter_clockwise());
    const double ro = 10 + d, ri = 4 - d;
    EXPECT_NEAR(region_area_mm2(out), kPi * (ro * ro - ri * ri), perimeter(out) * tol) << d;
    EXPECT_LE(largest_deviation(out, ring, std::abs(d)), tol) << d;
  }
}

// The region within w of a curve: a straight open line gives a stadium (2 w L + pi w^2); an arc
// of radius R through 90 degrees gives the annular sector and two half discs (2 theta R w +
// pi w^2); a closed circle gives a ring. Vertices within tol of w from the curve.
TEST(Geometry, OffsetOfACurveIsTheSlotAroundIt) {
  const double w = 3, tol = 0.001;
  const Contour line = Contour::polyline({{0, 0}, {30, 0}}, false);
  const std::vector<Contour> slot = offset_curve(line, w, tol);
  ASSERT_EQ(slot.size(), 1u);
  EXPECT_NEAR(region_area_mm2(slot), 2 * w * 30 + kPi * w * w, perimeter(slot) * tol);
  EXPECT_LE(largest_deviation(slot, {line}, w), tol);

  const double R = 25, th = kPi / 2;
  Contour bend;
  bend.pieces = {ContourPiece::arc({R, 0}, {0, R}, {0, 0}, true)};
  const std::vector<Contour> curved = offset_curve(bend, w, tol);
  ASSERT_EQ(curved.size(), 1u);
  EXPECT_NEAR(region_area_mm2(curved), 2 * th * R * w + kPi * w * w, perimeter(curved) * tol);
  EXPECT_LE(largest_deviation(curved, {bend}, w), tol);

  const Contour loop = Contour::circle({5, 5}, 12);
  const std::vector<Contour> band = offset_curve(loop, w, tol);
  ASSERT_EQ(band.size(), 2u);
  EXPECT_NEAR(region_area_mm2(band), kPi * (15 * 15 - 9 * 9), perimeter(band) * tol);
  EXPECT_LE(largest_deviation(band, {loop}, w), tol);
}

TEST(Geometry, BadContoursAreRefusedWithWhatIsWrong) {
  const Contour open = Contour::polyline({{0, 0}, {1, 0}, {1, 1}}, false);
  try {
    (void)offset_region({Contour::circle({0, 0}, 1), open}, 1, 0.01);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("contour 2 is open"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)offset_region({Contour::circle({0, 0}, 1)}, 1, 0), InputError);
  EXPECT_THROW((void)offset_curve(open, 0, 0.01), InputError);
  EXPECT_THROW((void)offset_curve(open, 1, 100), InputError);
  try {
    (void)offset_region({Contour::circle({2e6, 0}, 1)}, 1, 0.01);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("within 1 km"), std::string::npos) << e.what();
  }
  // 25 circles of 900 m at the finest tolerance need 2.4e7 chords: refused before any is made.
  std::vector<Contour> huge;
  for (int i = 0; i < 25; ++i) huge.push_back(Contour::circle({0, 0}, 9e5 - i));
  EXPECT_THROW((void)offset_region(huge, 1, 1e-5), InputError);

  Contour gap;
  gap.closed = true;
  gap.pieces = {ContourPiece::line({0, 0}, {10, 0}), ContourPiece::line({10, 0.01}, {0, 0})};
  try {
    gap.check(0.001);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("piece 2 starts 0.01 mm from where piece 1 ends"),
              std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(gap.check(0.02));
}
