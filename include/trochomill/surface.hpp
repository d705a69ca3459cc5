// Machined-surface geometry from the path: the slot walls (path level, the envelope of the
// tool circles; tooth level, the envelope of the tooth-tip trajectories) and the density of
// the cutting edge's imprints on the floor (Wagih 2023 Section 4; docs/models.md section 8).
#pragma once

#include <cstddef>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/path.hpp"
#include "trochomill/texture.hpp"

namespace trochomill {

/// One slot wall over a range of y: the machined wall's x (mm) at each y (mm).
struct WallProfile {
  std::vector<double> y_mm;
  std::vector<double> x_mm;
  double waviness_mm = 0;  ///< peak-to-valley of x over the range (mm)
  double peak_y_mm = 0;    ///< y of the least-cut point (the cusp) (mm)
};

struct Walls {
  WallProfile left;   ///< the wall at -x: x = min over the cut of the tool's leftmost point
  WallProfile right;  ///< the wall at +x
};

/// Walls left by circles of radius `radius_mm` centred on the samples with z <= z_max_mm
/// (path level when the samples are the dense tool-centre path), evaluated at `points`
/// equally spaced y in [y_from_mm, y_to_mm]. Circles are exact; the only discretisation is
/// the y grid (the cusp's height is found to within its slope times half a spacing).
/// Throws InputError when no circle reaches a wall point of the range.
[[nodiscard]] Walls walls_from_circles(const PathSamples& samples, double radius_mm,
                                       double z_max_mm, double y_from_mm, double y_to_mm,
                                       int points);

/// Walls left by the tooth tips (tooth level): the envelope of each tooth's tip polyline
/// (consecutive samples joined by chords; sample at a fine spindle angle), for tips with
/// z <= z_max_mm, over the same y grid. With a finite band_mm, only chords with an end within
/// band_mm of the extreme tip x (per wall) count: a speed-up valid when the profile lies
/// within the band (the caller checks).
[[nodiscard]] Walls walls_from_tips(const ToothTracks& tips, double z_max_mm, double y_from_mm,
                                    double y_to_mm, int points,
                                    double band_mm = std::numeric_limits<double>::infinity());

/// Bottom imprint density (Wagih 2023 Figs. 21-22): the floor carries one circle of radius R
/// per tooth pass, centred on the tool centre; at each of `points` equally spaced x across
/// [-half_width, half_width] the density is the number of circle crossings of the line x = X
/// per mm of slot length (`advance_mm` is the slot length the given centres cover).
struct ImprintDensity {
  std::vector<double> x_mm;
  std::vector<double> crossings_per_mm;
};
[[nodiscard]] ImprintDensity bottom_imprint_density(const std::vector<double>& centre_x_mm,
                                                    double radius_mm, double half_width_mm,
                                                    double advance_mm, int points);

/// The floor the teeth's end edges leave along the line x = x_mm (mm, the samples' frame):
/// heights z_mm (mm) at y_from_mm + j dy_mm, the lowest any end edge passed each point at
/// (NaN where none did: the point was not cut). Tooth k's end edge runs from the tool's axis
/// (the centre plus the radial runout, docs/models.md section 4) out along the tooth's
/// angle to its radius R_k (R plus its radial seating); at distance r from the axis it lies
/// (R_k - rc - r) tan(dish) above the tooth's tip for r <= R_k - rc and on the corner arc
/// of radius rc beyond; the tip at the sample's z less the axial runout's e_ax cos(alpha_k -
/// lambda) and the axial seating. Between samples the centre moves linearly; a point is cut
/// where an edge's direction passes it (found in steps of at most 5 degrees of spindle
/// rotation, linear in between). `omega_rad_per_s` is the signed spindle speed (negative:
/// clockwise seen from +z). Throws InputError on a bad grid or tool.
struct FloorProfile {
  double x_mm = 0, y_from_mm = 0, dy_mm = 0;
  std::vector<double> z_mm;
};
[[nodiscard]] FloorProfile floor_profile(const PathSamples& samples, const Tool& tool,
                                         double omega_rad_per_s, double x_mm, double y_from_mm,
                                         double dy_mm, std::size_t points);

/// The texture along the feed of a wall whose profile covers one period of y (its last point
/// is the first again: a tooth-level wall of one step), material side up (+x on the left wall,
/// -x on the right). Throws InputError for a profile of fewer than 3 points.
[[nodiscard]] ProfileTexture wall_texture(const WallProfile& wall, bool left,
                                          std::optional<double> cutoff_mm = {});

}  // namespace trochomill
