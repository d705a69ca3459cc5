// The cutter model shared by the simulation, the force models and the wear topography: the
// edge contour of a solid end mill or an indexable insert mill (corner arc, main edge at the
// lead angle, flute length), each tooth's angle and radial and axial offsets (runout and
// insert seating), the segments along the edge (kappa) with sub-segments inward (tau), and the
// structured grid of one edge (Bergmann 2021 Section 4.1). Lengths in mm, angles in radians
// inside (degrees at the job interface).
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "trochomill/geometry.hpp"
#include "trochomill/settings/sim.hpp"

namespace trochomill {

struct Job;

/// An interval (mm, lo < hi): material along a dexel, or heights along the edge.
struct Interval {
  double lo = 0, hi = 0;
};

/// The cutting tool as the simulation sees it: a solid end mill or an indexable insert mill,
/// each tooth (insert) an edge of the same contour at its own angle, with its own radial and
/// axial offset (runout plus, for inserts, their seating). The contour in the axial plane,
/// from the tip up: the corner arc (radius rc, tangent to the face) and then the main edge at
/// the lead angle kappa_r to the face (90 degrees: a cylindrical flank at radius R; less: the
/// edge runs inward, as on a face mill), up to the flute length (the edge's axial reach).
/// Each edge is split into segments along the axis (kappa) with sub-segments inward (tau),
/// the grid the force and wear models address.
struct SimTool {
  double radius_mm = 0, corner_radius_mm = 0, flute_length_mm = 0;
  double helix_rad = 0;
  double lead_rad = 1.5707963267948966;  ///< lead angle kappa_r of the main edge (rad)
  std::vector<double> tooth_angle_rad;   ///< at t = 0, height 0
  std::vector<double> radial_offset_mm;  ///< per tooth: runout and insert seating
  std::vector<double> axial_offset_mm;   ///< per tooth (tip height)
  double omega_rad_per_s = 0;            ///< signed: negative for a cw spindle seen from +z
  double segment_mm = 0.05;              ///< segment length along the axis (kappa)
  int sub_segments = 5;                  ///< sub-segments inward per segment (tau)
  /// Contour radius at height h above the tip (mm); -1 where there is no edge (h < 0 or the
  /// edge has run in to the axis).
  [[nodiscard]] double profile_radius(double h) const;
  /// The sine of the edge's local angle to the face at height h: the factor from the radial
  /// depth of cut to the chip thickness normal to the edge (1 on a cylindrical flank).
  [[nodiscard]] double edge_sine(double h) const;
  /// The heights whose contour reaches radius rho (one interval: the contour is unimodal), or
  /// nothing.
  [[nodiscard]] std::optional<Interval> heights_reaching(double rho) const;
  /// The height of the contour's largest radius within [h0, h1].
  [[nodiscard]] double widest_height(double h0, double h1) const;
  /// Length along the edge (mm) from the tip up to height h (the corner arc, then the main
  /// edge), and its inverse.
  [[nodiscard]] double edge_length_at(double h) const;
  [[nodiscard]] double height_at_length(double s) const;
  /// Segments along the edge (kappa), `segment_mm` long each (the last shorter), up to the
  /// flute length.
  [[nodiscard]] int segments() const;
  /// The segment (kappa index) at height h.
  [[nodiscard]] int segment_at(double h) const;
};

/// A tool's contour with its constants taken once (the corner's top height, the flank's
/// slope): the same numbers as SimTool's methods of the same names, without their
/// trigonometry on every call (the simulation asks millions of times). Valid while the tool it
/// was made from is unchanged.
class ToolContour {
 public:
  explicit ToolContour(const SimTool& tool);
  /// SimTool::profile_radius (mm; h in mm above the tip).
  [[nodiscard]] double profile_radius(double h) const;
  /// SimTool::heights_reaching (rho in mm).
  [[nodiscard]] std::optional<Interval> heights_reaching(double rho) const;
  /// SimTool::edge_sine.
  [[nodiscard]] double edge_sine(double h) const;

 private:
  double radius_, rc_, rcen_, ht_, rt_, tan_lead_, sin_lead_, flank_ = 0;
  bool cylindrical_;
};

/// One cell of an edge's structured grid: segment kappa along the edge, sub-segment tau
/// inward from the outer edge across the face the chip meets (Bergmann 2021 Section 4.1).
/// `normal` is the contour's outward normal d_n (the segment's radial direction); `facet` is
/// the sub-segment's surface normal d_c, which sets the force direction (Eq. 2). For a new
/// sharp edge (edge_grid) every facet is the rake face, normal to the cutting direction, and
/// the sub-segments split the band evenly; the topography module fills them from a
/// digitised or synthetic insert (topography.hpp).
struct EdgeCell {
  int kappa = 0, tau = 0;
  double s_mm = 0;      ///< the segment's middle, along the edge from the tip
  double h_mm = 0;      ///< its height above the tip
  double r_mm = 0;      ///< its contour radius
  double width_mm = 0;  ///< w_s: the segment's length along the edge
  double depth_mm = 0;  ///< the sub-segment's middle, inward from the edge (projected)
  /// Unit normal in the tooth's frame (radial out, cutting direction, axial up).
  Vec3 normal = Vec3::Zero();
  /// The sub-segment's unit surface normal d_c, same frame.
  Vec3 facet = Vec3(0.0, 1.0, 0.0);
  double proj_mm = 0;      ///< Delta_proj at its outer end: inward distance from the outer edge
  double proj_end_mm = 0;  ///< Delta_proj at its inner end
  double para_mm = 0;      ///< w_j: its length along the surface (Delta_para difference)
};
struct EdgeGrid {
  int segments = 0, sub_segments = 0;
  double band_mm = 0;           ///< the band along the edge the sub-segments cover
  std::vector<EdgeCell> cells;  ///< kappa-major: cells[kappa * sub_segments + tau]
  [[nodiscard]] const EdgeCell& at(int kappa, int tau) const {
    return cells[static_cast<std::size_t>(kappa * sub_segments + tau)];
  }
};
/// The structured grid of one edge of the tool (all its teeth share the contour).
[[nodiscard]] EdgeGrid edge_grid(const SimTool& tool, double band_mm = 0.2);
[[nodiscard]] SimTool sim_tool(const Job& job, const SimSettings& s);

}  // namespace trochomill
