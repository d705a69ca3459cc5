// G-code out and in. The writer emits an NC program for one of four dialects with exact
// G2/G3 for circular arcs and biarc (or chord) fits of other curves within a deviation
// tolerance; the reader parses an RS274 subset into the same ToolPath model, so every
// analysis runs on any NC program.
#pragma once

#include <filesystem>
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

/// One circular arc (or line) of a fit, in the XY plane at constant z (mm, rad).
struct FitArc {
  bool is_line = false;
  Vec3 start, end;
  double cx = 0, cy = 0, radius_mm = 0;
  double sweep_rad = 0;  ///< signed, positive = counter-clockwise
};

/// Fits a planar (z = const) curve segment with tangent-continuous biarcs whose deviation
/// from the curve is at most tolerance_mm. Returns the arcs in order.
[[nodiscard]] std::vector<FitArc> fit_biarcs(const Segment& curve, double tolerance_mm);
/// Chords (G1) of a curve segment whose deviation is at most tolerance_mm.
[[nodiscard]] std::vector<Vec3> fit_chords(const Segment& curve, double tolerance_mm);

struct GcodeReadOptions {
  double rapid_rate_mm_per_min = 10000;    ///< speed given to G0 moves (mm/min)
  double arc_radius_tolerance_mm = 0.002;  ///< allowed start/end radius mismatch of arcs (mm)
};

/// What the reader saw besides the motion.
struct GcodeProgramInfo {
  double max_spindle_rpm = 0;
  double min_feed_mm_per_min = 0, max_feed_mm_per_min = 0;
  std::size_t lines = 0;
  std::size_t motion_blocks = 0;
  bool inch_units_seen = false;
  /// The job keys a trochomill program records in its header, `section.key = value` (TOML).
  std::vector<std::pair<std::string, std::string>> header_keys;
};

struct GcodeProgram {
  ToolPath path;
  GcodeProgramInfo info;
};

/// `[machine]` as the writer's and the reader's options: the dialect, arc output and tolerance
/// the writer uses, the rapid rate the reader gives G0 moves. The one place the machine's
/// settings become G-code options.
struct GcodeOptions {
  GcodeWriteOptions write;
  GcodeReadOptions read;
};
[[nodiscard]] GcodeOptions gcode_options(const Machine& machine);

/// Parses a program. Errors are InputError "name:line:column: what is wrong".
/// The path starts at the first move in X or Y (the machine's position before is unknown: a
/// Z-only approach to the clearance plane gives the start its height, it is not a move).
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

}  // namespace trochomill
