// The application layer shared by the CLI and the Python module (app.hpp).
#include "trochomill/app.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/study.hpp"

namespace trochomill {

std::pair<double, double> resolve_window(const ToolPath& path, const WindowRequest& r) {
  const std::string cycles = option_name("cycles"), from_s = option_name("from_s"),
                    to_s = option_name("to_s");
  if (r.cycles) {
    if (r.from_s || r.to_s) {
      throw InputError(fmt::format("give {} or {}/{}, not both", cycles, from_s, to_s));
    }
    const auto [a, b] = *r.cycles;
    const long long count = static_cast<long long>(path.cycles().size());
    if (count == 0) {
      throw InputError(
          fmt::format("{}: the path has no cycle marks (a planned trochoid has)", cycles));
    }
    if (a < 0 || b <= a || b > count) {  // before any narrowing
      throw InputError(fmt::format("{} '{}:{}': need 0 <= A < B <= {} (the path's cycles)", cycles,
                                   a, b, count));
    }
    return cycle_window(path, static_cast<int>(a), static_cast<int>(b));
  }
  for (const auto& [name, v] : {std::pair{&from_s, r.from_s}, std::pair{&to_s, r.to_s}}) {
    if (v && !(std::isfinite(*v) && *v >= 0 && *v <= 1e9)) {
      throw InputError(fmt::format("{} must be a finite time in [0, 1e9] s, got {}", *name, *v));
    }
  }
  const double from = r.from_s.value_or(0.0), to = r.to_s.value_or(path.duration_s());
  if (r.given() && !(to > from)) {
    throw InputError(
        fmt::format("the window {} to {} s is empty: {} must be after {}", from, to, to_s, from_s));
  }
  return {from, to};
}

std::pair<long long, long long> parse_cycle_range(std::string_view text) {
  const auto colon = text.find(':');
  const auto number = [](std::string_view s, long long& v) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return !s.empty() && ec == std::errc{} && end == s.data() + s.size();
  };
  long long a = 0, b = 0;
  if (colon == std::string_view::npos || !number(text.substr(0, colon), a) ||
      !number(text.substr(colon + 1), b)) {
    throw InputError(fmt::format("{} '{}': expected A:B, e.g. 3:4", option_name("cycles"), text));
  }
  return {a, b};
}

double memory_limit_bytes(std::optional<double> limit_gb) {
  if (limit_gb && !(*limit_gb > 0 && std::isfinite(*limit_gb))) {
    throw InputError(fmt::format("{} must be a finite number > 0 (GB), got {}",
                                 option_name("memory_limit_gb"), *limit_gb));
  }
  return limit_gb ? *limit_gb * 1e9 : default_memory_limit_bytes();
}

void check_memory(std::string_view what, double need_bytes, std::optional<double> limit_gb,
                  std::string_view advice) {
  const double limit = memory_limit_bytes(limit_gb);
  const std::string option = option_name("memory_limit_gb");
  if (!(need_bytes <= limit)) {
    throw InputError(
        fmt::format("{}: estimated memory {} exceeds the limit of {} ({}): {}; or raise {}", what,
                    memory_text(need_bytes), memory_text(limit), limit_gb ? option : "75 % of RAM",
                    advice, option));
  }
}

FeedTargets feed_targets(const Job& job, const FeedTargetRequest& r) {
  FeedTargets t = default_feed_targets(job);
  t.h_max_mm = r.h_max_mm;
  t.mrr_mm3_per_min = r.mrr_mm3_per_min;
  t.h_axial_max_mm = r.h_axial_max_mm;
  if (r.feed_step_percent) t.feed_step_percent = *r.feed_step_percent;
  if (r.piece_mm) t.piece_mm = *r.piece_mm;
  if (r.min_feed_mm_per_min) t.min_feed_mm_per_min = *r.min_feed_mm_per_min;
  if (r.max_feed_mm_per_min) t.max_feed_mm_per_min = *r.max_feed_mm_per_min;
  if (r.air_feed_mm_per_min) t.air_feed_mm_per_min = *r.air_feed_mm_per_min;
  return t;
}

void name_program_lines(ProcessMetrics& metrics, const GcodeProgram& lines) {
  if (lines.segment_lines.empty()) return;
  metrics.h_max_slot_source = lines.where(metrics.h_max_slot_segment);
  metrics.h_max_after_entry_source = lines.where(metrics.h_max_after_entry_segment);
  metrics.engagement_max_slot_source = lines.where(metrics.engagement_max_slot_segment);
  metrics.engagement_max_after_entry_source =
      lines.where(metrics.engagement_max_after_entry_segment);
  metrics.h_axial_max_source = lines.where(metrics.h_axial_max_segment);
}

ReportData report_data(Job job, ToolPath path, ReportRequest request, const RunHooks& hooks) {
  std::vector<Vary> varies = std::move(request.varies);
  const JobDocument* doc = request.document;
  const std::vector<Override> base = request.overrides;
  // The study's keys checked before the report's parts run (an unknown or repeated key, a key
  // without values).
  if (!varies.empty()) (void)plan_sweep(varies, {}, 0, Sampler::sobol, 0);
  ReportData d = build_report(std::move(job), std::move(path), std::move(request), hooks);
  if (varies.empty()) return d;
  ReportStudy st;
  st.points = run_compare(*doc, base, varies, 0, hooks);
  st.varies = std::move(varies);
  if (std::none_of(st.points.begin(), st.points.end(), [](const StudyPoint& p) { return p.ok; })) {
    throw InputError(fmt::format(
        "report {}: every point of the study failed (the first: {}); nothing was written",
        option_name("vary"), st.points.front().error));
  }
  d.study = std::move(st);
  return d;
}

}  // namespace trochomill
