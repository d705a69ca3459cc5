// G-code out and in. The writer emits an NC program for one of four dialects with exact
// G2/G3 for circular arcs and biarc (or chord) fits of other curves within a deviation
// tolerance; the reader parses an RS274 subset into the same ToolPath model, so every
// analysis runs on any NC program.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "trochomill/job.hpp"
#include "trochomill/path.hpp"

namespace trochomill {

struct GcodeWriteOptions {
  Dialect dialect = Dialect::linuxcnc;
  ArcOutput arc_output = ArcOutput::arcs;
  double tolerance_mm = 0.001;  ///< max deviation of the fitted arcs/chords from the path (mm)
  int decimals = 4;             ///< coordinate decimals (mm)
};

/// Writes the whole program for a planned job: header (units, plane, absolute mode,
/// spindle, feed, coolant, a comment block with the job's parameters), motion, program end.
[[nodiscard]] std::string write_gcode(const Job& job, const ToolPath& path,
                                      const GcodeWriteOptions& options);

/// Fits a planar (z = const) curve segment with tangent-continuous biarcs whose deviation
/// from the curve is at most tolerance_mm. Returns the arcs in order.
[[nodiscard]] std::vector<FitArc> fit_biarcs(const Segment& curve, double tolerance_mm);
/// Chords (G1) of a curve segment whose deviation is at most tolerance_mm.
[[nodiscard]] std::vector<Vec3> fit_chords(const Segment& curve, double tolerance_mm);

/// One tool of a LinuxCNC tool table (`T1 P1 Z50.2 D6 ;comment`): the length offset G43 applies
/// and the diameter (mm).
struct ToolTableEntry {
  double length_mm = 0;
  double diameter_mm = 0;
};

/// One canonical move as the interpreter resolved it (what `check-gcode --trace` prints):
/// end points in the output frame (the job's work coordinate system, mm), the feed it runs at
/// (mm/min, the rapid rate for rapids) and the program line that made it.
struct GcodeMove {
  enum class Kind { rapid, feed, arc };
  Kind kind = Kind::feed;
  Vec3 start_mm = Vec3::Zero(), end_mm = Vec3::Zero();
  Vec3 centre_mm = Vec3::Zero();  ///< arcs: the centre, at the start's height along the axis
  Vec3 axis = Vec3::UnitZ();      ///< arcs: the plane's normal (G17 +Z, G18 +Y, G19 +X)
  double sweep_rad = 0;           ///< arcs: signed turn about the axis (+ = counter-clockwise)
  double feed_mm_per_min = 0;
  int plane = 17;  ///< the active plane: 17, 18 or 19
  /// The axes besides X Y Z at the move's end, output frame: A B C (degrees) and U V W (mm);
  /// `extra_axes` is true once the program has given a word of any of them.
  std::array<double, 6> extra_end{};
  bool extra_axes = false;
  bool path_started = false;  ///< false for the approach before the path starts (see read_gcode)
  std::string_view file;      ///< the file of the block (the program or a subroutine file)
  std::size_t line = 0;       ///< 1-based line in that file

  // What rewrite_feeds needs of the block that made the move.
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);
  std::size_t source = 0;  ///< 0: the program itself, else a subroutine file it calls
  /// A G0/G1/G2/G3 of the block's own words at a feed per minute (G94), without cutter
  /// compensation or G53, that moves no axis besides X Y Z: its end and centre are words of
  /// the block, so it can be split.
  bool plain = false;
  int motion = -1;  ///< the motion mode: 0, 1, 2, 3 (-1: a canned cycle and the like)
  /// Threading (G33, G33.1, G76): it runs at the pitch times the spindle speed; F is not its.
  bool synchronized = false;
  std::uint64_t block_run = 0;  ///< the block execution that made it (a loop's passes differ)
  std::size_t segment = npos;   ///< its segment in GcodeProgram::path (npos: none)
  /// The block's frame: the output-frame position of program zero (mm), the turn of the
  /// program's X/Y axes against the output frame's (rad, counter-clockwise), mm per program
  /// unit (1 or 25.4), G91 and G90.1.
  Vec3 program_zero_mm = Vec3::Zero();
  double program_turn_rad = 0;
  double unit_mm = 1;
  bool incremental = false, ijk_absolute = false;
  int feed_mode = 94;  ///< 94 per minute, 93 inverse time, 95 per revolution
  /// The modal feed (mm/min; G95: mm/rev) before the block and after its F word, and the feed
  /// settings counted (F words and modal restores) before the block and after it: a count that
  /// grows between two moves' blocks means a block without motion set the feed.
  double feed_before = 0, feed_word = 0;
  std::uint64_t feed_events_before = 0, feed_events = 0;
};

/// The interpreter's setting: the language, where the machine's offsets and home are, the
/// tool table, the limits that stop a runaway program. Machine positions are mm.
struct GcodeReadOptions {
  double rapid_rate_mm_per_min = 10000;  ///< speed given to G0 moves (mm/min)
  /// How far an R-form arc's radius may fall short of half its chord (mm); a centre-form arc's
  /// radii to start and end may differ as LinuxCNC allows (0.02 sqrt(2) mm, or 0.002 sqrt(2)
  /// in in G20, and 0.1 %).
  double arc_radius_tolerance_mm = 0.002;
  /// How far the arcs a spline (G5, G5.1, G5.2) is read as may deviate from its exact curve
  /// (mm): the path holds biarcs, tangent-continuous, within this of the curve.
  double spline_tolerance_mm = 0.001;
  /// The language: linuxcnc (RS274/NGC with O-words) or fanuc (Macro B); sinumerik and grbl
  /// read as linuxcnc's plain subset plus their unit words.
  Dialect dialect = Dialect::linuxcnc;
  /// Folders searched, in order, for `o<name> call`'s `name.ngc` when the program does not
  /// define the subroutine itself (the program's own folder is searched first).
  std::vector<std::filesystem::path> include_dirs;
  std::map<int, ToolTableEntry> tools;  ///< tool number -> entry; a missing tool has length 0
  /// The diameter (mm) cutter compensation takes for a tool neither `tools` nor the table has
  /// (the job's tool where a job reads the program; 0, LinuxCNC's, otherwise), with a warning.
  double missing_tool_diameter_mm = 0;
  /// A LinuxCNC tool table read when the program is (its entries over `tools`); empty: none.
  std::filesystem::path tool_table;
  /// Origins of G54, G55, ... G59.3 (index 0 .. 8) in machine coordinates (mm) and their XY
  /// rotations (degrees); unset ones are zero (a warning names them when a program uses them).
  std::array<std::optional<Vec3>, 9> work_offsets_mm;
  std::array<double, 9> work_rotation_deg{};
  /// G28 and G30 positions in machine coordinates (mm); unset: X0 Y0 of the output frame at
  /// `home_z_mm` above its origin (stated in a warning when a program uses them).
  std::optional<Vec3> g28_position_mm, g30_position_mm;
  double home_z_mm = 5;
  /// The work coordinate system the program starts in and the path is given in: 1 = G54 .. 9 =
  /// G59.3.
  int work_system = 1;
  /// How far above the last peck G73 and G83 return before feeding on (mm): LinuxCNC 2.9's
  /// 0.010 inch.
  double peck_clearance_mm = 0.254;
  /// false: the segments are not kept, only their summary (GcodeProgram::summary): a long
  /// program is then read in memory for its text alone.
  bool keep_path = true;
  std::uint64_t max_blocks = 200'000'000;  ///< interpreted blocks before "infinite loop?" stops
  /// The most memory (bytes) the kept path (and the trace's moves, when traced) may take
  /// while it is read; past it the reader stops with InputError naming the line ("does the
  /// program loop without end?"), before the process runs out. 0: no limit.
  double max_path_bytes = 0;
  int max_call_depth = 64;  ///< nested subroutine calls
  /// Called for every canonical move, in order (check-gcode --trace); may be empty.
  std::function<void(const GcodeMove&)> trace;
  /// Polled every 64k blocks; true stops the reader with Interrupted (Ctrl-C).
  std::function<bool()> cancel;
};

/// What the reader saw besides the motion.
struct GcodeProgramInfo {
  double max_spindle_rpm = 0;
  double min_feed_mm_per_min = 0, max_feed_mm_per_min = 0;
  std::size_t lines = 0;
  std::size_t motion_blocks = 0;
  std::uint64_t blocks_executed = 0;  ///< blocks interpreted (loops and calls count each pass)
  bool inch_units_seen = false;
  /// What the reader assumed (an offset, a home position) or ignored, each naming its line.
  std::vector<std::string> warnings;
  /// Where the program first reads its own feed (#<_feed>), "file:line:column"; empty: never.
  /// Its motion may then depend on its feeds (optimize-feed refuses it).
  std::string feed_read_at;
  /// The axes besides X Y Z the program moves (a subset of "ABCUVW"; empty: none), each one's
  /// range in the output frame (A B C degrees, U V W mm; indexed A B C U V W), and the time
  /// of the feed moves that turn or move only them (s: ABC at F degrees/min, UVW at F mm/min,
  /// G93 1/F min), which the path's time (its X Y Z motion) leaves out.
  std::string extra_axes;
  std::array<double, 6> extra_min{}, extra_max{};
  double extra_only_time_s = 0;
  /// The job keys a trochomill program records in its header, `section.key = value` (TOML).
  std::vector<std::pair<std::string, std::string>> header_keys;
  /// The tools its tool changes (M6) loaded, in order: T numbers, each with the program line
  /// ("file:line") of its M6.
  std::vector<std::pair<int, std::string>> tool_changes;
};

/// Where a segment of a read program comes from: the file (an index into
/// GcodeProgram::source_files: 0 the program, then the subroutine files it calls) and the
/// 1-based line of the block that made it.
struct SourceLine {
  std::uint32_t source = 0;
  std::uint32_t line = 0;
};

struct GcodeProgram {
  ToolPath path;  ///< empty when read with keep_path = false
  GcodeProgramInfo info;
  PathSummary summary;  ///< filled when read with keep_path = false (else summarize(path))
  std::vector<SourceLine> segment_lines;  ///< one per segment of `path`
  std::vector<std::string> source_files;  ///< the names SourceLine::source indexes
  /// "file:line" of the block that made segment i of `path` ("" past its end).
  [[nodiscard]] std::string where(std::size_t segment) const;
};

/// Reads a LinuxCNC tool table: lines `T<n> P<pocket> Z<length> D<diameter> ;comment` (other
/// axis words are allowed and ignored). Errors name file:line:column.
[[nodiscard]] std::map<int, ToolTableEntry> read_tool_table(const std::filesystem::path& file);

/// The share of the memory limit a program's path may take as it is read (the rest is the
/// work on it: samples, chips; GcodeReadOptions::max_path_bytes).
inline constexpr double kPathShareOfMemory = 0.25;
/// `[machine]` as the writer's and the reader's options: the dialect, arc output and tolerance
/// the writer uses, the rapid rate the reader gives G0 moves, a quarter of the default memory
/// limit (io.hpp) for the path as read. The one place the machine's
/// settings become G-code options.
struct GcodeOptions {
  GcodeWriteOptions write;
  GcodeReadOptions read;
};
[[nodiscard]] GcodeOptions gcode_options(const Machine& machine);

/// Interprets a program: RS274/NGC as LinuxCNC runs it (parameters, expressions, O-word
/// subroutines and loops, work offsets, G92, G28/G30/G53, canned cycles, feed modes) or Fanuc
/// with Macro B. Errors are InputError "name:line:column: what is wrong".
/// The path starts at the first move in X or Y (the machine's position before is unknown: a
/// Z-only approach to the clearance plane gives the start its height, it is not a move).
/// Positions are the tool tip in the output frame (options.work_system), mm.
[[nodiscard]] GcodeProgram read_gcode(std::string_view text, std::string_view source_name,
                                      const GcodeReadOptions& options = {});
/// The `section.key = value` comment lines of a program's leading comment block.
[[nodiscard]] std::vector<std::pair<std::string, std::string>> gcode_header_keys(
    std::string_view text);
[[nodiscard]] GcodeProgram read_gcode_file(const std::filesystem::path& file,
                                           const GcodeReadOptions& options = {});
/// Where a trochomill program's header (the job keys it was written with) disagrees with the
/// job in the sections the models read beside the moves ([tool], [slot], [path], [cutting]):
/// one sentence per key, naming the program as `name`. Empty for a program without such a
/// header (not written by trochomill).
[[nodiscard]] std::vector<std::string> header_mismatches(const Job& job, const GcodeProgram& prog,
                                                         const std::string& name);

/// The new feeds of one move for rewrite_feeds: the move in pieces, each ending at a point of
/// the move (output frame, mm; the last is the move's end) and fed at its feed (mm/min). Empty:
/// the move keeps its feed.
struct MoveFeeds {
  std::vector<Vec3> ends_mm;
  std::vector<double> feed_mm_per_min;
};
/// A program with its feeds rewritten.
struct FeedRewrite {
  std::string text;
  std::size_t blocks_changed = 0;  ///< blocks whose F word or motion words changed
  std::size_t lines_added = 0;     ///< lines of the pieces of split moves
};
/// Rewrites the feeds of `text`, a program read by read_gcode into `moves` (the trace, in
/// order, one MoveFeeds each). The text stays as it was except: a plain move of a block run
/// once (GcodeMove::plain) with several pieces is split into G1/G2/G3 lines in the block's own
/// frame (units, G90/G91, G90.1/G91.1, the work offset and rotation), arcs as arcs with I J K;
/// a block run more than once takes the slowest feed its runs need; coordinates are written
/// with the places the dialect's controls read (LinuxCNC 9, Sinumerik 6, Fanuc and Grbl 4 in
/// mm, one more in inch: rewrite_places); F words are written only
/// where the modal feed changes, and a kept move whose modal feed the rewrite would change gets
/// an F word of its own. Throws InputError where that is not possible (a move of a called file
/// that takes the caller's feed, a block run at different kept feeds).
[[nodiscard]] FeedRewrite rewrite_feeds(std::string_view text, const std::vector<GcodeMove>& moves,
                                        const std::vector<MoveFeeds>& feeds, Dialect dialect);
/// The coordinate places rewrite_feeds writes for a dialect (unit_mm: 1 mm or 25.4 inch).
[[nodiscard]] int rewrite_places(Dialect dialect, double unit_mm);

}  // namespace trochomill
