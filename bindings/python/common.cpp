// What the Python module's files share (common.hpp): job values and overrides from Python,
// the job, path and window of a function's arguments, arrays checked on the way in, the dicts
// and arrays several functions return, and the memory check.
#include "common.hpp"

#include <fmt/format.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>

#include "trochomill/app.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/io.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/units.hpp"

namespace trochomill::python {

namespace {

// "(n, 3)": an array's shape as Python writes it.
std::string shape_text(const py::array& a) {
  std::string out = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) out += fmt::format("{}{}", i ? ", " : "", a.shape(i));
  return out + (a.ndim() == 1 ? ",)" : ")");
}

}  // namespace

std::string toml_value(const py::handle& v, const std::string& key) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(v)) {
    return py::module_::import("json").attr("dumps")(v).cast<std::string>();
  }
  if (PyIndex_Check(v.ptr()) != 0) return py::str(py::int_(py::reinterpret_borrow<py::object>(v)));
  if (PyFloat_Check(v.ptr()) != 0 || py::hasattr(v, "__float__")) {
    const double d = v.cast<double>();
    if (std::isnan(d)) return "nan";
    if (std::isinf(d)) return d > 0 ? "inf" : "-inf";
    std::string out = fmt::format("{}", d);
    if (out.find_first_of(".e") == std::string::npos) out += ".0";
    return out;
  }
  if (py::isinstance<py::sequence>(v) || py::isinstance<py::array>(v)) {
    std::string out = "[";
    bool first = true;
    for (const py::handle item : v) {
      out += (first ? "" : ", ") + toml_value(item, key);
      first = false;
    }
    return out + "]";
  }
  throw InputError(
      fmt::format("{}: a {} cannot be a job value (allowed: bool, int, float, str "
                  "and lists of them)",
                  key, py::str(py::type::of(v).attr("__name__")).cast<std::string>()));
}

Override make_override(const std::string& key, const py::handle& value) {
  if (key.find('.') == std::string::npos) {
    throw InputError(fmt::format("'{}': a job key is section.key, e.g. path.step", key));
  }
  return Override{key, toml_value(value, key), ""};
}

std::vector<Override> overrides_of(const py::object& set) {
  std::vector<Override> out;
  if (set.is_none()) return out;
  for (const auto& [k, v] : set.cast<py::dict>()) {
    out.push_back(make_override(py::str(k).cast<std::string>(), v));
  }
  return out;
}

const PyJob& job_of(const py::object& job_or_path, const char* function) {
  if (py::isinstance<PyJob>(job_or_path)) return job_or_path.cast<const PyJob&>();
  if (py::isinstance<PyPath>(job_or_path)) {
    const PyPath& p = job_or_path.cast<const PyPath&>();
    if (p.job) return *p.job;
    throw InputError(fmt::format(
        "{}: this program was read without a job; read_gcode(program, job=...) gives it one",
        function));
  }
  throw py::type_error(fmt::format("{}: expected a Job or a Path", function));
}

py::object from_json(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}

ToolPath path_of(const py::object& job_or_path) {
  if (py::isinstance<PyPath>(job_or_path)) return job_or_path.cast<const PyPath&>().path;
  return plan_job(job_of(job_or_path, "path").job).path;
}

std::pair<double, double> window_of(const ToolPath& path, const py::object& cycles,
                                    std::optional<double> from_s, std::optional<double> to_s) {
  WindowRequest r;
  if (!cycles.is_none()) r.cycles = cycles.cast<std::pair<long long, long long>>();
  r.from_s = from_s;
  r.to_s = to_s;
  return resolve_window(path, r);
}

std::vector<double> degrees(const std::vector<double>& rad) {
  std::vector<double> out(rad.size());
  std::transform(rad.begin(), rad.end(), out.begin(), [](double r) { return rad_to_deg(r); });
  return out;
}

std::vector<double> finite_vector(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& a, const char* what) {
  if (a.ndim() != 1)
    throw InputError(fmt::format("{}: a 1-D array, got {} dimensions", what, a.ndim()));
  std::vector<double> v(a.data(), a.data() + a.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw InputError(
          fmt::format("{}[{}] is {}: every sample must be a finite number", what, i, v[i]));
    }
  }
  return v;
}

MeasuredForces measured_of(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& t_s,
    const py::array_t<double, py::array::c_style | py::array::forcecast>& f_n) {
  MeasuredForces meas;
  meas.t_s = finite_vector(t_s, "t_s");
  if (f_n.ndim() != 2 || f_n.shape(1) != 3 ||
      static_cast<std::size_t>(f_n.shape(0)) != meas.t_s.size()) {
    throw InputError(
        fmt::format("f_n: an array of shape ({}, 3) (F_x, F_y, F_z in N per time), got {}",
                    meas.t_s.size(), shape_text(f_n)));
  }
  if (meas.t_s.size() < 2) throw InputError("t_s: at least 2 samples");
  for (std::size_t i = 1; i < meas.t_s.size(); ++i) {
    if (!(meas.t_s[i] > meas.t_s[i - 1])) {
      throw InputError(fmt::format("t_s[{}] = {} does not follow t_s[{}] = {}: times must increase",
                                   i, meas.t_s[i], i - 1, meas.t_s[i - 1]));
    }
  }
  const double* f = f_n.data();
  for (std::size_t i = 0; i < meas.t_s.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(f[3 * i + static_cast<std::size_t>(k)])) {
        throw InputError(fmt::format("f_n[{}, {}] is not a finite force", i, k));
      }
    }
    meas.fx_n.push_back(f[3 * i]);
    meas.fy_n.push_back(f[3 * i + 1]);
    meas.fz_n.push_back(f[3 * i + 2]);
  }
  return meas;
}

py::dict profile_arrays(ProfileTexture& t) {
  std::vector<double> x(t.roughness_profile_mm.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    x[i] = t.profile_start_mm + static_cast<double>(i) * t.profile_dx_mm;
  }
  py::dict d;
  d["x_mm"] = to_array(std::move(x));
  d["roughness_mm"] = to_array(std::move(t.roughness_profile_mm));
  d["waviness_mm"] = to_array(std::move(t.waviness_profile_mm));
  return d;
}

MonitorSettings monitor_settings_without_job(const std::vector<Override>& keys) {
  Job defaults;
  apply_overrides(defaults, keys);
  return defaults.monitor;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace trochomill::python
