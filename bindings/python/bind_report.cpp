// report: the HTML report of `trochomill report`, one self-contained page.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "trochomill/app.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report/html.hpp"
#include "trochomill/signal.hpp"

namespace trochomill::python {

void bind_report(py::module_& m) {
  m.def(
      "report",
      [](const py::object& job_or_path, const py::object& output,
         const std::vector<std::string>& parts, const py::object& cycles,
         std::optional<double> from_s, std::optional<double> to_s, const py::object& signal,
         std::optional<double> rate_hz, std::optional<double> start_s,
         const py::object& measured_t_s, const py::object& measured_f_n, const py::object& vary,
         const py::object& progress, std::optional<double> memory_limit_gb) {
        const PyJob& pj = job_of(job_or_path, "report");
        const bool program = py::isinstance<PyPath>(job_or_path);
        ReportRequest r;
        r.job_file = pj.job.source;
        r.job_text = to_toml(pj.job);
        r.overrides = pj.overrides;
        r.with = parts;
        r.command = "trochomill.report (Python)";
        if (program) r.gcode_file = job_or_path.cast<const PyPath&>().source;
        ToolPath path = path_of(job_or_path);
        if (!cycles.is_none() || from_s || to_s) r.window_s = window_of(path, cycles, from_s, to_s);
        if (!signal.is_none()) {
          if (!rate_hz || !(std::isfinite(*rate_hz) && *rate_hz > 0 && *rate_hz <= 1e7)) {
            throw InputError("report: signal needs rate_hz, a sample rate in (0, 1e7] Hz");
          }
          Signal sig;
          sig.rate_hz = *rate_hz;
          sig.samples = finite_vector(
              signal.cast<py::array_t<double, py::array::c_style | py::array::forcecast>>(),
              "signal");
          r.signal = std::move(sig);
          r.signal_file = "signal (Python array)";
        }
        r.signal_start_s = start_s;
        if (measured_t_s.is_none() != measured_f_n.is_none()) {
          throw InputError("report: give measured_t_s and measured_f_n together");
        }
        if (!measured_t_s.is_none()) {
          using A = py::array_t<double, py::array::c_style | py::array::forcecast>;
          r.measured = measured_of(measured_t_s.cast<A>(), measured_f_n.cast<A>());
          r.measured_file = "measured (Python arrays)";
        }
        if (!vary.is_none()) {
          for (const auto& [k, values] : vary.cast<py::dict>()) {
            Vary v;
            v.key = k.cast<std::string>();
            for (const py::handle value : values.cast<py::list>()) {
              v.values.push_back(toml_value(value, v.key));
            }
            r.varies.push_back(std::move(v));
          }
          r.document = pj.doc.get();
        }
        r.check_simulation_memory = [memory_limit_gb, &pj](double need) {
          check_memory("report", need, memory_limit_gb,
                       fmt::format("coarsen simulation.resolution (now {} mm) or shorten the "
                                   "window (cycles, from_s/to_s)",
                                   pj.job.simulation.resolution_mm));
        };
        check_report_request(pj.job, r);
        check_memory("report", estimate_analysis_memory(pj.job, path), memory_limit_gb,
                     "lower analysis.steps_per_tooth or report on a shorter program");
        std::string html = run_released(
            [&](const RunHooks& h) {
              const ReportData d = report_data(pj.job, std::move(path), std::move(r), h);
              return report_html(d, h);
            },
            progress);
        if (!output.is_none()) {
          write_file_atomic(py::str(output).cast<std::string>(), html);
        }
        return html;
      },
      py::arg("job"), py::arg("output") = py::none(), py::kw_only(),
      py::arg("parts") = std::vector<std::string>{}, py::arg("cycles") = py::none(),
      py::arg("from_s") = py::none(), py::arg("to_s") = py::none(), py::arg("signal") = py::none(),
      py::arg("rate_hz") = py::none(), py::arg("start_s") = py::none(),
      py::arg("measured_t_s") = py::none(), py::arg("measured_f_n") = py::none(),
      py::arg("vary") = py::none(), py::arg("progress") = py::none(),
      py::arg("memory_limit_gb") = py::none(),
      R"(The HTML report of `trochomill report`: one self-contained page (returned as a str,
and written atomically to `output` when given). job: a Job (its planned path) or a Path
(read_gcode with a job). parts: "simulate" adds the tri-dexel window, "mechanism" or
"forces" make a default part required. The window of forces, simulation and calibration:
cycles=(A, B) or from_s/to_s (s), default the steady cycle. signal (1-D array) with rate_hz
(Hz) and start_s (s into it where the program starts): the acoustic monitor.
measured_t_s (n,) s and measured_f_n (n, 3) N: a calibration against them. vary: {key:
[values]}: a parameter study. The GIL is released while it runs.
progress: None or callable(phase: str, done: int, total: int).)");
}

}  // namespace trochomill::python
