// Process metrics of a slot program: see include/trochomill/analysis.hpp.
#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <optional>

#include "common/roots.hpp"
#include "trochomill/analysis.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// The steady-state window [first, last) of the engagement series, with its exact duration.
struct Window {
  std::size_t first = 0, last = 0;
  double t0_s = 0, duration_s = 0, length_mm = 0;
  bool periodic = false;
  bool operator==(const Window&) const = default;
};

// Cubic Hermite interpolation between samples i and i + 1 of a path at fraction f: positions
// and unit tangents times the chord h (exact at the samples, O(h^4 kappa^3) between them).
struct Hermite {
  double h00, h10, h01, h11;
  explicit Hermite(double f)
      : h00((1 + 2 * f) * (1 - f) * (1 - f)),
        h10(f * (1 - f) * (1 - f)),
        h01(f * f * (3 - 2 * f)),
        h11(f * f * (f - 1)) {}
  // One coordinate: positions p and tangent components t of the samples i and i + 1.
  [[nodiscard]] double at(const std::vector<double>& p, const std::vector<double>& t, std::size_t i,
                          double h) const {
    return h00 * p[i] + h10 * h * t[i] + h01 * p[i + 1] + h11 * h * t[i + 1];
  }
};

// How far the point q (mm) lies from the centre path at time t (s), less what the samples
// cannot resolve: between two samples on one path segment, the distance to the cubic Hermite
// interpolation on positions and unit tangents times the chord (exact at the samples,
// O(h^4 kappa^3) between them, e.g. below 1e-9 mm at h = f_z); across a corner of the
// program (a chorded arc, another feed), the distance to the chord between the samples less
// its sag, at most h |turn| / 4. nullopt outside the samples or at a sharp corner (> 45 deg).
std::optional<double> path_deviation_mm(const PathSamples& s, double t,
                                        const std::array<double, 3>& q) {
  const auto it = std::upper_bound(s.t_s.begin(), s.t_s.end(), t);
  if (it == s.t_s.begin() || it == s.t_s.end()) return std::nullopt;
  const auto j = static_cast<std::size_t>(it - s.t_s.begin()), i = j - 1;
  if (!(s.t_s[j] > s.t_s[i])) return std::nullopt;
  const double h = s.s_mm[j] - s.s_mm[i];
  if (s.segment[i] == s.segment[j]) {
    const Hermite w((t - s.t_s[i]) / (s.t_s[j] - s.t_s[i]));
    const double x = w.at(s.x_mm, s.tx, i, h), y = w.at(s.y_mm, s.ty, i, h),
                 z = w.at(s.z_mm, s.tz, i, h);
    return std::sqrt((x - q[0]) * (x - q[0]) + (y - q[1]) * (y - q[1]) + (z - q[2]) * (z - q[2]));
  }
  const double cosang =
      std::clamp(s.tx[i] * s.tx[j] + s.ty[i] * s.ty[j] + s.tz[i] * s.tz[j], -1.0, 1.0);
  const double turn = std::acos(cosang);
  if (turn > 0.25 * std::numbers::pi) return std::nullopt;
  const double ex = s.x_mm[j] - s.x_mm[i], ey = s.y_mm[j] - s.y_mm[i], ez = s.z_mm[j] - s.z_mm[i];
  const double ee = ex * ex + ey * ey + ez * ez;
  const double u =
      ee > 0
          ? std::clamp(
                ((q[0] - s.x_mm[i]) * ex + (q[1] - s.y_mm[i]) * ey + (q[2] - s.z_mm[i]) * ez) / ee,
                0.0, 1.0)
          : 0.0;
  const double dx = s.x_mm[i] + u * ex - q[0], dy = s.y_mm[i] + u * ey - q[1],
               dz = s.z_mm[i] + u * ez - q[2];
  return std::max(0.0, std::sqrt(dx * dx + dy * dy + dz * dz) - 0.25 * h * turn);
}

// Whether the cutting part of the path [c0, c1] repeats itself shifted by (0, step, 0) after
// `period` seconds, checked sample by sample over a stretch around sample i0 that holds at least
// one period and a full turn (2 pi) of the tangent (turn_s: full_turn_s), from i0 on: a true cycle
// passes everywhere; a shorter candidate (one step of path along a loop's side) leaves the shifted
// path as soon as the path bends. The tolerance is a quarter step (the candidate's offset turned by
// the bend is up to twice the step away) and at most 0.01 mm (a program's coordinate rounding, a
// few um, passes). The time (s) the tangent takes from sample i0 to turn by 2 pi in all (nullopt:
// it does not within the cutting part, up to c1).
std::optional<double> full_turn_s(const PathSamples& s, std::size_t i0, std::size_t c1) {
  double turned = 0;
  for (std::size_t i = i0 + 1; i <= c1; ++i) {
    turned += std::abs(std::atan2(s.tx[i - 1] * s.ty[i] - s.ty[i - 1] * s.tx[i],
                                  s.tx[i - 1] * s.tx[i] + s.ty[i - 1] * s.ty[i]));
    if (turned >= kTwoPi) return s.t_s[i] - s.t_s[i0];
  }
  return std::nullopt;
}

bool repeats_with_period(const PathSamples& s, std::size_t c0, std::size_t c1, std::size_t i0,
                         double turn_s, double period, double step_mm) {
  const double tol = std::min(0.01, 0.25 * step_mm);
  // The stretch to check: a full turn of the tangent from i0, and at least one period.
  const double span = std::max(period, turn_s);
  // From i0 on (the cycle starts there; before it may lie an entry), within the cutting part,
  // the shifted copy inside it too.
  const double lo = s.t_s[c0], hi = s.t_s[c1] - period;
  if (hi - lo < span) return false;
  const double from = std::clamp(s.t_s[i0], lo, hi - span), to = from + span;
  std::size_t checked = 0, total = 0;
  for (auto i = static_cast<std::size_t>(std::lower_bound(s.t_s.begin(), s.t_s.end(), from) -
                                         s.t_s.begin());
       i < s.size() && s.t_s[i] <= to; ++i) {
    const auto d =
        path_deviation_mm(s, s.t_s[i] + period, {s.x_mm[i], s.y_mm[i] + step_mm, s.z_mm[i]});
    ++total;
    if (!d) continue;
    if (*d > tol) return false;
    ++checked;
  }
  return checked > 0 && 2 * checked >= total;  // most of the stretch checked
}

// The first sample at this share of the cutting time [c0, c1].
std::size_t cutting_middle(const PathSamples& s, std::size_t c0, std::size_t c1, double at) {
  const double t_mid = s.t_s[c0] + at * (s.t_s[c1] - s.t_s[c0]);
  std::size_t mid = c0;
  while (mid < c1 && s.t_s[mid] < t_mid) ++mid;
  return mid;
}

// The start of cutting at or after sample `mid` (else `mid` itself) among the first `known`
// samples' flags, nullopt while they cannot tell yet. `next` (start it at max(mid, 1)) is where
// the search goes on: a caller whose flags grow scans each sample once.
std::optional<std::size_t> cutting_start(const std::vector<char>& cutting, std::size_t mid,
                                         std::size_t c1, std::size_t known, std::size_t& next) {
  for (; next <= c1; ++next) {
    if (next >= known) return std::nullopt;
    if (cutting[next] && !cutting[next - 1]) return next;
  }
  if (c1 >= known) return std::nullopt;
  return mid;
}

// The cycle from sample i0 on, if the cutting part [c0, c1] of the path repeats itself with the
// step there.
std::optional<Window> cycle_from(const PathSamples& s, std::size_t c0, std::size_t c1,
                                 std::size_t i0, double step_mm) {
  const std::size_t n = s.size();
  // The same point one step further along +Y, passed in the same direction: every
  // approach to it is a candidate period, the shortest one the path repeats itself over
  // is the cycle (docs/models.md section 8, the steady cycle). A nearer approach after a
  // short stretch of path is no cycle: where the path runs along +Y (a loop's side, a
  // circular family's advance) the shifted point comes by one step later on the same pass.
  const double tx = s.x_mm[i0], ty = s.y_mm[i0] + step_mm;
  double spacing = 0;
  for (std::size_t i = i0 + 1; i < std::min(n, i0 + 64); ++i) {
    spacing = std::max(spacing, std::hypot(s.x_mm[i] - s.x_mm[i - 1], s.y_mm[i] - s.y_mm[i - 1]));
  }
  std::size_t best = n;
  double best_d = std::numeric_limits<double>::infinity();
  const std::optional<double> turn_s = full_turn_s(s, i0, c1);  // once per start
  const auto try_candidate = [&](std::size_t j) -> std::optional<Window> {
    if (s.z_mm[j] >= 0) return std::nullopt;
    // Refine along the tangent: the point is reached at t + (target - p).t / v.
    const double v = (s.s_mm[j] - s.s_mm[j - 1]) / (s.t_s[j] - s.t_s[j - 1]);
    const double ds = (tx - s.x_mm[j]) * s.tx[j] + (ty - s.y_mm[j]) * s.ty[j];
    const double period = s.t_s[j] + ds / v - s.t_s[i0];
    if (!(period > 0) || !turn_s || !repeats_with_period(s, c0, c1, i0, *turn_s, period, step_mm)) {
      return std::nullopt;
    }
    Window w;
    w.first = i0;
    w.last = j;
    w.t0_s = s.t_s[i0];
    w.duration_s = period;
    w.length_mm = s.s_mm[j] + ds - s.s_mm[i0];
    w.periodic = true;
    return w;
  };
  for (std::size_t i = i0 + 1; i < n; ++i) {
    const double d = std::hypot(s.x_mm[i] - tx, s.y_mm[i] - ty);
    const double dir = s.tx[i] * s.tx[i0] + s.ty[i] * s.ty[i0];
    if (d <= spacing + 1e-9 && dir > 0.9 && d < best_d) {
      best = i;
      best_d = d;
    } else if (best < n && d > 2 * spacing + 1e-9) {
      // Past the nearest approach: a candidate.
      if (auto w = try_candidate(best)) return *w;
      best = n;
      best_d = std::numeric_limits<double>::infinity();
    }
  }
  if (best < n) {
    if (auto w = try_candidate(best)) return *w;
  }
  return std::nullopt;
}

Window find_window(const EngagementSeries& e, const std::vector<char>& cutting, double step_mm,
                   bool trochoidal) {
  const PathSamples& s = e.samples;
  const std::size_t n = s.size();
  std::size_t c0 = n, c1 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!cutting[i]) continue;
    c0 = std::min(c0, i);
    c1 = i;
  }
  // The cycle is looked for from the middle of the cutting time on, then later (a long entry,
  // a ramp down a deep slot, may take the first half).
  for (const double at : {0.5, 0.7, 0.85}) {
    if (!trochoidal || !(step_mm > 0)) break;  // no period to look for
    const std::size_t mid = cutting_middle(s, c0, c1, at);
    std::size_t next = std::max<std::size_t>(mid, 1);
    const std::optional<std::size_t> i0 = cutting_start(cutting, mid, c1, n, next);
    if (auto w = cycle_from(s, c0, c1, *i0, step_mm)) return *w;
  }
  // The middle third of the cutting time.
  Window w;
  const double span = s.t_s[c1] - s.t_s[c0];
  std::size_t a = c0, b = c0;
  while (a < c1 && s.t_s[a] < s.t_s[c0] + span / 3) ++a;
  b = a;
  while (b < c1 && s.t_s[b] < s.t_s[c0] + 2 * span / 3) ++b;
  if (b <= a) b = std::min(n, a + 1);
  w.first = a;
  w.last = b;
  w.t0_s = s.t_s[a];
  w.duration_s = s.t_s[b < n ? b : n - 1] - s.t_s[a];
  w.length_mm = s.s_mm[b < n ? b : n - 1] - s.s_mm[a];
  return w;
}

// Tool-centre position at time t (s) between samples uniform in time (step dt from t_first)
// by cubic Hermite interpolation on positions and unit tangents times the piece length:
// exact at the samples, error O(h^4 kappa^3) between them (below 1e-9 mm for h = f_z).
struct DenseCentre {
  const PathSamples* s = nullptr;
  double t_first = 0, dt = 0;
  [[nodiscard]] std::pair<double, double> at(double t) const {
    const PathSamples& p = *s;
    const auto n = static_cast<double>(p.size());
    const double uc = std::clamp((t - t_first) / dt, 0.0, n - 1.000001);
    const auto i = static_cast<std::size_t>(uc);
    const double f = uc - static_cast<double>(i);
    const double h = p.s_mm[i + 1] - p.s_mm[i];
    const Hermite w(f);
    return {w.at(p.x_mm, p.tx, i, h), w.at(p.y_mm, p.ty, i, h)};
  }
};

// Chips at angle phi (rad) for tooth k sitting there at time t: between its tip and the tip
// trajectory of the tooth before it (exact, with radial runout e at phase lambda), and
// between the tool circle and the circle one tooth period earlier (the translation model).
struct ToothChip {
  double trajectory_mm = 0, translation_mm = 0;
};

ToothChip tooth_chip(const DenseCentre& c, const Tool& tool, double omega, double e, double t,
                     double phi, int k) {
  const double R = tool.radius_mm(), lambda = deg_to_rad(tool.runout_phase_deg);
  const auto alpha = [&](int j) {
    return deg_to_rad(tool.tooth_angles_deg[static_cast<std::size_t>(j)]);
  };
  // The preceding tooth: the one that reached this angle most recently (Z = 1: itself).
  const int Z = tool.teeth;
  int prev = k;
  double delta = kTwoPi / std::abs(omega);
  for (int j = 0; j < Z; ++j) {
    if (j == k) continue;
    double d = omega < 0 ? alpha(k) - alpha(j) : alpha(j) - alpha(k);
    d = std::fmod(d, kTwoPi);
    if (d <= 0) d += kTwoPi;
    if (d / std::abs(omega) < delta) {
      delta = d / std::abs(omega);
      prev = j;
    }
  }
  const double psi = phi - alpha(k);  // spindle phase at t
  const auto [cx, cy] = c.at(t);
  const double ax = cx + e * std::cos(psi + lambda), ay = cy + e * std::sin(psi + lambda);
  const double ux = std::cos(phi), uy = std::sin(phi);
  // Tooth `prev` at time tau, relative to the axis at t; f = its offset across the ray.
  auto q = [&](double tau) {
    const auto [px, py] = c.at(tau);
    const double ps = psi + omega * (tau - t);
    return std::pair{px + e * std::cos(ps + lambda) + R * std::cos(ps + alpha(prev)) - ax,
                     py + e * std::sin(ps + lambda) + R * std::sin(ps + alpha(prev)) - ay};
  };
  auto f = [&](double tau) {
    const auto [qx, qy] = q(tau);
    return ux * qy - uy * qx;
  };
  // Regula falsi (Illinois) on a bracket of +-45/Z degrees of spindle rotation, where f
  // changes sign once; to 1e-13 s (the tip moves < 1e-9 mm in that time).
  const double lo = t - delta - 0.25 * delta, hi = t - delta + 0.25 * delta;
  const double root = detail::regula_falsi(f, lo, hi, f(lo), f(hi), 1e-13);
  const auto [qx, qy] = q(root);
  ToothChip out;
  out.trajectory_mm = R - (qx * ux + qy * uy);
  // Translation model: ray from the centre at t against the circle (centre at t - delta).
  const auto [ox0, oy0] = c.at(t - delta);
  const double ox = ox0 - cx, oy = oy0 - cy, tt = ox * ux + oy * uy;
  const double disc = R * R - (ox * ox + oy * oy - tt * tt);
  out.translation_mm = disc >= 0 ? R - (tt + std::sqrt(disc)) : R;
  return out;
}

// The floor beside each wall and in the middle (ProcessMetrics::floor), from the whole
// program's samples, and its texture: over a run-in, five cut-offs and a run-out in the middle
// of the cut stretch (ISO 21920-3's traverse), 0.8 mm ones first and longer ones where the Ra
// found asks for them and the slot holds them.
struct FloorFigures {
  std::array<FloorProfile, 3> floor;
  std::array<std::optional<ProfileTexture>, 3> texture_floor;
};
void predict_floor(const Job& job, const PathSamples& s, double omega, FloorFigures& m) {
  const double R = job.tool.radius_mm(), W = job.slot.width_mm, depth = job.slot.depth_mm;
  double ylo = std::numeric_limits<double>::infinity(), yhi = -ylo;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s.z_mm[i] <= -depth + 1e-6) {
      ylo = std::min(ylo, s.y_mm[i]);
      yhi = std::max(yhi, s.y_mm[i]);
    }
  }
  const double from = std::max(0.0, ylo) + 0.5 * R;
  const double to = std::min(job.slot.length_mm, yhi) - 0.5 * R;
  if (!(to - from >= 3 * 0.08)) return;  // a run-in, a sampling length and a run-out
  const double beside = 0.5 * W - 0.5 * R;
  const std::array<double, 3> xs = {-beside, 0.0, beside};
  tbb::parallel_for(std::size_t{0}, xs.size(), [&](std::size_t k) {
    // ISO 21920-3's default cut-off from Ra, found from the shortest (0.08 mm) up: the floor
    // is computed over a run-in, five cut-offs and a run-out (7 lc) in the middle of the cut
    // stretch, longer only when the Ra found asks for a longer cut-off.
    for (double lc = 0.08;;) {
      // ISO 21920-3 (as ISO 3274 before it): a lambda_s of 2.5 um up to the 0.8 mm cut-off
      // 8 um at 2.5 mm and 25 um at 8 mm, sampled lambda_s / 5 apart (at most 2e5 points). Marks
      // finer than lambda_s (dense imprints in the middle of a slot) are what an instrument
      // filters out too.
      const double ls = lc <= 0.8 ? 0.0025 : (lc <= 2.5 ? 0.008 : 0.025);
      const double length = std::min(to - from, 7 * lc), mid = 0.5 * (from + to);
      if (length < 3 * lc) return;  // not even a run-in, one sampling length and a run-out
      const double dy = std::max(ls / 5, length / 2e5);
      const auto points = static_cast<std::size_t>(std::floor(length / dy)) + 1;
      m.floor[k] = floor_profile(s, job.tool, omega, xs[k], mid - 0.5 * length, dy, points);
      // The longest run of cut points, heights above its lowest.
      const std::vector<double>& z = m.floor[k].z_mm;
      std::size_t best = 0, best_len = 0;
      for (std::size_t i = 0; i < z.size();) {
        std::size_t j = i;
        while (j < z.size() && !std::isnan(z[j])) ++j;
        if (j - i > best_len) {
          best = i;
          best_len = j - i;
        }
        i = j + 1;
      }
      if (static_cast<double>(best_len) * dy < 3 * lc) {
        m.texture_floor[k].reset();
        return;
      }
      std::vector<double> run(z.begin() + static_cast<std::ptrdiff_t>(best),
                              z.begin() + static_cast<std::ptrdiff_t>(best + best_len));
      const double lowest = *std::min_element(run.begin(), run.end());
      for (double& v : run) v -= lowest;
      ProfileFilterOptions o;
      o.lambda_s_mm = ls;
      m.texture_floor[k] = profile_texture(run, dy, lc, o);
      const double wanted = default_cutoff_mm(m.texture_floor[k]->roughness.ra_mm);
      if (wanted <= lc) {
        m.texture_floor[k]->cutoff_source = "ISO 21920-3 default from Ra";
        return;
      }
      if (3 * wanted > to - from) {  // not even a run-in, one length and a run-out of it
        m.texture_floor[k]->cutoff_source = fmt::format(
            "{:g} mm: the cut floor is too short for the {:g} mm ISO 21920-3 default from its Ra",
            lc, wanted);
        return;
      }
      lc = wanted;
    }
  });
}

// Runs `left` and `right` at once (a slot's two walls); their failures, the left one's first
// (null: none), for the caller to raise in the order of the code that took them in turn.
template <class Left, class Right>
std::array<std::exception_ptr, 2> both_sides(Left&& left, Right&& right) {
  std::array<std::exception_ptr, 2> failed;
  const auto guarded = [&failed](std::size_t k, auto& f) {
    try {
      f();
    } catch (...) {
      failed[k] = std::current_exception();
    }
  };
  tbb::parallel_invoke([&] { guarded(0, left); }, [&] { guarded(1, right); });
  return failed;
}

// A computation a TBB task may start early: whoever claims it first runs it (the caller of
// `get` when no task has started it), and `get` waits only for a run already under way, never
// on a task group (where this thread could pick up unrelated work, a line of the floor). The run
// is isolated: a thread in it never takes outside work (another point of a sweep) while its
// nested loops wait. `drop` keeps a run not yet started from starting.
template <class T>
class Claim {
 public:
  explicit Claim(std::function<T()> f) : f_(std::move(f)) {}
  void run() {
    int free = kFree;
    if (!state_.compare_exchange_strong(free, kClaimed)) return;
    try {
      tbb::this_task_arena::isolate([this] { value_.emplace(f_()); });
    } catch (...) {
      error_ = std::current_exception();
    }
    state_.store(kDone);
    state_.notify_all();
  }
  void drop() {
    int free = kFree;
    state_.compare_exchange_strong(free, kDone);
  }
  T& get() {
    run();
    state_.wait(kClaimed);  // returns at once unless another thread is running it
    if (error_) std::rethrow_exception(error_);
    return *value_;
  }

 private:
  static constexpr int kFree = 0, kClaimed = 1, kDone = 2;
  std::function<T()> f_;
  std::atomic<int> state_{kFree};
  std::optional<T> value_;
  std::exception_ptr error_;
};

// What needs only the path and its samples, not the engagement (the time with the machine's
// acceleration, the predicted floor) runs on TBB's threads while this one runs the kernel, and
// is taken where the figures need it: a failure is rethrown there, as if it had been computed
// there; figures that end before it drop it.
class Ahead {
 public:
  Ahead(const ToolPath& path, const Job& job, const PathSamples& s, double omega, bool floor)
      : accel_([&path, &job] { return estimate_time_s(path, job.machine); }),
        floor_([&job, &s, omega] {
          FloorFigures f;
          predict_floor(job, s, omega, f);
          return f;
        }),
        has_floor_(floor) {
    group_.run([this] {
      accel_.run();
      if (has_floor_) floor_.run();
    });
  }
  Ahead(const Ahead&) = delete;
  Ahead& operator=(const Ahead&) = delete;
  ~Ahead() {
    group_.cancel();
    group_.wait();
  }
  [[nodiscard]] bool has_floor() const { return has_floor_; }
  double accel_time_s() { return accel_.get(); }
  FloorFigures take_floor() { return std::move(floor_.get()); }

 private:
  Claim<double> accel_;
  Claim<FloorFigures> floor_;
  bool has_floor_;
  tbb::task_group group_;
};

// The steady cycle of a periodic window: the path from 2.5 cycles (or more, see below) before
// the window to 1.55 after, with the stock open ahead, so the engagement is the endless slot's
// (a real slot as long as the tool's reach, like the paper's 20 mm examples, never gets
// there), and in it the cycle [first, last) that starts cutting first from half a cycle before
// the window on.
struct Steady {
  EngagementSeries e;
  std::vector<char> cut;
  std::size_t first = 0, last = 0;
};
Steady steady_cycle(const Job& job, const ToolPath& path, const EngagementOptions& opt,
                    const Window& w, double dt_sample, double thr) {
  const double R = job.tool.radius_mm();
  const double T = w.duration_s;
  // History: 2.5 cycles rebuild the region a cycle's own orbit covers; when the orbit is
  // wider than the tool (a > R) it leaves an island at its centre that only the cycles
  // whose orbit passes over it remove, about (b + R) / s cycles back.
  const SlotGeometry sg = slot_geometry(job);
  const double a = sg.orbit_a_mm, b = sg.orbit_b_mm;
  const double history =
      2.5 + (a > R && job.path.step_mm > 0 ? std::ceil((b + R) / job.path.step_mm) : 0.0);
  const double from = std::max(0.0, w.t0_s - history * T);
  const double to = std::min(path.duration_s(), w.t0_s + 1.55 * T);
  std::vector<double> times;
  for (double t = from; t <= to; t += dt_sample) times.push_back(t);
  EngagementOptions so = opt;
  so.open_ahead = true;
  so.on_samples = nullptr;
  Steady st;
  st.e = compute_engagement(sample_at_times(path, times), job, so);
  const EngagementSeries& steady = st.e;
  std::vector<char>& steady_cut = st.cut;
  steady_cut.assign(steady.samples.size(), 0);
  for (std::size_t i = 0; i < steady_cut.size(); ++i) {
    steady_cut[i] = steady.swept_rate_mm2_per_s[i] > thr ? 1 : 0;
  }
  std::size_t j0 = 0;
  for (std::size_t i = 1; i < steady_cut.size(); ++i) {
    if (steady.samples.t_s[i] >= w.t0_s - 0.5 * T && steady_cut[i] && !steady_cut[i - 1]) {
      j0 = i;
      break;
    }
  }
  if (j0 == 0) {  // no cooling in the cycle: start where the window does
    while (j0 + 1 < steady_cut.size() && steady.samples.t_s[j0] < w.t0_s - 0.5 * T) ++j0;
  }
  std::size_t j1 = j0;
  while (j1 < steady_cut.size() && steady.samples.t_s[j1] < steady.samples.t_s[j0] + T - 1e-9) {
    ++j1;
  }
  st.first = j0;
  st.last = j1;
  return st;
}

// The steady cycle's run, started on TBB's threads while the kernel still runs over the whole
// program: from the window that the cutting flags known so far give with the last sample below
// the stock's top standing for the last cutting one (the window is looked for from the middle
// of the cutting time on, so it is known long before the kernel ends). Taken only where the
// window found afterwards is the same one (then the run is the same, and so are its figures);
// otherwise dropped.
class SteadyAhead {
 public:
  SteadyAhead(const Job& job, const ToolPath& path, const EngagementOptions& opt, double dt_sample,
              double thr, const PathSamples& s)
      : job_(job), path_(path), opt_(opt), dt_sample_(dt_sample), thr_(thr) {
    // Its progress is not the phase's, so it reports none; it stops (Interrupted) on its own
    // flag, which Ctrl-C sets through the progress hook (200 times a run) and which is set when
    // the run is dropped or the analysis ends without it.
    opt_.hooks.progress = [this, user = opt.hooks.cancel](std::size_t, std::size_t) {
      if (user != nullptr && user->load(std::memory_order_relaxed)) stop_.store(true);
    };
    opt_.hooks.phase = nullptr;
    opt_.hooks.cancel = &stop_;
    opt_.on_samples = nullptr;
    const double top = stock_top_mm(job, job.stock_mesh.get());
    for (std::size_t i = s.size(); i-- > 0;) {
      if (s.z_mm[i] < top) {
        c1_ = i;
        break;
      }
    }
    cutting_.assign(s.size(), 0);
  }
  SteadyAhead(const SteadyAhead&) = delete;
  SteadyAhead& operator=(const SteadyAhead&) = delete;
  ~SteadyAhead() {
    stop_.store(true);
    if (run_) run_->drop();
    group_.cancel();
    group_.wait();
  }
  // The kernel's progress: the series' first `done` samples are final.
  void on_samples(const EngagementSeries& e, std::size_t done) {
    if (settled_) return;
    for (; known_ < done; ++known_) {
      cutting_[known_] = e.swept_rate_mm2_per_s[known_] > thr_ || e.axial_chip_mm[known_] > 0;
      if (cutting_[known_] && c0_ == npos) c0_ = known_;
    }
    if (c0_ == npos) return;
    if (c1_ == npos || c1_ < c0_) {
      settled_ = true;
      return;
    }
    if (mid_ == npos) {
      mid_ = cutting_middle(e.samples, c0_, c1_, 0.5);
      next_ = std::max<std::size_t>(mid_, 1);
    }
    const std::optional<std::size_t> i0 = cutting_start(cutting_, mid_, c1_, known_, next_);
    if (!i0) return;  // not known yet
    settled_ = true;
    window_ = cycle_from(e.samples, c0_, c1_, *i0, job_.path.step_mm);
    if (!window_) return;
    run_.emplace([this] { return steady_cycle(job_, path_, opt_, *window_, dt_sample_, thr_); });
    group_.run([this] { run_->run(); });
  }
  // The run, if it was started for this window.
  std::optional<Steady> take(const Window& w) {
    if (!run_) return std::nullopt;
    if (w != *window_) {
      stop_.store(true);  // another window: the run stops where it is, or never starts
      run_->drop();
      return std::nullopt;
    }
    return std::move(run_->get());
  }

 private:
  static constexpr std::size_t npos = std::numeric_limits<std::size_t>::max();
  const Job& job_;
  const ToolPath& path_;
  EngagementOptions opt_;
  double dt_sample_, thr_;
  std::vector<char> cutting_;
  std::size_t known_ = 0, c0_ = npos, c1_ = npos, mid_ = npos, next_ = 0;
  bool settled_ = false;
  std::optional<Window> window_;
  std::atomic<bool> stop_{false};
  std::optional<Claim<Steady>> run_;
  tbb::task_group group_;
};

}  // namespace

double estimate_analysis_memory(const Job& job, const ToolPath& path) {
  const double per_tooth_s = tooth_period_s(job.tool, job.cutting);
  const double samples = path.duration_s() / per_tooth_s * job.analysis.steps_per_tooth;
  return process_base_bytes() + samples * 400.0;
}

ProcessMetrics analyze_process(const Job& job, const ToolPath& path, const RunHooks& hooks,
                               const AnalysisParts& parts) {
  if (path.empty()) throw InputError("analyze: the path is empty");
  ProcessMetrics m;
  m.parts = parts;
  m.parts.walls = parts.walls || parts.floor;
  EngagementOptions opt;
  opt.steps_per_tooth = job.analysis.steps_per_tooth;
  opt.hooks = hooks;
  hooks.begin("engagement");
  const PathSamples samples = engagement_samples(path, job, opt.steps_per_tooth);
  const double omega = rpm_to_rad_per_s(job.cutting.spindle_speed_rpm) *
                       (job.cutting.spindle_direction == SpindleDirection::cw ? -1.0 : 1.0);
  // The acceleration time and (in a straight slot, where the figures reach it) the floor are
  // computed beside the kernel.
  const bool straight_slot =
      !(job.slot.curved() || job.pocket.defined() || !(job.slot.width_mm > 0));
  Ahead ahead(path, job, samples, omega, parts.floor && straight_slot);
  // The steady cycle's run is started from the kernel's progress where a periodic window will
  // be looked for (below: the same threshold and sample spacing).
  const double thr = 1e-6 * 2 * job.tool.radius_mm() * (feed_rate_mm_per_min(job) / 60.0);
  const double dt_sample =
      samples.size() > 1 ? tooth_period_s(job.tool, job.cutting) / opt.steps_per_tooth : 0;
  // (With one thread it would only run after the kernel anyway. Where the floor is computed too,
  // the early run waits behind the floor's lines, which end before the kernel does on the
  // examples since their first look runs four points a vector: docs/PERFORMANCE.md.)
  std::optional<SteadyAhead> steady_ahead;
  if (straight_slot && job.path.type != PathType::linear && job.path.step_mm > 0 &&
      samples.size() > 1 && tbb::this_task_arena::max_concurrency() > 1) {
    steady_ahead.emplace(job, path, opt, dt_sample, thr, samples);
    opt.on_samples = [&steady_ahead](const EngagementSeries& so_far, std::size_t done) {
      steady_ahead->on_samples(so_far, done);
    };
  }
  m.series = compute_engagement(samples, job, opt);
  const EngagementSeries& e = m.series;
  const PathSamples& s = e.samples;
  const std::size_t n = s.size();
  const double R = job.tool.radius_mm(), W = job.slot.width_mm, depth = job.slot.depth_mm;
  const double feed = feed_rate_mm_per_min(job) / 60.0;  // mm/s

  // Cutting: the circle advances into stock (slivers on the trailing side do not count).
  std::vector<char> cutting(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    // The flutes advance into stock, or the end face descends into it (a plunge, a drill).
    cutting[i] = e.swept_rate_mm2_per_s[i] > thr || e.axial_chip_mm[i] > 0 ? 1 : 0;
    if (cutting[i]) m.cutting_time_total_s += dt_sample;
  }
  if (std::none_of(cutting.begin(), cutting.end(), [](char c) { return c != 0; })) {
    if (job.stock_min_mm && job.stock_max_mm) {
      const auto &lo = *job.stock_min_mm, &hi = *job.stock_max_mm;
      throw InputError(fmt::format(
          "analyze: the path never cuts the [stock] box ({:g} <= x <= {:g}, {:g} <= y <= {:g}, "
          "z < {:g} mm)",
          lo[0], hi[0], lo[1], hi[1], hi[2]));
    }
    throw InputError(
        fmt::format("analyze: the path never cuts the slot (|x| <= {:g}, 0 <= y <= {:g}, z < 0 mm)",
                    0.5 * W, job.slot.length_mm));
  }

  // Whole program.
  m.path_length_mm = path.length_mm();
  m.feed_length_mm = path.feed_length_mm();
  m.machining_time_s = path.duration_s();
  m.machining_time_accel_s = ahead.accel_time_s();
  m.slot_volume_mm3 = W * job.slot.length_mm * depth;
  // What the program removes: the plan-view area the tool sweeps into stock times the stock's
  // height over it, sample by sample (a program need not clear the slot, may cut it twice or
  // at several levels: docs/models.md section 7, removal rate).
  for (std::size_t i = 0; i < n; ++i) {
    m.removed_volume_mm3 += e.removal_rate_mm3_per_s[i] * dt_sample;
  }
  // The end faces: the largest axial chip (descent per tooth) and the descents into stock
  // (runs of samples whose end face cuts, apart from the flutes' radial chip).
  std::size_t i_axial = n;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = e.axial_chip_mm[i];
    if (a <= 0) continue;
    if (i == 0 || !(e.axial_chip_mm[i - 1] > 0)) ++m.descents_into_stock;
    if (i_axial == n || a > m.h_axial_max_mm) {
      m.h_axial_max_mm = a;
      i_axial = i;
    }
  }
  m.mrr_total_mm3_per_min = m.removed_volume_mm3 / m.machining_time_s * 60.0;
  m.feed_per_tooth_mm = job.cutting.feed_per_tooth_mm;
  // The largest chip, where it is, and the largest outside the entries, in one pass. A
  // planned path's entry ends at its first cycle mark; a program without marks (one read from
  // a file) has an entry at each descent into the stock: the descending feed moves below the
  // stock's top and the feed moves after them that stay within a tool diameter of where the
  // descent ended (the bore and its widening, as a helix's last turn or a start circle).
  const double entry_end_s = path.cycles().empty() ? 0.0 : path.cycles().front().start_time_s;
  std::vector<char> entry_segment;
  if (path.cycles().empty()) {
    const double top = stock_top_mm(job, nullptr);
    const auto& segs = path.segments();
    entry_segment.assign(segs.size(), 0);
    const double D = job.tool.diameter_mm;
    bool after_descent = false;
    Vec3 bottom = Vec3::Zero();  // where the last descent ended
    const auto near = [&](const Vec3& p) {
      return std::hypot(p.x() - bottom.x(), p.y() - bottom.y()) <= D;
    };
    for (std::size_t k = 0; k < segs.size(); ++k) {
      const Segment& sg = segs[k];
      if (sg.motion() == Motion::rapid) {
        after_descent = false;
        continue;
      }
      const double z0 = sg.start().z(), z1 = sg.end().z();
      if (z1 < z0 - 1e-9 && z1 < top) {
        entry_segment[k] = 1;
        after_descent = true;
        bottom = sg.end();
      } else if (after_descent && near(sg.end()) && near(sg.point_at(0.5 * sg.length_mm()))) {
        entry_segment[k] = 1;
      } else {
        after_descent = false;
      }
    }
  }
  const auto in_entry = [&](std::size_t i) {
    if (entry_segment.empty()) return s.t_s[i] < entry_end_s;
    return i < s.segment.size() && s.segment[i] < entry_segment.size() &&
           entry_segment[s.segment[i]] != 0;
  };
  std::size_t i_max = 0, i_after = n, i_eng = 0, i_eng_after = n;
  double h_after = 0;
  for (std::size_t i = 0; i < n; ++i) {
    // Plunge starts have no radial chip (engagement.hpp: radial_chip_mm).
    const double h = radial_chip_mm(e, i, R);
    if (h > m.h_max_slot_mm) {
      m.h_max_slot_mm = h;
      m.t_h_max_slot_s = s.t_s[i];
      i_max = i;
    }
    if (!in_entry(i) && (i_after == n || h > h_after)) {
      i_after = i;
      h_after = h;
    }
    const double deg = rad_to_deg(e.engagement_angle_rad[i]);
    if (deg > m.engagement_angle_max_slot_deg) {
      m.engagement_angle_max_slot_deg = deg;
      i_eng = i;
    }
    if (!in_entry(i) && (i_eng_after == n || deg > m.engagement_max_after_entry_deg)) {
      m.engagement_max_after_entry_deg = deg;
      i_eng_after = i;
    }
  }
  const auto at = [&](std::size_t i) { return Vec3(s.x_mm[i], s.y_mm[i], s.z_mm[i]); };
  const auto segment = [&](std::size_t i) {
    return i < s.segment.size() ? s.segment[i] : ProcessMetrics::npos;
  };
  if (n > 0) {
    m.h_max_slot_at_mm = at(i_max);
    m.h_max_slot_segment = segment(i_max);
    m.engagement_max_slot_at_mm = at(i_eng);
    m.engagement_max_slot_segment = segment(i_eng);
  }
  if (i_after < n) {
    m.h_max_after_entry_mm = h_after;
    m.h_max_after_entry_at_mm = at(i_after);
    m.h_max_after_entry_segment = segment(i_after);
  }
  if (i_axial < n) {
    m.h_axial_max_at_mm = at(i_axial);
    m.h_axial_max_segment = segment(i_axial);
  }
  if (i_eng_after < n) {
    m.engagement_max_after_entry_at_mm = at(i_eng_after);
    m.engagement_max_after_entry_segment = segment(i_eng_after);
  }
  // A slot along a curve: each cycle's step follows the bend, so there is no steady cycle;
  // the walls and floor of the straight slot's models do not apply. Whole-program figures.
  // A job of a [stock] alone (a program read from G-code) has no slot to hold a cycle to.
  if (job.slot.curved() || job.pocket.defined() || !(job.slot.width_mm > 0)) {
    m.periodic = false;
    m.performance_index_note =
        job.pocket.defined() ? "a pocket has no steady cycle: whole-program figures only"
        : job.slot.curved()
            ? "a slot along a curve has no steady cycle: whole-program figures only"
            : "the job has no [slot] (its [stock] is the program's stock): whole-program "
              "figures only";
    return m;
  }

  // Steady-state cycle, then the walls, floor and chips in it: a slot's figures. A program
  // read from G-code (a path without the planner's cycle marks) that is not a slot (a pocket,
  // a contour, a 3D surface) may repeat nothing the step explains or have no walls: then its
  // whole-program figures stand alone, with the reason (for a planned slot such a failure is
  // an error, as it was).
  const bool program = path.cycles().empty();
  ProcessMetrics whole;
  if (program) whole = m;
  try {
    const bool trochoidal = job.path.type != PathType::linear;
    const Window w = find_window(e, cutting, job.path.step_mm, trochoidal);
    m.periodic = w.periodic;
    m.cycle_time_s = w.duration_s;
    m.path_length_per_cycle_mm = w.length_mm;
    // The cycle's series: for a periodic path, the steady state of an endless slot
    // (steady_cycle), taken from the run started during the kernel's where its window is this
    // one.
    Steady steady;
    const EngagementSeries* cs = &e;
    const std::vector<char>* ccut = &cutting;
    std::size_t cf = w.first, cl = w.last;
    double t0 = w.t0_s;
    if (w.periodic) {
      std::optional<Steady> early = steady_ahead ? steady_ahead->take(w) : std::nullopt;
      steady = early ? std::move(*early) : steady_cycle(job, path, opt, w, dt_sample, thr);
      cs = &steady.e;
      ccut = &steady.cut;
      cf = steady.first;
      cl = steady.last;
      t0 = steady.e.samples.t_s[cf];
    }
    m.cycle_start_s = t0;
    double swept = 0, ap_sum = 0;
    int ap_n = 0;
    std::size_t i_h = cf;
    for (std::size_t i = cf; i < cl; ++i) {
      const EngagementSeries& c = *cs;
      const double ap = std::clamp(-c.samples.z_mm[i], 0.0, depth);
      swept += c.removal_rate_mm3_per_s[i] * dt_sample;
      if ((*ccut)[i]) {
        m.cutting_time_s += dt_sample;
        ap_sum += ap;
        ++ap_n;
      }
      if (c.h_max_mm[i] > m.h_max_mm) {
        m.h_max_mm = c.h_max_mm[i];
        i_h = i;
      }
      m.engagement_angle_max_deg =
          std::max(m.engagement_angle_max_deg, rad_to_deg(c.engagement_angle_rad[i]));
    }
    m.cutting_time_s = std::min(m.cutting_time_s, m.cycle_time_s);
    m.cooling_time_s = m.cycle_time_s - m.cutting_time_s;
    m.axial_depth_mm = ap_n > 0 ? ap_sum / ap_n : depth;
    m.t_h_max_s = cs->samples.t_s[i_h] - t0;
    m.mrr_swept_mm3_per_min = m.cycle_time_s > 0 ? swept / m.cycle_time_s * 60.0 : 0.0;
    m.mrr_mm3_per_min = w.periodic ? W * job.path.step_mm * m.axial_depth_mm / m.cycle_time_s * 60.0
                                   : m.mrr_swept_mm3_per_min;
    // A bound no cycle can pass: the tool sweeps at most its diameter times the depth at the
    // fastest feed of the cycle (a full slot). A rate above it is a wrong cycle, not a result
    // (1e-6 for rounding of the window's ends).
    {
      double v_max = 0;
      const PathSamples& q = cs->samples;
      for (std::size_t i = std::max<std::size_t>(cf, 1); i < std::min(cl + 1, q.size()); ++i) {
        if (q.t_s[i] > q.t_s[i - 1]) {
          v_max = std::max(v_max, (q.s_mm[i] - q.s_mm[i - 1]) / (q.t_s[i] - q.t_s[i - 1]));
        }
      }
      if (v_max == 0) v_max = feed;  // a window shorter than a sample: the programmed feed
      const double full_slot = 2 * R * depth * v_max * 60.0;
      if (m.mrr_mm3_per_min > full_slot * (1 + 1e-6) ||
          m.mrr_swept_mm3_per_min > full_slot * (1 + 1e-6)) {
        throw Error(fmt::format(
            "analyze: the steady cycle found ({:.6g} s, {:.6g} mm of path from t = {:.6g} s) "
            "removes "
            "{:.6g} mm^3/min, more than a full slot at the cycle's fastest feed (D a_p v_f = "
            "{:.6g} mm^3/min): no result is given for a cycle that cannot be; please report the "
            "job",
            m.cycle_time_s, m.path_length_per_cycle_mm, m.cycle_start_s, m.mrr_mm3_per_min,
            full_slot));
      }
    }

    // The steady cycle is all a caller asked for (the walls and the floor cost most).
    if (!parts.walls && !parts.floor) {
      set_performance_index(job, m);
      return m;
    }

    const EngagementSeries& ce = *cs;
    const PathSamples& q = ce.samples;
    const std::vector<char>& cc = *ccut;
    const std::size_t qn = q.size();

    // Walls over one period of y around the cycle's contact with each wall.
    const double period =
        w.periodic ? job.path.step_mm : std::max(1.0, 2 * job.cutting.feed_per_tooth_mm);
    std::size_t il = cf, ir = cf;
    for (std::size_t i = cf; i < std::max(cl, cf + 1) && i < qn; ++i) {
      if (q.x_mm[i] < q.x_mm[il]) il = i;
      if (q.x_mm[i] > q.x_mm[ir]) ir = i;
    }
    // Dense centre samples (every 0.01 mm, or s / 100) from a cycle and a half before the
    // window to two and a half after: every circle that reaches either wall's period window.
    const double ds = std::min(0.01, period / 100);
    // Dense centre samples (every 0.01 mm, or s / 100) from a cycle and a half before the
    // window to two and a half after, where the centre is within `wall_reach` of its extreme x
    // (found on the tooth-pass samples): only circles there can reach a wall's profile
    // (checked below: the walls must lie well inside it, else every sample is taken).
    const double wall_reach = 0.5 + 2 * m.feed_per_tooth_mm;
    const double dt_dense = ds / feed;
    auto dense_samples = [&](bool all) {
      const double span = std::max(w.duration_s, 1.0 / feed);
      const double from = std::max(0.0, t0 - 1.5 * span);
      const double to = std::min(path.duration_s(), t0 + 2.5 * span);
      double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo;
      for (std::size_t i = 0; i < n; ++i) {
        if (s.z_mm[i] >= 0) continue;
        xlo = std::min(xlo, s.x_mm[i]);
        xhi = std::max(xhi, s.x_mm[i]);
      }
      std::vector<double> times;
      double last = -1;
      for (std::size_t i = 0; i < n; ++i) {
        if (s.t_s[i] < from - dt_sample || s.t_s[i] > to + dt_sample) continue;
        if (!all && s.x_mm[i] > xlo + wall_reach && s.x_mm[i] < xhi - wall_reach) continue;
        const double a = std::max({from, s.t_s[i] - dt_sample, last + dt_dense});
        const double b = std::min(to, s.t_s[i] + dt_sample);
        for (double t = a; t <= b; t += dt_dense) times.push_back(last = t);
      }
      return sample_at_times(path, times);
    };
    PathSamples dense = dense_samples(false);
    constexpr int kWallPoints = 2001;
    double yl = q.y_mm[il], yr = q.y_mm[ir];
    // One period of a wall around y_c. A short slot's end can leave part of the steady
    // contact's period uncut: then the period before it (or after, or two before) is used,
    // the profile being periodic.
    const std::array<double, 5> shifts = {0.0, -1.0, 1.0, -2.0, 2.0};
    auto path_side = [&](bool left, double yc) {
      const Walls both =
          walls_from_circles(dense, R, -1e-9, yc - period / 2, yc + period / 2, kWallPoints);
      return left ? both.left : both.right;
    };
    auto path_wall = [&](bool left, double& yc) {
      for (std::size_t k = 0;; ++k) {
        try {
          WallProfile prof = path_side(left, yc + shifts[k] * period);
          yc += shifts[k] * period;
          return prof;
        } catch (const InputError&) {
          if (k + 1 == shifts.size()) throw;
        }
      }
    };
    // The two walls at once (each its own period window; the left one's failure first, as when
    // they were taken in turn).
    const auto both_path_walls = [&] {
      WallProfile l, r;
      const auto failed =
          both_sides([&] { l = path_wall(true, yl); }, [&] { r = path_wall(false, yr); });
      if (failed[0]) std::rethrow_exception(failed[0]);
      m.walls_path.left = std::move(l);
      if (failed[1]) std::rethrow_exception(failed[1]);
      m.walls_path.right = std::move(r);
    };
    try {
      both_path_walls();
    } catch (const InputError&) {
      // A program without a steady cycle whose window has no slot walls (a spiral, a pocket:
      // nothing cuts along the walls' y there): the walls, their texture and the floor's
      // imprints are not modelled (null); the whole-program figures stand. With a steady
      // cycle the walls exist, and a failure is a fault to report.
      if (w.periodic) throw;
      return m;
    }
    if (std::max(m.walls_path.left.waviness_mm, m.walls_path.right.waviness_mm) >
        0.5 * wall_reach) {
      dense = dense_samples(true);
      both_path_walls();
    }

    // Tooth level: tooth tips every 0.1 degree of spindle rotation while the centre is near a
    // wall (within the path-level waviness + runout + 2 f_z of its extreme) in the windows.
    const double dt_tip = deg_to_rad(0.1) / std::abs(omega);
    {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (std::size_t i = 0; i < dense.size(); ++i) {
        if (dense.z_mm[i] >= 0) continue;
        lo = std::min(lo, dense.x_mm[i]);
        hi = std::max(hi, dense.x_mm[i]);
      }
      const double e_r = job.tool.runout_radial_mm;
      // The tooth-level wall lies within the path-level waviness plus runout and the tooth
      // cusps (about f_z^2 / 8R) of the extreme; centres farther than `band` from their extreme
      // cannot put a tip on it. Checked after the fact: the band doubles until the profile
      // fits inside it.
      const double fz = m.feed_per_tooth_mm;
      const double base = 2 * e_r + fz * fz / R + 0.002;
      // Centres between dense samples by cubic Hermite interpolation (positions and unit
      // tangents times the chord length): error O(ds^4 kappa^3), far below a micrometre for
      // ds = 0.01 mm, and no length inversion per tip sample.
      auto tips_for = [&](bool left, double yc, double band) {
        std::vector<double> times;
        PathSamples ts;
        auto add = [&](std::size_t i, double t) {
          const double a = dense.t_s[i], b = dense.t_s[i + 1];
          const double u = b > a ? std::clamp((t - a) / (b - a), 0.0, 1.0) : 0.0;
          const double h = dense.s_mm[i + 1] - dense.s_mm[i];
          const double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
          const double h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
          ts.t_s.push_back(t);
          ts.x_mm.push_back(h00 * dense.x_mm[i] + h10 * h * dense.tx[i] + h01 * dense.x_mm[i + 1] +
                            h11 * h * dense.tx[i + 1]);
          ts.y_mm.push_back(h00 * dense.y_mm[i] + h10 * h * dense.ty[i] + h01 * dense.y_mm[i + 1] +
                            h11 * h * dense.ty[i + 1]);
          ts.z_mm.push_back(h00 * dense.z_mm[i] + h10 * h * dense.tz[i] + h01 * dense.z_mm[i + 1] +
                            h11 * h * dense.tz[i + 1]);
          times.push_back(t);
        };
        std::vector<std::size_t> breaks;  // sentinel samples between runs
        double last_end = -1, grid_next = -std::numeric_limits<double>::infinity();
        // Only times when some tooth points within delta of the wall's normal can put a tip
        // within the band of the extreme: R (1 - cos delta) <= band + 2 e, with margin.
        const double wall_dir = left ? kPi : 0.0;
        const double delta =
            1.2 * std::acos(std::max(-1.0, 1.0 - (band + 2 * e_r) / R)) + 2 * deg_to_rad(0.1);
        auto tooth_near = [&](double t) {
          for (const double a_deg : job.tool.tooth_angles_deg) {
            if (std::abs(std::remainder(omega * t + deg_to_rad(a_deg) - wall_dir, kTwoPi)) <=
                delta) {
              return true;
            }
          }
          return false;
        };
        for (std::size_t i = 0; i + 1 < dense.size(); ++i) {
          if (dense.z_mm[i] >= 0) continue;
          const bool near = left ? dense.x_mm[i] <= lo + band : dense.x_mm[i] >= hi - band;
          // A tip at the wall is within its extreme's reach of the centre's y: |sin| of the
          // angle from the extreme below sqrt(2 band / R), so |dy| <= R sqrt(2 band / R).
          const double reach = R * std::sqrt(2 * band / R) + 0.01;
          if (!near || std::abs(dense.y_mm[i] - yc) > period / 2 + reach) continue;
          const double a = dense.t_s[i], b = dense.t_s[i + 1];
          if (b - a > 1.5 * dt_dense) continue;  // a gap between near-wall runs
          const double from = std::max(a, grid_next);
          const auto steps = static_cast<long>(std::floor((b - from) / dt_tip));
          for (long k = 0; k <= steps; ++k) {
            const double t = from + static_cast<double>(k) * dt_tip;
            grid_next = t + dt_tip;
            if (!tooth_near(t)) continue;
            if (!times.empty() && t > last_end + 1.5 * dt_tip) {
              // A gap: a sentinel sample (lifted below) so no chord joins the two runs.
              breaks.push_back(times.size());
              add(i, t);
            }
            add(i, t);
            last_end = t;
          }
        }
        if (times.size() < 2) {  // the band is too narrow for any tip: it widens (below)
          throw InputError("analyze: no tooth-tip samples near the wall");
        }
        ToothTracks tr = tooth_tracks(ts, job.tool, job.cutting);
        for (const std::size_t b : breaks) {
          for (auto& z : tr.z_mm) z[b] = std::numeric_limits<double>::infinity();
        }
        return walls_from_tips(tr, -1e-9, yc - period / 2, yc + period / 2, kWallPoints, band);
      };
      // A wall at tooth level.
      const auto tooth_wall = [&](const bool left) {
        const double wp = left ? m.walls_path.left.waviness_mm : m.walls_path.right.waviness_mm;
        double& yc = left ? yl : yr;
        for (double band = 1.5 * wp + base;; band *= 2) {
          Walls tw;
          bool cut = false;
          for (std::size_t k = 0; k < shifts.size() && !cut; ++k) {
            // As for the path level: a period the tips cut. Where no tip within the band
            // reaches some y of the period, the band is too narrow for this wall (a step or
            // feed that leaves deeper scallops than the path-level waviness): it widens.
            try {
              tw = tips_for(left, yc + shifts[k] * period, band);
              if (shifts[k] != 0) {
                yc += shifts[k] * period;
                (left ? m.walls_path.left : m.walls_path.right) = path_side(left, yc);
              }
              cut = true;
            } catch (const InputError&) {
              if (k + 1 == shifts.size() && band > R) throw;
            }
          }
          if (!cut) continue;
          const WallProfile& prof = left ? tw.left : tw.right;
          // Complete when the profile lies within the band of the extreme tip reach: a centre
          // beyond the band puts its tips (radius <= R + e) beyond the band too.
          const double extreme = left ? lo - R - e_r : hi + R + e_r;
          const double worst =
              left ? *std::max_element(prof.x_mm.begin(), prof.x_mm.end()) - extreme
                   : extreme - *std::min_element(prof.x_mm.begin(), prof.x_mm.end());
          if (worst < band || band > R) {
            (left ? m.walls_tooth.left : m.walls_tooth.right) = prof;
            break;
          }
        }
      };
      // Each side's wall, then its texture along y (one period of the tooth-level profile), the
      // two sides at once; a failure is raised in the order of the code that took them in turn:
      // the left wall's, the right wall's, then the left texture's, the right texture's.
      std::array<std::exception_ptr, 2> texture_failed;
      const auto side = [&](const bool left) {
        tooth_wall(left);
        try {
          const WallProfile& wall = left ? m.walls_tooth.left : m.walls_tooth.right;
          if (wall.x_mm.size() >= 3) {
            (left ? m.texture_left : m.texture_right) = wall_texture(wall, left);
          }
        } catch (...) {
          texture_failed[left ? 0 : 1] = std::current_exception();
        }
      };
      const auto wall_failed = both_sides([&] { side(true); }, [&] { side(false); });
      for (const auto& failed : {wall_failed, texture_failed}) {
        for (const std::exception_ptr& f : failed) {
          if (f) std::rethrow_exception(f);
        }
      }
    }

    // Bottom imprints: one circle per tooth pass at the floor in the window.
    {
      std::vector<double> xs;
      const std::size_t step = static_cast<std::size_t>(opt.steps_per_tooth);
      for (std::size_t i = cf; i < cl; i += step) {
        if (q.z_mm[i] <= -depth + 1e-6) xs.push_back(q.x_mm[i]);
      }
      const double advance =
          w.periodic ? job.path.step_mm : std::abs(q.y_mm[std::min(cl, qn - 1)] - q.y_mm[cf]);
      if (!xs.empty() && advance > 0) {
        m.imprint = bottom_imprint_density(xs, R, 0.5 * W, advance, job.analysis.imprint_points);
      }
    }

    if (parts.floor) {
      FloorFigures f = ahead.take_floor();  // a straight slot's, so computed ahead
      m.floor = std::move(f.floor);
      m.texture_floor = std::move(f.texture_floor);
    }

    // Exact chip between adjacent teeth's tip trajectories, at the angle of each sample's
    // h_max where the previous tooth's circle bounds it (elsewhere the older surface does and
    // the trajectories do not enter).
    {
      DenseCentre dc;
      dc.s = &q;
      dc.t_first = q.t_s.front();
      dc.dt = dt_sample;
      m.h_max_per_tooth_mm.assign(static_cast<std::size_t>(job.tool.teeth), 0.0);
      for (std::size_t i = cf; i < cl; ++i) {
        if (!cc[i] || ce.h_max_mm[i] <= 0) continue;
        const double phi = ce.h_max_angle_rad[i], t = q.t_s[i];
        const ToothChip plain = tooth_chip(dc, job.tool, omega, 0.0, t, phi, 0);
        if (std::abs(plain.translation_mm - ce.h_max_mm[i]) > 1e-7) {
          // The older surface bounds the chip: the same for every tooth.
          for (auto& h : m.h_max_per_tooth_mm) h = std::max(h, ce.h_max_mm[i]);
          continue;
        }
        m.chip_translation_error_mm = std::max(
            m.chip_translation_error_mm, std::abs(plain.trajectory_mm - plain.translation_mm));
        for (int k = 0; k < job.tool.teeth; ++k) {
          const ToothChip c = tooth_chip(dc, job.tool, omega, job.tool.runout_radial_mm, t, phi, k);
          auto& h = m.h_max_per_tooth_mm[static_cast<std::size_t>(k)];
          h = std::max(h, c.trajectory_mm);
        }
      }
      m.h_max_tooth_mm =
          *std::max_element(m.h_max_per_tooth_mm.begin(), m.h_max_per_tooth_mm.end());
    }

    set_performance_index(job, m);
    return m;
  } catch (const Interrupted&) {
    throw;
  } catch (const IoError&) {
    throw;
  } catch (const Error& err) {
    if (!program) throw;
    whole.periodic = false;
    whole.performance_index_note = fmt::format(
        "the program is not a slot whose cycle repeats with the step ({}): whole-program "
        "figures only",
        err.what());
    return whole;
  }
}

void set_performance_index(const Job& job, ProcessMetrics& m,
                           std::optional<double> predicted_force_max_n) {
  m.force_max_predicted_n = predicted_force_max_n;
  const double w_max_um = job.measured.waviness_um.value_or(
      1000.0 * std::max(m.walls_tooth.left.waviness_mm, m.walls_tooth.right.waviness_mm));
  const std::optional<double> force =
      job.measured.force_max_n ? job.measured.force_max_n : predicted_force_max_n;
  std::optional<double> ra_um = job.measured.roughness_ra_um;
  if (!ra_um && m.texture_left && m.texture_right) {
    ra_um = 1000.0 * std::max(m.texture_left->roughness.ra_mm, m.texture_right->roughness.ra_mm);
  }
  if (force && ra_um && *ra_um > 0 && w_max_um > 0) {
    m.performance_index = m.mrr_mm3_per_min / (*force * *ra_um * w_max_um);
    m.performance_index_note = fmt::format(
        "MRR {:.1f} mm^3/min (model), F_R,max {:.4g} N ({}), Ra {:.4g} um ({}), W_max {:.3g} "
        "um ({})",
        m.mrr_mm3_per_min, *force,
        job.measured.force_max_n ? "measured"
                                 : "predicted over the steady cycle, [material] " +
                                       std::string(to_string(*job.material.model)),
        *ra_um,
        job.measured.roughness_ra_um ? "measured" : "predicted, the rougher wall, ISO 21920-2",
        w_max_um, job.measured.waviness_um ? "measured" : "model, tooth level");
  } else {
    m.performance_index.reset();
    m.performance_index_note =
        "needs [measured] force_max (N) or a [material] force model, and [measured] "
        "roughness_ra (um) or the walls' predicted texture; waviness (um) is optional";
  }
}

}  // namespace trochomill
