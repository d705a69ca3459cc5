// The model chains as Python functions: analyze, compare, mechanism, recommend, simulate,
// forces, calibrate, monitor, synth_signal. Each returns the CLI's JSON document (the same
// keys, units in their names) as a dict, with its series as numpy arrays beside it. Long
// calls release the GIL and stop on Ctrl-C (run_released).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common.hpp"
#include "trochomill/analysis.hpp"
#include "trochomill/feed.hpp"
#include "trochomill/force.hpp"
#include "trochomill/io.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/report.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/units.hpp"

namespace trochomill::python {

namespace {

// The feed targets of schedule_feed and optimize_feed: the arguments over the job's [machine]
// limits, as the CLI's flags (checked by the library: InputError).
FeedTargets feed_targets(const Job& job, std::optional<double> h_max_mm,
                         std::optional<double> mrr_mm3_per_min,
                         std::optional<double> min_feed_mm_per_min,
                         std::optional<double> max_feed_mm_per_min,
                         std::optional<double> air_feed_mm_per_min, double feed_step_percent,
                         double piece_mm) {
  FeedTargets t = default_feed_targets(job);
  t.h_max_mm = h_max_mm;
  t.mrr_mm3_per_min = mrr_mm3_per_min;
  if (min_feed_mm_per_min) t.min_feed_mm_per_min = *min_feed_mm_per_min;
  if (max_feed_mm_per_min) t.max_feed_mm_per_min = *max_feed_mm_per_min;
  if (air_feed_mm_per_min) t.air_feed_mm_per_min = *air_feed_mm_per_min;
  t.feed_step_percent = feed_step_percent;
  t.piece_mm = piece_mm;
  return t;
}

// The path of an argument: a Path as it is, a Job's planned path.
ToolPath path_of(const py::object& job_or_path) {
  if (py::isinstance<PyPath>(job_or_path)) return job_or_path.cast<const PyPath&>().path;
  return plan_path(job_of(job_or_path, "path").job).path;
}

// A time window: cycles=(A, B) (trochoid cycles A inclusive to B exclusive, from 0), or
// from_s / to_s (s of programmed time), or the whole path.
std::pair<double, double> window_of(const ToolPath& path, const py::object& cycles,
                                    std::optional<double> from_s, std::optional<double> to_s) {
  if (!cycles.is_none()) {
    if (from_s || to_s) throw InputError("give cycles or from_s/to_s, not both");
    const auto ab = cycles.cast<std::pair<long long, long long>>();
    const long long count = static_cast<long long>(path.cycles().size());
    if (ab.first < 0 || ab.second <= ab.first || ab.second > count) {
      throw InputError(fmt::format("cycles ({}, {}): need 0 <= A < B <= {} (the path's cycles)",
                                   ab.first, ab.second, count));
    }
    return cycle_window(path, static_cast<int>(ab.first), static_cast<int>(ab.second));
  }
  for (const auto& [name, v] : {std::pair{"from_s", from_s}, std::pair{"to_s", to_s}}) {
    if (v && !(std::isfinite(*v) && *v >= 0 && *v <= 1e9)) {
      throw InputError(fmt::format("{} must be a finite time in [0, 1e9] s, got {}", name, *v));
    }
  }
  return {from_s.value_or(0.0), to_s.value_or(path.duration_s())};
}

std::vector<double> degrees(const std::vector<double>& rad) {
  std::vector<double> out(rad.size());
  std::transform(rad.begin(), rad.end(), out.begin(), [](double r) { return rad_to_deg(r); });
  return out;
}

// A 1-D float64 array, every value finite (`what` names it in the message).
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

// "(n, 3)": an array's shape as Python writes it.
std::string shape_text(const py::array& a) {
  std::string out = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) out += fmt::format("{}{}", i ? ", " : "", a.shape(i));
  return out + (a.ndim() == 1 ? ",)" : ")");
}

// Measured forces from t_s (n,) increasing and f_n (n, 3), every value finite.
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

py::dict analyze_series(EngagementSeries&& e) {
  PathSamples& s = e.samples;
  std::vector<double> mrr(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    mrr[i] = e.removal_rate_mm3_per_s[i] * 60.0;
  }
  py::dict d;
  d["engagement_deg"] = to_array(degrees(e.engagement_angle_rad));
  d["t_s"] = to_array(std::move(s.t_s));
  d["x_mm"] = to_array(std::move(s.x_mm));
  d["y_mm"] = to_array(std::move(s.y_mm));
  d["z_mm"] = to_array(std::move(s.z_mm));
  d["h_max_mm"] = to_array(std::move(e.h_max_mm));
  d["teeth_in_cut"] = to_array(std::move(e.teeth_in_cut));
  d["mrr_mm3_per_min"] = to_array(std::move(mrr));
  d["radial_engagement_mm"] = to_array(std::move(e.radial_engagement_mm));
  return d;
}

py::dict force_arrays(ForceSeries&& s) {
  const auto n = static_cast<py::ssize_t>(s.size());
  std::vector<double> fr(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) fr[i] = s.resultant_n(i);
  py::dict d;
  d["f_resultant_n"] = to_array(std::move(fr));
  d["t_s"] = to_array(std::move(s.t_s));
  d["f_x_n"] = to_array(std::move(s.fx_n));
  d["f_y_n"] = to_array(std::move(s.fy_n));
  d["f_z_n"] = to_array(std::move(s.fz_n));
  d["torque_nm"] = to_array(std::move(s.torque_nm));
  d["power_w"] = to_array(std::move(s.power_w));
  const py::ssize_t teeth = s.teeth;
  d["tooth_f_x_n"] = to_array(std::move(s.tooth_fx_n), {n, teeth});
  d["tooth_f_y_n"] = to_array(std::move(s.tooth_fy_n), {n, teeth});
  d["tooth_f_z_n"] = to_array(std::move(s.tooth_fz_n), {n, teeth});
  d["tooth_torque_nm"] = to_array(std::move(s.tooth_torque_nm), {n, teeth});
  return d;
}

// The machined surface as a triangle mesh of its height field: vertices (n, 3) mm, faces
// (m, 3) vertex indices, two triangles per grid cell, counter-clockwise seen from above.
py::dict surface_mesh(const HeightField& f) {
  const std::size_t cols = f.x_mm_of_column.size(), rows = f.y_mm_of_row.size();
  std::vector<double> v;
  v.reserve(cols * rows * 3);
  for (std::size_t c = 0; c < cols; ++c) {
    for (std::size_t r = 0; r < rows; ++r) {
      v.insert(v.end(), {f.x_mm_of_column[c], f.y_mm_of_row[r], f.z_mm[c * rows + r]});
    }
  }
  std::vector<std::uint32_t> faces;
  if (cols > 1 && rows > 1) faces.reserve((cols - 1) * (rows - 1) * 6);
  for (std::size_t c = 0; c + 1 < cols; ++c) {
    for (std::size_t r = 0; r + 1 < rows; ++r) {
      const auto a = static_cast<std::uint32_t>(c * rows + r),
                 b = a + static_cast<std::uint32_t>(rows);
      faces.insert(faces.end(), {a, b, b + 1, a, b + 1, a + 1});
    }
  }
  py::dict d;
  const auto nv = static_cast<py::ssize_t>(v.size() / 3),
             nf = static_cast<py::ssize_t>(faces.size() / 3);
  d["vertices_mm"] = to_array(std::move(v), {nv, 3});
  d["faces"] = to_array(std::move(faces), {nf, 3});
  d["bottom_mm"] = f.bottom_mm;
  return d;
}

py::dict chip_map_dict(ChipMapData&& c) {
  const auto steps = static_cast<py::ssize_t>(c.t_s.size());
  const auto teeth = static_cast<py::ssize_t>(c.teeth);
  const auto segs = static_cast<py::ssize_t>(c.segments_per_tooth);
  py::dict d;
  d["t_s"] = to_array(std::move(c.t_s));
  d["tip_mm"] = to_array(std::move(c.tip_mm), {steps, 3});
  d["removed_mm3"] = to_array(std::move(c.removed_mm3), {steps, teeth});
  d["h_mm"] = to_array(std::move(c.h_mm), {steps, teeth, segs});
  d["w_mm"] = to_array(std::move(c.w_mm), {steps, teeth, segs});
  d["v_mm3"] = to_array(std::move(c.v_mm3), {steps, teeth, segs});
  d["segment_height_mm"] = to_array(std::move(c.segment_height_mm));
  d["resolution_mm"] = c.resolution_mm;
  d["steps_per_rev"] = c.steps_per_rev;
  return d;
}

// A profile texture's evaluated R and W profiles: x_mm (along the input), roughness_mm,
// waviness_mm.
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

// The monitor's settings without a job file: the defaults with `keys` applied, as the CLI's
// `monitor` without --job (only the sections that stand alone may be set).
MonitorSettings monitor_settings_without_job(const std::vector<Override>& keys) {
  Job defaults;
  apply_overrides(defaults, keys);
  return defaults.monitor;
}

// The one surface of a texture JSON document.
py::dict first_surface(const std::string& json) {
  const py::list surfaces = from_json(json)["surfaces"];
  return surfaces[0];
}

// A height map as a dict: z_mm (ny, nx), dx_mm, dy_mm, x0_mm, y0_mm, description.
py::dict height_map_dict(HeightMap&& m) {
  py::dict d;
  d["dx_mm"] = m.dx_mm;
  d["dy_mm"] = m.dy_mm;
  d["x0_mm"] = m.x0_mm;
  d["y0_mm"] = m.y0_mm;
  d["description"] = m.description;
  d["z_mm"] =
      to_array(std::move(m.z_mm), {static_cast<py::ssize_t>(m.ny), static_cast<py::ssize_t>(m.nx)});
  return d;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

void bind_models(py::module_& m) {
  m.def(
      "analyze",
      [](const py::object& job_or_path, std::optional<double> memory_limit_gb,
         const py::object& progress) {
        const Job& job = job_of(job_or_path, "analyze").job;
        const ToolPath path = path_of(job_or_path);
        check_memory("analyze", estimate_analysis_memory(job, path), memory_limit_gb,
                     fmt::format("{:.0f} s of program at {:g} rpm, {} samples per tooth pass: "
                                 "lower analysis.steps_per_tooth or analyse a shorter program",
                                 path.duration_s(), job.cutting.spindle_speed_rpm,
                                 job.analysis.steps_per_tooth));
        ProcessMetrics pm = run_released(
            [&](const RunHooks& h) { return analyze_with_forces(job, path, h); }, progress);
        py::dict out = from_json(metrics_json(job, pm));
        out["series"] = analyze_series(std::move(pm.series));
        py::dict walls;  // the steady cycle's walls, as the JSON reports their texture
        if (pm.periodic && pm.texture_left) walls["left"] = profile_arrays(*pm.texture_left);
        if (pm.periodic && pm.texture_right) walls["right"] = profile_arrays(*pm.texture_right);
        out["wall_texture_profiles"] = walls;
        py::dict floor;  // the floor's lines, as the JSON reports their texture
        const char* lines[] = {"left", "middle", "right"};
        for (std::size_t k = 0; k < 3; ++k) {
          if (!pm.texture_floor[k]) continue;
          py::dict d = profile_arrays(*pm.texture_floor[k]);
          d["line_x_mm"] = pm.floor[k].x_mm;
          floor[lines[k]] = d;
        }
        out["floor_texture_profiles"] = floor;
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("memory_limit_gb") = py::none(),
      py::arg("progress") = py::none(),
      R"(Engagement, chip thickness, times, removal rate, walls and texture of a slot program.

job: a Job (its planned path) or a Path (planned, or read from G-code with a job).
Returns the keys of `trochomill analyze --json` (units in their names: _mm, _s, _deg,
_mm3_per_min; cycle_* keys None when the path has no steady cycle) and "series": float64
arrays t_s, x_mm, y_mm, z_mm, engagement_deg, h_max_mm, mrr_mm3_per_min,
radial_engagement_mm and the int32 array teeth_in_cut, one entry per sample;
"wall_texture_profiles": per wall ("left", "right") the predicted R and W profiles the wall
texture was evaluated on (x_mm along the feed, roughness_mm, waviness_mm);
"floor_texture_profiles": the same for the floor's lines ("left", "middle", "right", beside
each wall and in the middle, at x = line_x_mm across the slot).
progress: None or callable(phase: str, done: int, total: int).)");

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
              RunHooks inner;
              inner.cancel = h.cancel;
              return run_study(
                  *job.doc, job.overrides, varies, threads,
                  [&inner](const Job& j) {
                    return analyze_with_forces(j, plan_path(j).path, inner);
                  },
                  h);
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

  m.def(
      "mechanism",
      [](const PyJob& pj, const std::optional<std::string>& model,
         std::optional<double> flank_wear_mm) {
        std::vector<Override> more;
        if (model) more.push_back({"mechanism.model", "\"" + *model + "\"", "model"});
        if (flank_wear_mm)
          more.push_back({"tool.flank_wear", fmt::format("{}", *flank_wear_mm), "flank_wear_mm"});
        const Job job = more.empty() ? pj.job : pj.with(more);
        const MechanismSettings& st = job.mechanism;
        const bool use_wear = job.tool.flank_wear_mm > 0;
        MechanismCurve c = mechanism_curve(job, st, use_wear);
        const ZoneSummary z = summarize_zones(c, st, use_wear);
        py::dict out = from_json(mechanism_json(job, st, c, z, use_wear));
        out["theta_deg"] = to_array(degrees(c.theta_rad));
        out["psi_deg"] = to_array(degrees(c.psi_rad));
        out["gamma_k_deg"] = to_array(degrees(c.gamma_k_rad));
        out["kappa_deg"] = to_array(degrees(c.kappa_rad));
        out["k_re_pct"] = to_array(use_wear ? std::move(c.k_re_wear_pct) : std::move(c.k_re_pct));
        if (use_wear) out["k_re_wear_pct"] = out["k_re_pct"];
        out["t_s"] = to_array(std::move(c.t_s));
        out["h_mm"] = to_array(std::move(c.h_mm));
        out["teeth_in_contact"] = to_array(std::move(c.teeth_in_contact));
        out["zone"] = to_array(std::move(c.zone));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("model") = py::none(),
      py::arg("flank_wear_mm") = py::none(),
      R"(Chip thickness, K_re and the cutting-mechanism zones over one trochoid cycle (Pivkin
2025): the keys of `trochomill mechanism --json` with the curves as arrays over the cycle:
theta_deg, t_s, h_mm, psi_deg, teeth_in_contact, gamma_k_deg, kappa_deg, k_re_pct (with the
flank wear when the tool has one) and zone (int32: 0 not cutting, 1 CZI, 2 CZII, 3 CZIII).
model: "exact" or "pivkin2025" (default the job's mechanism.model); flank_wear_mm: VB_B (mm).)");

  m.def(
      "recommend",
      [](const PyJob& pj, std::optional<double> share, bool feed) {
        std::vector<Override> more;
        if (share) more.push_back({"mechanism.share", fmt::format("{}", *share), "share"});
        const Job job = more.empty() ? pj.job : pj.with(more);
        const Recommendation r = recommend(job, job.mechanism, job.tool.flank_wear_mm > 0, feed);
        return from_json(recommendation_json(job, job.mechanism, r, feed));
      },
      py::arg("job"), py::kw_only(), py::arg("share") = py::none(), py::arg("feed") = false,
      R"(The smallest trochoid step (mm), or with feed=True the feed per tooth (mm) at the job's
step, whose cutting part is at least `share` (0..1, default mechanism.share) in CZIII: the
keys of `trochomill recommend --json` (with its "explanation").)");

  m.def(
      "simulate",
      [](const py::object& job_or_path, const py::object& cycles, std::optional<double> from_s,
         std::optional<double> to_s, const py::object& progress,
         std::optional<double> memory_limit_gb) {
        const Job& job = job_of(job_or_path, "simulate").job;
        const ToolPath path = path_of(job_or_path);
        const auto [from, to] = window_of(path, cycles, from_s, to_s);
        const MemoryEstimate est = estimate_simulation_memory(job, path, from, to);
        const double need = est.total(true);
        check_memory("simulate", need, memory_limit_gb,
                     fmt::format("coarsen simulation.resolution (now {} mm) or shorten the "
                                 "window (cycles, from_s/to_s)",
                                 job.simulation.resolution_mm));
        const auto t0 = std::chrono::steady_clock::now();
        JobSimulation js = run_released(
            [&](const RunHooks& h) {
              SimControl control;
              control.hooks = h;
              control.reserve_chip_entries = static_cast<std::size_t>(est.chip_entries);
              return simulate_job(job, path, from, to, control);
            },
            progress);
        const double wall = seconds_since(t0);
        py::dict out = from_json(simulation_json(job, js, from, to, wall, need));
        const SimTool tool = sim_tool(job, job.simulation);
        const SimResult& r = js.result;
        const auto steps = static_cast<py::ssize_t>(r.steps.size());
        const auto teeth = static_cast<py::ssize_t>(job.tool.teeth);
        std::vector<double> t(r.steps.size()), tip(r.steps.size() * 3), removed,
            h_max(r.steps.size()), h_mean(r.steps.size());
        std::vector<std::int32_t> engaged(r.steps.size());
        removed.reserve(r.steps.size() * static_cast<std::size_t>(teeth));
        for (std::size_t i = 0; i < r.steps.size(); ++i) {
          const SimStep& st = r.steps[i];
          t[i] = st.t_s;
          std::copy(st.tip_mm.begin(), st.tip_mm.end(),
                    tip.begin() + static_cast<std::ptrdiff_t>(3 * i));
          removed.insert(removed.end(), st.removed_mm3.begin(), st.removed_mm3.end());
          h_max[i] = st.h_max_mm;
          h_mean[i] = st.h_mean_mm;
          engaged[i] = st.engaged_segments;
        }
        py::dict series;
        series["t_s"] = to_array(std::move(t));
        series["tip_mm"] = to_array(std::move(tip), {steps, 3});
        series["removed_mm3"] = to_array(std::move(removed), {steps, teeth});
        series["h_max_mm"] = to_array(std::move(h_max));
        series["h_mean_mm"] = to_array(std::move(h_mean));
        series["engaged_segments"] = to_array(std::move(engaged));
        out["series"] = series;
        out["chip_map"] = chip_map_dict(chip_map_data(r, tool, job.simulation));
        out["surface"] =
            surface_mesh(surface_height_field(*js.work, default_surface_step_mm(*js.work)));
        try {
          out["floor"] = height_map_dict(simulated_floor(job, js));
          out["floor_note"] = "";
        } catch (const InputError& e) {  // the window left no floor cut across the slot
          out["floor"] = py::none();
          out["floor_note"] = e.what();
        }
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("cycles") = py::none(), py::arg("from_s") = py::none(),
      py::arg("to_s") = py::none(), py::arg("progress") = py::none(),
      py::arg("memory_limit_gb") = py::none(),
      R"(Tri-dexel material removal (Bergmann 2021) over a window of the path: cycles=(A, B)
(trochoid cycles A to B-1) or from_s/to_s (s of programmed time), default the whole path.
Returns the keys of `trochomill simulate --json`, "series" (t_s, tip_mm (n, 3),
removed_mm3 (n, teeth), h_max_mm, h_mean_mm, engaged_segments per step), "chip_map" (t_s,
tip_mm, removed_mm3 and float32 h_mm, w_mm, v_mm3 (steps, teeth, segments), the
segment_height_mm of each edge segment above the tip) and "surface" (the machined surface:
vertices_mm (n, 3), faces (m, 3) uint32, bottom_mm) and "floor" (the slot's floor as a
height map at the dexel spacing, as floor.x3p: z_mm (ny, nx), dx_mm, dy_mm, x0_mm, y0_mm; None
with the reason in "floor_note" when the window left no floor cut across the slot). The GIL
is released while it runs.
progress: None or callable(phase: str, done: int, total: int).)");

  m.def(
      "forces",
      [](const py::object& job_or_path, bool fast, const py::object& cycles,
         std::optional<double> from_s, std::optional<double> to_s, const py::object& progress,
         std::optional<double> memory_limit_gb) {
        const Job& job = job_of(job_or_path, "forces").job;
        const ToolPath path = path_of(job_or_path);
        const auto [from, to] = window_of(path, cycles, from_s, to_s);
        if (!job.material.model) {
          throw InputError(fmt::format(
              "{}: no [material] force model; give [material] model and coefficients or name "
              "(see `trochomill materials`)",
              job.source));
        }
        std::size_t reserve = 0;
        if (!fast) {
          const MemoryEstimate est = estimate_simulation_memory(job, path, from, to);
          check_memory("forces", est.total(false), memory_limit_gb,
                       "shorten the window (cycles, from_s/to_s), coarsen simulation.resolution "
                       "or use fast=True");
          reserve = static_cast<std::size_t>(est.chip_entries);
        }
        JobForces jf = run_released(
            [&](const RunHooks& h) {
              SimControl control;
              control.hooks = h;
              control.reserve_chip_entries = reserve;
              return job_forces(job, path, from, to, fast, control);
            },
            progress);
        py::dict out = from_json(force_summary_json(job, jf, from, to));
        out["series"] = force_arrays(std::move(jf.series));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("fast") = true, py::arg("cycles") = py::none(),
      py::arg("from_s") = py::none(), py::arg("to_s") = py::none(),
      py::arg("progress") = py::none(), py::arg("memory_limit_gb") = py::none(),
      R"(Cutting forces on the workpiece with the job's [material] model: the keys of
`trochomill forces --json` and "series": t_s, f_x_n, f_y_n, f_z_n, f_resultant_n (N),
torque_nm (N m), power_w (W), and per tooth tooth_f_x_n, tooth_f_y_n, tooth_f_z_n,
tooth_torque_nm (steps, teeth). fast=True: chips from the analytic engagement; False: from
the dexel simulation. Window as for simulate.)");

  m.def(
      "calibrate",
      [](const py::object& job_or_path,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& t_s,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& f_n,
         const std::vector<std::string>& fit, const std::optional<std::string>& model, bool fast,
         std::optional<double> cutoff_hz, std::optional<double> max_shift_s,
         const py::object& cycles, std::optional<double> from_s, std::optional<double> to_s,
         const py::object& progress, std::optional<double> memory_limit_gb) {
        const Job& job = job_of(job_or_path, "calibrate").job;
        const MeasuredForces meas = measured_of(t_s, f_n);
        CalibrationOptions o;
        if (model) {
          o.model = parse_force_model(*model);
        } else if (job.material.model) {
          o.model = *job.material.model;
        }
        o.fit = fit;
        o.fast = fast;
        if (cutoff_hz) o.cutoff_hz = *cutoff_hz;
        if (max_shift_s) o.max_shift_s = *max_shift_s;
        const ToolPath path = path_of(job_or_path);
        if (cycles.is_none() && !from_s && !to_s) {
          o.from_s = std::max(0.0, meas.t_s.front());
          o.to_s = std::min(path.duration_s(), meas.t_s.back());
        } else {
          std::tie(o.from_s, o.to_s) = window_of(path, cycles, from_s, to_s);
        }
        check_memory("calibrate", estimate_calibration_memory(job, path, o, meas.t_s.size()),
                     memory_limit_gb,
                     fmt::format("the model window is {:.1f} s: a few cycles hold the "
                                 "coefficients as well",
                                 o.to_s - o.from_s));
        const CalibrationResult r = run_released(
            [&](const RunHooks& h) {
              CalibrationOptions oo = o;
              oo.hooks = h;
              return calibrate_forces(job, path, meas, oo);
            },
            progress);
        py::dict out = from_json(calibration_json(r));
        out["material_toml"] = material_toml(r);
        return out;
      },
      py::arg("job"), py::arg("t_s"), py::arg("f_n"), py::kw_only(),
      py::arg("fit") = std::vector<std::string>{}, py::arg("model") = py::none(),
      py::arg("fast") = false, py::arg("cutoff_hz") = py::none(),
      py::arg("max_shift_s") = py::none(), py::arg("cycles") = py::none(),
      py::arg("from_s") = py::none(), py::arg("to_s") = py::none(),
      py::arg("progress") = py::none(), py::arg("memory_limit_gb") = py::none(),
      R"(Fits the force model to measured forces: t_s (n,) s, increasing; f_n (n, 3) N on the
workpiece (F_x, F_y, F_z). fit: the parameters (k_c, k_n, m, m_n, k_a, m_a | k_tc, k_rc,
k_ac, k_te, k_re, k_ae, runout_radial, runout_phase, runout_axial; default the model's main
coefficients); model: bergmann, kienzle or linear (default the job's); cutoff_hz: low-pass
of both signals (default from the tooth-passing frequency); max_shift_s: the alignment
search (default half a revolution); the model window: cycles or from_s/to_s, default the
measurement's span. Returns the keys of `trochomill calibrate --json` and "material_toml"
(the fitted [material] block).)");

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
              const ReportData d = build_report(pj.job, std::move(path), std::move(r), h);
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

  m.def(
      "monitor",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& samples,
         double rate_hz, const py::object& job_obj, double start_s, const py::object& set) {
        if (!(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= 1e7)) {
          throw InputError(fmt::format("rate_hz must be in (0, 1e7] Hz, got {}", rate_hz));
        }
        if (!(std::isfinite(start_s) && start_s >= 0 && start_s <= 1e9)) {
          throw InputError(fmt::format("start_s must be in [0, 1e9] s, got {}", start_s));
        }
        const std::vector<Override> keys = overrides_of(set);
        std::optional<Job> job;
        MonitorSettings ms;
        if (!job_obj.is_none()) {
          const PyJob& pj = job_obj.cast<const PyJob&>();
          job = keys.empty() ? pj.job : pj.with(keys);
          ms = job->monitor;
        } else {
          ms = monitor_settings_without_job(keys);
        }
        Signal sig;
        sig.rate_hz = rate_hz;
        sig.samples = finite_vector(samples, "samples");
        MonitorReport r = run_released([&](const RunHooks&) {
          return analyze_signal(sig, ms, job ? &*job : nullptr, start_s);
        });
        py::dict out = from_json(monitor_json(r, "<array>", sig, ms));
        py::dict windows;
        windows["t_s"] = to_array(std::move(r.kf.t_s));
        windows["rms_low"] = to_array(std::move(r.kf.rms_low));
        windows["rms_high"] = to_array(std::move(r.kf.rms_high));
        windows["k_f"] = to_array(std::move(r.kf.k_f));
        out["windows"] = windows;
        return out;
      },
      py::arg("samples"), py::arg("rate_hz"), py::kw_only(), py::arg("job") = py::none(),
      py::arg("start_s") = 0.0, py::arg("set") = py::none(),
      R"(The vibroacoustic monitor (Pivkin 2025): k_f = RMS(low band) / RMS(high band) per
window and per trochoid cycle, with flags. samples: one channel (float64, any unit) at
rate_hz (Hz); job: the cycle timing and the model's zones (without one the cycles come from
the signal's period); start_s: where the program starts in the recording (s); set:
{"monitor.key": value} overrides (bands low_min/low_max/high_min/high_max in Hz, order,
window in s). Returns the keys of `trochomill monitor --json`, "windows" (t_s, rms_low,
rms_high, k_f arrays).)");

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

  m.def(
      "texture_profile",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& z, double dx_mm,
         std::optional<double> lambda_c_mm, std::optional<double> lambda_s_mm, bool robust) {
        TextureEntry e;
        e.surface = "profile";
        const std::vector<double> heights = finite_vector(z, "z_mm");
        e.description = fmt::format("profile of {} points every {:g} mm", heights.size(), dx_mm);
        ProfileFilterOptions o;
        o.lambda_s_mm = lambda_s_mm;
        o.robust = robust;
        e.texture = run_released(
            [&](const RunHooks&) { return profile_texture(heights, dx_mm, lambda_c_mm, o); });
        py::dict out = first_surface(texture_json("<array>", {e}));
        out["profile"] = profile_arrays(e.texture);
        return out;
      },
      py::arg("z_mm"), py::arg("dx_mm"), py::kw_only(), py::arg("lambda_c_mm") = py::none(),
      py::arg("lambda_s_mm") = py::none(), py::arg("robust") = false,
      R"(Roughness and waviness of a profile (ISO 16610-21 Gaussian filter, ISO 21920-2
parameters), as `trochomill texture` reports a CSV profile: z_mm heights (mm) every dx_mm (mm);
lambda_c_mm the cut-off (default the ISO 21920-3 one for its Ra, found by iteration and
stated), lambda_s_mm the S-filter, robust the ISO 16610-31 robust filter. Returns the keys
of the CLI's JSON surface (ra_mm, rq_mm, rz_mm, rt_mm, rsm_mm, wa_mm, wt_mm, lambda_c_mm,
evaluation_length_mm, ...) and "profile": x_mm (along the input), roughness_mm (R profile)
and waviness_mm (W profile, the filter's mean line) over the evaluation length.)");

  m.def(
      "texture_areal",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& z, double dx_mm,
         double dy_mm, std::optional<double> s_mm, std::optional<double> l_mm,
         const std::string& form, int degree, std::optional<double> memory_limit_gb) {
        if (z.ndim() != 2) {
          throw InputError(fmt::format(
              "z_mm: a 2-D array (rows along y, columns along x), got {} dimensions", z.ndim()));
        }
        // An areal texture holds about 12 copies of the map at its peak (as the CLI counts).
        check_memory("texture_areal", static_cast<double>(z.size()) * 100.0 + 40e6, memory_limit_gb,
                     "evaluate a smaller map");
        HeightMap map;
        map.ny = static_cast<std::size_t>(z.shape(0));
        map.nx = static_cast<std::size_t>(z.shape(1));
        map.dx_mm = dx_mm;
        map.dy_mm = dy_mm;
        map.z_mm.assign(z.data(), z.data() + z.size());
        map.description =
            fmt::format("map of {} x {} points every {:g} x {:g} mm", map.nx, map.ny, dx_mm, dy_mm);
        check_height_map(map, "z_mm");
        ArealFilterOptions o;
        o.s_mm = s_mm;
        o.l_mm = l_mm;
        o.degree = degree;
        if (form == "plane") {
          o.form = FormRemoval::plane;
        } else if (form == "polynomial") {
          o.form = FormRemoval::polynomial;
        } else if (form == "none") {
          o.form = FormRemoval::none;
        } else {
          throw InputError(fmt::format("form '{}': plane, polynomial or none", form));
        }
        TextureEntry e;
        e.surface = "surface";
        e.description = map.description;
        e.areal = run_released([&](const RunHooks&) { return areal_texture(map, o); });
        return first_surface(texture_json("<array>", {e}));
      },
      py::arg("z_mm"), py::arg("dx_mm"), py::arg("dy_mm"), py::kw_only(),
      py::arg("s_mm") = py::none(), py::arg("l_mm") = py::none(), py::arg("form") = "plane",
      py::arg("degree") = 2, py::arg("memory_limit_gb") = py::none(),
      R"(Areal texture of a height map (ISO 16610-61 Gaussian filter, ISO 25178-2 parameters), as
`trochomill texture` reports an X3P surface: z_mm heights (mm) as (rows along y, columns
along x), every dx_mm along x and dy_mm along y; s_mm the S-filter's nesting index (default
none), l_mm the L-filter's (default the ISO 21920-3 cut-off for the S-L surface's Sa), form
the F-operator ("plane", "polynomial" of `degree`, "none"). Returns the keys of the CLI's
JSON surface: the S-F and S-L surfaces' Sa, Sq, Ssk, Sku, Sp, Sv, Sz (mm), Sdr (%), Sal (mm)
and Str, with the filters used. A simulation's floor (simulate(...)["floor"]) is such a map.)");

  m.def(
      "spectrum",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& samples,
         double rate_hz, int nfft, bool with_spectrogram) {
        if (!(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= 1e7)) {
          throw InputError(fmt::format("rate_hz must be in (0, 1e7] Hz, got {}", rate_hz));
        }
        if (nfft < 16 || nfft > (1 << 24)) {
          throw InputError(fmt::format("nfft must be in [16, 16777216], got {}", nfft));
        }
        Signal sig;
        sig.rate_hz = rate_hz;
        sig.samples = finite_vector(samples, "samples");
        Spectrum sp = run_released([&](const RunHooks&) { return welch(sig, nfft); });
        py::dict out;
        out["f_hz"] = to_array(std::move(sp.f_hz));
        out["psd_per_hz"] = to_array(std::move(sp.psd));
        if (with_spectrogram) {
          Spectrogram sg = run_released([&](const RunHooks&) { return spectrogram(sig, nfft); });
          const auto frames = static_cast<py::ssize_t>(sg.db.size());
          const auto bins = static_cast<py::ssize_t>(sg.f_hz.size());
          std::vector<double> db;
          db.reserve(static_cast<std::size_t>(frames * bins));
          for (const auto& row : sg.db) db.insert(db.end(), row.begin(), row.end());
          py::dict g;
          g["t_s"] = to_array(std::move(sg.t_s));
          g["f_hz"] = to_array(std::move(sg.f_hz));
          g["db"] = to_array(std::move(db), {frames, bins});
          out["spectrogram"] = g;
        }
        return out;
      },
      py::arg("samples"), py::arg("rate_hz"), py::kw_only(), py::arg("nfft") = 4096,
      py::arg("spectrogram") = false,
      R"(Welch power spectral density of one channel, as `trochomill spectrum` (to choose the
monitor's bands): samples (float64, any unit U) at rate_hz (Hz), nfft a power of two
(Hann windows, half overlap). Returns f_hz and psd_per_hz (U^2/Hz) arrays; with
spectrogram=True also "spectrogram": t_s (frame centres), f_hz and db (frames, bins:
20 log10 of the amplitude).)");

  m.def(
      "keys", [] { return from_json(job_keys_json()); },
      R"(Every key of the job file, as `trochomill keys --json`: a list of dicts with section,
key, type, unit, allowed (range or choices), default and doc.)");

  m.def(
      "materials", [] { return from_json(materials_json(material_library())); },
      R"(The materials library (force model coefficients with their sources), as `trochomill
materials --json`: a list of dicts; a job names one with [material] name.)");

  m.def(
      "schedule_feed",
      [](const py::object& job_or_path, std::optional<double> h_max_mm,
         std::optional<double> mrr_mm3_per_min, std::optional<double> min_feed_mm_per_min,
         std::optional<double> max_feed_mm_per_min, std::optional<double> air_feed_mm_per_min,
         double feed_step_percent, double piece_mm, const py::object& progress) {
        const PyJob& pj = job_of(job_or_path, "schedule_feed");
        const ToolPath path = path_of(job_or_path);
        const FeedTargets t =
            feed_targets(pj.job, h_max_mm, mrr_mm3_per_min, min_feed_mm_per_min,
                         max_feed_mm_per_min, air_feed_mm_per_min, feed_step_percent, piece_mm);
        FeedSchedule fs = run_released(
            [&](const RunHooks& h) { return schedule_feed(pj.job, path, t, h); }, progress);
        PyPath p;
        p.path = std::move(fs.path);
        p.cycles = static_cast<int>(p.path.cycles().size());
        p.source = py::isinstance<PyPath>(job_or_path) ? job_or_path.cast<const PyPath&>().source
                                                       : std::string("plan");
        p.job = std::make_shared<const PyJob>(pj);
        py::dict out;
        out["path"] = std::move(p);
        out["time_before_s"] = fs.time_before_s;
        out["time_after_s"] = fs.time_after_s;
        out["h_max_before_mm"] = fs.h_max_before_mm;
        out["h_max_after_mm"] = fs.h_max_after_mm;
        out["pieces"] = fs.pieces;
        std::vector<std::int32_t> limit(fs.piece_limit.size());
        for (std::size_t i = 0; i < limit.size(); ++i)
          limit[i] = static_cast<std::int32_t>(fs.piece_limit[i]);
        out["piece_h_max_mm"] = to_array(std::move(fs.piece_h_max_mm));
        out["piece_feed_mm_per_min"] = to_array(std::move(fs.piece_feed_mm_per_min));
        out["piece_limit"] = to_array(std::move(limit));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("h_max_mm") = py::none(),
      py::arg("mrr_mm3_per_min") = py::none(), py::arg("min_feed_mm_per_min") = py::none(),
      py::arg("max_feed_mm_per_min") = py::none(), py::arg("air_feed_mm_per_min") = py::none(),
      py::arg("feed_step_percent") = 5.0, py::arg("piece_mm") = 0.5,
      py::arg("progress") = py::none(),
      R"(Chip-load feed scheduling, as `plan --feed-schedule` (docs/models.md section 15): each
piece of the path (at most piece_mm long) fed so that its largest chip is h_max_mm (default
the job's feed per tooth) and its removal rate at most mrr_mm3_per_min where given, within
min_feed_mm_per_min and max_feed_mm_per_min (default the
job's machine.min_feed and max_feed, else a tenth and three times its feed),
air_feed_mm_per_min where the tool cuts nothing (default machine.air_feed, else the max
feed), neighbouring pieces within feed_step_percent sharing the slower feed. job: a
Job (its planned path) or a Path. Returns "path" (the scheduled Path: path.gcode() is the
program), time_before_s, time_after_s, h_max_before_mm, h_max_after_mm, pieces, and per
feed piece piece_h_max_mm, piece_feed_mm_per_min and piece_limit (int32: 0 none, 1 min
feed, 2 max feed, 3 air, 4 plunge (kept at its feed), 5 removal cap).)");

  m.def(
      "optimize_feed",
      [](const std::string& program, const PyJob& pj, std::optional<double> h_max_mm,
         std::optional<double> mrr_mm3_per_min, std::optional<double> force_n,
         std::optional<double> power_w, std::optional<double> torque_nm,
         std::optional<double> min_feed_mm_per_min, std::optional<double> max_feed_mm_per_min,
         std::optional<double> air_feed_mm_per_min, double feed_step_percent, double piece_mm,
         const std::vector<std::string>& include_dirs, const std::string& engine,
         const std::optional<std::string>& stock, std::optional<int> rounds,
         const py::object& progress) {
        FeedOptimizeOptions o;
        if (engine != "kernel" && engine != "sim") {
          throw InputError(fmt::format(
              "optimize_feed: engine must be \"kernel\" or \"sim\", got \"{}\"", engine));
        }
        o.engine = engine == "sim" ? FeedEngine::sim : FeedEngine::kernel;
        if (stock) o.stock_mesh = std::make_shared<const Mesh>(read_mesh(*stock));
        if (rounds && (*rounds < 1 || *rounds > 100)) {
          throw InputError(fmt::format("optimize_feed: rounds must be 1 .. 100, got {}", *rounds));
        }
        o.targets =
            feed_targets(pj.job, h_max_mm, mrr_mm3_per_min, min_feed_mm_per_min,
                         max_feed_mm_per_min, air_feed_mm_per_min, feed_step_percent, piece_mm);
        o.force_n = force_n;
        o.power_w = power_w;
        o.torque_nm = torque_nm;
        o.read = gcode_options(pj.job.machine).read;
        for (const std::string& d : include_dirs) o.read.include_dirs.emplace_back(d);
        if (rounds) o.targets.iterations = *rounds;
        const std::string text = read_text_file(program);
        FeedOptimizeResult r = run_released(
            [&](const RunHooks& h) { return optimize_feed(pj.job, text, program, o, h); },
            progress);
        py::dict out = from_json(feed_summary_json(r));
        out["text"] = r.text;
        py::dict before, after;
        before["t_s"] = to_array(std::move(r.t_before_s));
        before["feed_mm_per_min"] = to_array(std::move(r.feed_before));
        before["h_max_mm"] = to_array(std::move(r.h_before));
        after["t_s"] = to_array(std::move(r.t_after_s));
        after["feed_mm_per_min"] = to_array(std::move(r.feed_after));
        after["h_max_mm"] = to_array(std::move(r.h_after));
        out["before"] = before;
        out["after"] = after;
        return out;
      },
      py::arg("program"), py::arg("job"), py::kw_only(), py::arg("h_max_mm") = py::none(),
      py::arg("mrr_mm3_per_min") = py::none(), py::arg("force_n") = py::none(),
      py::arg("power_w") = py::none(), py::arg("torque_nm") = py::none(),
      py::arg("min_feed_mm_per_min") = py::none(), py::arg("max_feed_mm_per_min") = py::none(),
      py::arg("air_feed_mm_per_min") = py::none(), py::arg("feed_step_percent") = 5.0,
      py::arg("piece_mm") = 0.5, py::arg("include_dirs") = std::vector<std::string>{},
      py::arg("engine") = "kernel", py::arg("stock") = py::none(), py::arg("rounds") = py::none(),
      py::arg("progress") = py::none(),
      R"(Feed optimisation of an NC program, as `trochomill optimize-feed PROGRAM --job JOB`
(docs/models.md section 15): program is the file's path, job a Job; the targets as
schedule_feed's plus force_n (N), power_w (W) and torque_nm (N m) caps from the job's
[material] model; include_dirs are searched for subroutine files; engine "kernel" (the
exact engagement, 2.5D programs) or "sim" (the tri-dexel simulation at the job's
[simulation] resolution: any motion); stock a closed mesh file (STL, PLY, OBJ; mm, the
program's frame) instead of the job's box; rounds of evaluation (default 12). Returns the summary of
`--json` (times, quantiles of h_max, removal rate and forces before and after, shares of
feed time by limit, blocks where the target cannot be held, warnings), "text" (the
rewritten program) and "before"/"after": per cutting sample t_s, feed_mm_per_min and
h_max_mm arrays.)");

  m.def(
      "synth_signal",
      [](const PyJob& pj, double rate_hz, int cycles, double kf_czi, double kf_czii,
         double kf_cziii, double wear_drift, double noise, double lead_s, std::uint32_t seed,
         std::optional<double> memory_limit_gb) {
        struct Range {
          const char* name;
          double v, lo, hi;
          bool open_lo;
        };
        for (const Range& r :
             {Range{"rate_hz", rate_hz, 0, 1e7, true},
              Range{"cycles", static_cast<double>(cycles), 1, 100000, false},
              Range{"kf_czi", kf_czi, 0, 100, true}, Range{"kf_czii", kf_czii, 0, 100, true},
              Range{"kf_cziii", kf_cziii, 0, 100, true},
              Range{"wear_drift", wear_drift, 0, 100, false}, Range{"noise", noise, 0, 100, false},
              Range{"lead_s", lead_s, 0, 1e4, false}}) {
          if (!(std::isfinite(r.v) && (r.open_lo ? r.v > r.lo : r.v >= r.lo) && r.v <= r.hi)) {
            throw InputError(fmt::format("{} must be in {}{}, {}], got {}", r.name,
                                         r.open_lo ? "(" : "[", r.lo, r.hi, r.v));
          }
        }
        SynthOptions o;
        o.rate_hz = rate_hz;
        o.cycles = cycles;
        o.kf_czi = kf_czi;
        o.kf_czii = kf_czii;
        o.kf_cziii = kf_cziii;
        o.wear_drift = wear_drift;
        o.noise = noise;
        o.lead_s = lead_s;
        o.seed = seed;
        check_memory(
            "synth_signal", synth_signal_memory_bytes(pj.job, o), memory_limit_gb,
            fmt::format("lower rate_hz (now {:g} Hz) or cycles (now {})", rate_hz, cycles));
        int covered = 0;
        Signal sig = run_released(
            [&](const RunHooks&) { return synth_signal(pj.job, pj.job.monitor, o, &covered); });
        py::dict out;
        out["rate_hz"] = sig.rate_hz;
        out["cycles"] = covered;
        out["start_s"] = lead_s;
        out["samples"] = to_array(std::move(sig.samples));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("rate_hz") = 100000.0, py::arg("cycles") = 12,
      py::arg("kf_czi") = 1.6, py::arg("kf_czii") = 1.15, py::arg("kf_cziii") = 1.0,
      py::arg("wear_drift") = 0.0, py::arg("noise") = 0.02, py::arg("lead_s") = 0.1,
      py::arg("seed") = 1, py::arg("memory_limit_gb") = py::none(),
      R"(A synthetic vibroacoustic signal following the model's zones, as `trochomill
synth-signal` writes it: per cycle of the steady trochoid, noise bands whose RMS ratio is
k_f of the zone (kf_czi, kf_czii, kf_cziii), a wear drift (k_f x (1 + wear_drift) by the last
cycle), white noise (RMS relative to cutting), lead_s (s) of air before the program.
Returns {"samples": float64 array, "rate_hz", "cycles" (covered), "start_s"}.)");
}

}  // namespace trochomill::python
