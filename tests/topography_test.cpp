// Wear topography: the cubic RBF against an analytic surface, mesh input/output
// round trips, the structured grid of a synthetic insert against its geometry, and a worn
// insert's larger passive force.
#include "trochomill/topography.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

double surface(double u, double v) {
  return 0.05 * std::sin(2 * u) * std::cos(3 * v) + 0.02 * u * u - 0.01 * v;
}

// The cubic RBF with its linear term reproduces a smooth surface (amplitude 0.1 mm) from
// scattered points within 1e-4 mm everywhere inside the data, both as one global system
// (800 points) and as a partition of unity (20,000 points, ~36 per cell).
TEST(Topography, CubicRbfReproducesAnAnalyticSurface) {
  for (const int n : {800, 20000}) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(0.0, 2.0), V(0.0, 1.0);
    std::vector<std::array<double, 2>> pts;
    std::vector<double> val;
    for (int i = 0; i < n; ++i) {
      const double u = U(rng), v = V(rng);
      pts.push_back({u, v});
      val.push_back(surface(u, v));
    }
    const CubicRbf rbf(pts, val);
    EXPECT_EQ(rbf.patches() > 1, n > 1500) << n;
    double worst = 0;
    std::uniform_real_distribution<double> Ui(0.1, 1.9), Vi(0.1, 0.9);
    for (int i = 0; i < 3000; ++i) {
      const double u = Ui(rng), v = Vi(rng);
      worst = std::max(worst, std::abs(rbf(u, v) - surface(u, v)));
    }
    EXPECT_LT(worst, 1e-4) << n << " points";
    // It interpolates: the data points themselves to rounding.
    for (int i = 0; i < 50; ++i) EXPECT_NEAR(rbf(pts[i][0], pts[i][1]), val[i], 1e-9);
  }
}

SimTool insert_tool() {
  SimTool t;
  t.radius_mm = 8, t.corner_radius_mm = 0.8, t.flute_length_mm = 1.5, t.segment_mm = 0.05;
  t.sub_segments = 5;
  return t;
}

// STL, PLY and OBJ written and read back give the same surface (STL stores float32: 1e-5 mm
// at 8 mm).
TEST(Topography, MeshFilesRoundTrip) {
  const SimTool tool = insert_tool();
  SyntheticInsert s;
  s.sections = 20, s.profile_points = 40;
  const Mesh m = synthetic_insert(tool, s);
  const auto dir = std::filesystem::temp_directory_path() / "trochomill_topo_test";
  std::filesystem::create_directories(dir);
  for (const char* ext : {".stl", ".ply", ".obj"}) {
    const auto f = dir / (std::string("insert") + ext);
    write_mesh(f, m);
    const Mesh r = read_mesh(f);
    EXPECT_EQ(r.triangles.size(), m.triangles.size()) << ext;
    // Every triangle's vertices match, in order.
    double worst = 0;
    for (std::size_t i = 0; i < m.triangles.size(); i += 7) {
      for (int q = 0; q < 3; ++q) {
        const auto& a = m.vertices[m.triangles[i][q]];
        const auto& b = r.vertices[r.triangles[i][q]];
        for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(a[c] - b[c]));
      }
    }
    EXPECT_LT(worst, 1e-5) << ext;
  }
  EXPECT_THROW((void)read_mesh(dir / "missing.stl"), InputError);
  EXPECT_THROW(write_mesh(dir / "insert.xyz", m), InputError);
  std::filesystem::remove_all(dir);
}

// A new honed insert (zero rake, r_beta 0.02 mm) sampled in a 0.2 mm band: along the surface
// from the outer edge inward the profile is a quarter of the hone (r_beta pi / 2) then the
// rake face up to 0.2 mm deep, so the sub-segments' widths sum to 0.2 - r_beta + r_beta pi / 2
// (within 2 um: the sampled curve is 2000 steps and the RBF's fit); the innermost facets are
// the rake face (normal +y within 1 degree) and the outermost leans outward.
TEST(Topography, SyntheticInsertSamplesToItsGeometry) {
  const SimTool tool = insert_tool();
  SyntheticInsert s;
  s.edge_radius_mm = 0.02;
  EdgeTopography info;
  const EdgeGrid g = sample_topography(synthetic_insert(tool, s), tool, 0.2, &info);
  EXPECT_GT(info.facets_kept, 0u);
  EXPECT_LT(info.facets_kept, info.facets_total);  // the flank is culled
  const double expect = 0.2 - 0.02 + 0.02 * kPi / 2;
  for (int k = 2; k < g.segments - 2; k += 3) {
    double sum = 0;
    for (int t = 0; t < g.sub_segments; ++t) sum += g.at(k, t).para_mm;
    EXPECT_NEAR(sum, expect, 2e-3) << k;
    const EdgeCell& inner = g.at(k, g.sub_segments - 1);
    EXPECT_GT(inner.facet[1], std::cos(deg_to_rad(1.0))) << k;
    const EdgeCell& outer = g.at(k, 0);
    EXPECT_LT(outer.facet[1], inner.facet[1]) << k;
    EXPECT_NEAR(outer.proj_mm, 0.0, 1e-12);
    EXPECT_NEAR(g.at(k, g.sub_segments - 1).proj_end_mm, 0.2, 2e-3);
    for (int t = 1; t < g.sub_segments; ++t) EXPECT_GE(g.at(k, t).proj_mm, g.at(k, t - 1).proj_mm);
    // The facet lies in the section plane: (radial, axial) along the contour normal.
    const auto& n = outer.normal;
    EXPECT_NEAR(outer.facet[0] * n[2] - outer.facet[2] * n[0], 0.0, 1e-9);
  }
}

// A worn insert on a 10 mm edge (sections 0.05 mm apart, points along them 0.001-0.01 mm
// apart), through STL and back: on every segment the profile runs along the land (VB - r_beta),
// round the hone (r_beta pi / 2) and over the rake face to 0.2 mm deep (0.2 - r_beta), within
// 2 um, and its outermost sub-segment is the land (facet normal radial within 1 degree). Without
// the along-edge scaling of the RBF's domain the land bulged 2 um between sections and most
// segments lost part of it.
TEST(Topography, AWornInsertFromStlKeepsItsLandOnEverySegment) {
  SimTool tool = insert_tool();
  tool.flute_length_mm = 10;
  SyntheticInsert s;
  s.vb_mm = 0.15;
  const auto f = std::filesystem::temp_directory_path() / "trochomill_worn_insert.stl";
  write_mesh(f, synthetic_insert(tool, s));
  EdgeTopography info;
  const EdgeGrid g = sample_topography(read_mesh(f), tool, 0.2, &info);
  std::filesystem::remove(f);
  EXPECT_LT(info.s_scale, 0.5);
  const double expect = 0.15 - 0.02 + 0.02 * kPi / 2 + 0.2 - 0.02;
  for (int k = 0; k < g.segments; ++k) {
    double sum = 0;
    for (int t = 0; t < g.sub_segments; ++t) sum += g.at(k, t).para_mm;
    EXPECT_NEAR(sum, expect, 2e-3) << k;
    EXPECT_LT(std::abs(g.at(k, 0).facet[1]), std::sin(deg_to_rad(1.0))) << k;
  }
}

// A worn insert (flank wear land VB 0.15 mm) turns the effective direction outward for thin
// chips, so at the same chip and width the force normal to the edge (the passive force) grows
// and the cutting force falls; over a full slot the mean feed-direction force F_y (the normal
// force's mean, models.md section 12) grows by more than 20 % with Bergmann's coefficients.
TEST(Topography, AWornInsertRaisesThePassiveForce) {
  const SimTool tool = insert_tool();
  Material m;
  m.model = ForceModel::bergmann;
  m.k_c = 1926.08, m.k_n = 502.64, m.m = 0.28;
  SyntheticInsert s;
  const EdgeGrid fresh = sample_topography(synthetic_insert(tool, s), tool, 0.2);
  s.vb_mm = 0.15;
  const EdgeGrid worn = sample_topography(synthetic_insert(tool, s), tool, 0.2);
  const SegmentForces fn(m, fresh, deg_to_rad(80)), fw(m, worn, deg_to_rad(80));
  const int k = fresh.segments - 3;  // on the straight edge
  for (const double h : {0.01, 0.05, 0.1}) {
    const auto a = fn.force(k, h, 0.05), b = fw.force(k, h, 0.05);
    EXPECT_GT(b[0], 1.2 * a[0]) << h;  // radial (passive)
    EXPECT_LT(b[1], a[1]) << h;        // cutting
  }
  // Through a job: a full slot in Inconel with synthetic wear states [0, 0.15].
  const auto job_for = [](int state) {
    return parse_job(R"(
[tool]
type = "insert_mill"
diameter = 16.0
teeth = 2
corner_radius = 0.8
flute_length = 1.5
edge_radius = 0.02
[slot]
width = 16.0
length = 40.0
depth = 1.0
[path]
type = "linear"
step = 1.0
[cutting]
feed_per_tooth = 0.1
cutting_speed = 40.0
[material]
name = "inconel718-bergmann2021"
[topography]
synthetic_vb = [0.0, 0.15]
state = )" + std::to_string(state) +
                         R"(
[forces]
fast_steps_per_rev = 720
)",
                     "worn.toml");
  };
  double fy[2];
  for (int st = 0; st < 2; ++st) {
    const Job j = job_for(st);
    const ToolPath p = plan_path(j).path;
    const double rev = 60.0 / spindle_speed_rpm(j), t0 = 3.0;
    const JobForces f = job_forces(j, p, t0, t0 + 5 * rev, true);
    fy[st] = f.summary.f_y_mean_n;
  }
  EXPECT_GT(fy[0], 10.0);
  EXPECT_GT(fy[1], 1.2 * fy[0]);
}

}  // namespace
}  // namespace trochomill
