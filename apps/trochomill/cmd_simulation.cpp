// simulate and forces: the tri-dexel simulation of a window of the path, and the cutting
// forces over it (from the simulation's chips or the fast analytic source).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report.hpp"
#include "trochomill/sim.hpp"

namespace trochomill::cli {

void register_simulation_commands(CLI::App& app, int& exit_code) {
  // simulate
  {
    struct Args {
      JobArgs job;
      WindowArgs window;
      std::string gcode, json, out;
      std::optional<double> memory_gb, stl_step_mm;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "simulate", "tri-dexel material removal: per-step chip thickness and removed volume");
    add_job_args(cmd, a->job);
    add_stock_mesh_alias(cmd, a->job);
    cmd->add_option("--gcode", a->gcode, "simulate this NC program instead of the job's path");
    add_window_args(cmd, a->window, "window");
    cmd->add_option("--json", a->json, "write the summary as JSON (- for stdout)");
    cmd->add_option(
        "--out", a->out,
        "directory for series.csv, chips.h5, walls.csv, floor.csv, surface.stl and floor.x3p");
    add_memory_limit(cmd, a->memory_gb);
    cmd->add_option("--stl-step", a->stl_step_mm,
                    "grid step of surface.stl, mm (default: the dexel spacing, coarser when the "
                    "mesh would pass 4 million triangles)")
        ->check(finite_above(0, 1e3));
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json}, {&a->job.file, &a->gcode});
      check_output_dir(a->out, "--out");
      const Job job = a->job.load();
      const ToolPath path = job_path(job, a->gcode, a->memory_gb);
      const auto [from, to] = a->window.resolve(path);
      // Refuse before starting when the estimate passes the limit.
      const MemoryEstimate est = estimate_simulation_memory(job, path, from, to);
      // The records are not kept: the outputs stream as the steps are made.
      const double need = est.streamed(!a->out.empty());
      if (a->stl_step_mm && !(*a->stl_step_mm > 0)) {  // bad input refused before the run
        throw InputError(fmt::format("--stl-step must be > 0 mm, got {}", *a->stl_step_mm));
      }
      const double limit = memory_limit_bytes(a->memory_gb);
      if (need > limit) {
        throw InputError(fmt::format(
            "simulate: estimated memory {} (boards {}, path samples {}, process {}, outputs {}) "
            "exceeds the limit of {} ({}); coarsen [simulation] resolution (now {} mm), shorten "
            "the window (--cycles, --from/--to) or raise --memory-limit",
            memory_text(need), memory_text(est.boards_bytes), memory_text(est.stream_bytes),
            memory_text(est.base_bytes), memory_text(a->out.empty() ? 0.0 : est.writing_bytes()),
            memory_text(limit), a->memory_gb ? "--memory-limit" : "75 % of RAM",
            job.simulation.resolution_mm));
      }
      // Ctrl-C stops after the current step; what was computed is written, marked incomplete.
      // A Ctrl-C during the output writing leaves --out without any file of this run.
      const GuardedRun run(true);
      SimControl control;
      control.hooks = run.hooks();
      control.keep_records = false;  // series.csv and chips.h5 are written as the steps come
      std::optional<SimulationOutputs> outputs;
      if (!a->out.empty()) control.sink = &outputs.emplace(a->out, job);
      const auto t_start = std::chrono::steady_clock::now();
      const JobSimulation js = simulate_job(job, path, from, to, control);
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      RunHooks writing = control.hooks;
      if (!js.result.complete) writing.cancel = nullptr;  // the first Ctrl-C stopped the run
      std::string note;
      if (outputs) note = outputs->finish(js, a->stl_step_mm, writing);
      run.done();
      if (!a->json.empty()) emit(a->json, simulation_json(job, js, from, to, wall, need));
      if (a->json != "-") fmt::print("{}", simulation_text(a->job.file, job, js, from, to, wall));
      if (!note.empty()) fmt::print(stderr, "simulate: {}\n", note);
      run.finish("interrupted: the outputs were written in full");
      exit_code = js.result.complete ? 0 : interrupted_exit_code();
    });
  }
  // forces
  {
    struct Args {
      JobArgs job;
      WindowArgs window;
      std::string gcode, json, csv;
      std::optional<double> memory_gb;
      bool fast = false;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "forces", "cutting forces F_x, F_y, F_z, torque and power over time ([material] model)");
    add_job_args(cmd, a->job);
    cmd->add_option("--gcode", a->gcode, "this NC program instead of the job's path");
    cmd->add_flag("--fast", a->fast,
                  "chips from the analytic engagement (axial discs, helix lag) instead of the "
                  "dexel simulation");
    add_window_args(cmd, a->window, "window");
    cmd->add_option("--csv", a->csv, "write the series as CSV (- for stdout)");
    cmd->add_option("--json", a->json, "write the summary as JSON (- for stdout)");
    add_memory_limit(cmd, a->memory_gb);
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json, &a->csv}, {&a->job.file, &a->gcode});
      const Job job = a->job.load();
      const ToolPath path = job_path(job, a->gcode, a->memory_gb);
      const auto [from, to] = a->window.resolve(path);
      if (!job.material.model) {
        throw InputError(fmt::format(
            "{}: no [material] force model; give [material] model and coefficients or name (see "
            "`trochomill materials`)",
            a->job.file));
      }
      std::size_t reserve = 0;
      if (!a->fast) {
        const MemoryEstimate est = estimate_simulation_memory(job, path, from, to);
        const double limit = memory_limit_bytes(a->memory_gb);
        if (est.total(false) > limit) {
          throw InputError(
              fmt::format("forces: the simulation would need {} ({} is {}); shorten the window "
                          "(--cycles, --from/--to), coarsen [simulation] resolution or use --fast",
                          memory_text(est.total(false)),
                          a->memory_gb ? "--memory-limit" : "75 % of RAM", memory_text(limit)));
        }
        reserve = static_cast<std::size_t>(est.chip_entries);
      }
      // In simulation mode Ctrl-C stops after the current step; the forces of what was
      // simulated are written, marked incomplete (exit 130), as simulate does.
      const GuardedRun run(true);
      SimControl control;
      control.hooks = run.hooks();
      control.reserve_chip_entries = reserve;
      const JobForces jf = job_forces(job, path, from, to, a->fast, control);
      run.done();
      if (!a->csv.empty()) emit(a->csv, force_series_csv(jf.series));
      if (!a->json.empty()) emit(a->json, force_summary_json(job, jf, from, to));
      if (summary_to_stdout({&a->json, &a->csv})) {
        fmt::print("{}", force_summary_text(job, jf, from, to));
      }
      run.finish("interrupted: the outputs were written in full");
      exit_code = jf.chips.complete ? 0 : interrupted_exit_code();
    });
  }
}

}  // namespace trochomill::cli
