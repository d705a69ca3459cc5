// The `trochomill` Python module: exceptions, the job, paths and NC programs. The models are
// bound in bind_<domain>.cpp, one file per domain as the CLI's command groups. Units as at
// the CLI: mm, s, mm/min, rpm, degrees, N; every array and key carries its unit in its name.
#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string_view>

#include "common.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report/path.hpp"
#include "trochomill/version.hpp"

namespace trochomill::python {

namespace {

PyJob job_from_document(JobDocument doc, std::vector<Override> overrides) {
  PyJob j;
  j.doc = std::make_shared<const JobDocument>(std::move(doc));
  j.overrides = std::move(overrides);
  j.job = j.doc->build(j.overrides);
  attach_rest_stock(j.job);  // [pocket] rest_of: the earlier program's stock
  return j;
}

// The job's keys (the document after the overrides) as nested dicts, read by tomllib.
py::dict job_dict(const Job& job) {
  const py::module_ tomllib = py::module_::import("tomllib");
  py::dict out;
  for (const auto& [key, value] : job.flat_keys) {
    const auto dot = key.find('.');
    const py::str section(key.substr(0, dot));
    if (!out.contains(section)) out[section] = py::dict();
    py::dict table = out[section];
    table[py::str(key.substr(dot + 1))] = tomllib.attr("loads")("v = " + value)["v"];
  }
  return out;
}

// Columns of a sampled path: t_s, s_mm, x_mm, y_mm, z_mm, feed_mm_per_min, rapid.
py::dict sample_dict(const ToolPath& path, PathSamples&& s) {
  std::vector<double> feed(s.size());
  py::array_t<bool> rapid(static_cast<py::ssize_t>(s.size()));
  auto r = rapid.mutable_unchecked<1>();
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Segment& seg = path.segments()[s.segment[i]];
    feed[i] = seg.speed_mm_per_min();
    r(static_cast<py::ssize_t>(i)) = seg.motion() == Motion::rapid;
  }
  py::dict d;
  d["t_s"] = to_array(std::move(s.t_s));
  d["s_mm"] = to_array(std::move(s.s_mm));
  d["x_mm"] = to_array(std::move(s.x_mm));
  d["y_mm"] = to_array(std::move(s.y_mm));
  d["z_mm"] = to_array(std::move(s.z_mm));
  d["feed_mm_per_min"] = to_array(std::move(feed));
  d["rapid"] = rapid;
  return d;
}

PyPath read_program(const py::object& program, const py::object& job_obj) {
  std::shared_ptr<const PyJob> job;
  if (!job_obj.is_none()) job = std::make_shared<const PyJob>(job_obj.cast<const PyJob&>());
  GcodeReadOptions ro = job ? gcode_options(job->job.machine).read : GcodeReadOptions{};
  ro.max_path_bytes = kPathShareOfMemory * default_memory_limit_bytes();  // an endless loop
  if (job) ro.missing_tool_diameter_mm = job->job.tool.diameter_mm;       // as the CLI's --gcode
  PyPath p;
  GcodeProgram prog;
  const bool is_file = py::isinstance(program, py::module_::import("os").attr("PathLike")) ||
                       (py::isinstance<py::str>(program) &&
                        program.cast<std::string>().find('\n') == std::string::npos);
  if (is_file) {
    const std::filesystem::path file = program.cast<std::filesystem::path>();
    p.source = file.string();
    prog = read_gcode_file(file, ro);
  } else {
    p.source = "<text>";
    prog = read_gcode(program.cast<std::string>(), p.source, ro);
  }
  p.warnings = prog.info.warnings;
  if (job) {
    for (std::string& w : header_mismatches(job->job, prog, p.source)) {
      p.warnings.push_back(std::move(w));
    }
    p.path = to_slot_frame(prog.path, slot_placement(job->job));
  } else {
    p.path = std::move(prog.path);
  }
  p.cycles = static_cast<int>(p.path.cycles().size());
  p.job = std::move(job);
  p.lines.segment_lines = std::move(prog.segment_lines);
  p.lines.source_files = std::move(prog.source_files);
  p.lines.info.extra_axes = prog.info.extra_axes;
  p.lines.info.extra_min = prog.info.extra_min;
  p.lines.info.extra_max = prog.info.extra_max;
  p.lines.info.extra_only_time_s = prog.info.extra_only_time_s;
  return p;
}

}  // namespace

void bind_job(py::module_& m) {
  py::class_<PyJob, std::shared_ptr<PyJob>>(
      m, "Job", R"(A job: tool, slot, path, cutting conditions, machine, material and settings.

Read from a TOML job file (the CLI's), TOML text or a dict of sections; validated as the CLI
validates it (trochomill.InputError names the key or file:line:column and what is allowed).
Units: mm, s, mm/min, rpm, degrees (`trochomill keys` lists every key with its unit).)")
      .def_static(
          "from_toml",
          [](const std::filesystem::path& file, const py::object& set) {
            return job_from_document(JobDocument::load(file), overrides_of(set));
          },
          py::arg("path"), py::arg("set") = py::none(),
          "Reads a job file; `set`: {\"section.key\": value} overrides, as the CLI's --set.")
      .def_static(
          "from_text",
          [](const std::string& text, const std::string& name, const py::object& set) {
            return job_from_document(JobDocument::parse(text, name), overrides_of(set));
          },
          py::arg("text"), py::arg("name") = "<text>", py::arg("set") = py::none(),
          "Parses a job from TOML text; `name` names it in messages.")
      .def_static(
          "from_dict",
          [](const py::dict& d, const std::string& name) {
            std::vector<Override> keys;
            for (const auto& [section, table] : d) {
              const std::string s = py::str(section).cast<std::string>();
              if (!py::isinstance<py::dict>(table)) {
                throw InputError(fmt::format(
                    "'{}': a section is a dict of its keys, e.g. {{\"tool\": {{\"diameter\": "
                    "10.0}}}}",
                    s));
              }
              for (const auto& [k, v] : table.cast<py::dict>()) {
                keys.push_back(make_override(s + "." + py::str(k).cast<std::string>(), v));
              }
            }
            // The keys are overrides of an empty document: a message names the key.
            return job_from_document(JobDocument::parse("", name), std::move(keys));
          },
          py::arg("sections"), py::arg("name") = "<dict>",
          "A job from {section: {key: value}}, e.g. {\"tool\": {\"diameter\": 10.0, ...}, ...}.")
      .def(
          "set",
          [](PyJob& j, const std::string& key, const py::object& value) {
            std::vector<Override> all = j.overrides;
            all.push_back(make_override(key, value));
            Job built = j.doc->build(all);  // validated before anything changes
            attach_rest_stock(built);
            j.overrides = std::move(all);
            j.job = std::move(built);
          },
          py::arg("key"), py::arg("value"),
          "Sets \"section.key\" to value (bool, int, float, str or a list), as --set does; the "
          "job is validated again and stays as it was when the value is refused.")
      .def(
          "copy", [](const PyJob& j) { return std::make_shared<PyJob>(j); },
          "An independent copy (set on it leaves this job as it is).")
      .def(
          "to_dict", [](const PyJob& j) { return job_dict(j.job); },
          "The job's keys as given (file and overrides): {section: {key: value}}.")
      .def(
          "to_toml", [](const PyJob& j) { return to_toml(j.job); },
          "The job's keys as a TOML document (Job.from_text reads it back).")
      .def_property_readonly(
          "source", [](const PyJob& j) { return j.doc->source(); }, "where the job came from")
      .def_property_readonly(
          "feed_rate_mm_per_min", [](const PyJob& j) { return feed_rate_mm_per_min(j.job); },
          "the tool-centre feed f_r (mm/min)")
      .def_property_readonly(
          "spindle_speed_rpm", [](const PyJob& j) { return spindle_speed_rpm(j.job); },
          "the spindle speed n (rpm)")
      .def_property_readonly(
          "tooth_period_s",
          [](const PyJob& j) { return tooth_period_s(j.job.tool, j.job.cutting); },
          "the time between two teeth (s)")
      .def("__repr__", [](const PyJob& j) {
        return fmt::format("<trochomill.Job {} ({} overrides)>", j.doc->source(),
                           j.overrides.size());
      });
}

void bind_path(py::module_& m) {
  py::class_<PyPath, std::shared_ptr<PyPath>>(m, "Path", R"(A tool-centre path (mm, s).

Planned from a job (plan) in the slot's frame, or read from an NC program (read_gcode): in
the job's slot frame when read with a job, else in the program's work frame.)")
      .def_property_readonly(
          "length_mm", [](const PyPath& p) { return p.path.length_mm(); }, "path length (mm)")
      .def_property_readonly(
          "feed_length_mm", [](const PyPath& p) { return p.path.feed_length_mm(); },
          "length of the feed moves (mm)")
      .def_property_readonly(
          "duration_s", [](const PyPath& p) { return p.path.duration_s(); },
          "time at the programmed feeds and rapid rate, without acceleration limits (s)")
      .def(
          "time_s",
          [](const PyPath& p) {
            if (!p.job) return p.path.duration_s();
            return estimate_time_s(p.path, p.job->job.machine);
          },
          "time with the job's [machine] acceleration limit (s); duration_s without a job")
      .def_property_readonly(
          "segments", [](const PyPath& p) { return p.path.segments().size(); },
          "number of path segments (lines and curves)")
      .def_property_readonly(
          "cycles", [](const PyPath& p) { return p.cycles; },
          "trochoid cycles (passes of the linear family) marked on the path")
      .def_property_readonly(
          "cycle_start_s",
          [](const PyPath& p) {
            std::vector<double> t;
            for (const CycleMark& c : p.path.cycles()) t.push_back(c.start_time_s);
            return to_array(std::move(t));
          },
          "programmed time where each cycle starts (s)")
      .def_property_readonly(
          "extra_axes",
          [](const PyPath& p) {
            // As check-gcode's JSON: each axis besides X Y Z the program moves, its range.
            py::dict d;
            for (const char c : p.lines.info.extra_axes) {
              const auto k = static_cast<std::size_t>(std::string_view("ABCUVW").find(c));
              const std::string unit = k < 3 ? "deg" : "mm";
              py::dict r;
              r[py::str("min_" + unit)] = p.lines.info.extra_min[k];
              r[py::str("max_" + unit)] = p.lines.info.extra_max[k];
              d[py::str(std::string(1, c))] = r;
            }
            return d;
          },
          "the axes besides X Y Z a program read from G-code moves, each one's range in the "
          "work frame: {'A': {'min_deg': .., 'max_deg': ..}, 'U': {'min_mm': .., 'max_mm': ..}}; "
          "the path holds the X Y Z motion only")
      .def_property_readonly(
          "extra_axes_only_time_s", [](const PyPath& p) { return p.lines.info.extra_only_time_s; },
          "time of the feed moves that move only axes besides X Y Z (s: A B C at F degrees/min, "
          "U V W at F mm/min), which duration_s leaves out")
      .def_readonly("warnings", &PyPath::warnings,
                    "what the reader assumed or found (a program read from G-code)")
      .def_readonly("source", &PyPath::source, "\"plan\" or the program's name")
      .def_property_readonly(
          "job", [](const PyPath& p) -> py::object { return p.job ? py::cast(p.job) : py::none(); },
          "the job the path belongs to (None for a program read without one)")
      .def(
          "sample",
          [](const PyPath& p, std::optional<double> dt_s, std::optional<double> ds_mm) {
            if (dt_s && ds_mm) throw InputError("sample: give dt_s or ds_mm, not both");
            const double step = dt_s ? *dt_s : ds_mm ? *ds_mm : 0.0;
            if (!dt_s && !ds_mm) throw InputError("sample: give dt_s (s) or ds_mm (mm)");
            if (!(step > 0 && step <= 1e3)) {
              throw InputError(fmt::format("sample: {} must be in (0, 1000], got {}",
                                           dt_s ? "dt_s" : "ds_mm", step));
            }
            const double count = (dt_s ? p.path.duration_s() : p.path.length_mm()) / step;
            check_memory("sample", (count + 2) * 8.0 * 14.0, std::nullopt, "take a coarser step");
            PathSamples s = dt_s ? sample_by_time(p.path, *dt_s) : sample_by_length(p.path, *ds_mm);
            return sample_dict(p.path, std::move(s));
          },
          py::arg("dt_s") = py::none(), py::arg("ds_mm") = py::none(),
          "Samples every dt_s seconds of programmed time, or every ds_mm of length (the last "
          "sample at the end): a dict of float64 arrays t_s, s_mm, x_mm, y_mm, z_mm, "
          "feed_mm_per_min and the bool array rapid.")
      .def(
          "gcode",
          [](const PyPath& p, const std::optional<std::string>& dialect) {
            if (!p.job) {
              throw InputError(
                  "gcode: this program was read without a job; a job gives the "
                  "tool, machine and placement the program needs");
            }
            // A planned pocket's program was written once already (for its line count).
            if (!dialect && !p.gcode.empty()) return p.gcode;
            const Job job =
                dialect ? p.job->with({Override{"machine.dialect", *dialect, ""}}) : p.job->job;
            return write_gcode(job, p.path, gcode_options(job.machine).write);
          },
          py::arg("dialect") = py::none(),
          "The program as G-code text (linuxcnc, fanuc, sinumerik, grbl, haas or mach3; default "
          "the job's "
          "machine.dialect), as `trochomill plan` writes it.")
      .def_property_readonly(
          "pocket",
          [](const PyPath& p) -> py::object {
            return p.pocket_json.empty() ? py::none() : from_json(p.pocket_json);
          },
          "A planned pocket's figures and the engagement kernel's proof on its program, as "
          "`trochomill plan --json` writes them (a dict: target_engagement_deg, "
          "clearing_max_engagement_deg, clearing_max_at_mm, replans, proven, plans, "
          "open_mm2_by_level, unreachable, machining_time_s, program_lines, ...); None for a slot "
          "or a program read.")
      .def("__repr__", [](const PyPath& p) {
        return fmt::format("<trochomill.Path {}: {} segments, {:.3f} mm, {:.3f} s>", p.source,
                           p.path.segments().size(), p.path.length_mm(), p.path.duration_s());
      });

  m.def(
      "plan",
      [](const PyJob& job, std::optional<double> memory_limit_gb) {
        if (job.job.pocket.defined()) {
          check_memory("plan", estimate_pocket_memory(job.job), memory_limit_gb,
                       fmt::format("a pocket of layer '{}' cleared at {:g} degrees with a {:g} "
                                   "mm tool: raise pocket.max_engagement or pocket.max_step_down, "
                                   "use a larger tool or split the pocket",
                                   job.job.pocket.boundary, job.job.pocket.max_engagement_deg,
                                   job.job.tool.diameter_mm));
        } else {
          check_memory("plan", estimate_plan_memory(job.job), memory_limit_gb,
                       fmt::format("a {:g} mm slot at a {:g} mm step: raise path.step or plan a "
                                   "shorter slot",
                                   job.job.slot.length_mm, job.job.path.step_mm));
        }
        PyPath p;
        if (job.job.pocket.defined()) {
          PlannedPocket pp = plan_pocket(job.job);  // proven by the kernel
          const std::string code =
              write_gcode(job.job, pp.path, gcode_options(job.job.machine).write);
          p.pocket_json =
              pocket_json(pp.info, pp.proof, pp.path, job.job.machine,
                          static_cast<std::size_t>(std::count(code.begin(), code.end(), '\n')));
          p.cycles = pp.info.passes;
          p.path = std::move(pp.path);
          p.gcode = code;
        } else {
          PlannedPath planned = plan_job(job.job);
          p.path = std::move(planned.path);
          p.cycles = planned.info.cycles;
        }
        p.source = "plan";
        p.job = std::make_shared<const PyJob>(job);
        return p;
      },
      py::arg("job"), py::arg("memory_limit_gb") = py::none(),
      "Plans the job's program: a slot's (entry, the path family's cycles, exit) in the slot "
      "frame, or with [pocket] the pocket's clearing (the drawing's frame), in mm: a Path. "
      "memory_limit_gb: refuse above this estimate (default 75 % of RAM).");

  m.def("read_gcode", &read_program, py::arg("program"), py::arg("job") = py::none(),
        "Reads an NC program as LinuxCNC (or the job's machine.dialect) runs it: `program` a "
        "file name (str without a newline, or os.PathLike) or the program's text. With a job, "
        "the path is put in the job's slot frame (its placement) and the job's [machine] "
        "(dialect, offsets, tool table, rapid rate) reads it, its tool standing in for a tool "
        "the table lacks; `warnings` lists what was assumed and where the program's header "
        "disagrees with the job.");
}

}  // namespace trochomill::python

PYBIND11_MODULE(_trochomill, m) {
  namespace tp = trochomill::python;
  namespace py = pybind11;
  m.doc() =
      "trochomill: trochoidal milling paths, engagement, mechanism, simulation, forces "
      "and monitoring (units: mm, s, mm/min, rpm, degrees, N)";
  m.attr("__version__") = trochomill::kVersion;

  static py::exception<trochomill::Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<trochomill::InputError> input_error(m, "InputError", PyExc_ValueError);
  input_error.doc() =
      "Bad input: the message names the key or file:line:column and what is allowed; "
      "`problems` lists each problem.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const trochomill::InputError& e) {
      py::object instance = py::reinterpret_borrow<py::object>(input_error.ptr())(e.what());
      instance.attr("problems") = py::cast(e.problems());
      PyErr_SetObject(input_error.ptr(), instance.ptr());
    } catch (const trochomill::IoError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const trochomill::Interrupted& e) {
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    } catch (const trochomill::Error& e) {
      error(e.what());
    }
  });
  tp::bind_job(m);
  tp::bind_path(m);
  // The models, in the order the module has always registered them (its attributes' order).
  tp::bind_analysis(m);      // analyze
  tp::bind_study(m);         // compare
  tp::bind_mechanism(m);     // mechanism, recommend
  tp::bind_simulation(m);    // simulate, forces, calibrate
  tp::bind_report(m);        // report
  tp::bind_monitor(m);       // monitor
  tp::bind_bench(m);         // _analyze_seconds, _monitor_filters
  tp::bind_texture(m);       // texture_profile, texture_areal
  tp::bind_spectrum(m);      // spectrum
  tp::bind_tool(m);          // keys, materials
  tp::bind_feed(m);          // schedule_feed, optimize_feed
  tp::bind_synth_signal(m);  // synth_signal
  tp::bind_geometry(m);      // read_drawing
}
