// Pocket clearing at a guaranteed engagement (docs/models.md, "Pockets"): the region the tool
// centre may reach (the pocket less its islands, shrunk by the tool radius and the stock to
// leave, through Clipper), a helical entry where the region is widest, then passes that each
// step hold the tool's engagement in the stock at or below the target by the exact engagement
// kernel's removed region (RemovedRegion), links that stay down where the tool would cut
// nothing and lift elsewhere, the same passes at each depth level, and a finishing pass along
// walls and islands. Lengths mm, angles degrees; the drawing's frame is the workpiece's,
// the top face z = 0.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "trochomill/engagement.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/progress.hpp"

namespace trochomill {

/// A part of the pocket the clearing leaves: beyond the tool's reach (narrower than the tool
/// with the stock to leave on both sides: a neck, a slit, a corner's cusp), or within reach
/// but not at the target (an inside corner's last material, left to the finishing pass).
struct PocketLeftover {
  double area_mm2 = 0;
  Vec2 at_mm = Vec2::Zero();  ///< a point of it (the mean of its outline's vertices)
};

struct PocketInfo {
  double target_engagement_deg = 0;  ///< [pocket] max_engagement (or from max_chip)
  /// The feed per tooth over the tool radius, f_z / R: above about 0.02 the planner's discs
  /// a tooth apart no longer hold the target (docs/models.md, "Pockets").
  double tooth_advance_share = 0;
  /// The planner's own largest engagement at its step points (degrees), entries excepted.
  double planned_max_engagement_deg = 0;
  int parts = 0;   ///< connected regions the tool centre may reach (each entered once)
  int levels = 0;  ///< depth levels
  int passes = 0;  ///< clearing passes per level, all parts
  /// Channels per level (parts narrower than channel_width_mm) cleared by trochoidal loops
  /// along their medial axis, all parts.
  int channels = 0;
  double channel_width_mm = 0;  ///< [pocket] channel_width, or 2 D (mm)
  /// The swept band of channels no trochoid could start into, at the deepest level's plan
  /// (mm^2): left to the finishing pass.
  double channels_left_mm2 = 0;
  /// The channels' family ([path] type; empty: the loops, circles about the axis' points) and
  /// the length of the channels' axis (mm, one level: the deepest's plan) stepped along by its
  /// cycles, by loops (circles: all of it without a family; with one, the channels' ends and
  /// starts, where its cycles would reach past the axis) and by loops where no cycle of the
  /// family held the target.
  std::string channel_family;
  double channel_family_mm = 0;
  double channel_loops_mm = 0;
  double channel_unheld_mm = 0;
  /// The channels' family dropped: no plan with its cycles held the target by the kernel (its
  /// least largest clearing engagement, degrees), so the channels were cleared by loops.
  std::string channel_family_dropped;
  double channel_family_dropped_deg = 0;
  int links_down = 0;             ///< links per level that stay down in cleared area
  int lifts = 0;                  ///< links per level that lift over stock
  double clearing_length_mm = 0;  ///< feed length of one level's clearing passes that cut
  /// Length of one level's passes that runs through cleared area, cutting nothing (their runs
  /// at least R long): fed at the link feed (machine.air_feed, else max_feed, else the rapid
  /// rate).
  double air_length_mm = 0;
  /// Beyond the tool's reach: the pocket less what a tool centre in the region sweeps, less
  /// the inside corners' cusps below 1.5 (1 - pi/4) (R + stock)^2 each (mm^2).
  std::vector<PocketLeftover> unreachable;
  /// Parts just wider than the tool with the stock (narrower than D + 2 stock + R / 10 and
  /// more): too narrow for a channel's loops to hold the target, so the finishing pass cuts
  /// them as a slot at full depth; their area in the pocket (mm^2, about) and a point.
  std::vector<PocketLeftover> slotted;
  double cusps_mm2 = 0;  ///< the small leftovers not listed (inside corners' cusps)
  /// Within reach but left by the clearing because reaching it would pass the target (an
  /// inside corner's last material): the finishing pass takes it (mm^2, on the planner's grid).
  double left_for_finish_mm2 = 0;
  /// Rest machining ([pocket] rest_of): the earlier program's tool diameter (mm; 0: no rest_of)
  /// and, of the area this clearing must cover at the deepest level, what that program had
  /// removed (mm^2, on the planner's grid).
  double rest_tool_diameter_mm = 0;
  double rest_cleared_mm2 = 0;
  /// How each part is entered at the deepest level: a helix, straight down a pre-drilled hole
  /// ([pocket] entry_holes), or from above where nothing stands (beside a [stock] box the pocket
  /// runs past, or what rest_of's program cleared).
  int helix_entries = 0, hole_entries = 0, open_entries = 0;
  /// The pocket runs past the [stock] box or a [stock] mesh leaves air: the air (mm^2 of the
  /// area the clearing covers at the deepest level, on the planner's grid) counts as cleared.
  double open_mm2 = 0;
  /// The same per level, from the top (mm^2): with a [stock] mesh the air differs from level
  /// to level (a cored hole, a step); empty without one.
  std::vector<double> open_mm2_by_level;
  /// The levels' distinct plans (levels whose stock is the same share one): 1 unless rest_of
  /// or a [stock] mesh makes them differ.
  int plans = 1;
  /// Each level's clearing passes and their cutting length (mm), from the top: the figures
  /// above are the deepest level's; these differ from level to level where the plans do.
  std::vector<int> passes_by_level;
  std::vector<double> clearing_length_by_level_mm;
  /// With rest_of: each level's area the earlier program had cleared (mm^2), from the top.
  std::vector<double> rest_cleared_by_level_mm2;
  /// The path's entries: [first, last) segment index ranges (the helices and the finishing
  /// pass's lead-in), where the target does not hold.
  std::vector<std::pair<std::size_t, std::size_t>> entries;
  std::size_t finish_first_segment = 0;  ///< the finishing pass's first segment (or the end)
  /// The segments at the link feed (runs through cleared area, links that stay down), in
  /// increasing order: they must cut nothing.
  std::vector<std::size_t> air_segments;
  /// The steps' aim below the target (degrees): 1.2, more where the proof sent the plan back.
  double aim_margin_deg = 0;
  int replans = 0;  ///< plans the proof sent back (plan_pocket)
  /// The first plan's largest clearing engagement by the kernel and where (mm), and whether the
  /// plan given holds the target within kProofTolerance.
  double first_proof_max_deg = 0;
  Vec3 first_proof_at_mm = Vec3::Zero();
  bool proven = false;
};

/// Reads [pocket] rest_of (the earlier program, through the job's [machine] reading options)
/// into job.pocket.rest: its horizontal moves by height and its tool's radius (rest_tool_diameter,
/// else its header's tool.diameter). Nothing without rest_of; again only when the file or
/// diameter changed. Throws InputError naming the key for a program that cannot be read, that
/// never cuts below the top, or whose tool is unknown, smaller than the job's or not finite.
void attach_rest_stock(Job& job);

/// The engagement kernel's reading of a planned pocket (compute_engagement on its path, one
/// sample per tooth), the proof of the target: the largest engagement and chip of the clearing
/// outside its entries and where (the tool centre, mm), the share of its cutting time (samples
/// that cut) above the target, and the same largest figures of the finishing pass and of the
/// moves at the link feed.
struct PocketProof {
  double clearing_max_engagement_deg = 0;
  Vec3 clearing_max_at_mm = Vec3::Zero();
  double clearing_max_chip_mm = 0;         ///< at the feed: the link feed's own below
  double clearing_share_above_target = 0;  ///< 0 .. 1
  double finish_max_engagement_deg = 0;
  Vec3 finish_max_at_mm = Vec3::Zero();
  double finish_max_chip_mm = 0;
  /// The same of the moves at the link feed (PocketInfo::air_segments): a graze at most.
  double air_max_engagement_deg = 0;
  Vec3 air_max_at_mm = Vec3::Zero();
  double air_max_chip_mm = 0;
  /// What the moves at the link feed remove in all (mm^3, the kernel's removal rate over
  /// their samples): the feed marks and slivers their chip comes from, in proportion.
  double air_removed_mm3 = 0;
};

/// The clearing's largest engagement outside the entries that the proof accepts: the target and
/// this share of it (2 %: the kernel samples the teeth at their own phase, the planner at its
/// steps').
inline constexpr double kProofTolerance = 0.02;

/// The feed per tooth over the tool radius up to which the planner holds the target (the
/// plate's pocket holds at 0.01 and 0.02, not at 0.05 or 0.1: docs/models.md, "Pockets").
inline constexpr double kPocketToothShare = 0.02;

struct PlannedPocket {
  ToolPath path;
  PocketInfo info;
  PocketProof proof;  ///< the kernel's reading of `path` (prove_pocket)
};

/// Plans the job's pocket ([pocket], its contours read by the job) and proves it
/// (prove_pocket): where the kernel finds the clearing's engagement above the target by more
/// than kProofTolerance, plans it again with the steps' aim 0.5 degrees lower, up to three
/// times (PocketInfo::replans), and gives the first plan that holds, else the one of least
/// largest engagement (PocketInfo::proven false). Throws InputError when the tool does not fit
/// or the helix does not, Error without a pocket.
[[nodiscard]] PlannedPocket plan_pocket(const Job& job);

[[nodiscard]] PocketProof prove_pocket(const Job& job, const PlannedPocket& pocket,
                                       const RunHooks& hooks = {});
/// The same from the kernel's series of the pocket's path already computed (`analyze`'s: one
/// sample per tooth pass or finer), with the plan's entries and finishing pass.
[[nodiscard]] PocketProof prove_pocket(const PocketInfo& info, const EngagementSeries& series);

/// The memory `plan` of a pocket job takes (bytes), before planning: the process (30 MB), the
/// planner's grids (a byte a cell of the coverage) and steps (200 B each) and the kernel's
/// proof on the program (450 B a sample, one a tooth pass), the clearing taken as 5 times the
/// pocket's area over the side step of the target (the example pocket: 3.4 times). An upper
/// bound within a factor of 3 of the measured peak on the examples (docs/PERFORMANCE.md).
[[nodiscard]] double estimate_pocket_memory(const Job& job);

/// The job's program: the pocket's (plan_pocket) with [pocket], else the slot's (plan_slot).
[[nodiscard]] PlannedPath plan_job(const Job& job);

/// The pocket's depth levels: equal, each at most [pocket] max_step_down deep (one without
/// it); the first is at z = -depth / levels.
[[nodiscard]] int pocket_level_count(const Pocket& pocket);

}  // namespace trochomill
