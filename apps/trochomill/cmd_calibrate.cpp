// calibrate: force coefficients (and runout) fitted to measured forces, or the linear model
// by regression on mean slot forces; writes a [material] block.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <tuple>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report.hpp"

namespace trochomill::cli {

void register_calibration_commands(CLI::App& app, int& exit_code) {
  struct Args {
    JobArgs job;
    WindowArgs window;
    std::string measured, mean, model, fit, columns, json, write, gcode, time_unit = "s",
                                                                         force_unit = "N";
    std::optional<double> cutoff_hz, max_shift_s, memory_gb;
    bool fast = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "calibrate", "fit force coefficients (and runout) to measured forces; write [material]");
  add_job_args(cmd, a->job);
  add_memory_limit(cmd, a->memory_gb);
  cmd->add_option("--measured", a->measured, "measured forces, CSV (t, F_x, F_y, F_z)");
  cmd->add_option("--mean-forces", a->mean,
                  "mean forces of full-immersion slot tests, CSV (feed_per_tooth_mm, f_x_n, "
                  "f_y_n, f_z_n): linear model by regression");
  cmd->add_option("--model", a->model,
                  "bergmann, kienzle or linear (default: the job's, else bergmann)");
  cmd->add_option("--fit", a->fit,
                  "parameters, comma separated: k_c,k_n,m,m_n,k_a,m_a | k_tc,k_rc,k_ac,k_te,"
                  "k_re,k_ae, runout_radial,runout_phase,runout_axial (default: the model's)");
  cmd->add_flag("--fast", a->fast, "the fast chip source, as for forces");
  cmd->add_option("--columns", a->columns,
                  "time,fx,fy,fz column names (default t_s,f_x_n,f_y_n,f_z_n)");
  cmd->add_option("--time-unit", a->time_unit, "s or ms")->capture_default_str();
  cmd->add_option("--force-unit", a->force_unit, "N or kN")->capture_default_str();
  cmd->add_option("--cutoff", a->cutoff_hz,
                  "low-pass of both signals, Hz (default 10 x tooth "
                  "passing, below 0.4 x the coarser rate)")
      ->check(finite_above(0, 1e7));
  cmd->add_option("--max-shift", a->max_shift_s,
                  "alignment search +-, s (default half a revolution)")
      ->check(finite_above(0, 1e3));
  cmd->add_option("--gcode", a->gcode, "this NC program instead of the job's path");
  cmd->add_option("--from", a->window.from_s,
                  "model window start, s (default: the measurement's start)")
      ->check(finite_in(0, 1e9));
  cmd->add_option("--to", a->window.to_s, "model window end, s (default: the measurement's end)")
      ->check(finite_in(0, 1e9));
  cmd->add_option("--cycles", a->window.cycles, "A:B: the model window as trochoid cycles");
  cmd->add_option("--json", a->json, "write the result as JSON (- for stdout)");
  cmd->add_option("--write", a->write, "write the [material] block to this file (- for stdout)");
  cmd->final_callback([a, &exit_code] {
    check_outputs({&a->json, &a->write}, {&a->job.file, &a->measured, &a->mean, &a->gcode});
    const Job job = a->job.load();
    if (a->measured.empty() == a->mean.empty()) {
      throw InputError("calibrate: give --measured FILE or --mean-forces FILE (one)");
    }
    exit_code = 0;
    if (!a->mean.empty()) {
      const MeanForceFit f = fit_mean_forces(job, read_mean_forces(a->mean));
      const std::string block = mean_force_toml(f);
      if (!a->write.empty()) emit(a->write, block);
      if (!a->json.empty()) emit(a->json, mean_force_json(f));
      if (a->json != "-" && a->write != "-") fmt::print("{}", block);
      return;
    }
    ForceCsvFormat fmt_in;
    if (!a->columns.empty()) {
      const std::vector<std::string> cols = split_trimmed(a->columns);
      if (cols.size() != 4 ||
          std::any_of(cols.begin(), cols.end(), [](const std::string& c) { return c.empty(); })) {
        throw InputError(
            fmt::format("--columns '{}': expected four names time,fx,fy,fz", a->columns));
      }
      fmt_in.time = cols[0], fmt_in.fx = cols[1], fmt_in.fy = cols[2], fmt_in.fz = cols[3];
    }
    if (a->time_unit == "ms") {
      fmt_in.time_to_s = 1e-3;
    } else if (a->time_unit != "s") {
      throw InputError(fmt::format("--time-unit '{}': s or ms", a->time_unit));
    }
    if (a->force_unit == "kN") {
      fmt_in.force_to_n = 1e3;
    } else if (a->force_unit != "N") {
      throw InputError(fmt::format("--force-unit '{}': N or kN", a->force_unit));
    }
    CalibrationOptions o;
    if (!a->model.empty()) {
      o.model = parse_force_model(a->model);
    } else if (job.material.model) {
      o.model = *job.material.model;
    }
    if (!a->fit.empty()) {
      for (const auto& p : split_trimmed(a->fit)) {
        if (p.empty()) throw InputError(fmt::format("--fit '{}': an empty name", a->fit));
        o.fit.push_back(p);
      }
    }
    o.fast = a->fast;
    if (a->cutoff_hz) o.cutoff_hz = *a->cutoff_hz;
    if (a->max_shift_s) o.max_shift_s = *a->max_shift_s;
    const MeasuredForces meas = read_measured_forces(a->measured, fmt_in);
    const ToolPath path = job_path(job, a->gcode, a->memory_gb);
    if (!a->window.given()) {
      o.from_s = std::max(0.0, meas.t_s.front());
      o.to_s = std::min(path.duration_s(), meas.t_s.back());
    } else {
      std::tie(o.from_s, o.to_s) = a->window.resolve(path);
    }
    check_memory("calibrate", estimate_calibration_memory(job, path, o, meas.t_s.size()),
                 a->memory_gb,
                 fmt::format("the model window is {:.1f} s{}: a few cycles (--cycles A:B or "
                             "--from/--to) hold the coefficients as well",
                             o.to_s - o.from_s, o.fast ? "" : " of simulation (or use --fast)"));
    const GuardedRun run(true);
    o.hooks = run.hooks();
    const CalibrationResult r = calibrate_forces(job, path, meas, o);
    run.done();
    for (const std::string& w : r.warnings) fmt::print(stderr, "warning: {}\n", w);
    const std::string block = material_toml(r);
    if (!a->write.empty()) emit(a->write, block);
    if (!a->json.empty()) emit(a->json, calibration_json(r));
    if (a->json != "-" && a->write != "-") fmt::print("{}", calibration_text(a->measured, r));
    run.finish("interrupted: the outputs were written in full");
  });
}

}  // namespace trochomill::cli
