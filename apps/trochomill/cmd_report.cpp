// report: one self-contained HTML page with the figures of a job (report_html). It runs what
// the page needs: plan (or the NC program), analyze, the mechanism where the family has one,
// the fast forces where the job has a [material] model (new against worn with wear states),
// and on request the simulation window, the monitor of a recording, a calibration against a
// measured record and a parameter study.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <set>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/io.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/report.hpp"
#include "trochomill/sim.hpp"

namespace trochomill::cli {
namespace {

const std::set<std::string> kWithItems = {"mechanism", "forces", "simulate"};

// A wear state's label: the mesh file's name, or the synthetic insert's flank wear.
std::string state_label(const Job& job, std::size_t state) {
  const TopographySettings& t = job.topography;
  if (!t.files.empty())
    return fmt::format("state {} ({})", state, t.files[state].filename().string());
  if (!t.synthetic_vb_mm.empty()) {
    return fmt::format("state {} (VB {:g} mm)", state, t.synthetic_vb_mm[state]);
  }
  return job.tool.flank_wear_mm > 0 ? fmt::format("VB {:g} mm", job.tool.flank_wear_mm)
                                    : std::string("sharp edge");
}

}  // namespace

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
    // Everything asked for is checked before any work.
    std::set<std::string> with;
    for (const std::string& item : split_trimmed(a->with)) {
      if (item.empty()) continue;
      if (!kWithItems.count(item)) {
        throw InputError(fmt::format(
            "report: --with '{}': unknown item; allowed: mechanism, forces, simulate", item));
      }
      with.insert(item);
    }
    if (!a->signal.file.empty() && !a->start_s) {
      throw InputError(
          "report: --signal needs --start T: the time in the recording where the program starts "
          "(the monitor's cycles come from the job's planned path)");
    }
    if (a->start_s && a->signal.file.empty()) throw InputError("report: --start needs --signal");
    std::vector<Vary> varies;
    for (const auto& v : a->vary) varies.push_back(parse_vary(v));

    ReportData d;
    d.job = a->job.load();
    const Job& job = d.job;
    d.job_file = a->job.file;
    d.gcode_file = a->gcode;
    d.job_text = read_text_file(a->job.file);
    for (const Override& o : a->job.overrides()) d.overrides.push_back(o.key + "=" + o.value);
    d.command = a->command;
    d.path = job_path(job, a->gcode);
    const ToolPath& path = d.path;
    const bool want_forces = job.material.model.has_value() || with.count("forces");
    if (with.count("forces") && !job.material.model) {
      throw InputError(fmt::format(
          "report: --with forces: {} has no [material] force model (give [material] name or "
          "coefficients; see `trochomill materials`)",
          a->job.file));
    }
    std::optional<Signal> signal;
    if (!a->signal.file.empty()) {
      signal = a->signal.read();
      validate(job.monitor, signal->rate_hz);
    }
    std::optional<MeasuredForces> measured;
    if (!a->measured.empty()) {
      if (!job.material.model) {
        throw InputError(fmt::format(
            "report: --measured: {} has no [material] force model to calibrate", a->job.file));
      }
      measured = read_measured_forces(a->measured, ForceCsvFormat{});
    }
    // Memory: the analysis, and the simulation when asked for (its window is known only after
    // the analysis found the steady cycle: checked again then).
    check_memory("report", estimate_analysis_memory(job, path), a->memory_gb,
                 "lower [analysis] steps_per_tooth or report on a shorter program");

    const GuardedRun run(true);
    const RunHooks hooks = run.hooks();
    d.metrics = analyze_with_forces(job, path, hooks);
    const ProcessMetrics& m = d.metrics;
    const auto [from, to] =
        a->window.given()
            ? a->window.resolve(path)
            : std::pair<double, double>{m.cycle_start_s, m.cycle_start_s + m.cycle_time_s};

    // Mechanism: the job's chip model, and the other one where it applies too.
    {
      const bool use_wear = job.tool.flank_wear_mm > 0;
      try {
        ReportMechanism mech;
        mech.use_wear = use_wear;
        mech.curve = mechanism_curve(job, job.mechanism, use_wear);
        mech.zones = summarize_zones(mech.curve, job.mechanism, use_wear);
        MechanismSettings other = job.mechanism;
        other.model = other.model == ChipModel::exact ? ChipModel::pivkin2025 : ChipModel::exact;
        try {
          mech.other = mechanism_curve(job, other, use_wear);
        } catch (const InputError& e) {
          d.notes.push_back(
              fmt::format("mechanism: the other chip model does not apply: {}", e.what()));
        }
        d.mechanism = std::move(mech);
        if (!a->gcode.empty()) {
          d.notes.push_back(
              "mechanism: the cycle of the job's [path] family, not of the NC program's moves");
        }
      } catch (const InputError& e) {
        if (with.count("mechanism")) throw;
        d.notes.push_back(fmt::format("mechanism: not shown: {}", e.what()));
      }
    }
    // Forces (fast chips) over the window; new against worn with wear states.
    if (want_forces) {
      SimControl control;
      control.hooks = hooks;
      ReportForces f;
      f.from_s = from;
      f.to_s = to;
      f.forces = job_forces(job, path, from, to, true, control);
      const std::size_t states = job.topography.states();
      const auto state = static_cast<std::size_t>(std::max(job.topography.state, 0));
      f.state_label = state_label(job, state);
      if (states > 1) {
        Job worn = job;
        worn.topography.state = static_cast<int>(state + 1 < states ? states - 1 : 0);
        f.worn = job_forces(worn, path, from, to, true, control);
        f.worn_label = state_label(worn, static_cast<std::size_t>(worn.topography.state));
      }
      d.forces = std::move(f);
    } else {
      d.notes.push_back(fmt::format(
          "forces: not shown: {} has no [material] force model (see `trochomill materials`)",
          a->job.file));
    }
    if (measured) {
      CalibrationOptions o;
      o.model = *job.material.model;
      o.fast = true;
      o.from_s = std::max(0.0, measured->t_s.front());
      o.to_s = std::min(path.duration_s(), measured->t_s.back());
      if (a->window.given()) std::tie(o.from_s, o.to_s) = std::pair{from, to};
      o.hooks = hooks;
      ReportCalibration c;
      c.measured_file = a->measured;
      c.result = calibrate_forces(job, path, *measured, o);
      Job fitted = job;
      fitted.material = c.result.material;
      fitted.tool = c.result.tool;
      SimControl control;
      control.hooks = hooks;
      c.model = job_forces(fitted, path, o.from_s, o.to_s, true, control).series;
      c.measured = std::move(*measured);
      for (const std::string& w : c.result.warnings) d.notes.push_back("calibration: " + w);
      d.calibration = std::move(c);
    }
    if (with.count("simulate")) {
      const MemoryEstimate est = estimate_simulation_memory(job, path, from, to);
      check_memory("report --with simulate", est.total(false), a->memory_gb,
                   fmt::format("coarsen [simulation] resolution (now {} mm) or shorten the "
                               "window (--cycles, --from/--to)",
                               job.simulation.resolution_mm));
      SimControl control;
      control.hooks = hooks;
      control.reserve_chip_entries = static_cast<std::size_t>(est.chip_entries);
      ReportSimulation s;
      const auto t_start = std::chrono::steady_clock::now();
      s.sim = simulate_job(job, path, from, to, control);
      if (!s.sim.result.complete) throw Interrupted("report: interrupted, nothing written");
      s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      s.from_s = from;
      s.to_s = to;
      s.memory_estimate_bytes = est.total(false);
      d.simulation = std::move(s);
    }
    if (signal) {
      ReportMonitor mo;
      mo.signal_file = a->signal.file;
      mo.settings = job.monitor;
      mo.report = analyze_signal(*signal, job.monitor, &job, *a->start_s);
      int nfft = 4096;
      while (nfft > 64 && static_cast<std::size_t>(nfft) > signal->samples.size()) nfft /= 2;
      mo.spectrum = welch(*signal, nfft);
      mo.spectrogram = spectrogram(*signal, std::min(nfft, 1024));
      mo.signal = std::move(*signal);
      d.monitor = std::move(mo);
    }
    if (!varies.empty()) {
      const JobDocument doc = JobDocument::load(a->job.file);
      RunHooks inner;
      inner.cancel = hooks.cancel;
      ReportStudy st;
      st.varies = varies;
      st.points = run_study(
          doc, a->job.overrides(), varies, 0,
          [&inner](const Job& j) { return analyze_with_forces(j, plan_path(j).path, inner); },
          hooks);
      d.study = std::move(st);
    }
    const std::string html = report_html(d, hooks);
    run.done();
    hooks.check("report: interrupted, nothing written");
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
