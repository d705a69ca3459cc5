// The hooks of bench/python_bench.py (not part of the package's API): the C++ analysis timed
// alone, and the monitor's band filters as second-order sections.
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "common.hpp"
#include "trochomill/force.hpp"
#include "trochomill/signal.hpp"

namespace trochomill::python {

void bind_bench(py::module_& m) {
  // For bench/python_bench.py: the C++ call alone (analyze_with_forces, no conversion), the
  // fastest of `repeat` runs (s), to set beside analyze's.
  m.def(
      "_analyze_seconds",
      [](const py::object& job_or_path, int repeat) {
        const Job& job = job_of(job_or_path, "analyze").job;
        const ToolPath path = path_of(job_or_path);
        const py::gil_scoped_release release;
        double best = 1e300;
        for (int i = 0; i < std::max(repeat, 1); ++i) {
          const auto t0 = std::chrono::steady_clock::now();
          const ProcessMetrics pm = analyze_with_forces(job, path);
          best = std::min(best, seconds_since(t0));
          if (pm.series.samples.size() == 0) best = -1;  // keeps the result used
        }
        return best;
      },
      py::arg("job"), py::arg("repeat") = 5);
  // The monitor's two band filters as second-order sections (rows b0 b1 b2 a0 a1 a2), to
  // compare with scipy.signal.butter and to time against scipy.signal.sosfilt.
  m.def(
      "_monitor_filters",
      [](double rate_hz, const py::object& set) {
        const MonitorSettings ms = monitor_settings_without_job(overrides_of(set));
        validate(ms, rate_hz);
        auto rows = [](const Sos& sos) {
          std::vector<double> v;
          for (const auto& sec : sos.sections) v.insert(v.end(), sec.begin(), sec.end());
          const auto n = static_cast<py::ssize_t>(sos.sections.size());
          return to_array(std::move(v), {n, 6});
        };
        return py::make_tuple(
            rows(butter_bandpass(ms.order, ms.low_min_hz, ms.low_max_hz, rate_hz)),
            rows(butter_bandpass(ms.order, ms.high_min_hz, ms.high_max_hz, rate_hz)));
      },
      py::arg("rate_hz"), py::arg("set") = py::none());
}

}  // namespace trochomill::python
