// trochomill command-line interface: parses arguments, calls the library, formats output.
// Exit codes: 0 success, 2 bad input (arguments, job file, NC program), 1 runtime failure.
#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <tuple>

#include "trochomill/analysis.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"
#include "trochomill/job.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/path.hpp"
#include "trochomill/report.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/topography.hpp"
#include "trochomill/units.hpp"
#include "trochomill/version.hpp"

namespace tmill = trochomill;

namespace {

struct JobArgs {
  std::string job_file;
  std::vector<std::string> sets;
};

void add_job_args(CLI::App* cmd, JobArgs& a) {
  cmd->add_option("JOB", a.job_file, "job file (TOML)")->required();
  cmd->add_option("--set", a.sets,
                  "override a job key: section.key=value (repeatable), e.g. path.step=0.8")
      ->take_all();
}

tmill::Job load(const JobArgs& a) {
  std::vector<tmill::Override> ov;
  for (const auto& s : a.sets) ov.push_back(tmill::parse_override(s));
  return tmill::load_job(a.job_file, ov);
}

// The job's planned path, or the NC program's when one is given.
tmill::ToolPath job_path(const tmill::Job& job, const std::string& gcode_file) {
  if (gcode_file.empty()) return tmill::plan_path(job).path;
  tmill::GcodeReadOptions ro;
  ro.rapid_rate_mm_per_min = job.machine.rapid_rate_mm_per_min;
  return tmill::read_gcode_file(gcode_file, ro).path;
}

// Writes text to a file atomically, or to stdout for "-".
void emit(const std::string& target, const std::string& text) {
  if (target == "-") {
    std::fwrite(text.data(), 1, text.size(), stdout);
    std::fflush(stdout);
  } else {
    tmill::write_file_atomic(target, text);
  }
}

std::string samples_csv(const tmill::PathSamples& s, const tmill::ToothTracks& tr) {
  std::string out = "t_s,s_mm,x_mm,y_mm,z_mm,tx,ty,tz,curvature_per_mm,segment";
  for (int k = 0; k < tr.teeth; ++k)
    out += fmt::format(",tooth{0}_x_mm,tooth{0}_y_mm,tooth{0}_z_mm", k);
  out += '\n';
  for (std::size_t i = 0; i < s.size(); ++i) {
    fmt::format_to(std::back_inserter(out),
                   "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{}", s.t_s[i],
                   s.s_mm[i], s.x_mm[i], s.y_mm[i], s.z_mm[i], s.tx[i], s.ty[i], s.tz[i],
                   s.curvature_per_mm[i], s.segment[i]);
    for (int k = 0; k < tr.teeth; ++k) {
      fmt::format_to(std::back_inserter(out), ",{:.9g},{:.9g},{:.9g}", tr.x_mm[k][i], tr.y_mm[k][i],
                     tr.z_mm[k][i]);
    }
    out += '\n';
  }
  return out;
}

struct Box {
  tmill::Vec3 lo = tmill::Vec3::Constant(std::numeric_limits<double>::infinity());
  tmill::Vec3 hi = tmill::Vec3::Constant(-std::numeric_limits<double>::infinity());
};

// Bounding box: line end points, curves sampled every quarter degree of parameter (for an
// arc of radius r the error is below r (1 - cos(pi/1440)) = 2.4e-6 r).
Box bounding_box(const tmill::ToolPath& path) {
  Box b;
  auto add = [&](const tmill::Vec3& p) {
    b.lo = b.lo.cwiseMin(p);
    b.hi = b.hi.cwiseMax(p);
  };
  for (const auto& seg : path.segments()) {
    add(seg.start());
    add(seg.end());
    if (seg.kind() == tmill::Segment::Kind::curve) {
      const int n = std::max(4, static_cast<int>(std::abs(seg.u1() - seg.u0()) * 720.0 / M_PI));
      for (int k = 1; k < n; ++k) add(seg.point_u(seg.u0() + (seg.u1() - seg.u0()) * k / n));
    }
  }
  return b;
}

// The window of a path: --cycles A:B, or --from/--to (s), or the whole path.
std::pair<double, double> parse_window(const tmill::ToolPath& path, const std::string& cycles,
                                       std::optional<double> from_s, std::optional<double> to_s) {
  double from = 0, to = path.duration_s();
  if (!cycles.empty()) {
    if (from_s || to_s) throw tmill::InputError("give --cycles or --from/--to, not both");
    const auto colon = cycles.find(':');
    char* e1 = nullptr;
    char* e2 = nullptr;
    const std::string a = cycles.substr(0, colon);
    const std::string b = colon == std::string::npos ? "" : cycles.substr(colon + 1);
    const long ca = std::strtol(a.c_str(), &e1, 10), cb = std::strtol(b.c_str(), &e2, 10);
    if (colon == std::string::npos || a.empty() || b.empty() || *e1 != '\0' || *e2 != '\0') {
      throw tmill::InputError(fmt::format("--cycles '{}': expected A:B, e.g. 3:4", cycles));
    }
    return tmill::cycle_window(path, static_cast<int>(ca), static_cast<int>(cb));
  }
  if (from_s) from = *from_s;
  if (to_s) to = *to_s;
  return {from, to};
}

// Ctrl-C sets a flag the simulation polls after each step (it then stops, and what was
// computed is written, marked incomplete); the previous handler comes back on scope exit.
class InterruptGuard {
 public:
  InterruptGuard() {
    flag().store(false);
    struct sigaction sa {};
    sa.sa_handler = [](int) { flag().store(true); };
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_);
  }
  ~InterruptGuard() { sigaction(SIGINT, &old_, nullptr); }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static std::atomic<bool>& flag() {
    static std::atomic<bool> f{false};
    return f;
  }

 private:
  struct sigaction old_ {};
};

// A progress bar with ETA on stderr (for terminals).
std::function<void(std::size_t, std::size_t)> progress_bar(
    std::chrono::steady_clock::time_point start) {
  return [start](std::size_t done, std::size_t total) {
    const double f =
        static_cast<double>(done) / static_cast<double>(std::max<std::size_t>(1, total));
    const double el =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int w = 30, filled = static_cast<int>(f * w);
    fmt::print(stderr, "\r[{}{}] {:5.1f} %  ETA {:.0f} s   ",
               std::string(static_cast<std::size_t>(filled), '#'),
               std::string(static_cast<std::size_t>(w - filled), '.'), 100 * f,
               f > 0 ? el * (1 - f) / f : 0.0);
  };
}

// "a,b,c" -> {"a", "b", "c"} (spaces dropped; empty items kept, for the caller to refuse).
std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  for (const char c : text + ",") {
    if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur += c;
    }
  }
  return out;
}

// Writes a WAV atomically: a temporary file beside the target, then a rename.
void emit_wav(const std::string& target, const tmill::Signal& sig) {
  const std::string tmp = fmt::format("{}.tmp{}", target, static_cast<long>(::getpid()));
  try {
    tmill::write_wav(tmp, sig);
    std::filesystem::rename(tmp, target);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
}

// "LO:HI" in Hz.
std::pair<double, double> parse_band(const std::string& opt, const std::string& text) {
  const auto colon = text.find(':');
  char* e1 = nullptr;
  char* e2 = nullptr;
  const std::string a = text.substr(0, colon),
                    b = colon == std::string::npos ? "" : text.substr(colon + 1);
  const double lo = std::strtod(a.c_str(), &e1), hi = std::strtod(b.c_str(), &e2);
  if (colon == std::string::npos || a.empty() || b.empty() || *e1 != '\0' || *e2 != '\0' ||
      !(lo > 0 && hi > lo)) {
    throw tmill::InputError(fmt::format(
        "{} '{}': expected LOW:HIGH in Hz with 0 < LOW < HIGH, e.g. 2000:5000", opt, text));
  }
  return {lo, hi};
}

// Signal-reading options shared by monitor and spectrum.
struct SignalArgs {
  std::string file;
  std::optional<double> rate;
  std::string format = "auto";
  int channel = 0;
};

void add_signal_args(CLI::App* cmd, SignalArgs& a, bool required) {
  auto* o = cmd->add_option("SIGNAL", a.file,
                            "WAV/FLAC/AIFF (libsndfile), CSV, raw .f32/.s16 (- for stdin, raw)");
  if (required) o->required();
  cmd->add_option("--rate", a.rate, "sample rate, Hz (raw data, CSV without a time column)");
  cmd->add_option("--format", a.format, "auto, wav, csv, f32 or s16 (default: by extension)");
  cmd->add_option("--channel", a.channel, "0-based channel (or CSV data column)")
      ->check(CLI::NonNegativeNumber);
}

tmill::Signal read_signal_args(const SignalArgs& a) {
  tmill::SignalReadOptions o;
  o.format = tmill::parse_sample_format(a.format);
  o.rate_hz = a.rate;
  o.channel = a.channel;
  return tmill::read_signal(a.file, o);
}

int run(int argc, char** argv) {
  CLI::App app{"trochomill: plan, analyse and simulate trochoidal slot milling"};
  app.set_version_flag("--version", std::string("trochomill ") + tmill::kVersion);
  app.require_subcommand(1);

  // plan
  JobArgs plan_args;
  std::string plan_out, plan_dialect;
  double plan_tol = 0;
  bool plan_chords = false;
  auto* plan = app.add_subcommand("plan", "write the slot program of a job as G-code");
  add_job_args(plan, plan_args);
  plan->add_option("-o,--output", plan_out, "output G-code file (- for stdout)")->required();
  plan->add_option("--dialect", plan_dialect,
                   "linuxcnc | fanuc | sinumerik | grbl (default: [machine] dialect)");
  plan->add_option("--tolerance", plan_tol,
                   "max deviation of fitted arcs/chords, mm (default: [machine] arc_tolerance)");
  plan->add_flag("--chords", plan_chords, "write curves as G1 chords instead of biarcs");

  // path
  JobArgs path_args;
  std::string path_csv, path_gcode;
  std::optional<int> path_spr;
  std::optional<double> path_dt, path_ds;
  auto* pathc = app.add_subcommand("path", "sample the tool-centre and tooth-tip trajectories");
  add_job_args(pathc, path_args);
  pathc->add_option("--csv", path_csv, "write the samples as CSV (- for stdout)");
  pathc->add_option("--gcode", path_gcode,
                    "take the path from this NC program instead of planning it");
  auto* o_spr = pathc->add_option("--steps-per-rev", path_spr, "samples per spindle revolution");
  auto* o_dt = pathc->add_option("--dt", path_dt, "time step, s");
  auto* o_ds = pathc->add_option("--ds", path_ds, "path-length step, mm");
  o_spr->excludes(o_dt)->excludes(o_ds);
  o_dt->excludes(o_ds);

  // check-gcode
  std::string cg_file, cg_json;
  double cg_rapid = 10000, cg_accel = 0;
  auto* cg = app.add_subcommand("check-gcode",
                                "parse an NC program and report length, time, bounding box");
  cg->add_option("FILE", cg_file, "G-code file")->required();
  cg->add_option("--rapid-rate", cg_rapid, "rapid traverse rate, mm/min")
      ->check(CLI::PositiveNumber);
  cg->add_option("--max-acceleration", cg_accel,
                 "path acceleration limit for the time estimate, mm/s^2")
      ->check(CLI::NonNegativeNumber);
  cg->add_option("--json", cg_json, "write the report as JSON (- for stdout)");

  // analyze
  JobArgs an_args;
  std::string an_gcode, an_json, an_csv;
  auto* an = app.add_subcommand(
      "analyze", "engagement, chip thickness, times, MRR, waviness of a slot program");
  add_job_args(an, an_args);
  an->add_option("--gcode", an_gcode, "analyse this NC program instead of the planned path");
  an->add_option("--json", an_json, "write the metrics as JSON (- for stdout)");
  an->add_option("--csv", an_csv, "write the time series as CSV (- for stdout)");

  // compare
  JobArgs cmp_args;
  std::vector<std::string> cmp_vary;
  std::string cmp_json, cmp_csv;
  int cmp_threads = 0;
  auto* cmp = app.add_subcommand("compare", "analyse a grid of job variants in parallel");
  add_job_args(cmp, cmp_args);
  cmp->add_option("--vary", cmp_vary,
                  "section.key=v1,v2,... (repeatable: several give a grid), e.g. "
                  "path.aspect_ratio=0.8,1.0,1.2")
      ->required();
  cmp->add_option("--json", cmp_json, "write the study as JSON (- for stdout)");
  cmp->add_option("--csv", cmp_csv, "write the study as CSV (- for stdout)");
  cmp->add_option("--threads", cmp_threads, "worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber);

  // mechanism
  JobArgs mech_args;
  std::string mech_model, mech_json, mech_csv;
  std::optional<double> mech_wear;
  auto* mech = app.add_subcommand(
      "mechanism", "chip thickness, K_re and cutting-mechanism zones over a trochoid cycle");
  add_job_args(mech, mech_args);
  mech->add_option("--model", mech_model,
                   "chip model: exact or pivkin2025 (default: [mechanism] model)");
  mech->add_option("--wear", mech_wear, "flank wear VB_B, mm (default: [tool] flank_wear)");
  mech->add_option("--json", mech_json, "write curves and zone summary as JSON (- for stdout)");
  mech->add_option("--csv", mech_csv, "write the curves as CSV (- for stdout)");

  // recommend
  JobArgs rec_args;
  std::string rec_model, rec_json;
  std::optional<double> rec_share, rec_wear;
  bool rec_feed = false;
  auto* rec = app.add_subcommand("recommend",
                                 "smallest trochoid step (or feed per tooth) for a CZIII share");
  add_job_args(rec, rec_args);
  rec->add_option("--model", rec_model,
                  "chip model: exact or pivkin2025 (default: [mechanism] model)");
  rec->add_option("--share", rec_share,
                  "required CZIII share of the cutting part, 0..1 "
                  "(default: [mechanism] share = 0.5)");
  rec->add_option("--wear", rec_wear,
                  "flank wear VB_B, mm (classify with the wear-corrected K_re)");
  rec->add_flag("--feed", rec_feed, "recommend the feed per tooth at the job's step instead");
  rec->add_option("--json", rec_json, "write the recommendation as JSON (- for stdout)");

  // monitor
  SignalArgs mon_sig;
  std::string mon_job, mon_json, mon_csv, mon_low, mon_high;
  std::vector<std::string> mon_sets;
  double mon_start = 0;
  std::optional<int> mon_order;
  std::optional<double> mon_window;
  bool mon_stream = false;
  auto* mon = app.add_subcommand(
      "monitor", "vibroacoustic k_f = RMS(low band) / RMS(high band) per trochoid cycle, flags");
  add_signal_args(mon, mon_sig, false);
  mon->add_option("--job", mon_job, "job file: cycle timing, [monitor] settings, model zones");
  mon->add_option("--set", mon_sets, "override a job key (repeatable)")->take_all();
  mon->add_option("--start", mon_start, "time in the signal where the program starts, s");
  mon->add_option("--low", mon_low, "low band LOW:HIGH, Hz (default 2000:5000)");
  mon->add_option("--high", mon_high, "high band LOW:HIGH, Hz (default 8000:13000)");
  mon->add_option("--order", mon_order, "Butterworth order per band (default 4)");
  mon->add_option("--window", mon_window, "RMS window, s (default 0.005)");
  mon->add_option("--json", mon_json, "write the results as JSON (- for stdout)");
  mon->add_option("--csv", mon_csv, "write the per-window series as CSV (- for stdout)");
  mon->add_flag("--stream", mon_stream,
                "live: read samples from stdin (--format f32, s16 or csv; --rate), one JSON line "
                "per window");

  // synth-signal
  JobArgs syn_args;
  std::string syn_out;
  tmill::SynthOptions syn;
  auto* synth = app.add_subcommand(
      "synth-signal", "synthetic vibroacoustic signal following the model's zones (WAV)");
  add_job_args(synth, syn_args);
  synth->add_option("-o,--output", syn_out, "output WAV file")->required();
  synth->add_option("--rate", syn.rate_hz, "sample rate, Hz (default 100000)");
  synth->add_option("--cycles", syn.cycles, "trochoid cycles to cover (default 12)");
  synth->add_option("--kf-czi", syn.kf_czi, "k_f in CZI (default 1.6)");
  synth->add_option("--kf-czii", syn.kf_czii, "k_f in CZII (default 1.15)");
  synth->add_option("--kf-cziii", syn.kf_cziii, "k_f in CZIII (default 1.0)");
  synth->add_option("--wear-drift", syn.wear_drift,
                    "k_f grows by this fraction from the first cycle to the last (default 0)");
  synth->add_option("--noise", syn.noise, "white noise RMS relative to cutting (default 0.02)");
  synth->add_option("--lead", syn.lead_s, "air before the program start, s (default 0.1)");
  synth->add_option("--seed", syn.seed, "random seed (default 1)");

  // spectrum
  SignalArgs spec_sig;
  int spec_nfft = 4096;
  std::string spec_csv, spec_sg;
  auto* spec = app.add_subcommand("spectrum", "Welch spectrum and spectrogram, to choose bands");
  add_signal_args(spec, spec_sig, true);
  spec->add_option("--nfft", spec_nfft, "FFT length, a power of two (default 4096)");
  spec->add_option("--csv", spec_csv, "write the PSD as CSV (- for stdout)");
  spec->add_option("--spectrogram", spec_sg, "write the spectrogram as CSV (t_s, f_hz, db)");

  // simulate
  JobArgs sim_args;
  std::string sim_gcode, sim_json, sim_out, sim_cycles;
  std::optional<double> sim_from, sim_to;
  auto* sim = app.add_subcommand(
      "simulate", "tri-dexel material removal: per-step chip thickness and removed volume");
  add_job_args(sim, sim_args);
  sim->add_option("--gcode", sim_gcode, "simulate this NC program instead of the job's path");
  sim->add_option("--from", sim_from, "window start, s of programmed time (default 0)");
  sim->add_option("--to", sim_to, "window end, s (default: the path's end)");
  sim->add_option("--cycles", sim_cycles,
                  "A:B: trochoid cycles A (inclusive) to B (exclusive), from 0");
  sim->add_option("--json", sim_json, "write the summary as JSON (- for stdout)");
  sim->add_option("--out", sim_out,
                  "directory for series.csv, chips.h5, walls.csv, floor.csv and surface.stl");
  std::optional<double> sim_mem_gb, sim_stl_step;
  sim->add_option("--memory-limit", sim_mem_gb,
                  "refuse to start above this estimate, GB (default: 75 % of RAM)");
  sim->add_option("--stl-step", sim_stl_step,
                  "grid step of surface.stl, mm (default: the dexel spacing, coarser when the "
                  "mesh would pass 4 million triangles)");

  // forces
  JobArgs fo_args;
  std::string fo_gcode, fo_json, fo_csv, fo_cycles;
  std::optional<double> fo_from, fo_to;
  bool fo_fast = false;
  auto* fo = app.add_subcommand(
      "forces", "cutting forces F_x, F_y, F_z, torque and power over time ([material] model)");
  add_job_args(fo, fo_args);
  fo->add_option("--gcode", fo_gcode, "this NC program instead of the job's path");
  fo->add_flag("--fast", fo_fast,
               "chips from the analytic engagement (axial discs, helix lag) instead of the "
               "dexel simulation");
  fo->add_option("--from", fo_from, "window start, s of programmed time (default 0)");
  fo->add_option("--to", fo_to, "window end, s (default: the path's end)");
  fo->add_option("--cycles", fo_cycles, "A:B: trochoid cycles A (inclusive) to B (exclusive)");
  fo->add_option("--csv", fo_csv, "write the series as CSV (- for stdout)");
  fo->add_option("--json", fo_json, "write the summary as JSON (- for stdout)");

  // calibrate
  JobArgs ca_args;
  std::string ca_measured, ca_mean, ca_model, ca_fit, ca_columns, ca_json, ca_write, ca_gcode,
      ca_cycles, ca_time_unit = "s", ca_force_unit = "N";
  std::optional<double> ca_from, ca_to, ca_cutoff, ca_shift;
  bool ca_fast = false;
  auto* ca = app.add_subcommand(
      "calibrate", "fit force coefficients (and runout) to measured forces; write [material]");
  add_job_args(ca, ca_args);
  ca->add_option("--measured", ca_measured, "measured forces, CSV (t, F_x, F_y, F_z)");
  ca->add_option("--mean-forces", ca_mean,
                 "mean forces of full-immersion slot tests, CSV (feed_per_tooth_mm, f_x_n, "
                 "f_y_n, f_z_n): linear model by regression");
  ca->add_option("--model", ca_model,
                 "bergmann, kienzle or linear (default: the job's, else bergmann)");
  ca->add_option("--fit", ca_fit,
                 "parameters, comma separated: k_c,k_n,m,m_n,k_a,m_a | k_tc,k_rc,k_ac,k_te,"
                 "k_re,k_ae, runout_radial,runout_phase,runout_axial (default: the model's)");
  ca->add_flag("--fast", ca_fast, "the fast chip source, as for forces");
  ca->add_option("--columns", ca_columns,
                 "time,fx,fy,fz column names (default t_s,f_x_n,f_y_n,f_z_n)");
  ca->add_option("--time-unit", ca_time_unit, "s or ms (default s)");
  ca->add_option("--force-unit", ca_force_unit, "N or kN (default N)");
  ca->add_option("--cutoff", ca_cutoff,
                 "low-pass of both signals, Hz (default 10 x tooth "
                 "passing, below 0.4 x the coarser rate)");
  ca->add_option("--max-shift", ca_shift, "alignment search +-, s (default half a revolution)");
  ca->add_option("--gcode", ca_gcode, "this NC program instead of the job's path");
  ca->add_option("--from", ca_from, "model window start, s (default: the measurement's start)");
  ca->add_option("--to", ca_to, "model window end, s (default: the measurement's end)");
  ca->add_option("--cycles", ca_cycles, "A:B: the model window as trochoid cycles");
  ca->add_option("--json", ca_json, "write the result as JSON (- for stdout)");
  ca->add_option("--write", ca_write, "write the [material] block to this file");

  // materials
  bool ma_json = false;
  auto* ma = app.add_subcommand("materials", "list the materials library (data/materials)");
  ma->add_flag("--json", ma_json, "as JSON");

  // insert (synthetic insert meshes) and topography (the sampled edge grid)
  JobArgs in_args;
  std::string in_out;
  tmill::SyntheticInsert in_spec;
  std::optional<double> in_edge;
  auto* ins = app.add_subcommand(
      "insert",
      "write a synthetic insert mesh (new, or worn with a flank wear land) for the "
      "job's tool, in the tooth frame");
  add_job_args(ins, in_args);
  ins->add_option("-o,--output", in_out, "mesh file: .stl, .ply or .obj")->required();
  ins->add_option("--vb", in_spec.vb_mm, "flank wear land width VB, mm (default 0: new)");
  ins->add_option("--edge-radius", in_edge, "hone radius, mm (default [tool] edge_radius or 0.02)");
  ins->add_option("--rake", in_spec.rake_deg, "rake angle, degrees (default 0)");
  ins->add_option("--clearance", in_spec.clearance_deg, "clearance angle, degrees (default 7)");
  ins->add_option("--sections", in_spec.sections, "profile sections along the edge (default 200)");
  ins->add_option("--points", in_spec.profile_points, "points per profile (default 120)");

  JobArgs tg_args;
  std::string tg_mesh, tg_csv, tg_json;
  auto* tg = app.add_subcommand(
      "topography",
      "sample a digitised (or synthetic) edge into the structured grid and report it");
  add_job_args(tg, tg_args);
  tg->add_option("--mesh", tg_mesh, "this mesh instead of the job's [topography] state");
  tg->add_option("--csv", tg_csv, "write the grid as CSV (- for stdout)");
  tg->add_option("--json", tg_json, "write the summary as JSON (- for stdout)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }

  if (*plan) {
    const tmill::Job job = load(plan_args);
    const tmill::PlannedPath planned = tmill::plan_path(job);
    tmill::GcodeWriteOptions opt;
    opt.dialect = plan_dialect.empty() ? job.machine.dialect : tmill::parse_dialect(plan_dialect);
    opt.arc_output = plan_chords ? tmill::ArcOutput::chords : job.machine.arc_output;
    opt.tolerance_mm = plan_tol > 0 ? plan_tol : job.machine.arc_tolerance_mm;
    if (plan->count("--tolerance") && !(plan_tol > 0)) {
      throw tmill::InputError(fmt::format("--tolerance must be > 0 mm, got {}", plan_tol));
    }
    const std::string code = tmill::write_gcode(job, planned.path, opt);
    emit(plan_out, code);
    if (plan_out != "-") {
      fmt::print(
          "{}: {} {} cycles, path {:.3f} mm, time {:.3f} s ({:.3f} s with acceleration), {} lines "
          "-> {}\n",
          plan_args.job_file, tmill::to_string(job.path.type), planned.info.cycles,
          planned.path.length_mm(), planned.path.duration_s(),
          tmill::estimate_time_s(planned.path, job.machine),
          std::count(code.begin(), code.end(), '\n'), plan_out);
    }
    return 0;
  }

  if (*pathc) {
    const tmill::Job job = load(path_args);
    const tmill::ToolPath tp = job_path(job, path_gcode);
    tmill::PathSamples s;
    if (path_dt) {
      s = tmill::sample_by_time(tp, *path_dt);
    } else if (path_ds) {
      s = tmill::sample_by_length(tp, *path_ds);
    } else {
      s = tmill::sample_by_spindle_angle(tp, path_spr.value_or(36), job.cutting.spindle_speed_rpm);
    }
    const tmill::ToothTracks tr = tmill::tooth_tracks(s, job.tool, job.cutting);
    if (!path_csv.empty()) emit(path_csv, samples_csv(s, tr));
    if (path_csv != "-") {
      fmt::print(
          "{} samples over {:.3f} s, path {:.3f} mm, {} teeth, f_z = {:.4g} mm, n = {:.0f} rpm{}\n",
          s.size(), tp.duration_s(), tp.length_mm(), tr.teeth, job.cutting.feed_per_tooth_mm,
          job.cutting.spindle_speed_rpm, path_csv.empty() ? "" : " -> " + path_csv);
    }
    return 0;
  }

  if (*an) {
    const tmill::Job job = load(an_args);
    const tmill::ToolPath tp = job_path(job, an_gcode);
    tmill::ProcessMetrics m = tmill::analyze_process(job, tp);
    tmill::fill_predicted_force(job, tp, m);
    if (!an_json.empty()) emit(an_json, tmill::metrics_json(job, m));
    if (!an_csv.empty()) emit(an_csv, tmill::series_csv(job, m.series));
    if (an_json != "-" && an_csv != "-") {
      fmt::print("{}: {}{}\n", an_args.job_file, tmill::to_string(job.path.type),
                 an_gcode.empty() ? "" : " (from " + an_gcode + ")");
      fmt::print("  machining time       {:.3f} s ({:.3f} s with acceleration), path {:.2f} mm\n",
                 m.machining_time_s, m.machining_time_accel_s, m.path_length_mm);
      fmt::print("  {} cycle        {:.4f} s, {:.3f} mm; cutting {:.4f} s, cooling {:.4f} s\n",
                 m.periodic ? "steady" : "window", m.cycle_time_s, m.path_length_per_cycle_mm,
                 m.cutting_time_s, m.cooling_time_s);
      fmt::print("  MRR                  {:.1f} mm^3/min steady, {:.1f} mm^3/min whole slot\n",
                 m.mrr_mm3_per_min, m.mrr_total_mm3_per_min);
      fmt::print(
          "  h_max                {:.5f} mm at {:.4f} s after cutting starts (f_z {:.4g} mm; "
          "{:.5f} mm over the program)\n",
          m.h_max_mm, m.t_h_max_s, m.feed_per_tooth_mm, m.h_max_slot_mm);
      fmt::print("  engagement max       {:.2f} deg\n", m.engagement_angle_max_deg);
      fmt::print(
          "  wall waviness        left {:.5f} mm, right {:.5f} mm (path); "
          "left {:.5f} mm, right {:.5f} mm (tooth)\n",
          m.walls_path.left.waviness_mm, m.walls_path.right.waviness_mm,
          m.walls_tooth.left.waviness_mm, m.walls_tooth.right.waviness_mm);
      if (m.force_max_predicted_n) {
        fmt::print("  F_R,max predicted    {:.1f} N ([material] {})\n", *m.force_max_predicted_n,
                   tmill::to_string(*job.material.model));
      }
      if (m.performance_index) fmt::print("  performance index    {:.6g}\n", *m.performance_index);
    }
    return 0;
  }

  if (*cmp) {
    std::vector<tmill::Override> base;
    for (const auto& s : cmp_args.sets) base.push_back(tmill::parse_override(s));
    std::vector<tmill::Vary> varies;
    for (const auto& v : cmp_vary) varies.push_back(tmill::parse_vary(v));
    (void)tmill::load_job(cmp_args.job_file, base);  // a bad base job is bad input (exit 2)
    const auto points = tmill::run_study(cmp_args.job_file, base, varies, cmp_threads);
    if (!cmp_json.empty()) emit(cmp_json, tmill::study_json(varies, points));
    if (!cmp_csv.empty()) emit(cmp_csv, tmill::study_csv(varies, points));
    if (cmp_json != "-" && cmp_csv != "-") fmt::print("{}", tmill::study_table(varies, points));
    const bool all_failed =
        std::none_of(points.begin(), points.end(), [](const tmill::StudyPoint& p) { return p.ok; });
    if (all_failed) {
      throw tmill::InputError("compare: every point of the grid failed (see the table)");
    }
    return 0;
  }

  if (mech->parsed() || rec->parsed()) {
    const bool is_mech = mech->parsed();
    const tmill::Job job = load(is_mech ? mech_args : rec_args);
    tmill::MechanismSettings st = tmill::mechanism_settings(job);
    const std::string& model = is_mech ? mech_model : rec_model;
    if (!model.empty()) st.model = tmill::parse_chip_model(model);
    const std::optional<double>& wear = is_mech ? mech_wear : rec_wear;
    if (wear) {
      if (!(*wear >= 0))
        throw tmill::InputError(fmt::format("--wear must be >= 0 mm, got {}", *wear));
      st.flank_wear_mm = *wear;
    }
    const bool use_wear = st.flank_wear_mm > 0;
    auto zones_json = [](const tmill::ZoneSummary& z) {
      nlohmann::json j = {{"CZI", z.share[0]}, {"CZII", z.share[1]}, {"CZIII", z.share[2]}};
      return j;
    };
    auto times_json = [](const tmill::ZoneSummary& z) {
      nlohmann::json j = nlohmann::json::object();
      const char* names[3] = {"CZI", "CZII", "CZIII"};
      for (int q = 0; q < 3; ++q) {
        j[names[q]] = {{"start_s", z.start_s[q]}, {"end_s", z.end_s[q]}};
      }
      return j;
    };
    if (is_mech) {
      const tmill::MechanismCurve c = tmill::mechanism_curve(job, st, use_wear);
      const tmill::ZoneSummary z = tmill::summarize_zones(c, st, use_wear);
      if (!mech_json.empty()) {
        nlohmann::json j = {{"model", tmill::to_string(st.model)},
                            {"edge_radius_mm", job.tool.edge_radius_mm},
                            {"flank_wear_mm", st.flank_wear_mm},
                            {"cycle_time_s", c.cycle_time_s},
                            {"cutting_time_s", z.cutting_time_s},
                            {"cutting_start_s", z.cutting_start_s},
                            {"h_max_mm", z.h_max_mm},
                            {"h_m_mm", z.h_m_mm},
                            {"transition_s", z.transition_s},
                            {"zone_share", zones_json(z)},
                            {"zone_times_s", times_json(z)},
                            {"thresholds_pct",
                             {{"czi_max", st.thresholds.czi_max_pct},
                              {"czii_max", st.thresholds.czii_max_pct},
                              {"transition", st.thresholds.transition_pct}}},
                            {"theta_deg", nlohmann::json::array()},
                            {"h_mm", c.h_mm},
                            {"k_re_pct", use_wear ? c.k_re_wear_pct : c.k_re_pct},
                            {"zone", c.zone}};
        for (const double th : c.theta_rad) j["theta_deg"].push_back(tmill::rad_to_deg(th));
        emit(mech_json, j.dump(2) + "\n");
      }
      if (!mech_csv.empty()) {
        std::string out =
            "theta_deg,t_s,h_mm,psi_deg,teeth_in_contact,gamma_k_deg,kappa_deg,k_re_pct,"
            "k_re_wear_pct,zone\n";
        for (std::size_t i = 0; i < c.theta_rad.size(); ++i) {
          fmt::format_to(std::back_inserter(out),
                         "{:.4f},{:.6f},{:.7f},{:.4f},{:.4f},{:.4f},{:.4f},{:.3f},{:.3f},{}\n",
                         tmill::rad_to_deg(c.theta_rad[i]), c.t_s[i], c.h_mm[i],
                         tmill::rad_to_deg(c.psi_rad[i]), c.teeth_in_contact[i],
                         tmill::rad_to_deg(c.gamma_k_rad[i]), tmill::rad_to_deg(c.kappa_rad[i]),
                         c.k_re_pct[i], c.k_re_wear_pct[i], c.zone[i]);
        }
        emit(mech_csv, out);
      }
      if (mech_json != "-" && mech_csv != "-") {
        fmt::print("{}: {} model, r_e {:g} mm{}\n", mech_args.job_file, tmill::to_string(st.model),
                   job.tool.edge_radius_mm,
                   use_wear ? fmt::format(", flank wear {:g} mm", st.flank_wear_mm) : "");
        fmt::print("  cycle {:.4f} s, cutting {:.4f} s, h_max {:.5f} mm, h_m {}\n", c.cycle_time_s,
                   z.cutting_time_s, z.h_max_mm,
                   st.friction_angle_deg > 0 ? fmt::format("{:.5f} mm", z.h_m_mm)
                                             : std::string("n/a (no [material] friction_angle)"));
        const char* names[3] = {"CZI  ", "CZII ", "CZIII"};
        for (int q = 0; q < 3; ++q) {
          fmt::print("  {} {:5.1f} % of the cutting part", names[q], 100 * z.share[q]);
          if (z.start_s[q] >= 0)
            fmt::print(", {:.4f} to {:.4f} s after cutting starts", z.start_s[q], z.end_s[q]);
          fmt::print("\n");
        }
      }
      return 0;
    }
    if (rec_share) st.share = *rec_share;
    const tmill::Recommendation r = tmill::recommend(job, st, use_wear, rec_feed);
    if (!rec_json.empty()) {
      nlohmann::json j = {{"found", r.found},
                          {rec_feed ? "min_feed_per_tooth_mm" : "min_step_mm",
                           r.found ? nlohmann::json(r.value) : nlohmann::json(nullptr)},
                          {"share", st.share},
                          {"model", tmill::to_string(st.model)},
                          {"flank_wear_mm", st.flank_wear_mm},
                          {"zone_share", zones_json(r.zones)},
                          {"explanation", r.explanation}};
      emit(rec_json, j.dump(2) + "\n");
    }
    if (rec_json != "-") fmt::print("{}\n", r.explanation);
    return 0;
  }

  if (sim->parsed()) {
    const tmill::Job job = load(sim_args);
    const tmill::ToolPath path = job_path(job, sim_gcode);
    const auto [from, to] = parse_window(path, sim_cycles, sim_from, sim_to);
    // Refuse before starting when the estimate passes the limit.
    const tmill::MemoryEstimate est = tmill::estimate_simulation_memory(job, path, from, to);
    const double need =
        est.boards_bytes + est.records_bytes + (sim_out.empty() ? 0.0 : est.dense_map_bytes);
    const double ram =
        static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
    if (sim_stl_step && !(*sim_stl_step > 0)) {  // bad input refused before the run
      throw tmill::InputError(fmt::format("--stl-step must be > 0 mm, got {}", *sim_stl_step));
    }
    if (sim_mem_gb && !(*sim_mem_gb > 0)) {
      throw tmill::InputError(fmt::format("--memory-limit must be > 0 GB, got {}", *sim_mem_gb));
    }
    const double limit = sim_mem_gb ? *sim_mem_gb * 1e9 : 0.75 * ram;
    if (need > limit) {
      throw tmill::InputError(fmt::format(
          "simulate: estimated memory {:.2f} GB (boards {:.2f}, records {:.2f}, HDF5 map {:.2f}) "
          "exceeds the limit of {:.2f} GB ({}); coarsen [simulation] resolution (now {} mm), "
          "shorten the window (--cycles, --from/--to) or raise --memory-limit",
          need / 1e9, est.boards_bytes / 1e9, est.records_bytes / 1e9,
          sim_out.empty() ? 0.0 : est.dense_map_bytes / 1e9, limit / 1e9,
          sim_mem_gb ? "--memory-limit" : "75 % of RAM", job.simulation.resolution_mm));
    }
    // Ctrl-C stops after the current step; what was computed is written, marked incomplete.
    const InterruptGuard guard;
    tmill::SimControl control;
    control.cancel = &InterruptGuard::flag();
    const bool tty = isatty(STDERR_FILENO) != 0;
    const auto t_start = std::chrono::steady_clock::now();
    if (tty) control.progress = progress_bar(t_start);
    const tmill::JobSimulation js = tmill::simulate_job(job, path, from, to, control);
    if (tty) fmt::print(stderr, "\r{}\r", std::string(60, ' '));
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    const tmill::SimResult& r = js.result;
    double h_max = 0;
    for (const auto& st : r.steps) h_max = std::max(h_max, st.h_max_mm);
    nlohmann::json j = {
        {"removed_volume_mm3", r.removed_mm3},
        {"removed_volume_by_board_mm3", r.removed_by_board_mm3},
        {"h_max_mm", h_max},
        {"steps", r.steps.size()},
        {"dexel_updates", r.dexel_updates},
        {"wall_time_s", wall},
        {"pre_roll_wall_s", js.pre_roll_wall_s},
        {"window_wall_s", js.window_wall_s},
        {"dexel_updates_per_s",
         js.window_wall_s > 0 ? static_cast<double>(r.dexel_updates) / js.window_wall_s : 0.0},
        {"from_s", from},
        {"to_s", to},
        {"resolution_mm", job.simulation.resolution_mm},
        {"steps_per_rev", job.simulation.steps_per_rev},
        {"memory_mb", static_cast<double>(js.memory_bytes) / 1048576.0},
        {"memory_estimate_mb", need / 1048576.0},
        {"complete", r.complete}};
    if (!sim_out.empty()) {
      const std::filesystem::path dir(sim_out);
      std::filesystem::create_directories(dir);
      const tmill::SimTool tool = tmill::sim_tool(job, job.simulation);
      emit((dir / "series.csv").string(), tmill::sim_series_csv(r, tool.tooth_angle_rad.size()));
      tmill::write_chip_map_h5(dir / "chips.h5", tmill::chip_map_data(r, tool, job.simulation));
      emit((dir / "walls.csv").string(),
           tmill::wall_profiles_csv(tmill::wall_profiles(*js.work, 0.0)));
      emit((dir / "floor.csv").string(),
           tmill::floor_profiles_csv(tmill::floor_profiles(*js.work)));
      double step = sim_stl_step.value_or(0.0);
      if (!sim_stl_step) {
        const auto& zb = js.work->boards[2];
        const double cells = static_cast<double>(zb.count_u()) * static_cast<double>(zb.count_v());
        step = zb.spacing() * std::max(1.0, std::ceil(std::sqrt(2.0 * cells / 4e6)));
      }
      emit((dir / "surface.stl").string(),
           tmill::height_field_stl(tmill::surface_height_field(*js.work, step)));
    }
    if (!sim_json.empty()) emit(sim_json, j.dump(2) + "\n");
    if (sim_json != "-") {
      fmt::print(
          "{}: {:.4f} to {:.4f} s, {} steps at {} per rev, {:g} mm dexels: removed "
          "{:.4f} mm^3, h_max {:.5f} mm, {} dexel updates, {:.2f} s, {:.1f} MB{}\n",
          sim_args.job_file, from, to, r.steps.size(), job.simulation.steps_per_rev,
          job.simulation.resolution_mm, r.removed_mm3, h_max, r.dexel_updates, wall,
          static_cast<double>(js.memory_bytes) / 1048576.0,
          r.complete ? "" : " (interrupted: incomplete)");
    }
    return r.complete ? 0 : 130;
  }

  if (fo->parsed()) {
    const tmill::Job job = load(fo_args);
    const tmill::ToolPath path = job_path(job, fo_gcode);
    const auto [from, to] = parse_window(path, fo_cycles, fo_from, fo_to);
    if (!job.material.model) {
      throw tmill::InputError(fmt::format(
          "{}: no [material] force model; give [material] model and coefficients or name (see "
          "`trochomill materials`)",
          fo_args.job_file));
    }
    if (!fo_fast) {
      const tmill::MemoryEstimate est = tmill::estimate_simulation_memory(job, path, from, to);
      const double ram = static_cast<double>(sysconf(_SC_PHYS_PAGES)) *
                         static_cast<double>(sysconf(_SC_PAGE_SIZE));
      if (est.boards_bytes + est.records_bytes > 0.75 * ram) {
        throw tmill::InputError(fmt::format(
            "forces: the simulation would need {:.2f} GB (75 % of RAM is {:.2f} GB); shorten "
            "the window (--cycles, --from/--to), coarsen [simulation] resolution or use --fast",
            (est.boards_bytes + est.records_bytes) / 1e9, 0.75 * ram / 1e9));
      }
    }
    // In simulation mode Ctrl-C stops after the current step; the forces of what was
    // simulated are written, marked incomplete (exit 130), as simulate does.
    const InterruptGuard guard;
    tmill::SimControl control;
    control.cancel = &InterruptGuard::flag();
    const bool tty = !fo_fast && isatty(STDERR_FILENO) != 0;
    if (tty) control.progress = progress_bar(std::chrono::steady_clock::now());
    const tmill::JobForces jf = tmill::job_forces(job, path, from, to, fo_fast, control);
    if (tty) fmt::print(stderr, "\r{}\r", std::string(60, ' '));
    if (!fo_csv.empty()) emit(fo_csv, tmill::force_series_csv(jf.series));
    if (!fo_json.empty()) emit(fo_json, tmill::force_summary_json(job, jf, from, to));
    if (fo_json != "-" && fo_csv != "-")
      fmt::print("{}", tmill::force_summary_text(job, jf, from, to));
    return jf.chips.complete ? 0 : 130;
  }

  if (ca->parsed()) {
    const tmill::Job job = load(ca_args);
    if (ca_measured.empty() == ca_mean.empty()) {
      throw tmill::InputError("calibrate: give --measured FILE or --mean-forces FILE (one)");
    }
    if (!ca_mean.empty()) {
      const tmill::MeanForceFit f = tmill::fit_mean_forces(job, tmill::read_mean_forces(ca_mean));
      const std::string block = tmill::mean_force_toml(f);
      if (!ca_write.empty()) tmill::write_file_atomic(ca_write, block);
      if (!ca_json.empty()) emit(ca_json, tmill::mean_force_json(f));
      if (ca_json != "-") fmt::print("{}", block);
      return 0;
    }
    tmill::ForceCsvFormat fmt_in;
    if (!ca_columns.empty()) {
      const std::vector<std::string> cols = split_list(ca_columns);
      if (cols.size() != 4 ||
          std::any_of(cols.begin(), cols.end(), [](const std::string& c) { return c.empty(); })) {
        throw tmill::InputError(
            fmt::format("--columns '{}': expected four names time,fx,fy,fz", ca_columns));
      }
      fmt_in.time = cols[0], fmt_in.fx = cols[1], fmt_in.fy = cols[2], fmt_in.fz = cols[3];
    }
    if (ca_time_unit == "ms") {
      fmt_in.time_to_s = 1e-3;
    } else if (ca_time_unit != "s") {
      throw tmill::InputError(fmt::format("--time-unit '{}': s or ms", ca_time_unit));
    }
    if (ca_force_unit == "kN") {
      fmt_in.force_to_n = 1e3;
    } else if (ca_force_unit != "N") {
      throw tmill::InputError(fmt::format("--force-unit '{}': N or kN", ca_force_unit));
    }
    tmill::CalibrationOptions o;
    if (!ca_model.empty()) {
      if (ca_model == "bergmann")
        o.model = tmill::ForceModel::bergmann;
      else if (ca_model == "kienzle")
        o.model = tmill::ForceModel::kienzle;
      else if (ca_model == "linear")
        o.model = tmill::ForceModel::linear;
      else
        throw tmill::InputError(fmt::format("--model '{}': bergmann, kienzle or linear", ca_model));
    } else if (job.material.model) {
      o.model = *job.material.model;
    }
    if (!ca_fit.empty()) {
      for (const auto& p : split_list(ca_fit)) {
        if (p.empty()) throw tmill::InputError(fmt::format("--fit '{}': an empty name", ca_fit));
        o.fit.push_back(p);
      }
    }
    o.fast = ca_fast;
    if (ca_cutoff) o.cutoff_hz = *ca_cutoff;
    if (ca_shift) o.max_shift_s = *ca_shift;
    const tmill::MeasuredForces meas = tmill::read_measured_forces(ca_measured, fmt_in);
    const tmill::ToolPath path = job_path(job, ca_gcode);
    if (ca_cycles.empty() && !ca_from && !ca_to) {
      o.from_s = std::max(0.0, meas.t_s.front());
      o.to_s = std::min(path.duration_s(), meas.t_s.back());
    } else {
      std::tie(o.from_s, o.to_s) = parse_window(path, ca_cycles, ca_from, ca_to);
    }
    const tmill::CalibrationResult r = tmill::calibrate_forces(job, path, meas, o);
    const std::string block = tmill::material_toml(r);
    if (!ca_write.empty()) tmill::write_file_atomic(ca_write, block);
    if (!ca_json.empty()) emit(ca_json, tmill::calibration_json(r));
    if (ca_json != "-") fmt::print("{}", tmill::calibration_text(ca_measured, r));
    return 0;
  }

  if (ma->parsed()) {
    const std::vector<tmill::Material> lib = tmill::material_library();
    fmt::print("{}", ma_json ? tmill::materials_json(lib)
                             : tmill::materials_text(lib, tmill::materials_dir().string()));
    return 0;
  }

  if (ins->parsed()) {
    const tmill::Job job = load(in_args);
    const tmill::SimTool tool = tmill::sim_tool(job, job.simulation);
    tmill::SyntheticInsert ins_spec = in_spec;
    ins_spec.edge_radius_mm =
        in_edge.value_or(job.tool.edge_radius_mm > 0 ? job.tool.edge_radius_mm : 0.02);
    ins_spec.face_mm = std::max(
        ins_spec.face_mm, 2 * job.topography.band_mm + ins_spec.vb_mm + ins_spec.edge_radius_mm);
    const tmill::Mesh mesh = tmill::synthetic_insert(tool, ins_spec);
    tmill::write_mesh(in_out, mesh);
    fmt::print(
        "{}: {} vertices, {} triangles (VB {:g} mm, hone {:g} mm, rake {:g}, clearance {:g} "
        "degrees)\n",
        in_out, mesh.vertices.size(), mesh.triangles.size(), ins_spec.vb_mm,
        ins_spec.edge_radius_mm, ins_spec.rake_deg, ins_spec.clearance_deg);
    return 0;
  }

  if (tg->parsed()) {
    const tmill::Job job = load(tg_args);
    const tmill::SimTool tool = tmill::sim_tool(job, job.simulation);
    tmill::EdgeTopography info;
    tmill::EdgeGrid grid;
    std::string source;
    if (!tg_mesh.empty()) {
      grid =
          tmill::sample_topography(tmill::read_mesh(tg_mesh), tool, job.topography.band_mm, &info);
      source = tg_mesh;
    } else if (job.topography.states() > 0) {
      grid = tmill::job_edge_grid(job, tool, &info);
      source = fmt::format("[topography] state {}", job.topography.state);
    } else {
      throw tmill::InputError(fmt::format(
          "{}: no [topography] (files or synthetic_vb) and no --mesh", tg_args.job_file));
    }
    if (!tg_csv.empty()) emit(tg_csv, tmill::edge_grid_csv(grid));
    if (!tg_json.empty()) emit(tg_json, tmill::topography_json(grid, info));
    if (tg_json != "-" && tg_csv != "-")
      fmt::print("{}", tmill::topography_text(source, grid, info));
    return 0;
  }

  if (mon->parsed()) {
    std::optional<tmill::Job> job;
    if (!mon_job.empty()) {
      std::vector<tmill::Override> ov;
      for (const auto& o : mon_sets) ov.push_back(tmill::parse_override(o));
      job = tmill::load_job(mon_job, ov);
    } else if (!mon_sets.empty()) {
      throw tmill::InputError("--set needs --job");
    }
    tmill::MonitorSettings m = job ? job->monitor : tmill::MonitorSettings{};
    if (!mon_low.empty()) std::tie(m.low_min_hz, m.low_max_hz) = parse_band("--low", mon_low);
    if (!mon_high.empty()) std::tie(m.high_min_hz, m.high_max_hz) = parse_band("--high", mon_high);
    if (mon_order) {
      if (*mon_order < 1 || *mon_order > 12)
        throw tmill::InputError(fmt::format("--order must be 1..12, got {}", *mon_order));
      m.order = *mon_order;
    }
    if (mon_window) m.window_s = *mon_window;
    if (mon_stream) {
      if (!mon_sig.file.empty() && mon_sig.file != "-")
        throw tmill::InputError("--stream reads stdin: give no SIGNAL (or -)");
      if (!mon_sig.rate) throw tmill::InputError("--stream needs --rate (Hz)");
      const std::string fmt_name = mon_sig.format == "auto" ? "f32" : mon_sig.format;
      const tmill::SampleFormat f = tmill::parse_sample_format(fmt_name);
      if (f != tmill::SampleFormat::f32 && f != tmill::SampleFormat::s16 &&
          f != tmill::SampleFormat::csv) {
        throw tmill::InputError("--stream reads --format f32, s16 or csv");
      }
      tmill::LiveMonitor live(*mon_sig.rate, m, job ? &*job : nullptr, mon_start);
      auto out = [](const tmill::LiveWindow& w) {
        const std::string line = tmill::live_json_line(w);
        std::fwrite(line.data(), 1, line.size(), stdout);
        std::fflush(stdout);  // one line per window, as soon as it completes
      };
      std::vector<double> x;
      if (f == tmill::SampleFormat::csv) {
        std::string line;
        long line_no = 0;
        while (std::getline(std::cin, line)) {
          ++line_no;
          if (line.empty() || line[0] == '#') continue;
          char* end = nullptr;
          const double v = std::strtod(line.c_str(), &end);
          if (end == line.c_str() || !std::isfinite(v)) {
            throw tmill::InputError(
                fmt::format("stdin:{}: '{}' is not a finite number", line_no, line));
          }
          live.push(&v, 1, out);
        }
        return 0;
      }
      const std::size_t w = f == tmill::SampleFormat::f32 ? 4 : 2;
      std::vector<unsigned char> buf(w * 4096);
      std::size_t have = 0;
      long long total = 0;
      for (;;) {
        const std::size_t got = std::fread(buf.data() + have, 1, buf.size() - have, stdin);
        have += got;
        const std::size_t n = have / w;
        x.resize(n);
        tmill::decode_raw(buf.data(), n, f, x.data());
        for (std::size_t i = 0; i < n; ++i) {
          if (!std::isfinite(x[i])) {
            throw tmill::InputError(
                fmt::format("stdin: sample {} is not finite", total + static_cast<long long>(i)));
          }
        }
        live.push(x.data(), n, out);
        total += static_cast<long long>(n);
        std::copy(buf.begin() + static_cast<std::ptrdiff_t>(n * w),
                  buf.begin() + static_cast<std::ptrdiff_t>(have), buf.begin());
        have -= n * w;
        if (got == 0) break;
      }
      if (have != 0) {
        throw tmill::InputError(
            fmt::format("stdin: {} trailing byte(s) after {} samples: truncated", have, total));
      }
      return 0;
    }
    if (mon_sig.file.empty()) throw tmill::InputError("monitor: give a SIGNAL file (or --stream)");
    const tmill::Signal sig = read_signal_args(mon_sig);
    tmill::validate(m, sig.rate_hz);
    const tmill::MonitorReport r = tmill::analyze_signal(sig, m, job ? &*job : nullptr, mon_start);
    if (!mon_json.empty()) emit(mon_json, tmill::monitor_json(r, mon_sig.file, sig, m));
    if (!mon_csv.empty()) emit(mon_csv, tmill::monitor_csv(r));
    if (mon_json != "-" && mon_csv != "-")
      fmt::print("{}", tmill::monitor_table(r, mon_sig.file, sig));
    return 0;
  }

  if (synth->parsed()) {
    const tmill::Job job = load(syn_args);
    const tmill::Signal sig = tmill::synth_signal(job, job.monitor, syn);
    emit_wav(syn_out, sig);
    fmt::print("{}: {:.3f} s at {:g} Hz, {} cycles from the program start at {:g} s -> {}\n",
               syn_args.job_file, sig.duration_s(), sig.rate_hz, syn.cycles, syn.lead_s, syn_out);
    return 0;
  }

  if (spec->parsed()) {
    const tmill::Signal sig = read_signal_args(spec_sig);
    const tmill::Spectrum sp = tmill::welch(sig, spec_nfft);
    if (!spec_csv.empty()) emit(spec_csv, tmill::spectrum_csv(sp));
    if (!spec_sg.empty()) emit(spec_sg, tmill::spectrogram_csv(tmill::spectrogram(sig, spec_nfft)));
    if (spec_csv != "-") {
      // The strongest peaks (local maxima of the PSD), and the power in 1 kHz bands.
      std::vector<std::size_t> peaks;
      for (std::size_t k = 1; k + 1 < sp.psd.size(); ++k) {
        if (sp.psd[k] > sp.psd[k - 1] && sp.psd[k] >= sp.psd[k + 1]) peaks.push_back(k);
      }
      std::sort(peaks.begin(), peaks.end(),
                [&](std::size_t a, std::size_t b) { return sp.psd[a] > sp.psd[b]; });
      fmt::print("{}: {:.3f} s at {:g} Hz, Welch nfft {} ({:.2f} Hz bins)\n", spec_sig.file,
                 sig.duration_s(), sig.rate_hz, spec_nfft, sig.rate_hz / spec_nfft);
      for (std::size_t i = 0; i < std::min<std::size_t>(8, peaks.size()); ++i) {
        fmt::print("  peak {:10.1f} Hz  {:.3e} /Hz\n", sp.f_hz[peaks[i]], sp.psd[peaks[i]]);
      }
    }
    return 0;
  }

  if (*cg) {
    tmill::GcodeReadOptions ro;
    ro.rapid_rate_mm_per_min = cg_rapid;
    const tmill::GcodeProgram prog = tmill::read_gcode_file(cg_file, ro);
    tmill::Machine m;
    m.rapid_rate_mm_per_min = cg_rapid;
    m.max_acceleration_mm_per_s2 = cg_accel;
    const Box b = bounding_box(prog.path);
    const double t_acc = tmill::estimate_time_s(prog.path, m);
    nlohmann::json j = {
        {"file", cg_file},
        {"lines", prog.info.lines},
        {"motion_blocks", prog.info.motion_blocks},
        {"segments", prog.path.segments().size()},
        {"path_length_mm", prog.path.length_mm()},
        {"feed_length_mm", prog.path.feed_length_mm()},
        {"time_s", prog.path.duration_s()},
        {"time_with_acceleration_s", t_acc},
        {"bbox_min_mm", {b.lo.x(), b.lo.y(), b.lo.z()}},
        {"bbox_max_mm", {b.hi.x(), b.hi.y(), b.hi.z()}},
        {"feed_min_mm_per_min", prog.info.min_feed_mm_per_min},
        {"feed_max_mm_per_min", prog.info.max_feed_mm_per_min},
        {"spindle_max_rpm", prog.info.max_spindle_rpm},
    };
    if (!cg_json.empty()) emit(cg_json, j.dump(2) + "\n");
    if (cg_json != "-") {
      fmt::print("{}: {} lines, {} segments\n", cg_file, prog.info.lines,
                 prog.path.segments().size());
      fmt::print("  path length   {:.4f} mm ({:.4f} mm at feed)\n", prog.path.length_mm(),
                 prog.path.feed_length_mm());
      fmt::print("  time          {:.4f} s at programmed feed", prog.path.duration_s());
      if (cg_accel > 0) fmt::print(", {:.4f} s with {:g} mm/s^2", t_acc, cg_accel);
      fmt::print(
          "\n  bounding box  x [{:.4f}, {:.4f}]  y [{:.4f}, {:.4f}]  z [{:.4f}, {:.4f}] mm\n",
          b.lo.x(), b.hi.x(), b.lo.y(), b.hi.y(), b.lo.z(), b.hi.z());
      fmt::print("  feed          {:g} to {:g} mm/min, spindle up to {:g} rpm\n",
                 prog.info.min_feed_mm_per_min, prog.info.max_feed_mm_per_min,
                 prog.info.max_spindle_rpm);
    }
    return 0;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const tmill::InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
}
