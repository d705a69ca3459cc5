// compare: a parameter study on a grid of job variants (the CLI's `compare`), as columns.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "common.hpp"
#include "trochomill/report/analysis.hpp"
#include "trochomill/study.hpp"

namespace trochomill::python {

void bind_study(py::module_& m) {
  m.def(
      "compare",
      [](const PyJob& job, const py::dict& vary, int threads, const py::object& progress) {
        if (threads < 0) throw InputError(fmt::format("threads must be >= 0, got {}", threads));
        std::vector<Vary> varies;
        for (const auto& [k, values] : vary) {
          Vary v;
          v.key = py::str(k).cast<std::string>();
          if (!py::isinstance<py::sequence>(values) || py::isinstance<py::str>(values)) {
            throw InputError(fmt::format("vary {}: a list of values", v.key));
          }
          for (const py::handle x : values) {
            v.values.push_back(toml_value(x, v.key));
          }
          varies.push_back(std::move(v));
        }
        const std::vector<StudyPoint> points = run_released(
            [&](const RunHooks& h) {
              return run_compare(*job.doc, job.overrides, varies, threads, h);
            },
            progress);
        py::dict doc = from_json(study_json(varies, points));
        // Columns: each varied key (its values as read back by TOML), ok, error, and every
        // metric of the points that ran (NaN where a point failed or has no value).
        py::dict cols;
        const py::module_ tomllib = py::module_::import("tomllib");
        // One entry per point, keyed by name: the value that took effect (the last override
        // of the key: a job's own override of a varied key comes before the study's), None
        // where a point has none. Appending every override of the key once gave a column
        // longer than the table, its rows shifted against the metrics.
        for (const Vary& v : varies) {
          py::list col;
          for (const StudyPoint& p : points) {
            const Override* last = nullptr;
            for (const Override& o : p.overrides) {
              if (o.key == v.key) last = &o;
            }
            col.append(last != nullptr ? tomllib.attr("loads")("v = " + last->value)["v"]
                                       : py::object(py::none()));
          }
          cols[py::str(v.key)] = py::module_::import("numpy").attr("asarray")(col);
        }
        py::list pts = doc["points"];
        std::vector<std::string> metric_keys;
        auto is_number = [](const py::handle& v) {
          return !py::isinstance<py::bool_>(v) &&
                 (py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v));
        };
        for (const py::handle p : pts) {
          if (!p["ok"].cast<bool>()) continue;
          for (const auto& [k, val] : p["metrics"].cast<py::dict>()) {
            const std::string key = py::str(k).cast<std::string>();
            if ((is_number(val) || val.is_none()) &&
                std::find(metric_keys.begin(), metric_keys.end(), key) == metric_keys.end()) {
              metric_keys.push_back(key);
            }
          }
        }
        py::array_t<bool> ok(static_cast<py::ssize_t>(py::len(pts)));
        py::list errors;
        py::ssize_t i = 0;
        for (const py::handle p : pts) {
          const py::dict pd = p.cast<py::dict>();
          ok.mutable_at(i++) = pd["ok"].cast<bool>();
          errors.append(pd.contains("error") ? pd["error"] : py::str(""));
        }
        cols["ok"] = ok;
        cols["error"] = errors;
        for (const std::string& key : metric_keys) {
          std::vector<double> col;
          const py::str k(key);
          for (const py::handle p : pts) {
            const py::dict pd = p.cast<py::dict>();
            py::object v = py::none();
            if (pd.contains("metrics")) {
              const py::dict md = pd["metrics"].cast<py::dict>();
              if (md.contains(k)) v = md[k];
            }
            col.push_back(is_number(v) ? v.cast<double>() : std::nan(""));
          }
          cols[k] = to_array(std::move(col));
        }
        return cols;
      },
      py::arg("job"), py::arg("vary"), py::kw_only(), py::arg("threads") = 0,
      py::arg("progress") = py::none(),
      R"(A parameter study: analyze on the grid of `vary` ({"section.key": [values]}; several
keys give their Cartesian product, the first varying slowest), in parallel (threads 0: all
cores), results in grid order whatever the thread count. Returns columns: each varied key,
"ok" (bool), "error" (str, empty where the point ran) and each number of `analyze`'s JSON
as a float64 array (NaN where the point failed or the metric is None).)");
}

}  // namespace trochomill::python
