// Wear topography of a cutting edge (Bergmann 2021 Section 4.1): a digitised insert or tooth
// surface (STL/PLY/OBJ) or a synthetic insert, its facets visible along the cutting
// direction, a cubic radial basis function through their points, and the structured grid
// (kappa along the edge, tau inward within a band) with each sub-segment's normal and
// distances. docs/models.md section 13.
//
// The mesh frame is the tooth's: x radial (out from the tool axis), y the cutting direction
// (the rake face faces +y), z axial (up from the tool tip), mm; the edge lies on the tool's
// contour (SimTool::profile_radius) at y = 0.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "trochomill/cutter.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/job.hpp"

namespace trochomill {

/// A synthetic insert edge for tests and examples: rake face (rake angle), honed edge
/// (radius r_beta), flank (clearance angle), and with vb_mm > 0 a flank wear land of width VB
/// (zero clearance, reaching VB behind the edge along the flank), honed to the rake face with
/// the same radius. It follows the tool's contour (corner radius, lead angle) over its edge.
struct SyntheticInsert {
  double edge_radius_mm = 0.02;  ///< r_beta
  double vb_mm = 0;              ///< flank wear land width VB
  double rake_deg = 0, clearance_deg = 7;
  double face_mm = 0.6;      ///< how far the rake face and flank extend from the edge
  int sections = 200;        ///< profile sections along the edge
  int profile_points = 120;  ///< points per section
};
[[nodiscard]] Mesh synthetic_insert(const SimTool& tool, const SyntheticInsert& s);

/// Cubic radial basis function phi(r) = r^3 with a linear polynomial term, interpolating
/// scattered values f(u, v). Up to `patch_points` points it is one global system; above, a
/// partition of unity of overlapping local interpolants blended with Wendland C2 weights.
class CubicRbf {
 public:
  /// Throws InputError for fewer than 3 points, mismatched sizes or non-finite data.
  CubicRbf(std::vector<std::array<double, 2>> points, std::vector<double> values,
           int patch_points = 1500);
  [[nodiscard]] double operator()(double u, double v) const;
  [[nodiscard]] std::size_t patches() const noexcept { return patches_.size(); }

 private:
  struct Patch {
    double cu = 0, cv = 0, radius = 0;  // support
    std::vector<std::array<double, 2>> x;
    std::vector<double> w;         // RBF weights
    std::array<double, 3> poly{};  // 1, u, v
    double su = 0, sv = 0;         // centring of the local coordinates
  };
  [[nodiscard]] static double eval_patch(const Patch& p, double u, double v);
  std::vector<Patch> patches_;
  double u0_ = 0, v0_ = 0, cell_ = 1;
  int nu_ = 1, nv_ = 1;
  std::vector<std::vector<int>> cells_;  // patches whose support touches each cell
};

/// The tool-edge topography: the mesh's points visible along the cutting direction, in
/// section coordinates about the edge, with their RBF.
struct EdgeTopography {
  double centre_mm = 0.3;  ///< L: the polar centre sits L inward and L behind the edge
  std::size_t points = 0;  ///< visible points used
  std::size_t facets_kept = 0, facets_total = 0;
  double s_min_mm = 0, s_max_mm = 0;  ///< extent along the edge covered by the mesh
  double s_scale = 1;  ///< along-edge scale of the RBF's domain (< 1 for meshes in sections)
};

/// Samples a mesh into the structured grid of `tool`'s edge (edge_grid's segments, tool's
/// sub_segments) within `band_mm` inward of the outer edge: per segment the visible profile
/// from the outer edge inward, split into sub-segments of equal length along the surface
/// (Delta_para), each with its normal d_c, Delta_proj at both ends and its width w_j.
/// Segments beyond the mesh keep a sharp edge. Throws InputError when no facet is visible.
[[nodiscard]] EdgeGrid sample_topography(const Mesh& mesh, const SimTool& tool, double band_mm,
                                         EdgeTopography* info = nullptr);

}  // namespace trochomill
