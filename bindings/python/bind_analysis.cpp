// analyze: the process metrics of a slot program (the CLI's `analyze`) with its series as
// arrays.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <optional>

#include "common.hpp"
#include "trochomill/analysis.hpp"
#include "trochomill/app.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/force.hpp"
#include "trochomill/report/analysis.hpp"

namespace trochomill::python {

namespace {

py::dict analyze_series(EngagementSeries&& e) {
  PathSamples& s = e.samples;
  std::vector<double> mrr(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    mrr[i] = e.removal_rate_mm3_per_s[i] * 60.0;
  }
  py::dict d;
  d["engagement_deg"] = to_array(degrees(e.engagement_angle_rad));
  d["t_s"] = to_array(std::move(s.t_s));
  d["x_mm"] = to_array(std::move(s.x_mm));
  d["y_mm"] = to_array(std::move(s.y_mm));
  d["z_mm"] = to_array(std::move(s.z_mm));
  d["h_max_mm"] = to_array(std::move(e.h_max_mm));
  d["teeth_in_cut"] = to_array(std::move(e.teeth_in_cut));
  d["mrr_mm3_per_min"] = to_array(std::move(mrr));
  d["radial_engagement_mm"] = to_array(std::move(e.radial_engagement_mm));
  d["axial_chip_mm"] = to_array(std::move(e.axial_chip_mm));
  return d;
}

}  // namespace

void bind_analysis(py::module_& m) {
  m.def(
      "analyze",
      [](const py::object& job_or_path, std::optional<double> memory_limit_gb,
         const py::object& progress, bool walls_part, bool floor_part, bool force_part) {
        const Job& job = job_of(job_or_path, "analyze").job;
        const AnalysisParts parts{walls_part, floor_part, force_part};
        const ToolPath path = path_of(job_or_path);
        check_memory("analyze", estimate_analysis_memory(job, path), memory_limit_gb,
                     fmt::format("{:.0f} s of program at {:g} rpm, {} samples per tooth pass: "
                                 "lower analysis.steps_per_tooth or analyse a shorter program",
                                 path.duration_s(), job.cutting.spindle_speed_rpm,
                                 job.analysis.steps_per_tooth));
        ProcessMetrics pm = run_released(
            [&](const RunHooks& h) { return analyze_with_forces(job, path, h, parts); }, progress);
        if (py::isinstance<PyPath>(job_or_path)) {
          name_program_lines(pm, job_or_path.cast<const PyPath&>().lines);
        }
        py::dict out = from_json(metrics_json(job, pm));
        out["series"] = analyze_series(std::move(pm.series));
        py::dict walls;  // the steady cycle's walls, as the JSON reports their texture
        if (pm.periodic && pm.texture_left) walls["left"] = profile_arrays(*pm.texture_left);
        if (pm.periodic && pm.texture_right) walls["right"] = profile_arrays(*pm.texture_right);
        out["wall_texture_profiles"] = walls;
        py::dict floor;  // the floor's lines, as the JSON reports their texture
        const char* lines[] = {"left", "middle", "right"};
        for (std::size_t k = 0; k < 3; ++k) {
          if (!pm.texture_floor[k]) continue;
          py::dict d = profile_arrays(*pm.texture_floor[k]);
          d["line_x_mm"] = pm.floor[k].x_mm;
          floor[lines[k]] = d;
        }
        out["floor_texture_profiles"] = floor;
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("memory_limit_gb") = py::none(),
      py::arg("progress") = py::none(), py::arg("walls") = true, py::arg("floor") = true,
      py::arg("force") = true,
      R"(Engagement, chip thickness, times, removal rate, walls and texture of a slot program.

job: a Job (its planned path) or a Path (planned, or read from G-code with a job).
Returns the keys of `trochomill analyze --json` (units in their names: _mm, _s, _deg,
_mm3_per_min; cycle_* keys None when the path has no steady cycle) and "series": float64
arrays t_s, x_mm, y_mm, z_mm, engagement_deg, h_max_mm, mrr_mm3_per_min,
radial_engagement_mm, axial_chip_mm (the end edges' chip: descent per tooth) and the int32 array teeth_in_cut, one entry per sample;
"wall_texture_profiles": per wall ("left", "right") the predicted R and W profiles the wall
texture was evaluated on (x_mm along the feed, roughness_mm, waviness_mm);
"floor_texture_profiles": the same for the floor's lines ("left", "middle", "right", beside
each wall and in the middle, at x = line_x_mm across the slot).
progress: None or callable(phase: str, done: int, total: int).
walls, floor, force: the parts of the analysis past the whole program and the steady cycle
(the walls and their texture, the predicted floor and its texture, the force model's
F_R,max and the performance index). A part left out costs nothing and its keys are None (its
profiles absent); every other figure is the same to the bit. The floor needs the walls:
floor=True computes them. The floor is about half of the analysis's time.)");
}

}  // namespace trochomill::python
