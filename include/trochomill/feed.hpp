// Feed optimisation of NC programs: `trochomill optimize-feed`. The program is read by the
// interpreter (gcode.hpp), its feed moves scheduled so the largest chip of every piece is the
// target (analysis.hpp: schedule_feed, the exact engagement against the job's stock), the
// program rewritten with the new feeds and nothing else changed (gcode.hpp: rewrite_feeds),
// then read again: its motion must be the input's, and its chips are evaluated anew for the
// summary.
#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/analysis.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/job.hpp"
#include "trochomill/progress.hpp"

namespace trochomill {

/// Where optimize-feed's chips come from.
enum class FeedEngine {
  kernel,  ///< the exact engagement kernel: 2.5D programs
  sim      ///< the tri-dexel simulation at [simulation] resolution_mm and steps_per_rev: any motion
};

struct FeedOptimizeOptions {
  /// The chip target, the removal cap and the feed limits (default_feed_targets(job)).
  FeedTargets targets;
  /// Caps from the job's [material] force model (fast chips, force.hpp): the resultant force
  /// on the workpiece (N), the spindle power (W) and torque (N m) held at or below them.
  std::optional<double> force_n, power_w, torque_nm;
  GcodeReadOptions read;  ///< how the program is read (gcode_options(job.machine).read)
  FeedEngine engine = FeedEngine::kernel;
  /// The stock as a closed mesh in the program's frame (mm; geometry.hpp read_mesh) for
  /// either engine; unset: the job's [stock] box (or the slot region).
  std::shared_ptr<const Mesh> stock_mesh;
  /// The simulation's estimated memory (bytes) above which it is refused before it starts.
  double memory_limit_bytes = std::numeric_limits<double>::infinity();
};

/// The tri-dexel simulation's chips over the whole of `path` (the slot frame), one sample per
/// time step: the largest chip of the step's engaged edge segments (sim.hpp SimStep h_max_mm),
/// made since the tooth before passed; the removal rate from the step's removed volume; a
/// step that removes more than a dexel cube with no chip on the edge is a plunge.
/// `stock_mesh` in the slot frame (null: the job's box). Throws Interrupted when cancelled.
[[nodiscard]] PathChips simulated_chips(const Job& job, const ToolPath& path,
                                        const Mesh* stock_mesh, const RunHooks& hooks = {});

/// Quantiles of a quantity over the cutting time (the time the tool cuts a chip > 0).
struct CutQuantiles {
  double p50 = 0, p90 = 0, p99 = 0, max = 0;
};

/// A block of the program where the chip stays above the target although its feed is at the
/// machine's minimum.
struct UnheldBlock {
  std::string file;
  std::size_t line = 0;
  double h_max_mm = 0;         ///< its largest chip at the minimum feed (mm)
  double feed_mm_per_min = 0;  ///< the minimum feed (mm/min)
};

struct FeedOptimizeResult {
  std::string text;     ///< the rewritten program
  FeedRewrite rewrite;  ///< its counts (its text moved to `text`)
  std::size_t moves = 0, moves_split = 0;
  /// Moves kept at their programmed feed or slower (slower where the radial or the axial
  /// chip passes its target): descents into the stock (a helix, ramp or plunge below its
  /// top) and axial chips (material removed with no radial chip).
  std::size_t moves_descending = 0, moves_axial = 0;
  /// Programmed time (s) at the programmed feeds and rapid rate, and with the machine's
  /// acceleration limit (path.hpp: estimate_time_s; equal when [machine] max_acceleration is
  /// 0), before and after.
  double time_before_s = 0, time_after_s = 0;
  double time_before_accel_s = 0, time_after_accel_s = 0;
  double cutting_time_before_s = 0, cutting_time_after_s = 0;  ///< time with a chip (s)
  /// The largest local chip h_max (mm) and the removal rate (mm^3/min) over the cutting time,
  /// before and after.
  CutQuantiles h_before_mm, h_after_mm, mrr_before, mrr_after;
  /// With a [material] force model: the resultant force (N), power (W) and torque (N m) over
  /// the cutting steps, before and after (the fast chip source over the whole program).
  bool forces = false;
  CutQuantiles force_before_n, force_after_n, power_before_w, power_after_w, torque_before_nm,
      torque_after_nm;
  double h_target_mm = 0;  ///< the chip target (mm)
  /// The axial chip target (mm, FeedTargets::h_axial_max_mm) and the largest axial chip
  /// (mm: the descent per tooth where the end face cuts stock) before and after.
  double h_axial_target_mm = 0, h_axial_max_before_mm = 0, h_axial_max_after_mm = 0;
  FeedEngine engine = FeedEngine::kernel;  ///< where the chips came from
  double sim_resolution_mm = 0;            ///< with the simulation: its dexel spacing (mm)
  int sim_steps_per_rev = 0;               ///< and its time steps per revolution
  /// Shares (0..1) of the rewritten program's feed time held by the chip target, the removal
  /// cap, the max and min feed, the air feed, descents and plunges kept at their programmed
  /// feed, descents slowed to the axial chip target, and kept (moves the rewrite does not
  /// feed: canned cycles, compensation, other files).
  double share_target = 0, share_mrr = 0, share_max_feed = 0, share_min_feed = 0, share_air = 0,
         share_plunge = 0, share_kept = 0, share_force = 0, share_power = 0, share_torque = 0,
         share_acceleration = 0, share_axial = 0;
  double min_feed_after_mm_per_min = 0, max_feed_after_mm_per_min = 0;
  std::vector<UnheldBlock> unheld;  ///< where the chip target cannot be held
  /// Where the axial chip target cannot be held (h_max_mm: the largest axial chip there).
  std::vector<UnheldBlock> unheld_axial;
  std::vector<std::string> warnings;  ///< the reader's, for the input program
  /// Per tooth-pass sample of the input and of the rewritten program: time (s), place along
  /// the path (mm), feed (mm/min; NaN in rapids) and chip (mm) (the report's before/after).
  std::vector<double> t_before_s, s_before_mm, feed_before, h_before;
  std::vector<double> t_after_s, s_after_mm, feed_after, h_after;
  /// With a [material] model: the resultant force (N) at every step of the fast chip source,
  /// before and after, with their places along the path (mm).
  std::vector<double> force_s_before_mm, force_before_series_n, force_s_after_mm,
      force_after_series_n;
};

/// Optimises the feeds of `text` (a program named `name`; its folder is searched for
/// subroutine files) for `job`. Throws InputError for a program the rewrite cannot keep
/// safe (gcode.hpp: rewrite_feeds), bad targets, or a program that never cuts the stock;
/// Error when the rewritten program's motion differs from the input's (it is not returned);
/// `hooks.cancel` stops it with Interrupted.
[[nodiscard]] FeedOptimizeResult optimize_feed(const Job& job, std::string_view text,
                                               std::string_view name,
                                               const FeedOptimizeOptions& options,
                                               const RunHooks& hooks = {});

/// The summary as JSON (times, chip and removal-rate quantiles before and after, the shares of
/// feed time by limit, the blocks where the target cannot be held, the reader's warnings) and
/// as text.
[[nodiscard]] std::string feed_summary_json(const FeedOptimizeResult& r);
[[nodiscard]] std::string feed_summary_text(const FeedOptimizeResult& r);

}  // namespace trochomill
