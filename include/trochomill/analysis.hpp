// Process metrics of a slot program (Wagih 2023 Sections 2-5; docs/models.md sections 7-8), for
// any path: planned from the job or read from G-code. Per-cycle quantities describe one
// steady-state cycle in the middle of the slot; whole-program quantities cover entry, cycles
// and exit.
//
// Steady-state cycle: it starts where the tool starts cutting (the swept rate becomes
// positive) at or after the middle of the cutting time, and ends where the path passes the
// same point shifted by the step s along +Y with the same direction (found on the samples
// and refined along the tangent), so it needs no cycle marks and works on imported G-code.
// A path without such a period (the linear family, a foreign program) gets the middle
// third of its cutting time as its window, and `periodic` is false.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "trochomill/engagement.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/surface.hpp"

namespace trochomill {

/// The parts of an analysis past the whole program's figures and the steady cycle's. Each
/// costs time (the floor about half of `analyze`, docs/PERFORMANCE.md): a caller that reads
/// only some metrics asks for theirs (report.hpp: analysis_parts_for). A part left out keeps
/// its fields at their defaults; the figures of the parts computed are the same to the bit.
struct AnalysisParts {
  /// The walls at path and tooth level, their texture, the floor's imprints and the teeth's
  /// exact chips (h_max_tooth_mm, chip_translation_error_mm).
  bool walls = true;
  /// The floor the end edges leave and its texture (floor, texture_floor). It needs the walls
  /// (a program whose window has no walls has no floor figures either): `floor` computes them.
  bool floor = true;
  /// The force model's F_R,max over the cycle and the performance index from it (force.hpp:
  /// analyze_with_forces; analyze_process never runs the force model).
  bool force = true;

  /// Only the whole program's and the steady cycle's figures (a simulation's window).
  [[nodiscard]] static AnalysisParts cycle_only() { return {false, false, false}; }
  [[nodiscard]] bool all() const { return walls && floor && force; }
  /// Whether every part `need` names is here.
  [[nodiscard]] bool has(const AnalysisParts& need) const {
    return (walls || !need.walls) && (floor || !need.floor) && (force || !need.force);
  }
  /// Adds the parts of `o`.
  AnalysisParts& operator|=(const AnalysisParts& o) {
    walls = walls || o.walls;
    floor = floor || o.floor;
    force = force || o.force;
    return *this;
  }
  friend bool operator==(const AnalysisParts&, const AnalysisParts&) = default;
};

struct ProcessMetrics {
  // Whole program.
  double path_length_mm = 0;          ///< all moves (mm)
  double feed_length_mm = 0;          ///< feed moves (mm)
  double machining_time_s = 0;        ///< at programmed feeds and rapid rate (s)
  double machining_time_accel_s = 0;  ///< with [machine] max_acceleration (s)
  double slot_volume_mm3 = 0;         ///< W L depth (mm^3)
  /// Volume the program removes from the slot's stock: the swept plan-view area times the
  /// depth cut, integrated over the samples (mm^3).
  double removed_volume_mm3 = 0;
  double mrr_total_mm3_per_min = 0;  ///< removed volume / machining time (mm^3/min)
  double feed_per_tooth_mm = 0;
  double h_max_slot_mm = 0;                  ///< largest local chip over the program (mm)
  double t_h_max_slot_s = 0;                 ///< when it occurs (s from program start)
  double engagement_angle_max_slot_deg = 0;  ///< largest engagement over the program (deg)
  double cutting_time_total_s = 0;           ///< time with the tool advancing into stock (s)
  Vec3 h_max_slot_at_mm = Vec3::Zero();      ///< the tool centre where h_max_slot occurs (mm)
  /// The largest chip outside the entries and where (mm): after the first cycle mark of a
  /// planned path; in a program without marks (read from a file) outside each descent into
  /// the stock and the feed moves after it within a tool diameter of where it ended.
  double h_max_after_entry_mm = 0;
  Vec3 h_max_after_entry_at_mm = Vec3::Zero();
  Vec3 engagement_max_slot_at_mm = Vec3::Zero();  ///< where the largest engagement is (mm)
  /// The largest engagement outside the entries (as h_max_after_entry) and where.
  double engagement_max_after_entry_deg = 0;
  Vec3 engagement_max_after_entry_at_mm = Vec3::Zero();
  /// The end edges' largest axial chip (mm): the descent per tooth period where a descending
  /// end face cuts stock no earlier position removed (engagement.hpp: axial_chip_mm), where it
  /// is, and how many descents into stock cut with the end face (runs of such samples: a
  /// plunge, each peck of a drilling cycle, a ramp, a helix).
  double h_axial_max_mm = 0;
  Vec3 h_axial_max_at_mm = Vec3::Zero();
  int descents_into_stock = 0;
  /// The path's segments where the three occur (npos: none), and for a program read from a
  /// file the blocks that made them ("file:line", filled by the caller that read it: the
  /// analysis knows only the path).
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);
  std::size_t h_max_slot_segment = npos, h_max_after_entry_segment = npos;
  std::size_t engagement_max_slot_segment = npos, engagement_max_after_entry_segment = npos;
  std::size_t h_axial_max_segment = npos;
  std::string h_max_slot_source, h_max_after_entry_source, engagement_max_slot_source,
      engagement_max_after_entry_source, h_axial_max_source;

  // Steady-state cycle (or window).
  bool periodic = false;
  double cycle_start_s = 0;             ///< program time where the cycle starts (s)
  double cycle_time_s = 0;              ///< (s)
  double path_length_per_cycle_mm = 0;  ///< (mm)
  double cutting_time_s = 0;            ///< engaged part of the cycle (s)
  double cooling_time_s = 0;            ///< cycle time - cutting time (s)
  double h_max_mm = 0;                  ///< largest local chip in the cycle (mm)
  double t_h_max_s = 0;                 ///< from the cycle's start of cutting to h_max (s)
  double engagement_angle_max_deg = 0;  ///< (deg)
  double mrr_mm3_per_min = 0;           ///< W s a_p / cycle time (window: swept rate) (mm^3/min)
  double mrr_swept_mm3_per_min = 0;     ///< mean of a_p x swept rate over the cycle (mm^3/min)
  double axial_depth_mm = 0;            ///< a_p in the cycle (mm)

  // Exact chip between adjacent teeth's tip trajectories (with runout) in the cycle.
  double h_max_tooth_mm = 0;               ///< largest chip of any tooth (mm)
  std::vector<double> h_max_per_tooth_mm;  ///< per tooth (mm)
  double chip_translation_error_mm = 0;    ///< max |trajectory chip - circle-translation chip| (mm)

  // Walls (steady state, one period of y) and floor.
  Walls walls_path;   ///< path level (envelope of tool circles)
  Walls walls_tooth;  ///< tooth level (envelope of tooth tips)
  /// The predicted texture of each wall along the feed (y): the tooth-level profile (material
  /// side up) repeated as the steady state repeats it, filtered at the ISO 21920-3 default
  /// cut-off for its Ra (surface.hpp: periodic_profile_texture). Absent without a tooth-level
  /// profile.
  std::optional<ProfileTexture> texture_left, texture_right;
  ImprintDensity imprint;
  /// The floor along the slot (y) beside the left wall, in the middle and beside the right
  /// wall (x = -(W/2 - D/4), 0, W/2 - D/4: where Wagih 2023 Section 3 measured the bottom's
  /// Ra), left by the end edges over the whole program (surface.hpp floor_profile), between
  /// half a tool radius inside the slot's ends and the tool centre's reach at the floor, and
  /// each one's texture along the feed (ISO 21920-3 default cut-off for its Ra; absent where
  /// less than three 0.8 mm cut-offs were cut). A flat end face (tool.dish_angle 0) without
  /// axial runout leaves a flat floor (zero texture).
  std::array<FloorProfile, 3> floor;
  std::array<std::optional<ProfileTexture>, 3> texture_floor;

  // Performance index (Wagih Eq. 7): F_R,max from [measured] or the force model, Ra from
  // [measured] or the walls' predicted texture (the larger), W_max from [measured] or the
  // tooth-level waviness. Units: (mm^3/min) / (N um um).
  std::optional<double> performance_index;
  std::optional<double> force_max_predicted_n;  ///< F_R,max from the force model (N), if run
  std::string performance_index_note;           ///< where its inputs came from, or what is missing

  EngagementSeries series;  ///< the time series (one sample per tooth pass / steps)
  /// The parts computed (the request, the floor with its walls); the outputs give null for
  /// the figures of a part left out.
  AnalysisParts parts;
};

/// Analyses `path` for `job` (the job gives tool, slot, cutting conditions, step, [analysis]
/// and [measured]): the whole program, the steady cycle and the `parts` asked for. Throws
/// InputError when the path never cuts the slot.
[[nodiscard]] ProcessMetrics analyze_process(const Job& job, const ToolPath& path,
                                             const RunHooks& hooks = {},
                                             const AnalysisParts& parts = {});
/// The memory analyze_process will hold (bytes), before running it: its samples (one per
/// tooth pass / steps_per_tooth over the whole path, about 400 bytes each as measured) and
/// the process (its resident memory now, at least 20 MB: process_base_bytes).
[[nodiscard]] double estimate_analysis_memory(const Job& job, const ToolPath& path);

/// Sets the performance index of `m`: F_R,max from [measured] force_max, else the predicted
/// one (force.hpp: fill_predicted_force), with [measured] roughness_ra and the waviness.
void set_performance_index(const Job& job, ProcessMetrics& m,
                           std::optional<double> predicted_force_max_n = std::nullopt);

/// What limits a piece's feed.
/// plunge: the piece descends into stock no earlier position touched (an axial chip the radial
/// model does not hold) and keeps its programmed feed.
/// force, power, torque: a cap of FeedTargets::caps.
/// acceleration: lowered so the machine reaches it (and slows to the next piece's) within the
/// piece at machine.max_acceleration.
enum class FeedLimit {
  none,
  min_feed,
  max_feed,
  air,
  plunge,
  mrr,
  force,
  power,
  torque,
  acceleration,
  axial  ///< the axial chip target (FeedTargets::h_axial_max_mm): a descent's end face
};
/// The chips along a path as a feed schedule reads them, per sample (one per tooth pass from
/// the engagement kernel, one per time step from the simulation).
struct PathChips {
  std::vector<double> t_s;           ///< time (s)
  std::vector<double> s_mm;          ///< place along the path (mm)
  std::vector<std::size_t> segment;  ///< the path's segment there
  /// Where the sample's chip began to be made (where the tooth before passed): time (s), place
  /// along the path (mm) and segment. The chip is in proportion to the feed over that stretch.
  std::vector<double> from_t_s, from_s_mm;
  std::vector<std::size_t> from_segment;
  std::vector<double> h_mm;           ///< the largest uncut chip thickness (mm; 0: none)
  std::vector<double> mrr_mm3_per_s;  ///< the removal rate (mm^3/s)
  /// Material removed without a chip on the side of the edge (an axial chip: a plunge into
  /// stock no earlier position touched); the feed schedule keeps such pieces' feed or goes
  /// slower (the axial chip target).
  std::vector<char> plunge;
  /// The end edges' axial chip (mm): the descent per tooth period where the end face cuts
  /// stock (a plunge, a ramp, a helix, a peck), 0 elsewhere. In proportion to the feed, as
  /// the radial chip.
  std::vector<double> axial_mm;
  [[nodiscard]] std::size_t size() const noexcept { return t_s.size(); }
};
/// The exact engagement kernel's chips (engagement.hpp), one sample per tooth pass: the
/// radial chip (radial_chip_mm) and the removal rate per level (removal_rate_mm3_per_s).
/// `stock_mesh`: the stock as a closed mesh in the path's frame (EngagementOptions).
[[nodiscard]] PathChips kernel_chips(const Job& job, const ToolPath& path,
                                     const RunHooks& hooks = {}, const Mesh* stock_mesh = nullptr);

/// What a feed schedule holds along a path (schedule_feed).
struct FeedTargets {
  /// The largest local chip (mm) each piece of the path is fed to; default: the job's f_z.
  std::optional<double> h_max_mm;
  /// The largest axial chip (mm: the descent per tooth where the end face cuts stock,
  /// PathChips::axial_mm) a descent may cut: a descent faster than that is slowed to it.
  /// Unset: the chip target (h_max_mm).
  std::optional<double> h_axial_max_mm;
  /// Cap on the removal rate (mm^3/min; PathChips::mrr_mm3_per_s: the kernel's counts the
  /// stock over each part of the engaged arcs, level by level). Unset: none.
  std::optional<double> mrr_mm3_per_min;
  double min_feed_mm_per_min = 0;  ///< the slowest feed allowed (mm/min, > 0)
  double max_feed_mm_per_min = 0;  ///< the fastest feed allowed (mm/min, >= min)
  double air_feed_mm_per_min = 0;  ///< feed where the tool cuts nothing (0: the max feed)
  double piece_mm = 0.5;           ///< the path is fed in pieces at most this long (mm)
  /// Neighbouring pieces of one move whose feeds differ by less than this (percent) share
  /// the slower feed, so the program changes F fewer times.
  double feed_step_percent = 5;
  int iterations = 12;  ///< rounds of engagement and rescaling (each a full engagement run)
  /// Further caps, evaluated each round on the path as it is then (one segment per piece,
  /// at the pieces' feeds): lowers `allowed` (mm/min, per piece) where a cap needs it and
  /// sets that piece's `limit` (optimize-feed's force, power and torque caps from the force
  /// model). Empty: none.
  std::function<void(const ToolPath& pieces, std::vector<double>& allowed,
                     std::vector<FeedLimit>& limit)>
      caps;
  /// The chips of the path as it is each round; empty: the engagement kernel (kernel_chips).
  /// optimize-feed's `--engine sim` gives the tri-dexel simulation's.
  std::function<PathChips(const ToolPath& pieces)> chips;
  /// The stock's top (mm, the path's frame): a piece that descends (a helix, ramp or plunge)
  /// below it keeps its programmed feed or goes slower, never faster: slower where its
  /// radial chip or its axial chip passes its target (the end edges' cut, whose cutting
  /// conditions the program's author chose for the descent). Unset:
  /// the job's (engagement.hpp: stock_top_mm without a mesh).
  std::optional<double> stock_top_mm;
};
/// Whether the part [from_mm, to_mm] of a segment (arc length, mm) descends and ends below
/// `top_mm` (mm): a descent into the stock, whose feed schedule_feed never raises.
[[nodiscard]] bool piece_descends_below(const Segment& seg, double from_mm, double to_mm,
                                        double top_mm);
/// The job's feed targets: the [machine] max_feed, min_feed and air_feed, where 0 gives three
/// times and a tenth of the job's feed, and the max feed; the chip target unset (the job's f_z).
[[nodiscard]] FeedTargets default_feed_targets(const Job& job);
/// A piece of a scheduled path: the part [from_mm, to_mm] of the input path's segment (arc
/// length along it, mm), its feed (mm/min) and what limits it.
struct FeedPiece {
  std::size_t segment = 0;
  double from_mm = 0, to_mm = 0;
  double feed_mm_per_min = 0;
  FeedLimit limit = FeedLimit::none;
};
/// A path with scheduled feeds and how it got them.
struct FeedSchedule {
  ToolPath path;               ///< the same geometry in pieces, each at its feed
  double time_before_s = 0;    ///< the input path's programmed time (s)
  double time_after_s = 0;     ///< the scheduled path's (s)
  double h_max_before_mm = 0;  ///< the largest chip at the input's feeds (mm)
  double h_max_after_mm = 0;   ///< at the scheduled feeds, before pieces are merged (mm)
  /// The largest axial chip (mm, PathChips::axial_mm) at the input's feeds and at the
  /// scheduled ones.
  double h_axial_max_before_mm = 0, h_axial_max_after_mm = 0;
  std::size_t pieces = 0;  ///< segments of the scheduled path
  /// Per feed piece (before merging): its largest chip (mm), feed (mm/min) and limit.
  std::vector<double> piece_h_max_mm, piece_feed_mm_per_min;
  std::vector<FeedLimit> piece_limit;
  /// The feed moves of the scheduled path as parts of the input's segments (after merging).
  std::vector<FeedPiece> feed_pieces;
  /// Where the chip target is missed by more than 3 % (the schedule's tolerance): the pieces
  /// over it, the worst one's chip (mm), where it starts (mm, the path's frame; s of the
  /// scheduled path), its feed (mm/min) and what held that feed. none: no piece over.
  struct Missed {
    std::size_t pieces = 0;
    double h_max_mm = 0;
    Vec3 at_mm = Vec3::Zero();
    double at_s = 0;
    double feed_mm_per_min = 0;
    FeedLimit limit = FeedLimit::none;
  };
  std::optional<Missed> missed;
};
/// What a FeedLimit means, in words ("the chip target", "the max feed", ...).
[[nodiscard]] const char* describe(FeedLimit limit) noexcept;
/// Schedules the feed along `path` so that the largest local chip of every piece is the
/// target (Wagih 2023's h_max from the exact engagement, docs/models.md section 15): the
/// chip grows in proportion to the feed per tooth where the engaged arcs stay the same, so
/// each piece's feed is scaled by target / h_max, bounded by the limits, and the engagement
/// evaluated again on the new path, `iterations` times. Rapids keep their rate. Throws
/// InputError for bad targets; `hooks.cancel` stops it with Interrupted.
[[nodiscard]] FeedSchedule schedule_feed(const Job& job, const ToolPath& path,
                                         const FeedTargets& targets, const RunHooks& hooks = {});

/// A key varied by a parameter study, with its values (TOML, as typed); parse_vary and the
/// studies themselves (compare, sweep) are in study.hpp.
struct Vary {
  std::string key;                  ///< "section.key"
  std::vector<std::string> values;  ///< TOML values as typed
};

/// One grid point of a study: its overrides and its metrics (or the error that stopped it).
struct StudyPoint {
  std::vector<Override> overrides;
  bool ok = false;
  std::string error;
  ProcessMetrics metrics;
};

}  // namespace trochomill
