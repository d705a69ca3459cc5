// Geometry: boxes, planar contours (lengths, exact areas and distances against sampled ones) and
// offsets through Clipper against closed forms and the exact distance to the input.
#include "trochomill/geometry.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"
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

// An SVG document written to a file of its own in the temporary directory.
std::filesystem::path svg_file(const std::string& name, const std::string& text) {
  const auto file = test::scratch_dir("geometry-svg") / name;
  std::ofstream(file, std::ios::binary) << text;
  return file;
}

// The contour that begins with the element `entity` ("rect #a"); fails the test when none does.
const DrawnContour& contour_of(const Drawing& d, const std::string& entity) {
  for (const DrawnContour& c : d.contours) {
    if (!c.entities.empty() && c.entities.front() == entity) return c;
  }
  ADD_FAILURE() << "no contour of " << entity;
  static const DrawnContour none;
  return none;
}

// The box of a contour from chords within a nanometre of it.
std::pair<Vec2, Vec2> box_of(const Contour& c) {
  Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
  for (const Vec2& p : c.points(1e-6)) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  return {lo, hi};
}

std::size_t arcs_in(const Contour& c) {
  return static_cast<std::size_t>(std::count_if(c.pieces.begin(), c.pieces.end(),
                                                [](const ContourPiece& p) { return p.is_arc(); }));
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

// The plan view of a mesh between two heights, against closed forms and against the vertical
// line itself. The block (80 x 80 mm, 10 deep) has a cored cavity of 32 sides, radius 12 mm at
// the top and 8 mm at its floor 6 mm down (a drafted core): between z0 and z1 the solid is the
// square less the cavity where it is narrowest, at z0 (its n-gon's area (n / 2) r^2 sin(2 pi /
// n)); at or below the cavity's floor, the whole square; above the block, nothing. Clipper's 1
// nm grid moves each of the few hundred vertices by 0.5 nm: the areas hold to 1e-4 mm^2.
// Then 2000 random points of the block's plan (and beside it) are tested with line_crossing
// (each crossing of the vertical line with a face; the solid lies between crossings 1-2, 3-4,
// ...): inside the region exactly when one of those intervals meets [z0, z1]. The mesh's own
// orientation first: its signed volume (divergence theorem) is the block's less the frustum's.
TEST(Geometry, AMeshsPlanViewBetweenTwoHeights) {
  const int n = 32;
  const double h = 40, bottom = -10, rt = 12, rf = 8, zf = -6;
  const Mesh m = test::cored_block_mesh(h, bottom, rt, rf, zf, n);
  auto ngon = [&](double r) { return 0.5 * n * r * r * std::sin(2 * kPi / n); };
  double vol = 0;
  for (const auto& t : m.triangles) {
    const Vec3& a = m.vertices[t[0]];
    vol += a.dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6;
  }
  const double frustum = -zf / 3 * (ngon(rt) + ngon(rf) + std::sqrt(ngon(rt) * ngon(rf)));
  EXPECT_NEAR(vol, 4 * h * h * -bottom - frustum, 1e-9 * 4 * h * h * -bottom);
  auto radius_at = [&](double z) { return rf + (rt - rf) * (z - zf) / -zf; };
  const double square = 4 * h * h;
  struct Case {
    double z0, z1, area;
  };
  const Case cases[] = {
      {-4, -1, square - ngon(radius_at(-4))},  // across the cavity
      {-2, -2, square - ngon(radius_at(-2))},  // a section
      {-4, 5, square - ngon(radius_at(-4))},   // up past the top
      {-6, -3, square},                        // the cavity's floor: met at its height
      {-9, -7, square},                        // below the cavity
      {-30, -20, 0},                           // below the block
      {1, 2, 0},                               // above it
  };
  for (const Case& c : cases) {
    const auto region = mesh_plan_region(m, c.z0, c.z1);
    EXPECT_NEAR(region_area_mm2(region), c.area, 1e-4) << c.z0 << " " << c.z1;
  }
  // The vertical line's own answer, for a tilted block too (its top from z = -1 to -5).
  const Mesh tilted = test::block_mesh(-20, 30, -10, 25, -12, {-1, -3, -3, -5});
  std::mt19937 rng(7);
  for (const Mesh* mesh : {&m, &tilted}) {
    for (const auto& [z0, z1] : {std::pair{-4.0, -1.0}, std::pair{-3.5, -3.0}, std::pair{-8.0, 0.0},
                                 std::pair{-2.0, -2.0}}) {
      const auto region = mesh_plan_region(*mesh, z0, z1);
      std::uniform_real_distribution<double> u(-45, 45);
      int disagree = 0, inside = 0;
      for (int k = 0; k < 1000; ++k) {
        const double x = u(rng), y = u(rng);
        std::vector<double> zs;
        for (const auto& t : mesh->triangles) {
          if (auto z = line_crossing(mesh->vertices[t[0]], mesh->vertices[t[1]],
                                     mesh->vertices[t[2]], 2, x, y)) {
            zs.push_back(*z);
          }
        }
        std::sort(zs.begin(), zs.end());
        ASSERT_EQ(zs.size() % 2, 0u) << x << " " << y;
        bool meets = false;
        for (std::size_t q = 0; q + 1 < zs.size(); q += 2) meets |= zs[q] <= z1 && zs[q + 1] >= z0;
        inside += meets;
        disagree += meets != region_contains(region, Vec2(x, y));
      }
      EXPECT_EQ(disagree, 0) << z0 << " " << z1;
      EXPECT_GT(inside, 10);  // the test sees the solid (the tilted top's corner above -2: 25)
    }
  }
  EXPECT_NE(
      test::message_of([&] { (void)mesh_plan_region(m, -1, -2); }).find("the first the lower"),
      std::string::npos);
  Mesh broken = m;
  broken.triangles.push_back({0, 1, 99999});
  EXPECT_NE(test::message_of([&] { (void)mesh_plan_region(broken, -2, -1); }), "no error");
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

// ---------------------------------------------------------------------------------------------
// SVG drawings (read_svg). Lines and circular arcs are exact, so their lengths and areas match
// the closed forms to rounding (1e-9 relative). Curves fitted with biarcs lie within the arc
// tolerance (0.002 mm) of the curve, so their area moves by at most perimeter x tolerance and
// their length by far less (second order); those bounds are the tolerances used.

constexpr const char* kSvgHead =
    R"svg(<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="100mm" viewBox="0 0 200 100">)svg";

TEST(Geometry, SvgShapesMeasureAsTheirClosedForms) {
  const auto file = svg_file("shapes.svg", std::string(kSvgHead) + R"svg(
  <rect id="rounded" x="10" y="10" width="30" height="20" rx="5"/>
  <rect id="oval" x="50" y="10" width="30" height="20" rx="20" ry="4"/>
  <circle id="round" cx="100" cy="50" r="10"/>
  <ellipse id="egg" cx="150" cy="50" rx="8" ry="4"/>
  <polygon id="tri" points="10,90 40,90 10,60"/>
  <polyline id="zig" points="100 90 110 80 120 90"/>
  <line id="bar" x1="150" y1="80" x2="190" y2="80"/>
</svg>)svg");
  const Drawing d = read_svg(file, DrawingOptions{});
  EXPECT_EQ(d.units, "mm");
  EXPECT_NEAR(d.mm_per_unit, 1, 1e-12);
  ASSERT_EQ(d.contours.size(), 7u);
  const double tol = DrawingOptions{}.arc_tolerance_mm;

  // A rounded rectangle: w h - (4 - pi) r^2, drawn clockwise on the screen: clockwise.
  const Contour& rounded = contour_of(d, "rect #rounded").contour;
  EXPECT_TRUE(rounded.closed);
  EXPECT_NEAR(rounded.signed_area_mm2(), -(600 - (4 - kPi) * 25), 1e-9 * 600);
  EXPECT_NEAR(rounded.length_mm(), 2 * 20 + 2 * 10 + 10 * kPi, 1e-9 * 100);
  EXPECT_EQ(arcs_in(rounded), 4u);
  // y mirrored about the page's bottom edge (100 mm): y 10..30 on the screen is 70..90.
  const auto [lo, hi] = box_of(rounded);
  EXPECT_NEAR(lo.x(), 10, 1e-9);
  EXPECT_NEAR(lo.y(), 70, 1e-9);
  EXPECT_NEAR(hi.x(), 40, 1e-9);
  EXPECT_NEAR(hi.y(), 90, 1e-9);

  // rx beyond half the width is clamped to 15: w h - (4 - pi) rx ry, corners as biarcs.
  const Contour& oval = contour_of(d, "rect #oval").contour;
  EXPECT_NEAR(std::abs(oval.signed_area_mm2()), 600 - (4 - kPi) * 15 * 4, oval.length_mm() * tol);

  const Contour& round = contour_of(d, "circle #round").contour;
  EXPECT_NEAR(round.signed_area_mm2(), -100 * kPi, 1e-9 * 314);
  EXPECT_NEAR(round.length_mm(), 20 * kPi, 1e-9 * 63);
  EXPECT_EQ(arcs_in(round), 2u);
  EXPECT_EQ(round.pieces.size(), 2u);

  const Contour& egg = contour_of(d, "ellipse #egg").contour;
  EXPECT_NEAR(std::abs(egg.signed_area_mm2()), kPi * 8 * 4, egg.length_mm() * tol);

  // A triangle drawn counter-clockwise on the screen stays counter-clockwise.
  const Contour& tri = contour_of(d, "polygon #tri").contour;
  EXPECT_NEAR(tri.signed_area_mm2(), 450, 1e-9 * 450);

  const DrawnContour& zig = contour_of(d, "polyline #zig");
  EXPECT_FALSE(zig.contour.closed);
  EXPECT_NEAR(zig.contour.length_mm(), 2 * std::sqrt(200.0), 1e-12);
  const Contour& bar = contour_of(d, "line #bar").contour;
  EXPECT_NEAR(bar.length_mm(), 40, 1e-12);
  EXPECT_NEAR(bar.pieces.front().start.y(), 20, 1e-12);
  EXPECT_EQ(zig.layer, "0");
}

TEST(Geometry, SvgPathCommandsDrawWhatTheyDescribe) {
  const auto file = svg_file("paths.svg", std::string(kSvgHead) + R"svg(
  <path id="semi" d="M10 30 A10 10 0 0 1 30 30 Z"/>
  <path id="small-radii" d="M40 30 a 1 1 0 0 1 20 0 z"/>
  <path id="flat" d="M70 30 A 0 5 0 0 1 90 30"/>
  <path id="box" d="m 100 10 h 20 v 10 h -20 z"/>
  <path id="parabola" d="M130 30 Q 140 10 150 30 Z"/>
  <path id="numbers" d="M160,30l1.5e1-0 0-.5-14.5.0z"/>
  <path id="cubic-abs" d="M10 60 C 15 50 20 50 25 60 S 35 70 40 60 Q 45 55 50 60 T 60 60 A 5 3 30 1 0 70 60"/>
  <path id="cubic-rel" d="m10 70c5-10 10-10 15 0s10 10 15 0q5-5 10 0t10 0a5,3,30,1,0,10,0"/>
  <path id="cubic-full" d="M10 80 C 15 70 20 70 25 80 C 30 90 35 90 40 80 Q 45 75 50 80 Q 55 85 60 80 A 5 3 30 1 0 70 80"/>
  <path id="flags" d="M100 60a10 10 0 00 20 0"/>
  <path id="flags-spaced" d="M100 80 a 10 10 0 0 0 20 0"/>
</svg>)svg");
  const Drawing d = read_svg(file, DrawingOptions{});
  const double tol = DrawingOptions{}.arc_tolerance_mm;
  // A half circle over its diameter (sweep 1: clockwise on the screen, above the chord).
  const Contour& semi = contour_of(d, "path #semi").contour;
  EXPECT_NEAR(semi.signed_area_mm2(), -50 * kPi, 1e-9 * 157);
  EXPECT_NEAR(semi.length_mm(), 20 + 10 * kPi, 1e-9 * 51);
  // The top: y 30 - 10 on the screen, 80 mm up (box_of's chords stray 1e-6 mm inside).
  EXPECT_NEAR(box_of(semi).second.y(), 80, 1e-6);
  // Radii too small for the chord are scaled up (F.6.6): the same half circle.
  EXPECT_NEAR(contour_of(d, "path #small-radii").contour.signed_area_mm2(), -50 * kPi, 1e-9 * 157);
  // A zero radius: a line.
  const Contour& flat = contour_of(d, "path #flat").contour;
  EXPECT_EQ(arcs_in(flat), 0u);
  EXPECT_NEAR(flat.length_mm(), 20, 1e-12);
  EXPECT_NEAR(contour_of(d, "path #box").contour.signed_area_mm2(), -200, 1e-9 * 200);
  // A parabola over its chord: 2/3 base x height (20 x 10).
  EXPECT_NEAR(std::abs(contour_of(d, "path #parabola").contour.signed_area_mm2()), 400.0 / 3,
              60 * tol);
  // "1.5e1-0 0-.5-14.5.0": numbers without separators; a trapezoid of sides 15 and 14.5,
  // 0.5 high.
  EXPECT_NEAR(std::abs(contour_of(d, "path #numbers").contour.signed_area_mm2()),
              0.5 * (15 + 14.5) * 0.5, 1e-9);
  // Relative commands and the reflected control points of S and T draw what the absolute
  // ones with explicit control points do (10 mm lower); the same fit: lengths to rounding.
  const Contour& abs = contour_of(d, "path #cubic-abs").contour;
  const Contour& rel = contour_of(d, "path #cubic-rel").contour;
  const Contour& full = contour_of(d, "path #cubic-full").contour;
  EXPECT_NEAR(abs.length_mm(), rel.length_mm(), 1e-9);
  EXPECT_NEAR(abs.length_mm(), full.length_mm(), 1e-9);
  EXPECT_NEAR(abs.pieces.back().end.x(), 70, 1e-12);
  EXPECT_NEAR(rel.pieces.back().end.y(), 30, 1e-12);
  // Flags written without separators: the same arc (a half circle of radius 10).
  EXPECT_NEAR(contour_of(d, "path #flags").contour.length_mm(), 10 * kPi, 1e-9);
  EXPECT_NEAR(contour_of(d, "path #flags-spaced").contour.length_mm(), 10 * kPi, 1e-9);
}

// A cubic whose derivative vanishes inside (control points (0,0) (10,10) (0,10) (10,0): a cusp
// at t = 1/2, the point (5, 7.5)) folds back there; no biarc turns back, so before the reader
// split curves at their cusps the fit shrank its pieces towards the cusp without end (a fuzzed
// drawing hung for minutes). Read, it is a corner at the cusp and the curve elsewhere: the
// region it closes with its chord has the area Green's theorem gives the Bezier itself, within
// the length x the arc tolerance (each piece lies within it of the curve).
TEST(Geometry, SvgCuspIsACorner) {
  const auto file = svg_file("cusp.svg", std::string(kSvgHead) + R"svg(
  <path id="cusp" d="M 0 0 C 10 10 0 10 10 0 Z"/>
</svg>)svg");
  const Drawing d = read_svg(file, DrawingOptions{});
  const double tol = DrawingOptions{}.arc_tolerance_mm;
  const Contour& cusp = contour_of(d, "path #cusp").contour;
  // The Bezier B(t) in mm (y mirrored about 100 mm) and its Green integral, 1/2 (x y' - y x'),
  // by Simpson's rule on 20,000 intervals (a degree-5 integrand: exact to rounding).
  const auto B = [](double t) {
    const double s = 1 - t;
    return Vec2(3 * s * s * t * 10 + t * t * t * 10,
                100 - (3 * s * s * t * 10 + 3 * s * t * t * 10));
  };
  const auto dB = [](double t) {  // 3 ((1-t)^2 a + 2 t (1-t) b + t^2 c), a b c the legs
    const double s = 1 - t;
    return Vec2(3 * (s * s * 10 - 2 * t * s * 10 + t * t * 10), -3 * (s * s * 10 - t * t * 10));
  };
  const int n = 20000;
  const double h = 1.0 / n;
  double area = 0;
  for (int i = 0; i <= n; ++i) {
    const Vec2 p = B(i * h), dp = dB(i * h);
    const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    area += w * 0.5 * (p.x() * dp.y() - p.y() * dp.x());
  }
  area *= h / 3;
  // The chord back from (10, 100) to (0, 100): 1/2 (x y' - y x') = 1/2 (100 * 10).
  area += 0.5 * 100 * 10;
  EXPECT_NEAR(cusp.signed_area_mm2(), area, cusp.length_mm() * tol);
  // A piece ends on the cusp itself (the split point is exact to rounding).
  bool corner = false;
  for (const ContourPiece& p : cusp.pieces) corner |= (p.end - Vec2(5, 92.5)).norm() < 1e-9;
  EXPECT_TRUE(corner);
  // Every piece's end lies on the curve (within the tolerance).
  for (const ContourPiece& p : cusp.pieces) {
    if ((p.end - Vec2(0, 100)).norm() < 1e-9) continue;
    double best = 1e9;
    for (int i = 0; i <= 100000; ++i) best = std::min(best, (B(i * 1e-5) - p.end).norm());
    EXPECT_LT(best, tol) << p.end.transpose();
  }
}

// The same cusp as a NURBS (a cubic Bezier: knots 0 0 0 0 1 1 1 1, as a DXF spline gives it):
// no biarc turns back there (a DXF spline with it was refused); cusp_parameters finds it at
// u = 1/2 and fit_biarcs_at_cusps fits either side with its own tangent there, ending a piece on
// the cusp.
TEST(Geometry, NurbsCuspIsFittedAsACorner) {
  const NurbsCurve c(3, {0, 0, 0, 0, 1, 1, 1, 1}, {{0, 0, 0}, {10, 10, 0}, {0, 10, 0}, {10, 0, 0}},
                     {1, 1, 1, 1});
  const std::vector<double> cusps = cusp_parameters(c, 0, 1, 256);
  ASSERT_EQ(cusps.size(), 1u);
  EXPECT_NEAR(cusps[0], 0.5, 1e-9);
  const double tol = 0.002;
  const std::vector<FitArc> arcs = fit_biarcs_at_cusps(c, 0, 1, 4, tol);
  bool corner = false;
  for (std::size_t i = 0; i < arcs.size(); ++i) {
    const FitArc& a = arcs[i];
    corner |= (a.end - Vec3(5, 7.5, 0)).norm() < 1e-9;
    if (i > 0) {
      EXPECT_EQ(a.start, arcs[i - 1].end);  // a chain
    }
    // Each arc's middle within the tolerance of the curve (sampled every 1e-5).
    const ContourPiece piece = to_piece(a);
    const Vec2 mid = piece.point_at(0.5);
    double best = 1e9;
    for (int k = 0; k <= 100000; ++k) {
      const Vec3 q = c.point(k * 1e-5);
      best = std::min(best, (q.head<2>() - mid).norm());
    }
    EXPECT_LT(best, tol) << i;
  }
  EXPECT_TRUE(corner);
  // No cusp on a smooth curve: the same arcs as fit_biarcs.
  const NurbsCurve arch(3, {0, 0, 0, 0, 1, 1, 1, 1},
                        {{0, 0, 0}, {0, 10, 0}, {10, 10, 0}, {10, 0, 0}}, {1, 1, 1, 1});
  EXPECT_TRUE(cusp_parameters(arch, 0, 1, 256).empty());
  EXPECT_EQ(fit_biarcs_at_cusps(arch, 0, 1, 4, tol).size(), fit_biarcs(arch, 0, 1, 4, tol).size());
}

TEST(Geometry, SvgTransformsAndViewportsGiveMillimetres) {
  // A viewBox of 10 x 10 in one inch: a user unit is 2.54 mm.
  const Drawing inch = read_svg(svg_file("inch.svg", R"svg(<svg xmlns="http://www.w3.org/2000/svg"
      width="1in" height="1in" viewBox="0 0 10 10"><circle cx="5" cy="5" r="1"/></svg>)svg"),
                                DrawingOptions{});
  EXPECT_NEAR(inch.mm_per_unit, 2.54, 1e-12);
  EXPECT_EQ(inch.units, "user unit of 2.54 mm (viewBox)");
  ASSERT_EQ(inch.contours.size(), 1u);
  EXPECT_NEAR(std::abs(inch.contours[0].contour.signed_area_mm2()), kPi * 2.54 * 2.54, 1e-9);
  EXPECT_NEAR(box_of(inch.contours[0].contour).first.x(), 4 * 2.54, 1e-9);

  // No viewBox, unitless sizes: px at 96 per inch; y mirrored about the height (100 px).
  const Drawing px = read_svg(svg_file("px.svg", R"svg(<svg width="100" height="100">
      <rect width="96" height="96"/></svg>)svg"),
                              DrawingOptions{});
  EXPECT_EQ(px.units, "px (96 per in)");
  EXPECT_NEAR(std::abs(px.contours.at(0).contour.signed_area_mm2()), 25.4 * 25.4, 1e-9);
  EXPECT_NEAR(box_of(px.contours.at(0).contour).first.y(), 4 * 25.4 / 96, 1e-12);

  // xMidYMid meet: a 10 x 10 viewBox in 20 mm x 10 mm is 1 mm a unit, centred (5 mm in);
  // with "none" it is stretched twice as wide: a circle of 5 becomes a 10 x 5 ellipse.
  const std::string wide = R"svg(<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="10mm"
      viewBox="0 0 10 10" )svg";
  const Drawing meet =
      read_svg(svg_file("meet.svg", wide + R"svg(><rect width="10" height="10"/></svg>)svg"),
               DrawingOptions{});
  EXPECT_NEAR(box_of(meet.contours.at(0).contour).first.x(), 5, 1e-12);
  EXPECT_NEAR(box_of(meet.contours.at(0).contour).second.x(), 15, 1e-12);
  const Drawing none = read_svg(svg_file("none.svg", wide + R"svg(preserveAspectRatio="none">
      <circle cx="5" cy="5" r="5"/></svg>)svg"),
                                DrawingOptions{});
  const Contour& stretched = none.contours.at(0).contour;
  EXPECT_NEAR(std::abs(stretched.signed_area_mm2()), kPi * 10 * 5,
              stretched.length_mm() * DrawingOptions{}.arc_tolerance_mm);
  EXPECT_GT(stretched.pieces.size(), 2u);  // biarcs, not the two half circles

  // Nested groups: rotate(90) then translate(50, 50): the 20 x 10 rectangle stands at x 40..50,
  // y 50..70 on the screen (30..50 in mm, y up), still clockwise. A list "matrix(...)
  // scale(2)" scales first: a circle stays a circle (exact arcs). A skew keeps the area; a
  // mirror turns the orientation round (as the picture shows it).
  const Drawing t = read_svg(svg_file("transforms.svg", std::string(kSvgHead) + R"svg(
  <g transform="translate(50,50)"><g transform="rotate(90)">
    <rect id="turned" width="20" height="10"/></g></g>
  <circle id="scaled" transform="matrix(1 0 0 1 5 0) scale(2)" cx="10" cy="10" r="1"/>
  <rect id="skewed" transform="translate(100 10) skewX(45)" width="10" height="10"/>
  <rect id="mirrored" transform="translate(170 10) scale(-1, 1)" width="10" height="10"/>
  <g transform="rotate(90 150 50)"><circle id="about" cx="160" cy="50" r="2"/></g>
</svg>)svg"),
                             DrawingOptions{});
  const Contour& turned = contour_of(t, "rect #turned").contour;
  const auto [lo, hi] = box_of(turned);
  EXPECT_NEAR(lo.x(), 40, 1e-9);
  EXPECT_NEAR(lo.y(), 30, 1e-9);
  EXPECT_NEAR(hi.x(), 50, 1e-9);
  EXPECT_NEAR(hi.y(), 50, 1e-9);
  EXPECT_NEAR(turned.signed_area_mm2(), -200, 1e-9 * 200);
  const Contour& scaled = contour_of(t, "circle #scaled").contour;
  EXPECT_EQ(arcs_in(scaled), 2u);
  EXPECT_NEAR(std::abs(scaled.signed_area_mm2()), 4 * kPi, 1e-9);
  EXPECT_NEAR(scaled.pieces.front().centre->x(), 25, 1e-12);
  EXPECT_NEAR(scaled.pieces.front().centre->y(), 80, 1e-12);
  EXPECT_NEAR(std::abs(contour_of(t, "rect #skewed").contour.signed_area_mm2()), 100, 1e-9);
  EXPECT_NEAR(contour_of(t, "rect #mirrored").contour.signed_area_mm2(), 100, 1e-9);
  // rotate(90 150 50): the circle at (160, 50) turns to (150, 60) on the screen, 40 mm up.
  const Contour& about = contour_of(t, "circle #about").contour;
  EXPECT_NEAR(about.pieces.front().centre->x(), 150, 1e-9);
  EXPECT_NEAR(about.pieces.front().centre->y(), 40, 1e-9);
}

TEST(Geometry, SvgLayersAndIdsChooseWhatIsRead) {
  // Inkscape's namespace under another prefix; a layer's label beats the ids of groups in it.
  const auto file = svg_file("layers.svg", R"svg(<?xml version="1.0" encoding="UTF-8"?>
<svg xmlns="http://www.w3.org/2000/svg" xmlns:ink="http://www.inkscape.org/namespaces/inkscape"
     width="100mm" height="100mm" viewBox="0 0 100 100">
  <g ink:groupmode="layer" ink:label="Pocket" id="layer1">
    <g id="inner"><circle id="hole" cx="20" cy="20" r="5"/></g>
    <rect id="outline" x="40" y="10" width="20" height="20"/>
  </g>
  <g id="parts"><g><circle cx="70" cy="70" r="5"/></g></g>
  <circle cx="10" cy="90" r="2"/>
  <g style="fill:none;display: none"><circle id="hidden" cx="50" cy="50" r="3"/></g>
  <defs><circle id="defined" cx="50" cy="50" r="3"/></defs>
  <symbol id="sym"><circle cx="50" cy="50" r="3"/></symbol>
  <text id="label" x="5" y="5">a</text>
</svg>)svg");
  const Drawing all = read_svg(file, DrawingOptions{});
  EXPECT_EQ(all.layers, (std::vector<std::string>{"0", "Pocket", "parts"}));
  ASSERT_EQ(all.contours.size(), 4u);
  EXPECT_EQ(contour_of(all, "circle #hole").layer, "Pocket");
  EXPECT_EQ(all.contours[2].layer, "parts");
  EXPECT_EQ(all.contours[2].entities.front(), "circle (line 8)");
  const auto chosen = [&](std::vector<std::string> names) {
    DrawingOptions o;
    o.layers = std::move(names);
    return read_svg(file, o).contours.size();
  };
  EXPECT_EQ(chosen({"Pocket"}), 2u);
  EXPECT_EQ(chosen({"hole"}), 1u);
  EXPECT_EQ(chosen({"inner"}), 1u);  // a group's id: what it holds
  EXPECT_EQ(chosen({"0", "parts"}), 2u);
  const std::string missing = test::message_of([&] { (void)chosen({"Pocket", "nope"}); });
  EXPECT_NE(missing.find("no line, arc or curve in an element with the id or on the layer 'nope' "
                         "(the layers with shapes: 0, Pocket, parts; the ids: hole, inner, "
                         "layer1, outline, parts)"),
            std::string::npos)
      << missing;
  for (const char* skipped : {"hidden", "defined", "label"}) {
    EXPECT_NE(test::message_of([&] { (void)chosen({skipped}); }).find("no line, arc or curve"),
              std::string::npos)
        << skipped;
  }
}

// DXF groups libdxflib does not pass on, read as other writers write them: a spline-fit
// POLYLINE's frame (vertex flag 16) is not its curve; heights of -5e-14 are the plane z = 0;
// an LWPOLYLINE is named so; a file without handles names an entity by its line; an ellipse
// whose ratio is above 1 is the same ellipse with its axes named the other way round (its
// area pi a b in closed form); a file of points and text, or cut short, says so.
TEST(Geometry, DxfAsOtherWritersWriteIt) {
  const auto dir = std::filesystem::temp_directory_path() / "trochomill-dxf-test";
  std::filesystem::create_directories(dir);
  const auto read = [&](const std::string& entities, bool end = true) {
    std::ofstream(dir / "d.dxf") << "0\nSECTION\n2\nENTITIES\n"
                                 << entities << (end ? "0\nENDSEC\n0\nEOF\n" : "");
    return read_drawing(dir / "d.dxf", DrawingOptions{});
  };
  const auto vertex = [](double x, double y, int flags, const std::string& z = "0") {
    return fmt::format("0\nVERTEX\n8\nS\n10\n{}\n20\n{}\n30\n{}\n70\n{}\n", x, y, z, flags);
  };
  // Spline-fit (70 = 1 closed + 4): its frame, a 100 mm square, then its fitted vertices, a
  // 20 mm square (lines here: the test is which vertices are read).
  std::string poly = "0\nPOLYLINE\n8\nS\n66\n1\n70\n5\n";
  for (const auto& [x, y] :
       std::vector<std::pair<double, double>>{{0, 0}, {100, 0}, {100, 100}, {0, 100}})
    poly += vertex(x, y, 16);
  for (const auto& [x, y] :
       std::vector<std::pair<double, double>>{{40, 40}, {60, 40}, {60, 60}, {40, 60}})
    poly += vertex(x, y, 8);
  Drawing d = read(poly + "0\nSEQEND\n8\nS\n");
  ASSERT_EQ(d.contours.size(), 1u);
  EXPECT_DOUBLE_EQ(d.contours[0].contour.length_mm(), 80.0);  // the fitted square, not 400
  EXPECT_DOUBLE_EQ(std::abs(d.contours[0].contour.signed_area_mm2()), 400.0);
  // Heights of rounding: one plane (the same square at z 0 and -5e-14).
  poly = "0\nPOLYLINE\n8\nS\n66\n1\n70\n1\n" + vertex(40, 40, 0, "-5e-14") + vertex(60, 40, 0) +
         vertex(60, 60, 0, "-5e-14") + vertex(40, 60, 0) + "0\nSEQEND\n8\nS\n";
  d = read(poly);
  ASSERT_EQ(d.contours.size(), 1u);
  EXPECT_DOUBLE_EQ(d.contours[0].contour.length_mm(), 80.0);
  // A height that is one (a millimetre) is refused, with both heights.
  std::string m = test::message_of([&] {
    (void)read("0\nPOLYLINE\n8\nS\n66\n1\n70\n1\n" + vertex(40, 40, 0, "1") + vertex(60, 40, 0) +
               vertex(60, 60, 0) + "0\nSEQEND\n8\nS\n");
  });
  EXPECT_NE(m.find("a polyline out of the XY plane (its vertex 2 at z 0, its first at 1)"),
            std::string::npos)
      << m;
  // Three lines from one point, no handles: each named by the line its type is on.
  const std::string line = "0\nLINE\n8\nL\n10\n0\n20\n0\n11\n{}\n21\n{}\n";
  m = test::message_of([&] {
    (void)read(fmt::format(fmt::runtime(line), 10, 0) + fmt::format(fmt::runtime(line), 0, 10) +
               fmt::format(fmt::runtime(line), -10, 0));
  });
  // (Lines 6, 18 and 30: after the section's 4, a LINE's six groups take 12 lines.)
  EXPECT_NE(m.find("LINE at line 6, LINE at line 18, LINE at line 30 meet there"),
            std::string::npos)
      << m;
  // An LWPOLYLINE (handle A1) meeting two lines at its end: named as the file names it.
  m = test::message_of([&] {
    (void)read("0\nLWPOLYLINE\n5\nA1\n8\nL\n90\n2\n70\n0\n10\n0\n20\n0\n10\n0\n20\n-10\n" +
               fmt::format(fmt::runtime(line), 10, 0) + fmt::format(fmt::runtime(line), 0, 10));
  });
  EXPECT_NE(m.find("LWPOLYLINE #A1"), std::string::npos) << m;
  // Ellipses: semi-axes 10 and 20 given as ratio 2 about a 10 mm major axis, and as ratio 0.5
  // about the 20 mm one: the same curve (the fit within its 0.002 mm tolerance: areas within
  // 2 pi r t = 0.2 mm^2 of the closed form, lengths within 0.01 mm of each other).
  const std::string ellipse =
      "0\nELLIPSE\n8\nE\n10\n0\n20\n0\n30\n0\n11\n{}\n21\n{}\n31\n0\n"
      "40\n{}\n41\n0\n42\n6.283185307179586\n";
  const Drawing wide = read(fmt::format(fmt::runtime(ellipse), 10, 0, 2.0));
  const Drawing tall = read(fmt::format(fmt::runtime(ellipse), 0, 20, 0.5));
  ASSERT_EQ(wide.contours.size(), 1u);
  ASSERT_EQ(tall.contours.size(), 1u);
  EXPECT_NEAR(std::abs(wide.contours[0].contour.signed_area_mm2()), kPi * 10 * 20, 0.2);
  EXPECT_NEAR(wide.contours[0].contour.length_mm(), tall.contours[0].contour.length_mm(), 0.01);
  // Parameters many turns long (the fuzzer's 4e185: an int overflow, and a loop that could
  // not end for a huge start): taken within a turn; not finite: refused.
  const std::string arc =
      "0\nELLIPSE\n8\nE\n10\n0\n20\n0\n30\n0\n11\n10\n21\n0\n31\n0\n"
      "40\n0.5\n41\n{}\n42\n{}\n";
  EXPECT_EQ(read(fmt::format(fmt::runtime(arc), "1e300", "4e185")).contours.size(), 1u);
  EXPECT_EQ(read(fmt::format(fmt::runtime(arc), "0", "1e308")).contours.size(), 1u);
  m = test::message_of([&] { (void)read(fmt::format(fmt::runtime(arc), "-1e308", "1e308")); });
  EXPECT_NE(m.find("an ellipse whose parameters run from -1e+308 to 1e+308"), std::string::npos)
      << m;
  m = test::message_of([&] { (void)read(fmt::format(fmt::runtime(ellipse), 10, 0, 0.0)); });
  EXPECT_NE(m.find("an ellipse of axis ratio 0 (the minor axis over the major: need > 0)"),
            std::string::npos)
      << m;
  // Points and text bound nothing: the message lists what the file holds.
  m = test::message_of([&] {
    (void)read("0\nPOINT\n8\nP\n10\n0\n20\n0\n0\nTEXT\n8\nT\n10\n0\n20\n0\n40\n1\n1\nA\n");
  });
  EXPECT_NE(m.find("no line, arc or curve in it: its entities are 1 POINT, 1 TEXT"),
            std::string::npos)
      << m;
  // A rectangle drawn twice (a copy pasted in place): said so, not "a branch".
  std::string twice;
  for (int k = 0; k < 2; ++k) {
    twice += fmt::format(fmt::runtime(line), 10, 0);
    twice += "0\nLINE\n8\nL\n10\n10\n20\n0\n11\n10\n21\n10\n";
    twice += "0\nLINE\n8\nL\n10\n10\n20\n10\n11\n0\n21\n10\n";
    twice += "0\nLINE\n8\nL\n10\n0\n20\n10\n11\n0\n21\n0\n";
  }
  m = test::message_of([&] { (void)read(twice); });
  EXPECT_NE(m.find("LINE at line 6 and LINE at line 54 are the same line drawn twice"),
            std::string::npos)
      << m;
  // A block's INSERT on one layer: the message says which layers read without a problem.
  m = test::message_of([&] {
    (void)read(fmt::format(fmt::runtime(line), 10, 0) + "0\nINSERT\n8\nB\n2\nBOLT\n10\n0\n20\n0\n");
  });
  EXPECT_NE(m.find("an INSERT of block 'BOLT'"), std::string::npos) << m;
  EXPECT_NE(m.find("these read without a problem: L"), std::string::npos) << m;
  // Cut short inside its ENTITIES section.
  m = test::message_of([&] { (void)read(fmt::format(fmt::runtime(line), 10, 0), false); });
  EXPECT_NE(m.find("its ENTITIES section has no end (0 ENDSEC): the file is cut short"),
            std::string::npos)
      << m;
  std::filesystem::remove_all(dir);
}

TEST(Geometry, SvgBadInputIsRefusedWithWhatIsWrong) {
  const struct {
    const char* name;
    const char* text;
    const char* expect;
  } cases[] = {
      {"not-xml", "<svg><path d=\"M0 0 L 10", "not-xml.svg:1:15: not an SVG file (XML: "},
      {"html", "<html><body/></html>", "the root element is <html>, not <svg>"},
      {"bad-command", "<svg>\n<path id=\"p\" d=\"M0 0 L 10 10 x\"/></svg>",
       "path #p on layer '0': bad d at character 14 ('x'): expected a path command"},
      {"no-moveto", "<svg><path d=\"L 0 0\"/></svg>",
       "path (line 1) on layer '0': bad d at character 1 ('L'): expected a moveto"},
      {"short", "<svg><path d=\"M 0 0 10\"/></svg>",
       "bad d at its end (character 9): expected a number"},
      {"flag", "<svg><path d=\"M0 0 A 1 1 0 2 1 3 3\"/></svg>",
       "bad d at character 14 ('2'): expected a flag (0 or 1)"},
      {"huge-number", "<svg><path d=\"M0 0 L 1e400 1\"/></svg>",
       "bad d at character 8 ('1'): expected a finite number"},
      {"far", "<svg><path id=\"far\" d=\"M0 0 L 1e13 1\"/></svg>",
       "path #far on layer '0': a point or radius (2645833333333.3335, -0.26458333333333334) mm "
       "not finite or beyond 1000 km"},
      {"transform", "<svg><g transform=\"rotate(1 2)\"><path d=\"M0 0 1 1\"/></g></svg>",
       "bad transform at character 1 ('r'): expected rotate(angle [cx cy])"},
      {"unit", "<svg width=\"10em\" viewBox=\"0 0 1 1\"><path d=\"M0 0 L 1 1\"/></svg>",
       "<svg> width=\"10em\" (line 1): expected a unit of mm, cm, in, pt, pc, px, Q or none"},
      {"negative-width", "<svg width=\"-10mm\"><path d=\"M0 0 L 1 1\"/></svg>",
       "<svg> width=\"-10mm\" (line 1): expected a length > 0 (it is negative)"},
      {"viewbox", "<svg viewBox=\"0 0 0 1\"><path d=\"M0 0 L 1 1\"/></svg>",
       "viewBox=\"0 0 0 1\" (line 1): expected a width and a height > 0"},
      {"use", "<svg><use href=\"#a\"/></svg>", "use (line 1) on layer '0': a <use> of '#a'"},
      {"negative", "<svg><rect width=\"-1\" height=\"3\"/></svg>", "a negative width (-1)"},
      {"odd-points", "<svg><polygon points=\"1 2 3\"/></svg>", "expected a y coordinate"},
      {"gap", "<svg><path d=\"M0 0 L 10 0\"/><path d=\"M10.05 0 L 20 0\"/></svg>",
       "gap.svg: layer '0': a gap of 0.0132292 mm"},
      {"nothing", "<svg><text>a</text></svg>", "nothing.svg: no line, arc or curve in it"},
  };
  for (const auto& c : cases) {
    const auto file = svg_file(std::string(c.name) + ".svg", c.text);
    const std::string m = test::message_of([&] { (void)read_svg(file, DrawingOptions{}); });
    EXPECT_NE(m.find(c.expect), std::string::npos) << c.name << ": " << m;
    EXPECT_EQ(m.rfind(file.string(), 0), 0u) << c.name << ": starts with the file: " << m;
  }
  // Curves far beyond a machine's travel (18 arches 100 km across: about 2,900 arcs each
  // within 0.002 mm) stop the reading at the budget of fitted arcs, naming the element where it ran
  // out; the same arches 1 m across (70 arcs each) read.
  const auto arches = [](const char* size, int n) {
    std::string d = "M0 0";  // each arch an open path of its own, 1 mm above the one before
    for (int i = 0; i < n; ++i) d += fmt::format(" c 0 {0} {0} {0} {0} 0 m -{0} 1", size);
    return "<svg width=\"100mm\" viewBox=\"0 0 100 100\"><path id=\"arches\" d=\"" + d +
           "\"/></svg>";
  };
  const std::string m =
      test::message_of([&] { (void)read_svg(svg_file("far-arches.svg", arches("1e8", 18)), {}); });
  EXPECT_NE(m.find("path #arches on layer '0': the drawing's curves need more than 50000 arcs "
                   "within 0.002 mm (the arc tolerance)"),
            std::string::npos)
      << m;
  const Drawing near = read_svg(svg_file("arches.svg", arches("1e3", 18)), {});
  ASSERT_EQ(near.contours.size(), 18u);
  // Each arch 70 arcs (measured): the bounds only say it is fitted finely and read whole.
  for (const DrawnContour& c : near.contours) {
    EXPECT_GT(arcs_in(c.contour), 30u);
    EXPECT_LT(arcs_in(c.contour), 150u);
  }
  // Deep nesting is walked without recursion.
  std::string deep = "<svg>";
  for (int i = 0; i < 100000; ++i) deep += "<g>";
  deep += "<path d=\"M0 0 L 1 0\"/>";
  for (int i = 0; i < 100000; ++i) deep += "</g>";
  EXPECT_EQ(read_svg(svg_file("deep.svg", deep + "</svg>"), DrawingOptions{}).contours.size(), 1u);
  // read_drawing takes .svg in either case; other extensions are named.
  EXPECT_EQ(
      read_drawing(svg_file("upper.SVG", "<svg><path d=\"M0 0 H 1\"/></svg>"), DrawingOptions{})
          .contours.size(),
      1u);
  EXPECT_NE(test::message_of([] {
              (void)read_drawing("a.png", DrawingOptions{});
            }).find("a drawing must be a .dxf or .svg file (got '.png')"),
            std::string::npos);
}

// The medial axis against closed forms: a straight channel's is its centre line at half its
// width; a ring's, the middle circle; a T of channels meets at one junction. Every point's
// disc of its clearance lies in the region (16 points on its circle, 1 um inside).
TEST(Geometry, AMedialAxisIsTheChannelsCentreLine) {
  auto inside_discs = [](const std::vector<Contour>& region, const MedialBranch& b) {
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      if (b.clearance_mm[i] <= 1e-3) continue;  // at a wedge's tip: on the boundary
      for (int k = 0; k < 16; ++k) {
        const double a = 2 * M_PI * k / 16;
        const Vec2 q = b.points[i] + (b.clearance_mm[i] - 1e-3) * Vec2(std::cos(a), std::sin(a));
        EXPECT_TRUE(region_contains(region, q)) << q.transpose();
      }
    }
  };
  {
    const std::vector<Contour> strip{
        Contour::polyline({Vec2(0, 0), Vec2(60, 0), Vec2(60, 4), Vec2(0, 4)}, true)};
    const auto axis = medial_axis(strip, 120, 0.5);
    ASSERT_EQ(axis.size(), 1u);
    const MedialBranch& b = axis[0];
    EXPECT_FALSE(b.closed);
    // From x = 2 to 58 (where the corners' 45 degree spokes, pruned at 90 degrees, begin).
    const double x0 = std::min(b.points.front().x(), b.points.back().x());
    const double x1 = std::max(b.points.front().x(), b.points.back().x());
    EXPECT_NEAR(x0, 2, 1e-6);
    EXPECT_NEAR(x1, 58, 1e-6);
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      EXPECT_NEAR(b.points[i].y(), 2, 1e-6);  // the 1 nm grid's rounding, and more
      EXPECT_NEAR(b.clearance_mm[i], 2, 1e-6);
      if (i > 0) {
        EXPECT_LE((b.points[i] - b.points[i - 1]).norm(), 0.5 + 1e-12);
      }
    }
    inside_discs(strip, b);
  }
  {
    // A ring 4 mm wide about the origin, as offset_region gives it (chords within 1 um).
    const std::vector<Contour> ring =
        offset_region({Contour::circle(Vec2(0, 0), 14), Contour::circle(Vec2(0, 0), 10)}, 0, 1e-3);
    const auto axis = medial_axis(ring, 120, 0.5);
    ASSERT_EQ(axis.size(), 1u);
    EXPECT_TRUE(axis[0].closed);
    double len = 0;
    for (std::size_t i = 0; i < axis[0].points.size(); ++i) {
      // The chords lie within 1 um of the circles, their Voronoi edges between.
      EXPECT_NEAR(axis[0].points[i].norm(), 12, 2e-3);
      EXPECT_NEAR(axis[0].clearance_mm[i], 2, 2e-3);
      len += (axis[0].points[(i + 1) % axis[0].points.size()] - axis[0].points[i]).norm();
    }
    EXPECT_NEAR(len, 2 * M_PI * 12, 0.01);
    inside_discs(ring, axis[0]);
  }
  {
    // A T: a bar 4 wide from x = 0 to 40 at y 0..4 and a stem 4 wide down from its middle.
    const std::vector<Contour> tee{
        Contour::polyline({Vec2(0, 0), Vec2(18, 0), Vec2(18, -20), Vec2(22, -20), Vec2(22, 0),
                           Vec2(40, 0), Vec2(40, 4), Vec2(0, 4)},
                          true)};
    const auto axis = medial_axis(tee, 120, 0.5);
    ASSERT_EQ(axis.size(), 3u);
    // Each branch has one end at the junction: the point of x = 20 as far from the bar's top
    // wall as from the inside corners (18, 0) and (22, 0): 4 - y = sqrt(4 + y^2), y = 1.5.
    int at_junction = 0;
    for (const MedialBranch& b : axis) {
      EXPECT_FALSE(b.closed);
      for (const Vec2& e : {b.points.front(), b.points.back()}) {
        if ((e - Vec2(20, 1.5)).norm() < 1e-6) ++at_junction;
      }
      inside_discs(tee, b);
    }
    EXPECT_EQ(at_junction, 3);
  }
  {
    // A wedge with its tip at (40, 0): the axis runs along y = 0 from the incircle's centre
    // (x = r = area / half the perimeter = 160 / (4 + sqrt(1616)) = 3.6186 mm; the spokes to
    // the 84.3 degree corners at x = 0 pruned) into the tip itself, on the boundary, its
    // clearance (40 - x) sin(atan(0.1)).
    const std::vector<Contour> wedge{
        Contour::polyline({Vec2(0, 4), Vec2(0, -4), Vec2(40, 0)}, true)};
    const auto axis = medial_axis(wedge, 120, 0.5);
    ASSERT_EQ(axis.size(), 1u);
    const double r_in = 160 / (4 + std::sqrt(1616.0));
    const MedialBranch& b = axis[0];
    EXPECT_NEAR(std::min(b.points.front().x(), b.points.back().x()), r_in, 1e-6);
    EXPECT_NEAR(std::max(b.points.front().x(), b.points.back().x()), 40, 1e-6);
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      EXPECT_NEAR(b.points[i].y(), 0, 1e-6);
      EXPECT_NEAR(b.clearance_mm[i], (40 - b.points[i].x()) * std::sin(std::atan(0.1)), 1e-6);
    }
    inside_discs(wedge, b);
  }
  EXPECT_THROW((void)medial_axis({Contour::polyline({Vec2(0, 0), Vec2(1, 0)}, false)}, 120, 0.5),
               InputError);
}
