// The report's parts: runs what `trochomill report` (and the Python module's `report`) shows,
// from a job and its path, into a ReportData for report_html.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <set>

#include "trochomill/error.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report.hpp"

namespace trochomill {
namespace {

const std::set<std::string> kWithItems = {"mechanism", "forces", "simulate"};

bool asked(const ReportRequest& r, const char* item) {
  return std::find(r.with.begin(), r.with.end(), item) != r.with.end();
}

// A wear state's label: the mesh file's name, or the synthetic insert's flank wear.
std::string state_label(const Job& job, std::size_t state) {
  const TopographySettings& t = job.topography;
  if (!t.files.empty()) {
    return fmt::format("state {} ({})", state, t.files[state].filename().string());
  }
  if (!t.synthetic_vb_mm.empty()) {
    return fmt::format("state {} (VB {:g} mm)", state, t.synthetic_vb_mm[state]);
  }
  return job.tool.flank_wear_mm > 0 ? fmt::format("VB {:g} mm", job.tool.flank_wear_mm)
                                    : std::string("sharp edge");
}

std::string job_name(const ReportRequest& r) {
  return r.job_file.empty() ? std::string("the job") : r.job_file;
}

}  // namespace

void check_report_request(const Job& job, const ReportRequest& r) {
  for (const std::string& item : r.with) {
    if (!kWithItems.count(item)) {
      throw InputError(
          fmt::format("report: {} '{}': unknown item; allowed: mechanism, forces, simulate",
                      option_name("parts"), item));
    }
  }
  if (r.signal && !r.signal_start_s) {
    throw InputError(fmt::format(
        "report: {} needs {} T: the time in the recording where the program starts (the "
        "monitor's cycles come from the job's planned path)",
        option_name("signal"), option_name("start_s")));
  }
  if (r.signal_start_s && !r.signal)
    throw InputError(
        fmt::format("report: {} needs {}", option_name("start_s"), option_name("signal")));
  if (r.signal_start_s && !(std::isfinite(*r.signal_start_s) && *r.signal_start_s >= 0)) {
    throw InputError(
        fmt::format("report: {} {}: a time >= 0 s", option_name("start_s"), *r.signal_start_s));
  }
  if (r.signal) validate(job.monitor, r.signal->rate_hz);
  if (asked(r, "forces") && !job.material.model) {
    throw InputError(
        fmt::format("report: {} forces: {} has no [material] force model (give [material] name or "
                    "coefficients; see `trochomill materials`)",
                    option_name("parts"), job_name(r)));
  }
  if (r.measured && !job.material.model) {
    throw InputError(fmt::format("report: {}: {} has no [material] force model to calibrate",
                                 option_name("measured_t_s"), job_name(r)));
  }
  if (r.measured && r.measured->t_s.size() < 2) {
    throw InputError("report: " + option_name("measured_t_s") +
                     ": the record has fewer than two samples");
  }
  if (!r.varies.empty() && r.document == nullptr) {
    throw InputError("report: a study (" + option_name("vary") + ") needs the job's document");
  }
  if (r.window_s) {
    const auto [a, b] = *r.window_s;
    if (!(std::isfinite(a) && std::isfinite(b) && a >= 0 && b > a)) {
      throw InputError(fmt::format("report: the window {}..{} s is empty or not finite", a, b));
    }
  }
}

ReportData build_report(Job job, ToolPath path, ReportRequest r, const RunHooks& hooks) {
  check_report_request(job, r);
  ReportData d;
  d.job = std::move(job);
  d.path = std::move(path);
  d.job_file = r.job_file;
  d.gcode_file = r.gcode_file;
  d.job_text = r.job_text;
  for (const Override& o : r.overrides) d.overrides.push_back(o.key + "=" + o.value);
  d.command = r.command;
  const Job& jb = d.job;
  const ToolPath& p = d.path;

  d.metrics = analyze_with_forces(jb, p, hooks);
  const ProcessMetrics& m = d.metrics;
  const auto [from, to] =
      r.window_s ? *r.window_s
                 : std::pair<double, double>{m.cycle_start_s, m.cycle_start_s + m.cycle_time_s};

  // Mechanism: the job's chip model, and the other one where it applies too.
  const bool use_wear = jb.tool.flank_wear_mm > 0;
  try {
    ReportMechanism mech;
    mech.use_wear = use_wear;
    mech.curve = mechanism_curve(jb, jb.mechanism, use_wear);
    mech.zones = summarize_zones(mech.curve, jb.mechanism, use_wear);
    MechanismSettings other = jb.mechanism;
    other.model = other.model == ChipModel::exact ? ChipModel::pivkin2025 : ChipModel::exact;
    try {
      mech.other = mechanism_curve(jb, other, use_wear);
    } catch (const InputError& e) {
      d.notes.push_back(
          fmt::format("mechanism: the other chip model does not apply: {}", e.what()));
    }
    d.mechanism = std::move(mech);
    if (!r.gcode_file.empty()) {
      d.notes.push_back(
          "mechanism: the cycle of the job's [path] family, not of the NC program's moves");
    }
  } catch (const InputError& e) {
    if (asked(r, "mechanism")) throw;
    d.notes.push_back(fmt::format("mechanism: not shown: {}", e.what()));
  }
  hooks.check();

  // Forces (fast chips) over the window; new against worn with wear states. A program without
  // a steady cycle (a pocket, a slot along a curve) has no window of its own.
  if (jb.material.model && !(to > from)) {
    d.notes.push_back(
        "forces: not shown: the program has no steady cycle; give a window (its start and end, "
        "s of programmed time) for a part of it");
  } else if (jb.material.model) {
    SimControl control;
    control.hooks = hooks;
    ReportForces f;
    f.from_s = from;
    f.to_s = to;
    f.forces = job_forces(jb, p, from, to, true, control);
    const std::size_t states = jb.topography.states();
    const auto state = static_cast<std::size_t>(std::max(jb.topography.state, 0));
    f.state_label = state_label(jb, state);
    if (states > 1) {
      Job worn = jb;
      worn.topography.state = static_cast<int>(state + 1 < states ? states - 1 : 0);
      f.worn = job_forces(worn, p, from, to, true, control);
      f.worn_label = state_label(worn, static_cast<std::size_t>(worn.topography.state));
    }
    d.forces = std::move(f);
    if (cutting_direction_only(jb.material)) {
      d.notes.push_back("forces: " + cutting_direction_only_note(jb.material));
    }
  } else {
    d.notes.push_back(fmt::format(
        "forces: not shown: {} has no [material] force model (see `trochomill materials`)",
        job_name(r)));
  }
  if (r.measured) {
    CalibrationOptions o;
    o.model = *jb.material.model;
    o.fast = true;
    o.from_s = std::max(0.0, r.measured->t_s.front());
    o.to_s = std::min(p.duration_s(), r.measured->t_s.back());
    if (r.window_s) std::tie(o.from_s, o.to_s) = *r.window_s;
    o.hooks = hooks;
    ReportCalibration c;
    c.measured_file = r.measured_file;
    c.result = calibrate_forces(jb, p, *r.measured, o);
    Job fitted = jb;
    fitted.material = c.result.material;
    fitted.tool = c.result.tool;
    SimControl control;
    control.hooks = hooks;
    c.model = job_forces(fitted, p, o.from_s, o.to_s, true, control).series;
    c.measured = std::move(*r.measured);
    for (const std::string& w : c.result.warnings) d.notes.push_back("calibration: " + w);
    d.calibration = std::move(c);
  }
  if (asked(r, "simulate")) {
    const MemoryEstimate est = estimate_simulation_memory(jb, p, from, to);
    if (r.check_simulation_memory) r.check_simulation_memory(est.total(false));
    SimControl control;
    control.hooks = hooks;
    control.reserve_chip_entries = static_cast<std::size_t>(est.chip_entries);
    ReportSimulation s;
    const auto t_start = std::chrono::steady_clock::now();
    s.sim = simulate_job(jb, p, from, to, control);
    if (!s.sim.result.complete) throw Interrupted("interrupted");
    s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    s.from_s = from;
    s.to_s = to;
    s.memory_estimate_bytes = est.total(false);
    d.simulation = std::move(s);
  }
  if (r.signal) {
    ReportMonitor mo;
    mo.signal_file = r.signal_file;
    mo.settings = jb.monitor;
    mo.report = analyze_signal(*r.signal, jb.monitor, &jb, *r.signal_start_s);
    int nfft = 4096;
    while (nfft > 64 && static_cast<std::size_t>(nfft) > r.signal->samples.size()) nfft /= 2;
    mo.spectrum = welch(*r.signal, nfft);
    mo.spectrogram = spectrogram(*r.signal, std::min(nfft, 1024));
    mo.signal = std::move(*r.signal);
    d.monitor = std::move(mo);
  }
  hooks.check();
  return d;
}

}  // namespace trochomill
