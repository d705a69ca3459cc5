// The application layer: what every caller of the library (the CLI, the Python module) does
// around a model call, written once. Its messages name options by their API names, marked with
// option_name (`cycles`, `from_s`, `to_s`, `memory_limit_gb`); each caller renders them as its
// own (Error::message: the CLI's `--cycles`, Python's `cycles`), so the rule is one. Times s,
// memory bytes (limits GB where a user gives them).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "trochomill/analysis.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/path.hpp"
#include "trochomill/report/html.hpp"

namespace trochomill {

/// A time window of a path as a user asks for it: trochoid cycles A (inclusive) to B
/// (exclusive, from 0), or a start and an end in s of programmed time, or neither (the whole
/// path).
struct WindowRequest {
  std::optional<std::pair<long long, long long>> cycles;
  std::optional<double> from_s, to_s;
  [[nodiscard]] bool given() const { return cycles || from_s || to_s; }
};
/// The window (s): the cycles' times (cycle_window), or [from_s or 0, to_s or the path's end].
/// Throws InputError naming the option (`cycles`, `from_s`, `to_s`): both forms given, a cycle
/// range outside 0 <= A < B <= the path's cycles (checked before any narrowing), a time not finite
/// or outside [0, 1e9] s, or an end not after the start.
[[nodiscard]] std::pair<double, double> resolve_window(const ToolPath& path,
                                                       const WindowRequest& request);
/// Reads "A:B" (the CLI's form of a cycle range). Throws InputError naming `cycles`.
[[nodiscard]] std::pair<long long, long long> parse_cycle_range(std::string_view text);

/// The memory a run may take (bytes): `limit_gb` when given (a finite number > 0, else an
/// InputError naming `memory_limit_gb`), else default_memory_limit_bytes (75 % of the RAM).
[[nodiscard]] double memory_limit_bytes(std::optional<double> limit_gb);
/// Refuses a run whose estimate (bytes) passes the limit before anything is allocated: an
/// InputError that gives both numbers, where the limit came from (`memory_limit_gb` or 75 % of
/// RAM) and `advice` (what makes the run smaller). `what`: the run, e.g. "simulate".
void check_memory(std::string_view what, double need_bytes, std::optional<double> limit_gb,
                  std::string_view advice);

/// Names the blocks of the analysis's largest chip and engagement (ProcessMetrics' *_source,
/// "file:line") from the line table of the program the path was read from (its
/// segment_lines and source_files); nothing for a table without lines.
void name_program_lines(ProcessMetrics& metrics, const GcodeProgram& lines);

/// The feed schedule's targets as a user gives them, over the job's defaults
/// (default_feed_targets: the job's feed per tooth and its [machine] feed limits).
struct FeedTargetRequest {
  std::optional<double> h_max_mm, mrr_mm3_per_min, feed_step_percent, piece_mm;
  std::optional<double> min_feed_mm_per_min, max_feed_mm_per_min, air_feed_mm_per_min;
  std::optional<double> h_axial_max_mm;
};
[[nodiscard]] FeedTargets feed_targets(const Job& job, const FeedTargetRequest& request);

/// The report's data: build_report's parts, then the request's parameter study (compare's
/// grid over `request.varies`, built from `request.document` with `request.overrides`:
/// run_compare, in the study module above the report's). Throws InputError naming the option
/// `vary` when every point of the study failed: a page of failures is not written.
[[nodiscard]] ReportData report_data(Job job, ToolPath path, ReportRequest request,
                                     const RunHooks& hooks = {});

}  // namespace trochomill
