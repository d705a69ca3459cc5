// Exact 2D engagement of the tool with the stock: at every sample of any path (planned or
// read from G-code), the arcs of the tool circle that lie in stock not yet removed, the
// engagement angle, radial engagement, teeth in cut and the local maximum uncut chip
// thickness h_max (Wagih 2023 Sections 2-5).
//
// Model: the stock is the slot rectangle |x| <= W/2, 0 <= y <= L; the removed region is the
// union of the tool discs (radius R) at all earlier samples with the tool in the material
// (z < 0). The chip of the tooth at sample i is bounded by the surface the previous tooth
// left, i.e. the removed region up to sample i - m with m samples per tooth pass.
// Discs at samples stand for the continuous sweep: the error is at most ds^2 / (8 R) for
// sample spacing ds (1.4e-4 mm at f_z = 0.075 mm, R = 5 mm); no raster anywhere.
// Algorithm: the boundary of the removed region is kept as the exposed arcs of "alive"
// discs (arcs not covered by any other disc); a query walks the crossings of the tool
// circle with the exposed arcs (exact, holes included; where a crossing falls within 1e-9
// rad of a boundary vertex, each interval is tested directly instead of by parity), and
// discs whose exposed arcs vanish are dropped, so the work per sample stays proportional to
// the boundary near the tool. h_max is exact too: it is evaluated at every angle where the
// chip thickness can have a local maximum (see ChipQuery in src/engagement/kernel.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "trochomill/geometry.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/progress.hpp"

namespace trochomill {

/// One engaged arc of the tool circle: angles (rad) counter-clockwise from +X, from
/// start to end (start in [0, 2 pi], end > start, end - start <= 2 pi: an arc across 0 ends
/// past 2 pi).
struct AngleArc {
  double start_rad = 0;
  double end_rad = 0;
  [[nodiscard]] double sweep_rad() const noexcept { return end_rad - start_rad; }
};

struct EngagementSeries;

struct EngagementOptions {
  int steps_per_tooth = 1;  ///< samples per tooth pass (>= 1); the chip spans this many
  /// Stock unbounded along +Y (the slot end ignored): a steady-state cycle as in an endless
  /// slot, for slots too short to hold one.
  bool open_ahead = false;
  RunHooks hooks;  ///< progress over the samples; cancel throws Interrupted
  /// The stock as a closed mesh in the path's frame (mm) instead of the job's box: at a
  /// position's height z, the plan-view region where the solid lies between z and z plus the
  /// flute length (at most its top); its top is the mesh's. Throws InputError for an open
  /// mesh (a vertical line crossing it an odd number of times). Null: the job's [stock] mesh
  /// (Job::stock_mesh) where it has one, else its box.
  const Mesh* stock_mesh = nullptr;
  /// Called on the kernel's thread after every 256th sample with the series so far: its
  /// entries before `done` are final, the rest not computed yet (`analyze` starts the steady
  /// cycle's run from it once the window can be told).
  std::function<void(const EngagementSeries& so_far, std::size_t done)> on_samples;
};

/// Engagement along a path, structure of arrays (one entry per sample).
struct EngagementSeries {
  double tool_radius_mm = 0;
  int teeth = 0;
  int steps_per_tooth = 1;
  PathSamples samples;                       ///< the sampled tool-centre path
  std::vector<std::vector<AngleArc>> arcs;   ///< engaged arcs per sample (may be empty)
  std::vector<double> engagement_angle_rad;  ///< total engaged angle
  std::vector<double> radial_engagement_mm;  ///< R (1 - cos(angle)) equivalent radial depth
  std::vector<double> h_max_mm;              ///< local maximum uncut chip thickness
  std::vector<double> h_max_angle_rad;       ///< where on the circle h_max occurs
  std::vector<int> teeth_in_cut;             ///< teeth whose angle lies in an engaged arc
  /// Plan-view area the tool circle sweeps into stock per second (mm^2/s): the horizontal
  /// speed v times R times the integral of cos(phi - phi_v) over the engaged arcs where the
  /// circle advances (cos > 0). Times the axial depth it is the removal rate.
  std::vector<double> swept_rate_mm2_per_s;
  /// Material removal rate (mm^3/s): the swept rate of each part of the engaged arcs times
  /// the height of stock over it, from the position's height up to the nearest Z level
  /// above whose region removed it, else the stock's top (z = 0, or the [stock] box's top),
  /// at most the flute length; plus, where the tool descends, the end face's: the descent
  /// rate times the face's area over stock no earlier position removed.
  std::vector<double> removal_rate_mm3_per_s;
  /// The end edges' axial chip (mm): the descent per tooth period where the end face cuts
  /// stock no earlier position removed (a plunge, a ramp, a helix), 0 elsewhere.
  std::vector<double> axial_chip_mm;
};

/// The plan-view region a tool of radius R has removed: the union of the discs about the
/// centres cut so far, the exact kernel's region (compute_engagement). For planners that place
/// the tool by its engagement (pocket.hpp). Lengths mm, angles rad.
class RemovedRegion {
 public:
  /// Centres cut or asked about should lie in the box lo_mm .. hi_mm (others are slower).
  RemovedRegion(double radius_mm, const Vec2& lo_mm, const Vec2& hi_mm);
  RemovedRegion(RemovedRegion&&) noexcept;
  RemovedRegion& operator=(RemovedRegion&&) noexcept;
  ~RemovedRegion();
  /// The arcs of the tool circle about c outside the region (the stock it touches there),
  /// angles counter-clockwise from +X.
  [[nodiscard]] std::vector<AngleArc> uncut_arcs(const Vec2& c) const;
  /// Makes the queries of uncut_arcs within slack_mm of c faster until the next cut (the
  /// discs near them are found once); their answers are the same.
  void focus(const Vec2& c, double slack_mm) const;
  /// Adds the disc about c.
  void cut(const Vec2& c);
  /// Whether p lies inside a disc cut so far.
  [[nodiscard]] bool contains(const Vec2& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Centres of discs of radius `radius_mm` whose union is the region an earlier program removed
/// from a tool tip height z up (RestStock): its tool's sweep along its moves at z or below
/// (within 1e-4 mm), which is the sweep of a disc of radius_mm over the region within
/// R_rest - radius_mm of those moves. That region is this kernel's removed region of discs of
/// that radius along the moves (a tenth of it or `spacing_mm` apart, the smaller); the centres
/// are on its outline (its discs' exposed arcs) spacing_mm apart, and on a grid of
/// 0.9 radius_mm inside it. Short of the exact sweep by the scallops between neighbours,
/// spacing_mm^2 / 8 radius_mm (0.1 um at 0.05 mm and R = 3 mm). Empty where no move lies at
/// z or below. Throws InputError when the earlier tool is the smaller (its region is no union
/// of the larger discs).
[[nodiscard]] std::vector<Vec2> rest_disc_centres(const RestStock& rest, double z_mm,
                                                  double radius_mm, double spacing_mm);

/// Heights within this (mm) are one level: the kernel's 2.5D levels, an earlier program's.
inline constexpr double kLevelTolMm = 1e-4;

/// The spacing of rest_disc_centres' outline discs for a job (mm): a tooth's advance, as the
/// kernel's samples (0.005 mm to R / 10).
[[nodiscard]] inline double rest_spacing_mm(const Job& job) {
  const double lo = 0.005, hi = std::max(lo, 0.1 * job.tool.radius_mm());
  return std::clamp(job.cutting.feed_per_tooth_mm, lo, hi);
}

/// The radial chip of sample i (mm): its h_max, or 0 where the tool descends into stock no
/// earlier position touched (a helix, ramp or plunge start: the kernel caps h_max at the
/// radius there, but the chip is axial), and 0 where it has not moved across since the
/// sample before and does not descend (a retract or a dwell: the tooth passes where the one
/// before cut; the kernel measures the chip against the last surface a cutting move left,
/// which a vertical rapid does not renew). What the program's h_max and the feed schedule
/// count.
[[nodiscard]] inline double radial_chip_mm(const EngagementSeries& e, std::size_t i,
                                           double radius_mm) {
  if (i == 0) return e.h_max_mm[i];
  const PathSamples& s = e.samples;
  const bool plunging = s.z_mm[i] < s.z_mm[i - 1] && e.h_max_mm[i] >= radius_mm * (1 - 1e-12);
  // 1e-9 mm: no move across but rounding.
  const bool in_place = std::abs(s.x_mm[i] - s.x_mm[i - 1]) <= 1e-9 &&
                        std::abs(s.y_mm[i] - s.y_mm[i - 1]) <= 1e-9 && s.z_mm[i] >= s.z_mm[i - 1];
  return plunging || in_place ? 0.0 : e.h_max_mm[i];
}

/// The top of the stock the engagement kernel cuts (mm): the stock mesh's highest vertex when
/// one is given, else the job's [stock] box top, else the slot's top surface, 0. Throws
/// InputError for a mesh without triangles or with a coordinate that is not finite.
[[nodiscard]] double stock_top_mm(const Job& job, const Mesh* stock_mesh);

/// The samples the engagement of `path` is computed at: every tooth pass / steps_per_tooth
/// (time step 60 / (n Z steps_per_tooth) s). Throws InputError for steps_per_tooth < 1.
[[nodiscard]] PathSamples engagement_samples(const ToolPath& path, const Job& job,
                                             int steps_per_tooth);

/// Engagement at every sample of `path` (engagement_samples). Throws InputError for bad
/// options.
[[nodiscard]] EngagementSeries compute_engagement(const ToolPath& path, const Job& job,
                                                  const EngagementOptions& options = {});

/// The same on given samples (any spacing); the chip spans `steps_per_tooth` samples.
[[nodiscard]] EngagementSeries compute_engagement(const PathSamples& samples, const Job& job,
                                                  const EngagementOptions& options);

/// The largest radial chip (mm, radial_chip_mm) the engagement kernel finds on `path` from
/// `from_mm` of its length to its end: the judge of plan_slot.
[[nodiscard]] double kernel_chip_from_mm(const Job& job, const ToolPath& path, double from_mm);

/// The job's slot program (path.hpp plan_path) with the engagement kernel as the judge of a
/// slot along a curve: every caller that plans from a job plans through this.
[[nodiscard]] PlannedPath plan_slot(const Job& job);

}  // namespace trochomill
