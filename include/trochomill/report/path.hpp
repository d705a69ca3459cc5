// A path's samples with every tooth's tip (CSV) and `check-gcode`'s report of a program. Part of
// the report module (trochomill/report.hpp includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/gcode.hpp"
#include "trochomill/path.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/progress.hpp"

namespace trochomill {

/// `path`'s samples with every tooth's tip (mm, s).
[[nodiscard]] std::string path_samples_csv(const PathSamples& s, const ToothTracks& tr);
/// The same, handed to `sink` in pieces of about 1 MB (a file of any size, written as it is
/// made); `hooks`: the phase "writing CSV" with progress over the rows, cancelling throws
/// Interrupted.
void write_path_samples_csv(const PathSamples& s, const ToothTracks& tr,
                            const std::function<void(std::string_view)>& sink,
                            const RunHooks& hooks = {});
/// `check-gcode`'s report of a program: length, time (with the acceleration limit, when one
/// is given), bounding box, feeds and spindle speed.
[[nodiscard]] std::string gcode_check_json(const std::string& file, const GcodeProgram& prog,
                                           double time_with_acceleration_s);
[[nodiscard]] std::string gcode_check_text(const std::string& file, const GcodeProgram& prog,
                                           double time_with_acceleration_s,
                                           double max_acceleration_mm_per_s2);

/// What a pocket's plan did, for people (lines ending in newlines): parts, levels, passes and
/// links, the clearing length, the planner's largest engagement against the target, the
/// engagement kernel's proof on the program, the leftovers beyond reach (area and where) and
/// what the finishing pass is left.
[[nodiscard]] std::string pocket_summary(const PocketInfo& info, const PocketProof& proof);
/// The same as a JSON document (`plan --json`, Python's Path.pocket): the plan's figures and
/// the proof's, units in the keys (degrees, mm, mm^2), places as [x, y, z] in mm; and the
/// written program's (`program`: its path, the job's `machine` for the time with the
/// acceleration, the lines of its text): path_length_mm, machining_time_s,
/// machining_time_accel_s, program_lines.
[[nodiscard]] std::string pocket_json(const PocketInfo& info, const PocketProof& proof,
                                      const ToolPath& program, const Machine& machine,
                                      std::size_t program_lines);

}  // namespace trochomill
