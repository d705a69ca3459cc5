// plan, path and check-gcode: the slot program of a job, its sampled trajectories, and the
// report of any NC program.
#include <fmt/format.h>

#include <algorithm>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/report.hpp"

namespace trochomill::cli {

void register_path_commands(CLI::App& app, int& exit_code) {
  // plan
  {
    struct Args {
      JobArgs job;
      std::string out;
      std::optional<double> memory_gb;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("plan", "write the slot program of a job as G-code");
    add_job_args(cmd, a->job);
    add_memory_limit(cmd, a->memory_gb);
    cmd->add_option("-o,--output", a->out, "output G-code file (- for stdout)")->required();
    add_key_alias(cmd, a->job, "--dialect", "machine.dialect",
                  "linuxcnc | fanuc | sinumerik | grbl");
    add_key_alias(cmd, a->job, "--tolerance", "machine.arc_tolerance",
                  "max deviation of fitted arcs/chords, mm");
    add_key_flag(cmd, a->job, "--chords", "machine.arc_output", "chords",
                 "write curves as G1 chords instead of biarcs");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->out}, {&a->job.file});
      const Job job = a->job.load();
      check_memory("plan", estimate_plan_memory(job), a->memory_gb,
                   fmt::format("a {:g} mm slot at a {:g} mm step: raise [path] step or plan a "
                               "shorter slot",
                               job.slot.length_mm, job.path.step_mm));
      const PlannedPath planned = plan_path(job);
      const std::string code = write_gcode(job, planned.path, gcode_options(job.machine).write);
      emit(a->out, code);
      if (a->out != "-") {
        fmt::print(
            "{}: {} {} cycles, path {:.3f} mm, time {:.3f} s ({:.3f} s with acceleration), {} "
            "lines -> {}\n",
            a->job.file, to_string(job.path.type), planned.info.cycles, planned.path.length_mm(),
            planned.path.duration_s(), estimate_time_s(planned.path, job.machine),
            std::count(code.begin(), code.end(), '\n'), a->out);
      }
      exit_code = 0;
    });
  }
  // path
  {
    struct Args {
      JobArgs job;
      std::string csv, gcode;
      std::optional<int> steps_per_rev;
      std::optional<double> dt_s, ds_mm, memory_gb;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("path", "sample the tool-centre and tooth-tip trajectories");
    add_job_args(cmd, a->job);
    add_memory_limit(cmd, a->memory_gb);
    cmd->add_option("--csv", a->csv, "write the samples as CSV (- for stdout)");
    cmd->add_option("--gcode", a->gcode,
                    "take the path from this NC program instead of planning it");
    auto* o_spr =
        cmd->add_option("--steps-per-rev", a->steps_per_rev, "samples per spindle revolution")
            ->check(CLI::Range(1, 100000));
    auto* o_dt = cmd->add_option("--dt", a->dt_s, "time step, s")->check(finite_above(0, 1e3));
    auto* o_ds =
        cmd->add_option("--ds", a->ds_mm, "path-length step, mm")->check(finite_above(0, 1e3));
    o_spr->excludes(o_dt)->excludes(o_ds);
    o_dt->excludes(o_ds);
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->csv}, {&a->job.file, &a->gcode});
      const Job job = a->job.load();
      const ToolPath tp = job_path(job, a->gcode);
      // The samples and tooth tracks in memory (the CSV is written as it is made): 80 bytes a
      // sample, 24 per tooth, 10 % for the vectors' slack, 30 MB for the process (measured:
      // 190 bytes a sample with 4 teeth).
      const int spr = a->steps_per_rev.value_or(36);
      const double n = a->dt_s    ? tp.duration_s() / *a->dt_s
                       : a->ds_mm ? tp.length_mm() / *a->ds_mm
                                  : tp.duration_s() * job.cutting.spindle_speed_rpm / 60.0 * spr;
      check_memory("path", 30e6 + 1.1 * n * (80.0 + 24.0 * std::max(1, job.tool.teeth)),
                   a->memory_gb,
                   fmt::format("{:.3g} samples: sample coarser (--dt, --ds, --steps-per-rev)", n));
      const GuardedRun run(true);
      PathSamples s;
      if (a->dt_s) {
        s = sample_by_time(tp, *a->dt_s);
      } else if (a->ds_mm) {
        s = sample_by_length(tp, *a->ds_mm);
      } else {
        s = sample_by_spindle_angle(tp, a->steps_per_rev.value_or(36),
                                    job.cutting.spindle_speed_rpm);
      }
      const ToothTracks tr = tooth_tracks(s, job.tool, job.cutting);
      if (!a->csv.empty()) {
        emit_stream(a->csv, [&](const std::function<void(std::string_view)>& sink) {
          write_path_samples_csv(s, tr, sink, run.hooks());
        });
      }
      run.done();
      if (a->csv != "-") {
        fmt::print(
            "{} samples over {:.3f} s, path {:.3f} mm, {} teeth, f_z = {:.4g} mm, n = {:.0f} "
            "rpm{}\n",
            s.size(), tp.duration_s(), tp.length_mm(), tr.teeth, job.cutting.feed_per_tooth_mm,
            job.cutting.spindle_speed_rpm, a->csv.empty() ? "" : " -> " + a->csv);
      }
      run.finish("interrupted: the outputs were written in full");
      exit_code = 0;
    });
  }
  // check-gcode
  {
    struct Args {
      std::string file, json;
      Machine machine;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("check-gcode",
                                   "parse an NC program and report length, time, bounding box");
    cmd->add_option("FILE", a->file, "G-code file")->required();
    cmd->add_option("--rapid-rate", a->machine.rapid_rate_mm_per_min, "rapid traverse rate, mm/min")
        ->capture_default_str()
        ->check(finite_above(0, 1e6));
    cmd->add_option("--max-acceleration", a->machine.max_acceleration_mm_per_s2,
                    "path acceleration limit for the time estimate, mm/s^2")
        ->check(finite_in(0, 1e15));
    cmd->add_option("--json", a->json, "write the report as JSON (- for stdout)");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json}, {&a->file});
      const GcodeProgram prog = read_gcode_file(a->file, gcode_options(a->machine).read);
      const double t_acc = estimate_time_s(prog.path, a->machine);
      if (!a->json.empty()) emit(a->json, gcode_check_json(a->file, prog, t_acc));
      if (a->json != "-") {
        fmt::print("{}",
                   gcode_check_text(a->file, prog, t_acc, a->machine.max_acceleration_mm_per_s2));
      }
      exit_code = 0;
    });
  }
}

}  // namespace trochomill::cli
