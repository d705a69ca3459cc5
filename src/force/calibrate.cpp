// Calibration of the force models: bounded nonlinear least squares against measured forces
// (Ceres, in the plugin least_squares.hpp describes), and the classical mean-force regression of
// the linear model (force.hpp; docs/models.md section 12).
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>

#include "least_squares.hpp"
#include "trochomill/common/plugin.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/io.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

// ------------------------------------------------------------------ CSV

// A numeric table with the named columns (';' and tab separators and quotes accepted).
CsvTable read_table(const std::filesystem::path& file, const std::vector<std::string>& wanted) {
  CsvOptions o;
  o.columns = wanted;
  o.detect_separator = true;
  return parse_csv(read_text_file(file), file.string(), o);
}

// ------------------------------------------------------------------ parameters

struct ParamSpec {
  const char* name;
  double lo, hi, scale, fallback;
};

const std::vector<ParamSpec>& specs() {
  static const std::vector<ParamSpec> s = {{"k_c", 1.0, 1e5, 1000, 2000},
                                           {"k_n", -1e5, 1e5, 1000, 500},
                                           {"m", 0.0, 0.95, 1, 0.25},
                                           {"m_n", 0.0, 0.95, 1, 0.25},
                                           {"k_a", -1e5, 1e5, 1000, 0},
                                           {"m_a", 0.0, 0.95, 1, 0.25},
                                           {"k_tc", 1.0, 1e5, 1000, 1000},
                                           {"k_rc", -1e5, 1e5, 1000, 300},
                                           {"k_ac", -1e5, 1e5, 1000, 100},
                                           {"k_te", -1e4, 1e4, 10, 10},
                                           {"k_re", -1e4, 1e4, 10, 10},
                                           {"k_ae", -1e4, 1e4, 10, 1},
                                           {"runout_radial", 0.0, 0.2, 0.01, 0.005},
                                           {"runout_axial", -0.2, 0.2, 0.01, 0},
                                           {"runout_phase", -360, 360, 90, 0}};
  return s;
}

const ParamSpec& spec(const std::string& name) {
  for (const auto& s : specs()) {
    if (name == s.name) return s;
  }
  std::string all;
  for (const auto& s : specs()) all += (all.empty() ? "" : ", ") + std::string(s.name);
  throw InputError(
      fmt::format("{}: unknown parameter '{}' (one of {})", option_name("fit"), name, all));
}

// The coefficient named n (nullptr for the exponents m_n, m_a and the runout); const or not
// as the material is.
template <class M>
auto* material_field(M& m, const std::string& n) {
  if (n == "k_c") return &m.k_c;
  if (n == "k_n") return &m.k_n;
  if (n == "m") return &m.m;
  if (n == "k_a") return &m.k_a;
  if (n == "k_tc") return &m.k_tc;
  if (n == "k_rc") return &m.k_rc;
  if (n == "k_ac") return &m.k_ac;
  if (n == "k_te") return &m.k_te;
  if (n == "k_re") return &m.k_re;
  if (n == "k_ae") return &m.k_ae;
  return static_cast<decltype(&m.k_c)>(nullptr);
}

bool belongs(ForceModel model, const std::string& n) {
  if (n.rfind("runout_", 0) == 0) return true;
  if (model == ForceModel::linear) return n.size() == 4 && n.rfind("k_", 0) == 0;
  if (n == "k_c" || n == "k_n" || n == "m") return true;
  return model == ForceModel::kienzle && (n == "m_n" || n == "k_a" || n == "m_a");
}

double get_param(const Material& m, const Tool& t, const std::string& n) {
  if (n == "m_n") return m.m_n.value_or(m.m);
  if (n == "m_a") return m.m_a.value_or(m.m);
  if (n == "runout_radial") return t.runout_radial_mm;
  if (n == "runout_axial") return t.runout_axial_mm;
  if (n == "runout_phase") return t.runout_phase_deg;
  return *material_field(m, n);
}

void set_param(Material& m, Tool& t, const std::string& n, double v) {
  if (n == "m_n")
    m.m_n = v;
  else if (n == "m_a")
    m.m_a = v;
  else if (n == "runout_radial")
    t.runout_radial_mm = v;
  else if (n == "runout_axial")
    t.runout_axial_mm = v;
  else if (n == "runout_phase")
    t.runout_phase_deg = v;
  else
    *material_field(m, n) = v;
}

double interp(const std::vector<double>& t, const std::vector<double>& y, double x) {
  if (x <= t.front()) return y.front();
  if (x >= t.back()) return y.back();
  const auto it = std::upper_bound(t.begin(), t.end(), x);
  const auto j = static_cast<std::size_t>(it - t.begin());
  const double f = (x - t[j - 1]) / (t[j] - t[j - 1]);
  return y[j - 1] + f * (y[j] - y[j - 1]);
}

// interp for times that mostly grow from one call to the next (the model's steps against the
// record): the sample pair is searched forward from the last one, a binary search only when
// the time goes back or jumps ahead. The same pair as std::upper_bound's and the same arithmetic,
// so interp's values to the last bit; several series on the same times share the search.
class ForwardInterp {
 public:
  explicit ForwardInterp(const std::vector<double>& t) : t_(t) {}
  // Moves to time x; then value(y) is interp(t, y, x).
  void seek(double x) {
    x_ = x;
    if (x <= t_.front() || x >= t_.back()) return;
    // Back in time, or more than a few samples ahead (the first seek, a jump): binary search.
    if (!(t_[hi_ - 1] <= x) || (hi_ + kWalk < t_.size() && t_[hi_ + kWalk] <= x))
      hi_ = static_cast<std::size_t>(std::upper_bound(t_.begin(), t_.end(), x) - t_.begin());
    while (t_[hi_] <= x) ++hi_;
    w_ = (x - t_[hi_ - 1]) / (t_[hi_] - t_[hi_ - 1]);
  }
  double value(const std::vector<double>& y) const {
    if (x_ <= t_.front()) return y.front();
    if (x_ >= t_.back()) return y.back();
    return y[hi_ - 1] + w_ * (y[hi_] - y[hi_ - 1]);
  }

 private:
  static constexpr std::size_t kWalk = 8;
  const std::vector<double>& t_;
  std::size_t hi_ = 1;  // t_[hi_ - 1] <= x_ < t_[hi_] inside the record
  double x_ = 0, w_ = 0;
};

// ------------------------------------------------------------------ the model

// How much a record sampled every dt_s, without a low-pass filter ahead of the sampler, differs
// from the force after the fit's filter: the model's own forces f (x, y, z at the times t)
// taken at every dt_s and filtered at that rate, against the same forces filtered at the
// model's rate, relative RMS over the three axes. The force jumps where a tooth enters or
// leaves the cut alias into the band below the cutoff when the record is coarse: a record
// made that way biases the coefficients (k_c -3.4 % at 96 steps per revolution on the
// Bergmann example, -1.1 % at 192, none at 500; the measure is then 9 %, 4 % and 1.6 %).
// `smooth`: f filtered at the model's rate (once, by the caller).
double aliasing_share(const std::array<std::vector<double>, 3>& f,
                      const std::array<std::vector<double>, 3>& smooth,
                      const std::vector<double>& t, double dt_s, double cutoff_hz) {
  const auto n = static_cast<std::size_t>((t.back() - t.front()) / dt_s) + 1;
  if (n < 16) return 0;
  const Sos coarse = butter_lowpass(4, cutoff_hz, 1.0 / dt_s);
  double diff = 0, norm = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    const std::vector<double>& axis = f[a];
    std::vector<double> sampled(n);
    for (std::size_t k = 0; k < n; ++k)
      sampled[k] = interp(t, axis, t.front() + static_cast<double>(k) * dt_s);
    sampled = sosfiltfilt(coarse, sampled);
    for (std::size_t k = 0; k < n; ++k) {
      const double ref = interp(t, smooth[a], t.front() + static_cast<double>(k) * dt_s);
      diff += (sampled[k] - ref) * (sampled[k] - ref);
      norm += ref * ref;
    }
  }
  return norm > 0 ? std::sqrt(diff / norm) : 0.0;
}

// A warning when the record is coarse enough for that difference to pass 2 %, with the rate
// (a power of two times the record's, at most the model's) where it falls below.
std::optional<std::string> aliasing_note(const std::array<std::vector<double>, 3>& f,
                                         const std::array<std::vector<double>, 3>& smooth,
                                         const std::vector<double>& t, double dt_meas_s,
                                         double cutoff_hz) {
  const double dt_model = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  if (!(dt_meas_s > 1.5 * dt_model)) return std::nullopt;
  constexpr double kLimit = 0.02;
  const double share = aliasing_share(f, smooth, t, dt_meas_s, cutoff_hz);
  if (share <= kLimit) return std::nullopt;
  double dt = dt_meas_s;
  double at = share;
  while (dt > 1.5 * dt_model && at > kLimit) {
    dt = std::max(dt / 2, dt_model);
    at = aliasing_share(f, smooth, t, dt, cutoff_hz);
  }
  if (at > kLimit) {
    return fmt::format(
        "the measured record ({:.0f} Hz) is coarse for the force's jumps at tooth entry and "
        "exit: the model sampled at that rate differs from it by {:.1f} % after the {:.0f} Hz "
        "filter, and still {:.1f} % at the model's own {:.0f} Hz: the fitted coefficients may "
        "be biased unless the record was low-pass filtered before it was sampled",
        1.0 / dt_meas_s, 100 * share, cutoff_hz, 100 * at, 1.0 / dt);
  }
  return fmt::format(
      "the measured record ({:.0f} Hz) is coarse for the force's jumps at tooth entry and "
      "exit: the model sampled at that rate differs from it by {:.1f} % after the {:.0f} Hz "
      "filter, and the fitted coefficients may be biased by as much unless the record was "
      "low-pass filtered before it was sampled; record at {:.0f} Hz or more (a record from "
      "`trochomill forces`: raise [forces] fast_steps_per_rev {:.0f} times)",
      1.0 / dt_meas_s, 100 * share, cutoff_hz, 1.0 / dt, dt_meas_s / dt);
}

class ForceProblem {
 public:
  ForceProblem(const Job& job, const ToolPath& path, const CalibrationOptions& o)
      : job_(job), path_(path), o_(o) {
    if (o.fast) {
      // At least 500 steps per tooth pass: the model's steps then come 50 times faster than
      // the default cutoff (10 tooth-passing harmonics), so where a tooth enters or leaves
      // the cut the sampled force's jump is placed within 2 % of the cutoff's period
      // (models.md section 12).
      const int spr = std::max(job.forces.fast_steps_per_rev, 500 * std::max(1, job.tool.teeth));
      fast_.emplace(job, path, o.from_s, o.to_s, spr, nullptr, o.hooks);
    }
  }
  // Later chips (the fit's runout changes) only heed Ctrl-C: the fit reports per iteration.
  void quiet() {
    o_.hooks.phase = {}, o_.hooks.progress = {};
    if (fast_) fast_->set_hooks(o_.hooks);
  }
  // The model's filtered forces for these coefficients and tool (x, y, z per step).
  std::array<std::vector<double>, 3> forces(const Material& m, const Tool& t,
                                            std::vector<double>* times = nullptr) {
    Job j = job_;
    j.tool = t;
    const SimTool tool = sim_tool(j, j.simulation);
    const bool same_tool = chips_ && t.runout_radial_mm == tool_.runout_radial_mm &&
                           t.runout_axial_mm == tool_.runout_axial_mm &&
                           t.runout_phase_deg == tool_.runout_phase_deg;
    if (!same_tool) {
      if (fast_) {
        chips_ = fast_->chips(tool);
      } else {
        SimControl control;
        control.hooks = o_.hooks;
        chips_ = simulate_job(j, path_, o_.from_s, o_.to_s, control).result;
        if (!chips_->complete) {
          chips_.reset();
          throw Interrupted("interrupted");
        }
      }
      tool_ = t;
      if (!grid_) grid_ = job_edge_grid(j, tool);
    }
    const SegmentForces model(m, *grid_, deg_to_rad(job_.forces.ploughing_angle_deg));
    const ForceSeries s = compute_forces(*chips_, tool, *grid_, model);
    if (times) *times = s.t_s;
    std::array<std::vector<double>, 3> out{s.fx_n, s.fy_n, s.fz_n};
    if (sos_) sosfiltfilt_three(*sos_, out);
    return out;
  }
  void set_filter(const Sos& sos) { sos_ = sos; }
  // forces() for the fit, by the scaled coefficients `key`: the last ones' are kept, as the
  // fit's derivative by the time shift asks for them again (the forces do not depend on the
  // shift: of nine evaluations a Jacobian, with central differences over three coefficients
  // and the shift, two).
  const std::array<std::vector<double>, 3>& forces_for(const std::vector<double>& key,
                                                       const Material& m, const Tool& t) {
    if (!last_key_ || *last_key_ != key) {
      last_key_.reset();  // not valid until computed (forces() may throw Interrupted)
      last_ = forces(m, t);
      last_key_ = key;
    }
    return last_;
  }

 private:
  const Job& job_;
  const ToolPath& path_;
  CalibrationOptions o_;
  std::optional<FastChipSource> fast_;
  std::optional<SimResult> chips_;
  std::optional<EdgeGrid> grid_;
  Tool tool_;
  std::optional<Sos> sos_;
  std::optional<std::vector<double>> last_key_;
  std::array<std::vector<double>, 3> last_;
};

struct Residuals {
  ForceProblem* problem;
  const Material* base_m;
  const Tool* base_t;
  const std::vector<std::string>* names;
  const std::vector<double>* scales;
  const std::vector<double>* tm;                   // model step times
  const std::vector<std::size_t>* idx;             // model steps compared
  const std::vector<double>* t_meas;               // measured times
  const std::array<std::vector<double>, 3>* meas;  // filtered measured forces
  double shift_scale = 1;
  // x[0]: the scaled parameters; x[1][0]: the time shift (s) / shift_scale.
  bool operator()(double const* const* x, double* r) const {
    Material m = *base_m;
    Tool t = *base_t;
    for (std::size_t i = 0; i < names->size(); ++i) {
      set_param(m, t, (*names)[i], x[0][i] * (*scales)[i]);
    }
    const double shift = x[1][0] * shift_scale;
    const std::array<std::vector<double>, 3>* fp = nullptr;
    try {
      fp = &problem->forces_for(std::vector<double>(x[0], x[0] + names->size()), m, t);
    } catch (const Interrupted&) {
      return false;  // Ctrl-C: the iteration callback stops the solver
    }
    const std::array<std::vector<double>, 3>& f = *fp;
    const std::size_t n = idx->size();
    ForwardInterp at(*t_meas);
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t j = (*idx)[k];
      at.seek((*tm)[j] + shift);
      for (std::size_t a = 0; a < 3; ++a) r[a * n + k] = f[a][j] - at.value((*meas)[a]);
    }
    return true;
  }
};

}  // namespace

MeasuredForces read_measured_forces(const std::filesystem::path& file,
                                    const ForceCsvFormat& format) {
  const CsvTable t = read_table(file, {format.time, format.fx, format.fy, format.fz});
  MeasuredForces m;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    const double ts = r[0] * format.time_to_s;
    if (!m.t_s.empty() && !(ts > m.t_s.back())) {
      throw InputError(
          fmt::format("{}:{}: time {} does not increase", file.string(), t.line_of_row[i], r[0]));
    }
    m.t_s.push_back(ts);
    m.fx_n.push_back(r[1] * format.force_to_n);
    m.fy_n.push_back(r[2] * format.force_to_n);
    m.fz_n.push_back(r[3] * format.force_to_n);
  }
  if (m.t_s.size() < 16) {
    throw InputError(fmt::format("{}: {} samples; need at least 16", file.string(), m.t_s.size()));
  }
  return m;
}

CalibrationResult calibrate_forces(const Job& job, const ToolPath& path,
                                   const MeasuredForces& measured,
                                   const CalibrationOptions& options) {
  CalibrationOptions o = options;
  if (!(o.to_s > o.from_s)) {
    throw InputError(fmt::format("calibrate: empty window {:g}..{:g} s", o.from_s, o.to_s));
  }
  // Parameters: the model's own by default.
  std::vector<std::string> names = o.fit;
  if (names.empty()) {
    names = o.model == ForceModel::linear
                ? std::vector<std::string>{"k_tc", "k_rc", "k_ac", "k_te", "k_re", "k_ae"}
                : std::vector<std::string>{"k_c", "k_n", "m"};
  }
  for (const auto& n : names) {
    (void)spec(n);
    if (!belongs(o.model, n)) {
      throw InputError(fmt::format("{}: '{}' is not a parameter of the {} model",
                                   option_name("fit"), n, to_string(o.model)));
    }
    if (std::count(names.begin(), names.end(), n) > 1) {
      throw InputError(fmt::format("{}: '{}' given twice", option_name("fit"), n));
    }
  }
  const bool has_phase = std::count(names.begin(), names.end(), "runout_phase") > 0;
  const bool has_radial = std::count(names.begin(), names.end(), "runout_radial") > 0;
  if (has_phase && has_radial && job.tool.teeth == 2 && job.tool.tooth_angles_deg.size() == 2 &&
      std::abs(std::abs(job.tool.tooth_angles_deg[1] - job.tool.tooth_angles_deg[0]) - 180) <
          1e-9) {
    throw InputError(
        option_name("fit") +
        ": runout_radial and runout_phase together are not identifiable on two opposite "
        "teeth (only e cos(phase) changes the chips); fit runout_radial alone");
  }
  // Start: the job's coefficients when it has this model, the defaults otherwise.
  Material m0 = job.material;
  if (!m0.model || *m0.model != o.model) {
    m0 = Material{};
    for (const auto& s : specs()) {
      if (material_field(m0, s.name) != nullptr && belongs(o.model, s.name)) {
        *material_field(m0, s.name) = s.fallback;
      }
    }
  }
  m0.model = o.model;
  Tool t0 = job.tool;
  for (const auto& n : names) {
    if (n == "runout_radial" && t0.runout_radial_mm == 0) t0.runout_radial_mm = spec(n).fallback;
  }

  ForceProblem problem(job, path, o);
  // Model time grid and rates.
  std::vector<double> tm;
  auto f0 = problem.forces(m0, t0, &tm);  // unfiltered here; filtered below
  if (tm.size() < 16) throw InputError("calibrate: the window holds fewer than 16 model steps");
  const double dt_model = (tm.back() - tm.front()) / static_cast<double>(tm.size() - 1);
  const double dt_meas =
      (measured.t_s.back() - measured.t_s.front()) / static_cast<double>(measured.t_s.size() - 1);
  const double tooth_hz = spindle_speed_rpm(job) / 60.0 * job.tool.teeth;
  double cutoff = o.cutoff_hz;
  const double nyq = 0.5 / std::max(dt_model, dt_meas);
  std::vector<std::string> warnings;
  if (cutoff <= 0) {
    cutoff = std::min(10 * tooth_hz, 0.8 * nyq);
    if (cutoff < 10 * tooth_hz) {
      // The force jumps at each tooth's entry and exit need the first ten tooth-passing
      // harmonics; below 0.8 of the Nyquist frequency that takes 25 samples per tooth pass.
      const double per_pass_meas = 1.0 / (dt_meas * tooth_hz);
      const double per_pass_model = 1.0 / (dt_model * tooth_hz);
      warnings.push_back(fmt::format(
          "the {} has {:.1f} samples per tooth pass, fewer than the 25 that resolve the force "
          "jumps at tooth entry and exit (10 harmonics of {:.1f} Hz): both signals are cut at "
          "{:.0f} Hz and the fitted coefficients may be biased; record at {:.0f} Hz or more{}",
          per_pass_meas <= per_pass_model ? "measured record" : "model",
          std::min(per_pass_meas, per_pass_model), tooth_hz, cutoff, 25 * tooth_hz,
          per_pass_meas <= per_pass_model ? "" : " (raise [forces] fast_steps_per_rev)"));
    }
  }
  if (!(cutoff < nyq)) {
    throw InputError(fmt::format(
        "calibrate: cutoff {:g} Hz must be below half the coarser sample rate ({:g} Hz)", cutoff,
        nyq));
  }
  const Sos sos_model = butter_lowpass(4, cutoff, 1.0 / dt_model);
  const Sos sos_meas = butter_lowpass(4, cutoff, 1.0 / dt_meas);
  problem.set_filter(sos_model);
  // The model's forces filtered as problem.forces filters from now on (the raw ones are kept
  // only for the aliasing check).
  std::array<std::vector<double>, 3> f0s = f0;
  sosfiltfilt_three(sos_model, f0s);
  // (Only where the cutoff was not lowered for the same coarse record: one warning of it.)
  if (warnings.empty()) {
    if (auto w = aliasing_note(f0, f0s, tm, dt_meas, cutoff)) warnings.push_back(*w);
  }
  f0 = std::move(f0s);
  std::array<std::vector<double>, 3> mf{measured.fx_n, measured.fy_n, measured.fz_n};
  sosfiltfilt_three(sos_meas, mf);
  // Alignment: the shift (measured time = model time + shift) maximising the correlation of
  // the resultants, at the model's step, refined by a parabola.
  const double max_shift = o.max_shift_s >= 0 ? o.max_shift_s : 30.0 / spindle_speed_rpm(job);
  const int ns = static_cast<int>(std::ceil(max_shift / dt_model));
  std::vector<double> res_model(tm.size());
  for (std::size_t k = 0; k < tm.size(); ++k) {
    res_model[k] = std::sqrt(f0[0][k] * f0[0][k] + f0[1][k] * f0[1][k] + f0[2][k] * f0[2][k]);
  }
  std::vector<double> res_meas(measured.t_s.size());
  for (std::size_t k = 0; k < res_meas.size(); ++k) {
    res_meas[k] = std::sqrt(mf[0][k] * mf[0][k] + mf[1][k] * mf[1][k] + mf[2][k] * mf[2][k]);
  }
  std::vector<double> score(static_cast<std::size_t>(2 * ns + 1), -2.0);
  for (int j = -ns; j <= ns; ++j) {
    const double sh = j * dt_model;
    double sxy = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
    int n = 0;
    ForwardInterp at(measured.t_s);
    for (std::size_t k = 0; k < tm.size(); ++k) {
      const double tt = tm[k] + sh;
      if (tt < measured.t_s.front() || tt > measured.t_s.back()) continue;
      at.seek(tt);
      const double x = res_model[k], y = at.value(res_meas);
      sxy += x * y, sx += x, sy += y, sxx += x * x, syy += y * y;
      ++n;
    }
    if (n < static_cast<int>(tm.size() / 2)) continue;
    const double cov = sxy - sx * sy / n, vx = sxx - sx * sx / n, vy = syy - sy * sy / n;
    score[static_cast<std::size_t>(j + ns)] = vx > 0 && vy > 0 ? cov / std::sqrt(vx * vy) : -2.0;
  }
  // The best score; among scores within 1e-3 of it (a periodic force repeats each
  // revolution) the smallest shift.
  const double top = *std::max_element(score.begin(), score.end());
  if (top <= -2.0) {
    throw InputError(fmt::format(
        "calibrate: the measurement ({:g}..{:g} s) overlaps less than half of the model window "
        "({:g}..{:g} s) at every shift within +-{:g} s; give the window it covers",
        measured.t_s.front(), measured.t_s.back(), tm.front(), tm.back(), max_shift));
  }
  int jb = ns;
  for (int d = 0, found = 0; d <= ns && found == 0; ++d) {
    for (const int j : {ns - d, ns + d}) {
      if (score[static_cast<std::size_t>(j)] >= top - 1e-3) {
        jb = j;
        found = 1;
        break;
      }
    }
  }
  const double* best = &score[static_cast<std::size_t>(jb)];
  double shift = (jb - ns) * dt_model;
  if (jb > 0 && jb + 1 < static_cast<int>(score.size()) &&
      score[static_cast<std::size_t>(jb - 1)] > -2 &&
      score[static_cast<std::size_t>(jb + 1)] > -2) {
    const double a = score[static_cast<std::size_t>(jb - 1)], b = *best,
                 c = score[static_cast<std::size_t>(jb + 1)];
    const double den = a - 2 * b + c;
    if (den < 0) shift += 0.5 * (a - c) / den * dt_model;
  }
  // The residual samples: model steps whose time, shifted by up to two model steps either
  // way, the measurement covers (the shift is refined with the coefficients).
  const double shift_span = 2 * dt_model;
  std::vector<std::size_t> idx;
  for (std::size_t k = 0; k < tm.size(); ++k) {
    if (tm[k] + shift - shift_span < measured.t_s.front() ||
        tm[k] + shift + shift_span > measured.t_s.back()) {
      continue;
    }
    idx.push_back(k);
  }
  const std::size_t p = names.size();
  if (idx.size() * 3 <= p + 2) throw InputError("calibrate: too few overlapping samples");

  std::vector<double> scales(p), x(p);
  for (std::size_t i = 0; i < p; ++i) {
    const ParamSpec& s = spec(names[i]);
    const double v0 = get_param(m0, t0, names[i]);
    scales[i] = std::max(s.scale, std::abs(v0));
    x[i] = std::clamp(v0, s.lo, s.hi) / scales[i];
  }
  double xs = 0;  // the shift's correction, in model steps
  Residuals fn{&problem, &m0, &t0, &names, &scales, &tm, &idx, &measured.t_s, &mf, dt_model};
  xs = shift / dt_model;
  force_detail::LeastSquaresCall call;
  call.blocks = {x.data(), &xs};
  call.block_sizes = {static_cast<int>(p), 1};
  call.lower = {std::vector<double>(p), {shift / dt_model - 2}};
  call.upper = {std::vector<double>(p), {shift / dt_model + 2}};
  for (std::size_t i = 0; i < p; ++i) {
    const ParamSpec& s = spec(names[i]);
    call.lower[0][i] = s.lo / scales[i];
    call.upper[0][i] = s.hi / scales[i];
  }
  call.residuals = static_cast<int>(3 * idx.size());
  call.fn = fn;
  call.max_iterations = 100;
  call.function_tolerance = 1e-10;
  call.parameter_tolerance = 1e-10;
  call.gradient_tolerance = 1e-12;
  // Reports the solver's iterations and stops it on Ctrl-C.
  call.keep_going = [&o, &call](int iteration) {
    if (o.hooks.cancelled()) return false;
    if (o.hooks.progress) {
      const auto max = static_cast<std::size_t>(call.max_iterations);
      o.hooks.progress(std::min(max, static_cast<std::size_t>(iteration)), max);
    }
    return true;
  };
  const auto& ceres = plugin_table<force_detail::CeresTable>("ceres", force_detail::kCeresSymbol,
                                                             "calibrate's fit (Ceres)");
  problem.quiet();
  o.hooks.begin("fit");
  const force_detail::LeastSquaresResult fit = ceres.solve(call);
  o.hooks.check();

  CalibrationResult out;
  out.material = m0;
  out.tool = t0;
  out.warnings = std::move(warnings);
  for (std::size_t i = 0; i < p; ++i) set_param(out.material, out.tool, names[i], x[i] * scales[i]);
  // Statistics at the optimum: residuals and Jacobian (scaled parameters).
  const std::vector<double>& rv = fit.residuals;
  const std::size_t nr = rv.size();
  const double shift_final = xs * dt_model;
  double ssr = 0, sst = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    std::vector<double> ma(idx.size());
    double mean = 0;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      ma[k] = interp(measured.t_s, mf[a], tm[idx[k]] + shift_final);
      mean += ma[k];
    }
    mean /= static_cast<double>(idx.size());
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const double r = rv[a * idx.size() + k];
      ssr += r * r;
      sst += (ma[k] - mean) * (ma[k] - mean);
    }
  }
  out.rmse_n = std::sqrt(ssr / static_cast<double>(nr));
  out.r2 = sst > 0 ? 1 - ssr / sst : 0.0;
  // Columns: the p parameters, then the shift (the covariance accounts for both).
  Eigen::MatrixXd J =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nr), static_cast<Eigen::Index>(p + 1));
  for (int r = 0; r < fit.jacobian_rows; ++r) {
    for (int k = fit.jacobian_row_starts[static_cast<std::size_t>(r)];
         k < fit.jacobian_row_starts[static_cast<std::size_t>(r + 1)]; ++k) {
      J(r, fit.jacobian_cols[static_cast<std::size_t>(k)]) =
          fit.jacobian_values[static_cast<std::size_t>(k)];
    }
  }
  const double s2 = ssr / static_cast<double>(nr - p - 1);
  const Eigen::MatrixXd cov =
      (J.transpose() * J).completeOrthogonalDecomposition().pseudoInverse() * s2;
  for (std::size_t i = 0; i < p; ++i) {
    const ParamSpec& s = spec(names[i]);
    FittedParameter fp;
    fp.name = names[i];
    fp.value = x[i] * scales[i];
    fp.std_error =
        std::sqrt(std::max(0.0, cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)))) *
        scales[i];
    fp.ci95_lo = fp.value - 1.959964 * fp.std_error;
    fp.ci95_hi = fp.value + 1.959964 * fp.std_error;
    const double span = s.hi - s.lo;
    fp.at_bound = fp.value - s.lo < 1e-9 * span || s.hi - fp.value < 1e-9 * span;
    out.parameters.push_back(fp);
  }
  out.shift_s = shift_final;
  out.cutoff_hz = cutoff;
  out.samples = idx.size();
  out.iterations = fit.iterations;
  out.report = fit.report;
  out.material.source =
      fmt::format("trochomill calibrate: RMSE {:.3g} N, R^2 {:.4f}", out.rmse_n, out.r2);
  return out;
}

double estimate_calibration_memory(const Job& job, const ToolPath& path,
                                   const CalibrationOptions& o, std::size_t measured_samples) {
  Job j = job;
  if (o.fast) {
    // The fast source's steps (as ForceProblem sets them) in place of the simulation's.
    j.simulation.steps_per_rev =
        std::max(job.forces.fast_steps_per_rev, 500 * std::max(1, job.tool.teeth));
  }
  const MemoryEstimate sim = estimate_simulation_memory(j, path, o.from_s, o.to_s);
  const double steps =
      (o.to_s - o.from_s) * spindle_speed_rpm(job) / 60.0 * j.simulation.steps_per_rev;
  const double params = o.fit.empty() ? 6.0 : static_cast<double>(o.fit.size());
  // Per model step: t and three forces, twice (raw and filtered), three residuals with their
  // Jacobian rows (held twice by the solver).
  const double model = steps * (8.0 * 8 + 3 * (8.0 + 2 * 8.0 * params));
  // The record: t and three forces, their filtered copies and the resultant.
  const double record = static_cast<double>(measured_samples) * 8.0 * 9;
  const double chips = o.fast ? sim.records_bytes : sim.total(false) - sim.base_bytes;
  // Measured (VmHWM, bergmann2021 --fast, 4 and 16 s windows: 116 and 238 MB): the process
  // with Ceres holds 75 MB, and the terms above come to 1.2 times their sum.
  return 75e6 + 1.2 * (chips + model + record);
}

std::string material_toml(const CalibrationResult& r) {
  const Material& m = r.material;
  std::string s = "[material]\n";
  s += fmt::format("model = \"{}\"\n", to_string(*m.model));
  const auto line = [&](const std::string& key, double v, const char* unit) {
    std::string ci;
    for (const auto& p : r.parameters) {
      if (p.name == key) {
        ci = fmt::format("  # {}, 95 % CI [{:.6g}, {:.6g}]{}", unit, p.ci95_lo, p.ci95_hi,
                         p.at_bound ? " (at its bound)" : "");
      }
    }
    if (ci.empty()) ci = fmt::format("  # {} (not fitted)", unit);
    s += fmt::format("{} = {:.6g}{}\n", key, v, ci);
  };
  if (*m.model == ForceModel::linear) {
    line("k_tc", m.k_tc, "N/mm^2");
    line("k_rc", m.k_rc, "N/mm^2");
    line("k_ac", m.k_ac, "N/mm^2");
    line("k_te", m.k_te, "N/mm");
    line("k_re", m.k_re, "N/mm");
    line("k_ae", m.k_ae, "N/mm");
  } else {
    line("k_c", m.k_c, "N/mm^2");
    line("k_n", m.k_n, "N/mm^2");
    line("m", m.m, "-");
    if (*m.model == ForceModel::kienzle) {
      line("m_n", m.m_n.value_or(m.m), "-");
      line("k_a", m.k_a, "N/mm^2");
      line("m_a", m.m_a.value_or(m.m), "-");
    }
  }
  s += fmt::format("source = \"{}\"\n", m.source);
  for (const auto& p : r.parameters) {
    if (p.name.rfind("runout_", 0) == 0) {
      s += fmt::format("# fitted [tool] {} = {:.6g}  # 95 % CI [{:.6g}, {:.6g}]\n", p.name, p.value,
                       p.ci95_lo, p.ci95_hi);
    }
  }
  return s;
}

// ------------------------------------------------------------------ mean forces

std::vector<MeanForcePoint> read_mean_forces(const std::filesystem::path& file) {
  const CsvTable t = read_table(file, {"feed_per_tooth_mm", "f_x_n", "f_y_n", "f_z_n"});
  std::vector<MeanForcePoint> out;
  for (const auto& r : t.rows) out.push_back({r[0], r[1], r[2], r[3]});
  return out;
}

MeanForceFit fit_mean_forces(const Job& job, const std::vector<MeanForcePoint>& points) {
  if (points.size() < 2) {
    throw InputError(
        fmt::format("mean-force fit: need slot tests at 2 or more feeds, got {}", points.size()));
  }
  if (job.path.type != PathType::linear ||
      std::abs(job.slot.width_mm - job.tool.diameter_mm) > 1e-9 * job.tool.diameter_mm) {
    throw InputError(fmt::format(
        "mean-force fit: the closed form holds for full-immersion straight slots; the job must "
        "have [path] type = \"linear\" and [slot] width = [tool] diameter ({} mm), got {} with "
        "width {} mm (e.g. path.type = \"linear\" and slot.width = {})",
        job.tool.diameter_mm, to_string(job.path.type), job.slot.width_mm, job.tool.diameter_mm));
  }
  double fmin = 1e300, fmax = -1e300;
  for (const auto& p : points)
    fmin = std::min(fmin, p.feed_per_tooth_mm), fmax = std::max(fmax, p.feed_per_tooth_mm);
  if (!(fmax > fmin)) throw InputError("mean-force fit: the feeds per tooth must differ");
  MeanForceFit r;
  for (int a = 0; a < 3; ++a) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    const double n = static_cast<double>(points.size());
    for (const auto& p : points) {
      const double y = a == 0 ? p.fx_n : a == 1 ? p.fy_n : p.fz_n;
      sx += p.feed_per_tooth_mm, sy += y, sxx += p.feed_per_tooth_mm * p.feed_per_tooth_mm;
      sxy += p.feed_per_tooth_mm * y, syy += y * y;
    }
    const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    const double off = (sy - slope * sx) / n;
    const double sst = syy - sy * sy / n;
    double ssr = 0;
    for (const auto& p : points) {
      const double y = a == 0 ? p.fx_n : a == 1 ? p.fy_n : p.fz_n;
      ssr += (y - slope * p.feed_per_tooth_mm - off) * (y - slope * p.feed_per_tooth_mm - off);
    }
    r.slope[static_cast<std::size_t>(a)] = slope;
    r.offset[static_cast<std::size_t>(a)] = off;
    r.r2[static_cast<std::size_t>(a)] = sst > 0 ? 1 - ssr / sst : 1.0;
  }
  // Full-immersion straight slot, Z teeth, depth a, cw spindle (models.md section 12):
  // mean F_x = s (Z a / 4) K_tc f + s (Z a / pi) K_te with s = +1 (cw) or -1 (ccw),
  // mean F_y = (Z a / 4) K_rc f + (Z a / pi) K_re,
  // mean F_z = (Z a / pi) K_ac f + (Z a / 2) K_ae.
  const double za = job.tool.teeth * job.slot.depth_mm;
  const double sgn = job.cutting.spindle_direction == SpindleDirection::cw ? 1.0 : -1.0;
  Material& m = r.material;
  m.model = ForceModel::linear;
  m.k_tc = sgn * 4 * r.slope[0] / za;
  m.k_te = sgn * kPi * r.offset[0] / za;
  m.k_rc = 4 * r.slope[1] / za;
  m.k_re = kPi * r.offset[1] / za;
  m.k_ac = kPi * r.slope[2] / za;
  m.k_ae = 2 * r.offset[2] / za;
  m.source = fmt::format("mean-force fit of {} slot tests, R^2 {:.4f} {:.4f} {:.4f}", points.size(),
                         r.r2[0], r.r2[1], r.r2[2]);
  return r;
}

}  // namespace trochomill
