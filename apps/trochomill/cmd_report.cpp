// report: one self-contained HTML page with the figures of a job. The options become a
// ReportRequest (files read, the window resolved), the library runs the parts
// (build_report) and writes the page (report_html); the page is written atomically.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/app.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report.hpp"

namespace trochomill::cli {

void register_report_commands(CLI::App& app, int& exit_code, int argc, char** argv) {
  struct Args {
    JobArgs job;
    WindowArgs window;
    SignalArgs signal;
    std::optional<double> start_s, memory_gb;
    std::string gcode, with, measured, output;
    std::vector<std::string> vary;
    std::string command;
  };
  auto a = std::make_shared<Args>();
  // The program's name, not its path, and without the output file: the same command writes
  // the same page wherever it runs and whatever the page is called.
  a->command = "trochomill";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-o" || arg == "--output") {
      ++i;
      continue;
    }
    if (arg.rfind("--output=", 0) == 0 || (arg.rfind("-o", 0) == 0 && arg.size() > 2)) continue;
    a->command += " " + arg;
  }
  auto* cmd = app.add_subcommand(
      "report",
      "one self-contained HTML page with the figures: path, engagement, walls, "
      "mechanism, forces (and simulation, monitor, calibration, study on request)");
  add_job_args(cmd, a->job);
  add_stock_mesh_alias(cmd, a->job);
  cmd->add_option("-o,--output", a->output, "the HTML file to write")->required();
  cmd->add_option("--gcode", a->gcode, "report on this NC program instead of the planned path");
  cmd->add_option("--with", a->with,
                  "comma-separated parts besides the defaults: simulate (the tri-dexel window); "
                  "mechanism and forces are on by default where the job allows them and, "
                  "named here, required");
  add_window_args(cmd, a->window, "forces' and simulation's window (default: the steady cycle)");
  add_signal_args(cmd, a->signal, false, "--signal");
  cmd->add_option("--start", a->start_s,
                  "time in the signal where the program starts, s (the cycles come from the "
                  "job's planned path)")
      ->check(finite_in(0, 1e9));
  cmd->add_option("--measured", a->measured,
                  "calibrate the force model against this measured record (CSV: t_s, f_x_n, "
                  "f_y_n, f_z_n) and show the fit");
  cmd->add_option("--vary", a->vary,
                  "add a parameter study: section.key=v1,v2,... (repeatable, as compare)");
  add_memory_limit(cmd, a->memory_gb);
  cmd->final_callback([a, &exit_code] {
    check_outputs({&a->output}, {&a->job.file, &a->gcode, &a->signal.file, &a->measured});
    // Everything asked for is checked before any work (check_report_request).
    ReportRequest r;
    r.with = split_trimmed(a->with);
    r.with.erase(std::remove(r.with.begin(), r.with.end(), std::string()), r.with.end());
    for (const auto& v : a->vary) r.varies.push_back(parse_vary_flag(v));
    Job job = a->job.load();
    r.job_file = a->job.file;
    r.gcode_file = a->gcode;
    r.job_text = read_text_file(a->job.file);
    r.overrides = a->job.overrides();
    r.command = a->command;
    r.signal_start_s = a->start_s;
    if (!a->signal.file.empty()) {
      r.signal_file = a->signal.file;
      if (!a->start_s) check_report_request(job, r);  // before reading a long recording
      r.signal = a->signal.read();
    }
    if (!a->measured.empty()) {
      r.measured_file = a->measured;
      if (!job.material.model) check_report_request(job, r);  // before reading it
      r.measured = read_measured_forces(a->measured, ForceCsvFormat{});
    }
    std::optional<JobDocument> doc;
    if (!r.varies.empty()) {
      doc = JobDocument::load(a->job.file);
      r.document = &*doc;
    }
    ToolPath path = job_path(job, a->gcode, a->memory_gb);
    if (a->window.given()) r.window_s = a->window.resolve(path);
    const std::optional<double> limit_gb = a->memory_gb;
    r.check_simulation_memory = [limit_gb, &job](double need) {
      check_memory("report --with simulate", need, limit_gb,
                   fmt::format("coarsen [simulation] resolution (now {} mm) or shorten the "
                               "window (--cycles, --from/--to)",
                               job.simulation.resolution_mm));
    };
    check_report_request(job, r);
    check_memory("report", estimate_analysis_memory(job, path), a->memory_gb,
                 "lower [analysis] steps_per_tooth or report on a shorter program");

    const GuardedRun run(true);
    const RunHooks hooks = run.hooks();
    const ReportData d = report_data(job, std::move(path), std::move(r), hooks);
    if (d.study) print_failed_points("report --vary", d.study->points);
    const std::string html = report_html(d, hooks);
    run.done();
    hooks.check("interrupted");
    emit(a->output, html);
    std::string parts = "path, engagement, walls";
    if (d.mechanism) parts += ", mechanism";
    if (d.forces) parts += d.forces->worn ? ", forces (new and worn)" : ", forces";
    if (d.calibration) parts += ", calibration";
    if (d.simulation) parts += ", simulation";
    if (d.monitor) parts += ", monitor";
    if (d.study) parts += ", study";
    for (const std::string& n : d.notes) fmt::print(stderr, "report: {}\n", n);
    if (a->output != "-") {
      fmt::print("{}: {:.2f} MB: {}\n", a->output, static_cast<double>(html.size()) / 1e6, parts);
    }
    exit_code = 0;
  });
}

}  // namespace trochomill::cli
