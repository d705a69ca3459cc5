// schedule_feed and optimize_feed: chip-load feed scheduling of a planned path, and the feed
// optimisation of an NC program (the CLI's `plan --feed-schedule` and `optimize-feed`).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "trochomill/app.hpp"
#include "trochomill/feed.hpp"
#include "trochomill/io.hpp"

namespace trochomill::python {

namespace {

// The feed targets of schedule_feed and optimize_feed: the arguments over the job's [machine]
// limits, as the CLI's flags (checked by the library: InputError).
FeedTargets feed_targets(const Job& job, std::optional<double> h_max_mm,
                         std::optional<double> mrr_mm3_per_min,
                         std::optional<double> min_feed_mm_per_min,
                         std::optional<double> max_feed_mm_per_min,
                         std::optional<double> air_feed_mm_per_min, double feed_step_percent,
                         double piece_mm, std::optional<double> h_axial_max_mm) {
  return trochomill::feed_targets(
      job, {h_max_mm, mrr_mm3_per_min, feed_step_percent, piece_mm, min_feed_mm_per_min,
            max_feed_mm_per_min, air_feed_mm_per_min, h_axial_max_mm});
}

}  // namespace

void bind_feed(py::module_& m) {
  m.def(
      "schedule_feed",
      [](const py::object& job_or_path, std::optional<double> h_max_mm,
         std::optional<double> mrr_mm3_per_min, std::optional<double> min_feed_mm_per_min,
         std::optional<double> max_feed_mm_per_min, std::optional<double> air_feed_mm_per_min,
         double feed_step_percent, double piece_mm, const py::object& progress,
         std::optional<double> h_axial_max_mm) {
        const PyJob& pj = job_of(job_or_path, "schedule_feed");
        const ToolPath path = path_of(job_or_path);
        const FeedTargets t = feed_targets(pj.job, h_max_mm, mrr_mm3_per_min, min_feed_mm_per_min,
                                           max_feed_mm_per_min, air_feed_mm_per_min,
                                           feed_step_percent, piece_mm, h_axial_max_mm);
        FeedSchedule fs = run_released(
            [&](const RunHooks& h) { return schedule_feed(pj.job, path, t, h); }, progress);
        PyPath p;
        p.path = std::move(fs.path);
        p.cycles = static_cast<int>(p.path.cycles().size());
        p.source = py::isinstance<PyPath>(job_or_path) ? job_or_path.cast<const PyPath&>().source
                                                       : std::string("plan");
        p.job = std::make_shared<const PyJob>(pj);
        py::dict out;
        out["path"] = std::move(p);
        out["time_before_s"] = fs.time_before_s;
        out["time_after_s"] = fs.time_after_s;
        out["h_max_before_mm"] = fs.h_max_before_mm;
        out["h_max_after_mm"] = fs.h_max_after_mm;
        out["h_axial_max_before_mm"] = fs.h_axial_max_before_mm;
        out["h_axial_max_after_mm"] = fs.h_axial_max_after_mm;
        out["pieces"] = fs.pieces;
        std::vector<std::int32_t> limit(fs.piece_limit.size());
        for (std::size_t i = 0; i < limit.size(); ++i)
          limit[i] = static_cast<std::int32_t>(fs.piece_limit[i]);
        out["piece_h_max_mm"] = to_array(std::move(fs.piece_h_max_mm));
        out["piece_feed_mm_per_min"] = to_array(std::move(fs.piece_feed_mm_per_min));
        out["piece_limit"] = to_array(std::move(limit));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("h_max_mm") = py::none(),
      py::arg("mrr_mm3_per_min") = py::none(), py::arg("min_feed_mm_per_min") = py::none(),
      py::arg("max_feed_mm_per_min") = py::none(), py::arg("air_feed_mm_per_min") = py::none(),
      py::arg("feed_step_percent") = 5.0, py::arg("piece_mm") = 0.5,
      py::arg("progress") = py::none(), py::arg("h_axial_max_mm") = py::none(),
      R"(Chip-load feed scheduling, as `plan --feed-schedule` (docs/models.md section 15): each
piece of the path (at most piece_mm long) fed so that its largest chip is h_max_mm (default
the job's feed per tooth) and its removal rate at most mrr_mm3_per_min where given, within
a descent's axial chip (the descent per tooth where the end face cuts) at most
h_axial_max_mm (default h_max_mm; a descent is never fed faster than programmed),
min_feed_mm_per_min and max_feed_mm_per_min (default the
job's machine.min_feed and max_feed, else a tenth and three times its feed),
air_feed_mm_per_min where the tool cuts nothing (default machine.air_feed, else the max
feed), neighbouring pieces within feed_step_percent sharing the slower feed. job: a
Job (its planned path) or a Path. Returns "path" (the scheduled Path: path.gcode() is the
program), time_before_s, time_after_s, h_max_before_mm, h_max_after_mm,
h_axial_max_before_mm, h_axial_max_after_mm, pieces, and per feed piece piece_h_max_mm,
piece_feed_mm_per_min and piece_limit (int32: 0 the chip target, 1 min feed, 2 max feed,
3 air, 4 plunge (kept at its feed), 5 removal cap, 6 force cap, 7 power cap, 8 torque cap,
9 acceleration, 10 the axial chip target).)");

  m.def(
      "optimize_feed",
      [](const std::string& program, const PyJob& pj, std::optional<double> h_max_mm,
         std::optional<double> mrr_mm3_per_min, std::optional<double> force_n,
         std::optional<double> power_w, std::optional<double> torque_nm,
         std::optional<double> min_feed_mm_per_min, std::optional<double> max_feed_mm_per_min,
         std::optional<double> air_feed_mm_per_min, double feed_step_percent, double piece_mm,
         const std::vector<std::string>& include_dirs, const std::string& engine,
         const std::optional<std::string>& stock, std::optional<int> rounds,
         const py::object& progress, std::optional<double> memory_limit_gb,
         std::optional<double> h_axial_max_mm) {
        FeedOptimizeOptions o;
        // The sim engine's estimate is checked against it before the boards are made.
        o.memory_limit_bytes = memory_limit_bytes(memory_limit_gb);
        if (engine != "kernel" && engine != "sim") {
          throw InputError(fmt::format(
              "optimize_feed: engine must be \"kernel\" or \"sim\", got \"{}\"", engine));
        }
        o.engine = engine == "sim" ? FeedEngine::sim : FeedEngine::kernel;
        if (stock) o.stock_mesh = std::make_shared<const Mesh>(read_mesh(*stock));
        if (rounds && (*rounds < 1 || *rounds > 100)) {
          throw InputError(fmt::format("optimize_feed: rounds must be 1 .. 100, got {}", *rounds));
        }
        o.targets = feed_targets(pj.job, h_max_mm, mrr_mm3_per_min, min_feed_mm_per_min,
                                 max_feed_mm_per_min, air_feed_mm_per_min, feed_step_percent,
                                 piece_mm, h_axial_max_mm);
        o.force_n = force_n;
        o.power_w = power_w;
        o.torque_nm = torque_nm;
        o.read = gcode_options(pj.job.machine).read;
        for (const std::string& d : include_dirs) o.read.include_dirs.emplace_back(d);
        if (rounds) o.targets.iterations = *rounds;
        const std::string text = read_text_file(program);
        FeedOptimizeResult r = run_released(
            [&](const RunHooks& h) { return optimize_feed(pj.job, text, program, o, h); },
            progress);
        py::dict out = from_json(feed_summary_json(r));
        out["text"] = r.text;
        py::dict before, after;
        before["t_s"] = to_array(std::move(r.t_before_s));
        before["feed_mm_per_min"] = to_array(std::move(r.feed_before));
        before["h_max_mm"] = to_array(std::move(r.h_before));
        after["t_s"] = to_array(std::move(r.t_after_s));
        after["feed_mm_per_min"] = to_array(std::move(r.feed_after));
        after["h_max_mm"] = to_array(std::move(r.h_after));
        out["before"] = before;
        out["after"] = after;
        return out;
      },
      py::arg("program"), py::arg("job"), py::kw_only(), py::arg("h_max_mm") = py::none(),
      py::arg("mrr_mm3_per_min") = py::none(), py::arg("force_n") = py::none(),
      py::arg("power_w") = py::none(), py::arg("torque_nm") = py::none(),
      py::arg("min_feed_mm_per_min") = py::none(), py::arg("max_feed_mm_per_min") = py::none(),
      py::arg("air_feed_mm_per_min") = py::none(), py::arg("feed_step_percent") = 5.0,
      py::arg("piece_mm") = 0.5, py::arg("include_dirs") = std::vector<std::string>{},
      py::arg("engine") = "kernel", py::arg("stock") = py::none(), py::arg("rounds") = py::none(),
      py::arg("progress") = py::none(), py::arg("memory_limit_gb") = py::none(),
      py::arg("h_axial_max_mm") = py::none(),
      R"(Feed optimisation of an NC program, as `trochomill optimize-feed PROGRAM --job JOB`
(docs/models.md section 15): program is the file's path, job a Job; the targets as
schedule_feed's plus force_n (N), power_w (W) and torque_nm (N m) caps from the job's
[material] model; include_dirs are searched for subroutine files; engine "kernel" (the
exact engagement, 2.5D programs) or "sim" (the tri-dexel simulation at the job's
[simulation] resolution: any motion); stock a closed mesh file (STL, PLY, OBJ; mm, the
program's frame) instead of the job's box; rounds of evaluation (default 12);
memory_limit_gb (default 75 % of the RAM) bounds the sim engine's estimated memory. Returns the summary of
`--json` (times, quantiles of h_max, removal rate and forces before and after, shares of
feed time by limit, blocks where the target cannot be held, warnings), "text" (the
rewritten program) and "before"/"after": per cutting sample t_s, feed_mm_per_min and
h_max_mm arrays.)");
}

}  // namespace trochomill::python
