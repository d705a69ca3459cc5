// simulate, forces and calibrate: the tri-dexel simulation of a window of the path, the
// cutting forces over it, and the force model fitted to measured forces. Each returns the
// CLI's JSON document as a dict with its series as arrays.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "common.hpp"
#include "trochomill/cutter.hpp"
#include "trochomill/force.hpp"
#include "trochomill/report/force.hpp"
#include "trochomill/report/sim.hpp"
#include "trochomill/sim.hpp"

namespace trochomill::python {

namespace {

py::dict force_arrays(ForceSeries&& s) {
  const auto n = static_cast<py::ssize_t>(s.size());
  std::vector<double> fr(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) fr[i] = s.resultant_n(i);
  py::dict d;
  d["f_resultant_n"] = to_array(std::move(fr));
  d["t_s"] = to_array(std::move(s.t_s));
  d["f_x_n"] = to_array(std::move(s.fx_n));
  d["f_y_n"] = to_array(std::move(s.fy_n));
  d["f_z_n"] = to_array(std::move(s.fz_n));
  d["torque_nm"] = to_array(std::move(s.torque_nm));
  d["power_w"] = to_array(std::move(s.power_w));
  const py::ssize_t teeth = s.teeth;
  d["tooth_f_x_n"] = to_array(std::move(s.tooth_fx_n), {n, teeth});
  d["tooth_f_y_n"] = to_array(std::move(s.tooth_fy_n), {n, teeth});
  d["tooth_f_z_n"] = to_array(std::move(s.tooth_fz_n), {n, teeth});
  d["tooth_torque_nm"] = to_array(std::move(s.tooth_torque_nm), {n, teeth});
  return d;
}

// The machined surface as a triangle mesh of its height field: vertices (n, 3) mm, faces
// (m, 3) vertex indices, two triangles per grid cell, counter-clockwise seen from above.
py::dict surface_mesh(const HeightField& f) {
  const std::size_t cols = f.x_mm_of_column.size(), rows = f.y_mm_of_row.size();
  std::vector<double> v;
  v.reserve(cols * rows * 3);
  for (std::size_t c = 0; c < cols; ++c) {
    for (std::size_t r = 0; r < rows; ++r) {
      v.insert(v.end(), {f.x_mm_of_column[c], f.y_mm_of_row[r], f.z_mm[c * rows + r]});
    }
  }
  std::vector<std::uint32_t> faces;
  if (cols > 1 && rows > 1) faces.reserve((cols - 1) * (rows - 1) * 6);
  for (std::size_t c = 0; c + 1 < cols; ++c) {
    for (std::size_t r = 0; r + 1 < rows; ++r) {
      const auto a = static_cast<std::uint32_t>(c * rows + r),
                 b = a + static_cast<std::uint32_t>(rows);
      faces.insert(faces.end(), {a, b, b + 1, a, b + 1, a + 1});
    }
  }
  py::dict d;
  const auto nv = static_cast<py::ssize_t>(v.size() / 3),
             nf = static_cast<py::ssize_t>(faces.size() / 3);
  d["vertices_mm"] = to_array(std::move(v), {nv, 3});
  d["faces"] = to_array(std::move(faces), {nf, 3});
  d["bottom_mm"] = f.bottom_mm;
  return d;
}

py::dict chip_map_dict(ChipMapData&& c) {
  const auto steps = static_cast<py::ssize_t>(c.t_s.size());
  const auto teeth = static_cast<py::ssize_t>(c.teeth);
  const auto segs = static_cast<py::ssize_t>(c.segments_per_tooth);
  py::dict d;
  d["t_s"] = to_array(std::move(c.t_s));
  d["tip_mm"] = to_array(std::move(c.tip_mm), {steps, 3});
  d["removed_mm3"] = to_array(std::move(c.removed_mm3), {steps, teeth});
  d["h_mm"] = to_array(std::move(c.h_mm), {steps, teeth, segs});
  d["w_mm"] = to_array(std::move(c.w_mm), {steps, teeth, segs});
  d["v_mm3"] = to_array(std::move(c.v_mm3), {steps, teeth, segs});
  d["segment_height_mm"] = to_array(std::move(c.segment_height_mm));
  d["resolution_mm"] = c.resolution_mm;
  d["steps_per_rev"] = c.steps_per_rev;
  return d;
}

// A height map as a dict: z_mm (ny, nx), dx_mm, dy_mm, x0_mm, y0_mm, description.
py::dict height_map_dict(HeightMap&& m) {
  py::dict d;
  d["dx_mm"] = m.dx_mm;
  d["dy_mm"] = m.dy_mm;
  d["x0_mm"] = m.x0_mm;
  d["y0_mm"] = m.y0_mm;
  d["description"] = m.description;
  d["z_mm"] =
      to_array(std::move(m.z_mm), {static_cast<py::ssize_t>(m.ny), static_cast<py::ssize_t>(m.nx)});
  return d;
}

void bind_simulate(py::module_& m) {
  m.def(
      "simulate",
      [](const py::object& job_or_path, const py::object& cycles, std::optional<double> from_s,
         std::optional<double> to_s, const py::object& progress,
         std::optional<double> memory_limit_gb) {
        const Job& job = job_of(job_or_path, "simulate").job;
        const ToolPath path = path_of(job_or_path);
        const auto [from, to] = window_of(path, cycles, from_s, to_s);
        const MemoryEstimate est = estimate_simulation_memory(job, path, from, to);
        const double need = est.total(true);
        check_memory("simulate", need, memory_limit_gb,
                     fmt::format("coarsen simulation.resolution (now {} mm) or shorten the "
                                 "window (cycles, from_s/to_s)",
                                 job.simulation.resolution_mm));
        const auto t0 = std::chrono::steady_clock::now();
        JobSimulation js = run_released(
            [&](const RunHooks& h) {
              SimControl control;
              control.hooks = h;
              control.reserve_chip_entries = static_cast<std::size_t>(est.chip_entries);
              return simulate_job(job, path, from, to, control);
            },
            progress);
        const double wall = seconds_since(t0);
        py::dict out = from_json(simulation_json(job, js, from, to, wall, need));
        const SimTool tool = sim_tool(job, job.simulation);
        const SimResult& r = js.result;
        const auto steps = static_cast<py::ssize_t>(r.steps.size());
        const auto teeth = static_cast<py::ssize_t>(job.tool.teeth);
        std::vector<double> t(r.steps.size()), tip(r.steps.size() * 3), removed,
            h_max(r.steps.size()), h_mean(r.steps.size());
        std::vector<std::int32_t> engaged(r.steps.size());
        removed.reserve(r.steps.size() * static_cast<std::size_t>(teeth));
        for (std::size_t i = 0; i < r.steps.size(); ++i) {
          const SimStep& st = r.steps[i];
          t[i] = st.t_s;
          std::copy(st.tip_mm.begin(), st.tip_mm.end(),
                    tip.begin() + static_cast<std::ptrdiff_t>(3 * i));
          removed.insert(removed.end(), st.removed_mm3.begin(), st.removed_mm3.end());
          h_max[i] = st.h_max_mm;
          h_mean[i] = st.h_mean_mm;
          engaged[i] = st.engaged_segments;
        }
        py::dict series;
        series["t_s"] = to_array(std::move(t));
        series["tip_mm"] = to_array(std::move(tip), {steps, 3});
        series["removed_mm3"] = to_array(std::move(removed), {steps, teeth});
        series["h_max_mm"] = to_array(std::move(h_max));
        series["h_mean_mm"] = to_array(std::move(h_mean));
        series["engaged_segments"] = to_array(std::move(engaged));
        out["series"] = series;
        out["chip_map"] = chip_map_dict(chip_map_data(r, tool, job.simulation));
        out["surface"] =
            surface_mesh(surface_height_field(*js.work, default_surface_step_mm(*js.work)));
        try {
          out["floor"] = height_map_dict(simulated_floor(job, js));
          out["floor_note"] = "";
        } catch (const InputError& e) {  // the window left no floor cut across the slot
          out["floor"] = py::none();
          out["floor_note"] = e.what();
        }
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("cycles") = py::none(), py::arg("from_s") = py::none(),
      py::arg("to_s") = py::none(), py::arg("progress") = py::none(),
      py::arg("memory_limit_gb") = py::none(),
      R"(Tri-dexel material removal (Bergmann 2021) over a window of the path: cycles=(A, B)
(trochoid cycles A to B-1) or from_s/to_s (s of programmed time), default the whole path.
Returns the keys of `trochomill simulate --json`, "series" (t_s, tip_mm (n, 3),
removed_mm3 (n, teeth), h_max_mm, h_mean_mm, engaged_segments per step), "chip_map" (t_s,
tip_mm, removed_mm3 and float32 h_mm, w_mm, v_mm3 (steps, teeth, segments), the
segment_height_mm of each edge segment above the tip) and "surface" (the machined surface:
vertices_mm (n, 3), faces (m, 3) uint32, bottom_mm) and "floor" (the slot's floor as a
height map at the dexel spacing, as floor.x3p: z_mm (ny, nx), dx_mm, dy_mm, x0_mm, y0_mm; None
with the reason in "floor_note" when the window left no floor cut across the slot). The GIL
is released while it runs.
progress: None or callable(phase: str, done: int, total: int).)");
}

void bind_forces(py::module_& m) {
  m.def(
      "forces",
      [](const py::object& job_or_path, bool fast, const py::object& cycles,
         std::optional<double> from_s, std::optional<double> to_s, const py::object& progress,
         std::optional<double> memory_limit_gb) {
        const Job& job = job_of(job_or_path, "forces").job;
        const ToolPath path = path_of(job_or_path);
        const auto [from, to] = window_of(path, cycles, from_s, to_s);
        if (!job.material.model) {
          throw InputError(fmt::format(
              "{}: no [material] force model; give [material] model and coefficients or name "
              "(see `trochomill materials`)",
              job.source));
        }
        std::size_t reserve = 0;
        if (!fast) {
          const MemoryEstimate est = estimate_simulation_memory(job, path, from, to);
          check_memory("forces", est.total(false), memory_limit_gb,
                       "shorten the window (cycles, from_s/to_s), coarsen simulation.resolution "
                       "or use fast=True");
          reserve = static_cast<std::size_t>(est.chip_entries);
        }
        JobForces jf = run_released(
            [&](const RunHooks& h) {
              SimControl control;
              control.hooks = h;
              control.reserve_chip_entries = reserve;
              return job_forces(job, path, from, to, fast, control);
            },
            progress);
        py::dict out = from_json(force_summary_json(job, jf, from, to));
        out["series"] = force_arrays(std::move(jf.series));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("fast") = true, py::arg("cycles") = py::none(),
      py::arg("from_s") = py::none(), py::arg("to_s") = py::none(),
      py::arg("progress") = py::none(), py::arg("memory_limit_gb") = py::none(),
      R"(Cutting forces on the workpiece with the job's [material] model: the keys of
`trochomill forces --json` and "series": t_s, f_x_n, f_y_n, f_z_n, f_resultant_n (N),
torque_nm (N m), power_w (W), and per tooth tooth_f_x_n, tooth_f_y_n, tooth_f_z_n,
tooth_torque_nm (steps, teeth). fast=True: chips from the analytic engagement; False: from
the dexel simulation. Window as for simulate.)");
}

void bind_calibrate(py::module_& m) {
  m.def(
      "calibrate",
      [](const py::object& job_or_path,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& t_s,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& f_n,
         const std::vector<std::string>& fit, const std::optional<std::string>& model, bool fast,
         std::optional<double> cutoff_hz, std::optional<double> max_shift_s,
         const py::object& cycles, std::optional<double> from_s, std::optional<double> to_s,
         const py::object& progress, std::optional<double> memory_limit_gb) {
        const Job& job = job_of(job_or_path, "calibrate").job;
        const MeasuredForces meas = measured_of(t_s, f_n);
        CalibrationOptions o;
        if (model) {
          o.model = parse_force_model(*model);
        } else if (job.material.model) {
          o.model = *job.material.model;
        }
        o.fit = fit;
        o.fast = fast;
        if (cutoff_hz) o.cutoff_hz = *cutoff_hz;
        if (max_shift_s) o.max_shift_s = *max_shift_s;
        const ToolPath path = path_of(job_or_path);
        if (cycles.is_none() && !from_s && !to_s) {
          o.from_s = std::max(0.0, meas.t_s.front());
          o.to_s = std::min(path.duration_s(), meas.t_s.back());
        } else {
          std::tie(o.from_s, o.to_s) = window_of(path, cycles, from_s, to_s);
        }
        check_memory("calibrate", estimate_calibration_memory(job, path, o, meas.t_s.size()),
                     memory_limit_gb,
                     fmt::format("the model window is {:.1f} s: a few cycles hold the "
                                 "coefficients as well",
                                 o.to_s - o.from_s));
        const CalibrationResult r = run_released(
            [&](const RunHooks& h) {
              CalibrationOptions oo = o;
              oo.hooks = h;
              return calibrate_forces(job, path, meas, oo);
            },
            progress);
        py::dict out = from_json(calibration_json(r));
        out["material_toml"] = material_toml(r);
        return out;
      },
      py::arg("job"), py::arg("t_s"), py::arg("f_n"), py::kw_only(),
      py::arg("fit") = std::vector<std::string>{}, py::arg("model") = py::none(),
      py::arg("fast") = false, py::arg("cutoff_hz") = py::none(),
      py::arg("max_shift_s") = py::none(), py::arg("cycles") = py::none(),
      py::arg("from_s") = py::none(), py::arg("to_s") = py::none(),
      py::arg("progress") = py::none(), py::arg("memory_limit_gb") = py::none(),
      R"(Fits the force model to measured forces: t_s (n,) s, increasing; f_n (n, 3) N on the
workpiece (F_x, F_y, F_z). fit: the parameters (k_c, k_n, m, m_n, k_a, m_a | k_tc, k_rc,
k_ac, k_te, k_re, k_ae, runout_radial, runout_phase, runout_axial; default the model's main
coefficients); model: bergmann, kienzle or linear (default the job's); cutoff_hz: low-pass
of both signals (default from the tooth-passing frequency); max_shift_s: the alignment
search (default half a revolution); the model window: cycles or from_s/to_s, default the
measurement's span. Returns the keys of `trochomill calibrate --json` and "material_toml"
(the fitted [material] block).)");
}

}  // namespace

void bind_simulation(py::module_& m) {
  bind_simulate(m);
  bind_forces(m);
  bind_calibrate(m);
}

}  // namespace trochomill::python
