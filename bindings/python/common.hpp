// What the Python module's files share: the job and path objects Python holds, arrays handed
// to numpy without a copy, JSON text as Python objects, the arguments and results several
// functions share (common.cpp), long calls that release the GIL and stop on Ctrl-C, and the
// registration of each part of the module.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "trochomill/app.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/progress.hpp"
#include "trochomill/texture.hpp"

namespace trochomill::python {

namespace py = pybind11;

/// A job as Python holds it: the parsed document, the overrides applied to it in order, and
/// the validated job they make (rebuilt, and so validated, at each `set`).
struct PyJob {
  std::shared_ptr<const JobDocument> doc;
  std::vector<Override> overrides;
  Job job;

  /// The job with more overrides, validated as the CLI validates `--set`.
  [[nodiscard]] Job with(const std::vector<Override>& more) const {
    std::vector<Override> all = overrides;
    all.insert(all.end(), more.begin(), more.end());
    Job j = doc->build(all);
    attach_rest_stock(j);  // [pocket] rest_of: the earlier program's stock
    return j;
  }
};

/// A tool-centre path in the slot frame of its job (planned, or read from a program and put
/// in the job's slot frame), or in the program's work frame when read without a job.
struct PyPath {
  ToolPath path;
  std::shared_ptr<const PyJob> job;  ///< null for a program read without a job
  int cycles = 0;                    ///< trochoid cycles (planned paths)
  std::vector<std::string> warnings;
  std::string source;       ///< "plan" or the program's name
  GcodeProgram lines;       ///< a program's line table (segment_lines, source_files) only
  std::string pocket_json;  ///< a planned pocket's figures and proof (pocket_json), else empty
  std::string gcode;        ///< a planned pocket's program in the job's dialect, else empty
};

/// The job of an argument that may be a Job or a Path (the path's job).
[[nodiscard]] const PyJob& job_of(const py::object& job_or_path, const char* function);

/// A vector handed to numpy without a copy: the array owns it through a capsule.
template <class T>
py::array_t<T> to_array(std::vector<T>&& v) {
  auto* owned = new std::vector<T>(std::move(v));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>({static_cast<py::ssize_t>(owned->size())}, {sizeof(T)}, owned->data(),
                        owner);
}
/// The same with a shape (row-major, the vector's size their product).
template <class T>
py::array_t<T> to_array(std::vector<T>&& v, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(v));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  std::vector<py::ssize_t> strides(shape.size(), static_cast<py::ssize_t>(sizeof(T)));
  for (std::size_t i = shape.size(); i-- > 1;) strides[i - 1] = strides[i] * shape[i];
  return py::array_t<T>(shape, strides, owned->data(), owner);
}

/// A Python value (bool, int, float, str, a list of them) in TOML syntax, for the job key
/// `key` (named when the value's type cannot be one).
[[nodiscard]] std::string toml_value(const py::handle& v, const std::string& key);
/// "section.key" = value as an override, the value in TOML syntax; a key without a section is
/// refused.
[[nodiscard]] Override make_override(const std::string& key, const py::handle& value);
/// {"section.key": value} (None: none) as overrides; a key without a section is refused.
[[nodiscard]] std::vector<Override> overrides_of(const py::object& set);
/// JSON text (the CLI's --json documents) as Python objects (json.loads).
[[nodiscard]] py::object from_json(const std::string& text);

/// The path of an argument: a Path as it is, a Job's planned path.
[[nodiscard]] ToolPath path_of(const py::object& job_or_path);
/// A time window: cycles=(A, B) (trochoid cycles A inclusive to B exclusive, from 0), or
/// from_s / to_s (s of programmed time), or the whole path.
[[nodiscard]] std::pair<double, double> window_of(const ToolPath& path, const py::object& cycles,
                                                  std::optional<double> from_s,
                                                  std::optional<double> to_s);
/// Radians as degrees.
[[nodiscard]] std::vector<double> degrees(const std::vector<double>& rad);
/// A 1-D float64 array, every value finite (`what` names it in the message).
[[nodiscard]] std::vector<double> finite_vector(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& a, const char* what);
/// Measured forces from t_s (n,) increasing and f_n (n, 3), every value finite.
[[nodiscard]] MeasuredForces measured_of(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& t_s,
    const py::array_t<double, py::array::c_style | py::array::forcecast>& f_n);
/// A profile texture's evaluated R and W profiles: x_mm (along the input), roughness_mm,
/// waviness_mm (the profiles are moved out of `t`).
[[nodiscard]] py::dict profile_arrays(ProfileTexture& t);
/// The monitor's settings without a job file: the defaults with `keys` applied, as the CLI's
/// `monitor` without --job (only the sections that stand alone may be set).
[[nodiscard]] MonitorSettings monitor_settings_without_job(const std::vector<Override>& keys);
/// Wall-clock seconds since `t0`.
[[nodiscard]] double seconds_since(std::chrono::steady_clock::time_point t0);

/// Runs `work(hooks)` on a worker thread while the calling thread, with the GIL released,
/// waits; every 50 ms it takes the GIL to run Python's signal handlers, and a
/// KeyboardInterrupt (Ctrl-C) raises the hooks' cancel flag: the library stops at its next
/// check and the KeyboardInterrupt is raised. `progress` (None or a callable taking phase,
/// done, total) hears the phases and progress, with the GIL; an exception it raises cancels
/// the call and is raised. Other Python threads run meanwhile.
template <class F>
auto run_released(F&& work, const py::object& progress = py::none())
    -> std::invoke_result_t<F, const RunHooks&> {
  using R = std::invoke_result_t<F, const RunHooks&>;
  struct State {
    std::atomic<bool> cancel{false};
    std::mutex mutex;
    std::condition_variable done_cv;
    bool done = false;
    std::optional<R> result;
    std::exception_ptr error;
    std::optional<py::error_already_set> python_error;  // set with the GIL held
    std::string phase;
  };
  auto st = std::make_shared<State>();
  RunHooks hooks;
  hooks.cancel = &st->cancel;
  if (!progress.is_none()) {
    auto report = [st, progress](std::size_t done, std::size_t total) {
      const py::gil_scoped_acquire gil;
      if (st->python_error) return;
      try {
        progress(st->phase, done, total);
      } catch (py::error_already_set& e) {
        st->python_error = std::move(e);
        st->cancel = true;
      }
    };
    hooks.progress = report;
    hooks.phase = [st, report](std::string_view name) {
      {
        const py::gil_scoped_acquire gil;
        st->phase = std::string(name);
      }
      report(0, 0);
    };
  }
  {
    const py::gil_scoped_release release;
    std::thread worker([st, &work, &hooks] {
      try {
        st->result.emplace(work(hooks));
      } catch (...) {
        st->error = std::current_exception();
      }
      const std::lock_guard<std::mutex> lock(st->mutex);
      st->done = true;
      st->done_cv.notify_all();
    });
    std::unique_lock<std::mutex> lock(st->mutex);
    while (!st->done_cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return st->done; })) {
      lock.unlock();
      {
        const py::gil_scoped_acquire gil;
        if (!st->python_error && PyErr_CheckSignals() != 0) {
          st->python_error.emplace();  // fetches the KeyboardInterrupt (or the handler's error)
          st->cancel = true;
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  if (st->python_error) throw std::move(*st->python_error);
  if (st->error) std::rethrow_exception(st->error);
  return std::move(*st->result);
}

// Each part of the module registers its classes and functions; module.cpp calls them in the
// module's order (the order of its attributes). The CLI's command groups name the files.
void bind_job(py::module_& m);           // module.cpp: Job
void bind_path(py::module_& m);          // module.cpp: Path, plan, read_gcode
void bind_analysis(py::module_& m);      // bind_analysis.cpp: analyze
void bind_study(py::module_& m);         // bind_study.cpp: compare
void bind_mechanism(py::module_& m);     // bind_mechanism.cpp: mechanism, recommend
void bind_simulation(py::module_& m);    // bind_simulation.cpp: simulate, forces, calibrate
void bind_report(py::module_& m);        // bind_report.cpp: report
void bind_monitor(py::module_& m);       // bind_signal.cpp: monitor
void bind_bench(py::module_& m);         // bind_bench.cpp: _analyze_seconds, _monitor_filters
void bind_texture(py::module_& m);       // bind_texture.cpp: texture_profile, texture_areal
void bind_spectrum(py::module_& m);      // bind_signal.cpp: spectrum
void bind_tool(py::module_& m);          // bind_tool.cpp: keys, materials
void bind_feed(py::module_& m);          // bind_feed.cpp: schedule_feed, optimize_feed
void bind_synth_signal(py::module_& m);  // bind_signal.cpp: synth_signal
void bind_geometry(py::module_& m);      // bind_geometry.cpp: read_drawing

}  // namespace trochomill::python
