// Machined-surface geometry from the path: the slot walls (path level, the envelope of the
// tool circles; tooth level, the envelope of the tooth-tip trajectories) and the density of
// the cutting edge's imprints on the floor (Wagih 2023 Section 4; docs/models.md section 8).
#pragma once

#include <limits>
#include <vector>

#include "trochomill/path.hpp"

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

}  // namespace trochomill
