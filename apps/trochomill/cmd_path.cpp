// plan, path and check-gcode: the slot program of a job, its sampled trajectories, and the
// report of any NC program.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/analysis.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report.hpp"
#include "trochomill/units.hpp"

namespace trochomill::cli {

namespace {

// "G54" .. "G59.3" -> 1 .. 9.
int work_system_number(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  static const std::array<std::string, 9> kNames{"G54", "G55",   "G56",   "G57",  "G58",
                                                 "G59", "G59.1", "G59.2", "G59.3"};
  const auto it = std::find(kNames.begin(), kNames.end(), s);
  if (it == kNames.end()) {
    throw InputError(
        fmt::format("work system '{}': one of G54 G55 G56 G57 G58 G59 G59.1 G59.2 "
                    "G59.3",
                    s));
  }
  return static_cast<int>(it - kNames.begin()) + 1;
}

// "G55=100,0,-20" -> (2, (100, 0, -20)).
std::pair<int, Vec3> parse_offset(const std::string& s) {
  const auto eq = s.find('=');
  auto bad = [&] {
    return InputError(
        fmt::format("--offset '{}': write SYSTEM=X,Y,Z in mm, e.g. G55=100,0,-20", s));
  };
  if (eq == std::string::npos) throw bad();
  const int n = work_system_number(s.substr(0, eq));
  Vec3 v;
  std::size_t pos = eq + 1;
  for (int k = 0; k < 3; ++k) {
    const std::size_t end = k < 2 ? s.find(',', pos) : s.size();
    if (end == std::string::npos) throw bad();
    const std::string part = s.substr(pos, end - pos);
    char* stop = nullptr;
    v[k] = std::strtod(part.c_str(), &stop);
    if (part.empty() || *stop != '\0' || !std::isfinite(v[k]) || std::abs(v[k]) > 1e6) throw bad();
    pos = end + 1;
  }
  return {n, v};
}

// One move of --trace (append_fixed: fmt's "{:.9f}", a tenth of its time; a trace of a
// long program writes millions of numbers).
std::string trace_line(const GcodeMove& m) {
  const char* kind = m.kind == GcodeMove::Kind::rapid  ? "G0"
                     : m.kind == GcodeMove::Kind::feed ? "G1"
                     : m.sweep_rad > 0                 ? "G3"
                                                       : "G2";
  std::string s;
  s.reserve(m.kind == GcodeMove::Kind::arc ? 192 : 112);
  if (!m.path_started) s += "; ";
  s += kind;
  const auto num = [&](const char* before, double v) {
    s += before;
    append_fixed(s, v, 9);
  };
  num(" X", m.end_mm.x());
  num(" Y", m.end_mm.y());
  num(" Z", m.end_mm.z());
  if (m.kind == GcodeMove::Kind::arc) {
    num(" C", m.centre_mm.x());
    num(",", m.centre_mm.y());
    num(",", m.centre_mm.z());
    s += fmt::format(" A{:.0f},{:.0f},{:.0f}", m.axis.x(), m.axis.y(), m.axis.z());
    num(" T", m.sweep_rad * 180.0 / kPi);
  }
  if (m.extra_axes) {
    const auto& e = m.extra_end;
    num(" ABC:", e[0]);
    num(",", e[1]);
    num(",", e[2]);
    num(" UVW:", e[3]);
    num(",", e[4]);
    num(",", e[5]);
  }
  num(" F", m.feed_mm_per_min);
  s += " G";
  s += m.plane == 17 ? "17" : m.plane == 18 ? "18" : "19";
  s += ' ';
  s += m.file;
  s += ':';
  s += std::to_string(m.line);
  return s;
}

}  // namespace

void register_path_commands(CLI::App& app, int& exit_code) {
  // plan
  {
    struct Args {
      JobArgs job;
      std::string out, json;
      std::optional<double> memory_gb;
      bool schedule = false;
      bool strict = false;
      FeedTargetArgs targets;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("plan", "write the slot program of a job as G-code");
    add_job_args(cmd, a->job);
    add_stock_mesh_alias(cmd, a->job);
    add_memory_limit(cmd, a->memory_gb);
    cmd->add_option("-o,--output", a->out, "output G-code file (- for stdout)")->required();
    cmd->add_option("--json", a->json,
                    "a pocket job: write the plan's figures and the kernel's proof as JSON (- "
                    "for stdout)");
    add_key_alias(cmd, a->job, "--dialect", "machine.dialect",
                  "linuxcnc | fanuc | sinumerik | grbl | haas | mach3");
    add_key_alias(cmd, a->job, "--tolerance", "machine.arc_tolerance",
                  "max deviation of fitted arcs/chords, mm");
    add_key_flag(cmd, a->job, "--chords", "machine.arc_output", "chords",
                 "write curves as G1 chords instead of biarcs");
    cmd->add_flag("--feed-schedule", a->schedule,
                  "variable feed: each piece of the path fed so that its largest chip is the "
                  "target (--h-max), within --min-feed and --max-feed");
    add_feed_target_args(cmd, a->targets);
    cmd->add_flag("--strict", a->strict,
                  "a pocket job: write nothing and exit 1 where the kernel's proof finds the "
                  "clearing's engagement above the target + 2 % on every plan tried");
    cmd->final_callback([a, cmd, &exit_code] {
      check_outputs({&a->out, &a->json}, {&a->job.file});
      if (a->out == "-" && a->json == "-") {
        throw InputError("-o - and --json -: both to stdout; give one of them a file");
      }
      if (!a->json.empty() && a->json != "-" && a->json == a->out) {
        throw InputError(fmt::format("-o and --json name the same file '{}': give two", a->out));
      }
      const Job job = a->job.load();
      // Nor may an output be the stock mesh the job reads.
      for (const std::string* o : {&a->out, &a->json}) {
        std::error_code ec, ec2;
        if (!job.stock_mesh_path.empty() && !o->empty() && *o != "-" &&
            std::filesystem::weakly_canonical(*o, ec) ==
                std::filesystem::weakly_canonical(job.stock_mesh_path, ec2) &&
            !ec && !ec2) {
          throw InputError(fmt::format(
              "{} '{}' is the job's stock mesh ([stock] mesh): writing it would overwrite it",
              o == &a->out ? "-o" : "--json", *o));
        }
      }
      if (!a->json.empty() && !job.pocket.defined()) {
        throw InputError(fmt::format(
            "--json: the plan's JSON is a pocket's ({} has no [pocket]); a slot's figures are "
            "analyze --json's",
            a->job.file));
      }
      if (a->strict && !job.pocket.defined()) {
        throw InputError(fmt::format(
            "--strict: the proof it asks for is a pocket's ({} has no [pocket]); a slot's "
            "program is planned to its cycle, not proven",
            a->job.file));
      }
      if (job.pocket.defined()) {
        check_memory(
            "plan", estimate_pocket_memory(job), a->memory_gb,
            fmt::format(
                "a pocket of layer '{}' cleared at {:g} degrees with a {:g} mm "
                "tool: raise [pocket] max_engagement or max_step_down, use a larger tool or "
                "split the pocket",
                job.pocket.boundary, job.pocket.max_engagement_deg, job.tool.diameter_mm));
      } else {
        check_memory("plan", estimate_plan_memory(job), a->memory_gb,
                     fmt::format("a {:g} mm slot at a {:g} mm step: raise [path] step or plan a "
                                 "shorter slot",
                                 job.slot.length_mm, job.path.step_mm));
      }
      for (const char* o : kFeedTargetFlags) {
        if (cmd->count(o) > 0 && !a->schedule) {
          throw InputError(fmt::format("{} is an option of --feed-schedule", o));
        }
      }
      PlannedPath planned;
      std::optional<PocketInfo> pocket;
      std::optional<PocketProof> proof;  // --json
      if (job.pocket.defined()) {
        PlannedPocket pp = plan_pocket(job);  // proven by the kernel
        std::FILE* to = a->out == "-" || a->json == "-" ? stderr : stdout;
        fmt::print(to, "{}", pocket_summary(pp.info, pp.proof));
        if (a->strict && !pp.info.proven) {
          std::error_code ec;
          const bool stale = a->out != "-" && std::filesystem::exists(a->out, ec);
          throw Error(fmt::format(
              "plan --strict: the kernel finds {:.4g} degrees in the clearing for a target of "
              "{:g} (above it + {:g} %) on every plan tried: nothing was written{}",
              pp.proof.clearing_max_engagement_deg, pp.info.target_engagement_deg,
              100 * kProofTolerance,
              stale ? fmt::format(" ('{}' is an earlier program, not this job's)", a->out)
                    : std::string()));
        }
        if (!a->json.empty()) proof = pp.proof;
        planned.path = std::move(pp.path);
        planned.info.cycles = pp.info.passes;
        planned.info.levels = pp.info.levels;
        pocket = std::move(pp.info);
      } else {
        planned = plan_job(job);
      }
      std::optional<FeedSchedule> fs;
      if (a->schedule) {
        const GuardedRun run(true);
        fs = schedule_feed(job, planned.path, a->targets.resolve(job), run.hooks());
        run.done();
        run.finish("interrupted: nothing was written");
        planned.path = fs->path;
      }
      const std::string code = write_gcode(job, planned.path, gcode_options(job.machine).write);
      const auto lines = static_cast<std::size_t>(std::count(code.begin(), code.end(), '\n'));
      emit(a->out, code);
      if (!a->json.empty())
        emit(a->json, pocket_json(*pocket, *proof, planned.path, job.machine, lines));
      if (fs) {
        fmt::print(stderr,
                   "feed schedule: h_max {:.5f} -> {:.5f} mm (target {:g}), time {:.3f} -> "
                   "{:.3f} s ({:+.1f} %), {} pieces\n",
                   fs->h_max_before_mm, fs->h_max_after_mm,
                   a->targets.h_max_mm.value_or(job.cutting.feed_per_tooth_mm), fs->time_before_s,
                   fs->time_after_s, 100.0 * (fs->time_after_s / fs->time_before_s - 1.0),
                   fs->pieces);
        if (const auto& m = fs->missed) {
          const double target = a->targets.h_max_mm.value_or(job.cutting.feed_per_tooth_mm);
          const Vec3 at = slot_placement(job).to_work(m->at_mm);
          fmt::print(stderr,
                     "warning: feed schedule: the target {:g} mm is missed by more than 3 % on {} "
                     "pieces; the worst, h_max {:.5f} mm ({:+.1f} %), at X{:.3f} Y{:.3f} Z{:.3f} "
                     "({:.3f} s into the program) runs at {:g} mm/min, held by {}\n",
                     target, m->pieces, m->h_max_mm, 100.0 * (m->h_max_mm / target - 1.0), at.x(),
                     at.y(), at.z(), m->at_s, m->feed_mm_per_min, describe(m->limit));
        }
      }
      // stdout may hold the program or the JSON: the summary then goes to stderr.
      std::FILE* said = a->out == "-" || a->json == "-" ? stderr : stdout;
      if (pocket) {
        fmt::print(said,
                   "{}: pocket, path {:.3f} mm, time {:.3f} s ({:.3f} s with acceleration), {} "
                   "lines -> {}\n",
                   a->job.file, planned.path.length_mm(), planned.path.duration_s(),
                   estimate_time_s(planned.path, job.machine), lines, a->out);
      } else {
        fmt::print(
            said,
            "{}: {} {} cycles, path {:.3f} mm, time {:.3f} s ({:.3f} s with acceleration), {} "
            "lines -> {}\n",
            a->job.file, to_string(job.path.type), planned.info.cycles, planned.path.length_mm(),
            planned.path.duration_s(), estimate_time_s(planned.path, job.machine), lines, a->out);
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
      const ToolPath tp = job_path(job, a->gcode, a->memory_gb);
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
      GcodeReadOptions read;
      std::string dialect, tool_table, work_system = "G54";
      std::vector<std::string> offsets, includes;
      std::vector<double> g28, g30;
      bool trace = false;
      JobArgs job;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "check-gcode",
        "interpret an NC program (RS274/NGC as LinuxCNC runs it) and report its length, time, "
        "bounding box; --trace prints every move");
    cmd->add_option("FILE", a->file, "G-code file")->required();
    cmd->add_option("--rapid-rate", a->machine.rapid_rate_mm_per_min, "rapid traverse rate, mm/min")
        ->capture_default_str()
        ->check(finite_above(0, 1e6));
    cmd->add_option("--max-acceleration", a->machine.max_acceleration_mm_per_s2,
                    "path acceleration limit for the time estimate, mm/s^2")
        ->check(finite_in(0, 1e15));
    cmd->add_option("--dialect", a->dialect,
                    "language: linuxcnc (default), fanuc, sinumerik, grbl, haas or mach3")
        ->check(CLI::IsMember({"linuxcnc", "fanuc", "sinumerik", "grbl", "haas", "mach3"}));
    cmd->add_option("-I,--include", a->includes,
                    "folder searched for o<name> call's name.ngc (repeatable; the program's own "
                    "folder is searched first)")
        ->check(CLI::ExistingDirectory);
    cmd->add_option("--tool-table", a->tool_table,
                    "LinuxCNC tool table (T1 P1 Z<length> D<diameter>, mm) for G43's lengths")
        ->check(CLI::ExistingFile);
    cmd->add_option("--work-system", a->work_system,
                    "work coordinate system the program starts in and the moves are given in")
        ->capture_default_str()
        ->check(
            CLI::IsMember({"G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"}));
    cmd->add_option("--offset", a->offsets,
                    "a work offset in machine coordinates, SYSTEM=X,Y,Z mm (e.g. G55=100,0,-20; "
                    "repeatable)");
    cmd->add_option("--g28", a->g28, "G28 position in machine coordinates, X,Y,Z mm")
        ->delimiter(',')
        ->expected(3)
        ->check(finite_in(-1e6, 1e6));
    cmd->add_option("--g30", a->g30, "G30 position in machine coordinates, X,Y,Z mm")
        ->delimiter(',')
        ->expected(3)
        ->check(finite_in(-1e6, 1e6));
    cmd->add_option("--peck-clearance", a->read.peck_clearance_mm,
                    "G73/G83 retract between pecks, mm")
        ->capture_default_str()
        ->check(finite_in(0, 1e3));
    cmd->add_option("--max-blocks", a->read.max_blocks,
                    "blocks interpreted before the reader stops (a loop without end)")
        ->capture_default_str()
        ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40));
    cmd->add_flag("--trace", a->trace,
                  "print every move as the interpreter resolved it (one line each: kind, end "
                  "X Y Z mm, arc centre and turn, feed mm/min, plane, file:line)");
    cmd->add_option("--json", a->json, "write the report as JSON (- for stdout)");
    cmd->add_option("--job", a->job.file,
                    "read the machine from this job's [machine] (dialect, work offset and "
                    "origins, G28/G30 positions, tool table, rapid rate, acceleration); the "
                    "flags above override it")
        ->check(CLI::ExistingFile);
    cmd->add_option("--set", a->job.sets, "override a key of --job's job: section.key=value")
        ->take_all();
    cmd->final_callback([a, cmd, &exit_code] {
      check_outputs({&a->json}, {&a->file});
      if (!a->job.sets.empty() && a->job.file.empty()) {
        throw InputError("check-gcode: --set needs --job (the job whose keys it overrides)");
      }
      GcodeReadOptions ro = a->read;
      ro.rapid_rate_mm_per_min = a->machine.rapid_rate_mm_per_min;
      ro.work_system = work_system_number(a->work_system);
      if (!a->job.file.empty()) {
        // The job's machine first; each flag given on the command line over it.
        const Job job = a->job.load();
        GcodeReadOptions from_job = gcode_options(job.machine).read;
        from_job.include_dirs = ro.include_dirs;
        from_job.peck_clearance_mm = ro.peck_clearance_mm;
        from_job.max_blocks = ro.max_blocks;
        if (cmd->count("--rapid-rate") > 0) {
          from_job.rapid_rate_mm_per_min = ro.rapid_rate_mm_per_min;
        } else {
          a->machine.rapid_rate_mm_per_min = job.machine.rapid_rate_mm_per_min;
        }
        if (cmd->count("--max-acceleration") == 0) {
          a->machine.max_acceleration_mm_per_s2 = job.machine.max_acceleration_mm_per_s2;
        }
        if (cmd->count("--work-system") > 0) from_job.work_system = ro.work_system;
        ro = from_job;
      }
      if (!a->dialect.empty()) ro.dialect = trochomill::parse_dialect(a->dialect);
      for (const auto& d : a->includes) ro.include_dirs.emplace_back(d);
      if (!a->tool_table.empty()) ro.tool_table = a->tool_table;
      for (const std::string& o : a->offsets) {
        const auto [n, v] = parse_offset(o);
        ro.work_offsets_mm[static_cast<std::size_t>(n - 1)] = v;
      }
      if (!a->g28.empty()) ro.g28_position_mm = Vec3(a->g28[0], a->g28[1], a->g28[2]);
      if (!a->g30.empty()) ro.g30_position_mm = Vec3(a->g30[0], a->g30[1], a->g30[2]);
      std::function<void()> trace_flush;
      if (a->trace) {
        // Lines gathered in a buffer and written 64 kB at a time; a failed write (a full
        // disk, a closed pipe) stops the reading with the reason.
        auto buffer = std::make_shared<std::string>();
        const auto write_out = [buffer] {
          if (std::fwrite(buffer->data(), 1, buffer->size(), stdout) != buffer->size()) {
            throw IoError(fmt::format("--trace: writing to standard output failed: {}",
                                      std::strerror(errno)));
          }
          buffer->clear();
        };
        ro.trace = [buffer, write_out](const GcodeMove& m) {
          *buffer += trace_line(m);
          *buffer += '\n';
          if (buffer->size() >= (1U << 16)) write_out();
        };
        trace_flush = [write_out] {
          write_out();
          if (std::fflush(stdout) != 0) {
            throw IoError(fmt::format("--trace: writing to standard output failed: {}",
                                      std::strerror(errno)));
          }
        };
      }
      // The time with acceleration needs the whole path; without it the program is read as a
      // stream (its summary only).
      ro.keep_path = a->machine.max_acceleration_mm_per_s2 > 0;
      GcodeProgram prog;
      try {
        prog = read_gcode_file(a->file, ro);
      } catch (const IoError&) {
        throw;
      } catch (...) {
        if (trace_flush) trace_flush();  // the moves before the error, as they were read
        throw;
      }
      if (trace_flush) trace_flush();
      for (const std::string& w : prog.info.warnings) fmt::print(stderr, "warning: {}\n", w);
      if (a->trace) {
        exit_code = 0;
        return;
      }
      const double t_acc =
          ro.keep_path ? estimate_time_s(prog.path, a->machine) : prog.summary.duration_s;
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
