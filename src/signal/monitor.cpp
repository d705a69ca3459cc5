// k_f series (offline and streaming), cycle timing from the job or the signal, per-cycle
// profiles beside the mechanism model, ploughing and wear flags
// (include/trochomill/signal.hpp; docs/models.md section 10).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "trochomill/error.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/path.hpp"
#include "trochomill/signal.hpp"

namespace trochomill {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::size_t window_samples(const MonitorSettings& m, double rate_hz) {
  return static_cast<std::size_t>(std::llround(m.window_s * rate_hz));
}
}  // namespace

void validate(const MonitorSettings& m, double rate_hz) {
  const double nyq = 0.5 * rate_hz;
  auto band = [&](const char* name, double lo, double hi) {
    if (!(lo > 0 && lo < hi && hi < nyq)) {
      throw InputError(fmt::format(
          "[monitor] {} band {:g}-{:g} Hz must lie within 0 < low < high < rate / 2 = {:g} Hz "
          "(the signal's rate is {:g} Hz)",
          name, lo, hi, nyq, rate_hz));
    }
  };
  band("low", m.low_min_hz, m.low_max_hz);
  band("high", m.high_min_hz, m.high_max_hz);
  if (window_samples(m, rate_hz) < 8) {
    throw InputError(
        fmt::format("[monitor] window = {:g} s is {} samples at {:g} Hz: need at least 8",
                    m.window_s, window_samples(m, rate_hz), rate_hz));
  }
}

KfSeries kf_series(const Signal& s, const MonitorSettings& m, bool zero_phase) {
  validate(m, s.rate_hz);
  const Sos lo = butter_bandpass(m.order, m.low_min_hz, m.low_max_hz, s.rate_hz);
  const Sos hi = butter_bandpass(m.order, m.high_min_hz, m.high_max_hz, s.rate_hz);
  std::vector<double> yl, yh;
  if (zero_phase) {
    sosfiltfilt_pair(lo, hi, s.samples, yl, yh);
  } else {
    sosfilt_pair(lo, hi, s.samples, yl, yh);
  }
  const std::size_t w = window_samples(m, s.rate_hz);
  KfSeries k;
  k.window_s = static_cast<double>(w) / s.rate_hz;
  for (std::size_t start = 0; start + w <= yl.size(); start += w) {
    // Same accumulation order as KfStream: streaming equals offline causal bit for bit.
    double sl = 0, sh = 0;
    for (std::size_t i = start; i < start + w; ++i) {
      sl += yl[i] * yl[i];
      sh += yh[i] * yh[i];
    }
    const double rl = std::sqrt(sl / static_cast<double>(w)),
                 rh = std::sqrt(sh / static_cast<double>(w));
    k.t_s.push_back((static_cast<double>(start) + 0.5 * static_cast<double>(w)) / s.rate_hz);
    k.rms_low.push_back(rl);
    k.rms_high.push_back(rh);
    k.k_f.push_back(rh > 0 ? rl / rh : kNaN);
  }
  return k;
}

KfStream::KfStream(double rate_hz, const MonitorSettings& m)
    : rate_hz_(rate_hz),
      window_n_((validate(m, rate_hz), window_samples(m, rate_hz))),
      low_(butter_bandpass(m.order, m.low_min_hz, m.low_max_hz, rate_hz)),
      high_(butter_bandpass(m.order, m.high_min_hz, m.high_max_hz, rate_hz)) {}

void KfStream::push(const double* x, std::size_t n,
                    const std::function<void(const Window&)>& on_window) {
  // Both bands filtered a block at a time in one pass (SosFilter::process_pair: the values
  // step() gives, the two recursions side by side), then summed sample by sample in order.
  constexpr std::size_t kBlock = 4096;
  for (std::size_t at = 0; at < n; at += kBlock) {
    const std::size_t m = std::min(kBlock, n - at);
    y_low_.resize(m);
    y_high_.resize(m);
    SosFilter::process_pair(low_, high_, x + at, y_low_.data(), y_high_.data(), m);
    accumulate(m, on_window);
  }
}

void KfStream::accumulate(std::size_t n, const std::function<void(const Window&)>& on_window) {
  for (std::size_t i = 0; i < n; ++i) {
    const double yl = y_low_[i], yh = y_high_[i];
    sum_low_ += yl * yl;
    sum_high_ += yh * yh;
    if (++filled_ == window_n_) {
      Window w;
      const auto wn = static_cast<double>(window_n_);
      w.t_s = (static_cast<double>(index_) * wn + 0.5 * wn) / rate_hz_;
      w.rms_low = std::sqrt(sum_low_ / wn);
      w.rms_high = std::sqrt(sum_high_ / wn);
      w.k_f = w.rms_high > 0 ? w.rms_low / w.rms_high : kNaN;
      on_window(w);
      ++index_;
      filled_ = 0;
      sum_low_ = sum_high_ = 0;
    }
  }
}

std::vector<double> planned_cycle_bounds(const Job& job) {
  // The monitor's cycles are the straight slot's, all alike; a slot along a curve has cycles
  // of changing step (and needs the engagement kernel, above this module, to plan).
  if (job.slot.curved()) {
    throw InputError(fmt::format(
        "{}: the monitor follows the cycles of a straight slot; a slot along a drawing's "
        "contour ([slot] along = \"{}\") has cycles of changing step: monitor it with a "
        "straight job of the same tool and conditions",
        job.source, job.slot.along));
  }
  const PlannedPath pp = plan_path(job);
  const auto& marks = pp.path.cycles();
  if (marks.size() < 2) {
    throw InputError(
        fmt::format("{}: the planned path has {} cycle(s); monitoring needs two or "
                    "more",
                    job.source, marks.size()));
  }
  std::vector<double> b;
  for (const auto& mk : marks) b.push_back(mk.start_time_s);
  b.push_back(b.back() + (b.back() - b[b.size() - 2]));
  return b;
}

int cut_half(double t_s, int zone, double cutting_start_s, double cutting_span_s, double cycle_s) {
  if (zone <= 0 || !(cycle_s > 0)) return 0;
  const double into = std::fmod(t_s - cutting_start_s + 2 * cycle_s, cycle_s);
  return into < 0.5 * cutting_span_s ? 1 : 2;
}

ModelProfile model_profile(const Job& job, int bins) {
  const MechanismSettings& st = job.mechanism;
  const MechanismCurve c = mechanism_curve(job, st);
  const ZoneSummary z = summarize_zones(c, st, false);
  ModelProfile mp;
  for (int b = 0; b < bins; ++b) {
    const double t = (b + 0.5) / bins * c.cycle_time_s;
    const auto it = std::upper_bound(c.t_s.begin(), c.t_s.end(), t);
    const auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - c.t_s.begin() - 1));
    mp.k_re_pct.push_back(c.k_re_pct[i]);
    mp.zone.push_back(c.zone[i]);
    mp.half.push_back(cut_half(t, c.zone[i], z.cutting_start_s, z.cutting_span_s, c.cycle_time_s));
  }
  return mp;
}

KfRange pivkin2025_kf_range(int zone, int half, bool worn) {
  if (zone == 2) return worn ? KfRange{0.7, 2.5} : KfRange{0.85, 1.15};
  if (zone == 3) {
    if (!worn) return {0.9, 1.1};
    return half == 1 ? KfRange{1.5, 2.3} : KfRange{1.0, 1.7};
  }
  throw InputError(fmt::format("Pivkin 2025's k_f ranges cover CZII and CZIII, not zone {}", zone));
}

std::string kf_cell_name(int zone, int half) {
  return fmt::format("{} {}", zone == 2 ? "CZII" : "CZIII", half == 1 ? "up-cut" : "down-cut");
}

std::vector<KfJudgement> judge_kf(const double sum[2][2], const double count[2][2]) {
  std::vector<KfJudgement> out;
  for (int z = 0; z < 2; ++z) {
    for (int h = 0; h < 2; ++h) {
      if (!(count[z][h] >= kKfMinWindows)) continue;
      KfJudgement j;
      j.zone = z + 2;
      j.half = h + 1;
      j.k_f = sum[z][h] / count[z][h];
      j.windows = static_cast<int>(count[z][h]);
      j.new_range = pivkin2025_kf_range(j.zone, j.half, false);
      j.worn_range = pivkin2025_kf_range(j.zone, j.half, true);
      j.in_new = j.new_range.contains(j.k_f);
      j.in_worn = j.worn_range.contains(j.k_f);
      out.push_back(j);
    }
  }
  return out;
}

std::string kf_tool_state(const std::vector<KfJudgement>& judged) {
  if (judged.empty()) return "";
  const auto all = [&](bool KfJudgement::*in) {
    return std::all_of(judged.begin(), judged.end(), [&](const KfJudgement& j) { return j.*in; });
  };
  if (all(&KfJudgement::in_new)) return "new";
  if (all(&KfJudgement::in_worn)) return "worn";
  return "neither";
}

CycleTiming cycles_from_job(const Job& job, double start_s, double duration_s) {
  const std::vector<double> bounds = planned_cycle_bounds(job);
  CycleTiming ct;
  ct.source = "job";
  double sum = 0;
  for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
    const double a = start_s + bounds[k], b = start_s + bounds[k + 1];
    if (a >= 0 && b <= duration_s) {
      ct.start_s.push_back(a);
      ct.end_s.push_back(b);
      sum += b - a;
    }
  }
  if (ct.start_s.empty()) {
    throw InputError(fmt::format(
        "no whole cycle of the program (cycles from {:.3f} s to {:.3f} s after its start) lies "
        "in the signal ({:.3f} s) with {} {:g} s",
        bounds.front(), bounds.back(), duration_s, option_name("start_s"), start_s));
  }
  ct.period_s = sum / static_cast<double>(ct.start_s.size());
  return ct;
}

CycleTiming cycles_from_signal(const KfSeries& kf, double min_period_s, double max_period_s) {
  const std::size_t n = kf.t_s.size();
  std::vector<double> env(n);
  for (std::size_t i = 0; i < n; ++i) env[i] = std::hypot(kf.rms_low[i], kf.rms_high[i]);
  const double mean = std::accumulate(env.begin(), env.end(), 0.0) / static_cast<double>(n);
  for (double& v : env) v -= mean;
  double var = 0;
  for (const double v : env) var += v * v;
  const auto lag_lo =
      static_cast<std::size_t>(std::max(1.0, std::floor(min_period_s / kf.window_s)));
  const auto lag_hi =
      std::min(n / 2, static_cast<std::size_t>(std::ceil(max_period_s / kf.window_s)));
  CycleTiming none;
  none.source = "signal";
  if (!(var > 0) || lag_hi <= lag_lo + 2) {
    none.note = fmt::format(
        "the signal ({} windows) is too short or flat to find a cycle period between {:g} and "
        "{:g} s: no cycles (give the job and where its program starts in the signal to take them "
        "from the program)",
        n, min_period_s, max_period_s);
    return none;
  }
  std::vector<double> ac(lag_hi + 2, 0.0);
  for (std::size_t lag = lag_lo - 1; lag <= lag_hi + 1 && lag < n; ++lag) {
    double s = 0;
    for (std::size_t i = 0; i + lag < n; ++i) s += env[i] * env[i + lag];
    ac[lag] = s / var * static_cast<double>(n) / static_cast<double>(n - lag);
  }
  // The highest local maximum, then the smallest lag whose local maximum reaches 90 % of it
  // (a period's multiples correlate almost as well).
  double best = -1;
  for (std::size_t lag = lag_lo; lag <= lag_hi; ++lag) {
    if (ac[lag] >= ac[lag - 1] && ac[lag] >= ac[lag + 1]) best = std::max(best, ac[lag]);
  }
  if (best < 0.3) {
    none.note = fmt::format(
        "no cycle period stands out in the signal (autocorrelation peak {:.2f} < 0.3 between "
        "{:g} and {:g} s): no cycles (give the job and where its program starts in the signal to "
        "take them from the program)",
        best, min_period_s, max_period_s);
    return none;
  }
  std::size_t pk = lag_lo;
  for (std::size_t lag = lag_lo; lag <= lag_hi; ++lag) {
    if (ac[lag] >= ac[lag - 1] && ac[lag] >= ac[lag + 1] && ac[lag] >= 0.9 * best) {
      pk = lag;
      break;
    }
  }
  const double den = ac[pk - 1] - 2 * ac[pk] + ac[pk + 1];
  const double shift = den < 0 ? 0.5 * (ac[pk - 1] - ac[pk + 1]) / den : 0.0;
  CycleTiming ct;
  ct.source = "signal";
  ct.period_s = (static_cast<double>(pk) + shift) * kf.window_s;
  // Phase: fold the envelope over the period and start cycles where it rises most steeply.
  const int bins = std::max(8, static_cast<int>(std::lround(ct.period_s / kf.window_s)));
  std::vector<double> fold(static_cast<std::size_t>(bins), 0.0), cnt(fold.size(), 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double ph = std::fmod(kf.t_s[i], ct.period_s) / ct.period_s;
    const auto b = std::min(fold.size() - 1, static_cast<std::size_t>(ph * bins));
    fold[b] += env[i];
    cnt[b] += 1;
  }
  for (std::size_t b = 0; b < fold.size(); ++b) fold[b] = cnt[b] > 0 ? fold[b] / cnt[b] : 0.0;
  std::size_t rise = 0;
  double steepest = -1e300;
  for (std::size_t b = 0; b < fold.size(); ++b) {
    const double d = fold[(b + 1) % fold.size()] - fold[b];
    if (d > steepest) {
      steepest = d;
      rise = b;
    }
  }
  // The rise happens between bin `rise` and the next: the cycle starts at their boundary.
  const double t0 = static_cast<double>(rise + 1) / bins * ct.period_s;
  // Each cycle's own onset: the steepest rise of the envelope within a quarter period of the
  // folded estimate (no drift from a slightly wrong period); cycles only where the machine
  // cuts (the envelope above a quarter of its 95th percentile somewhere in the cycle).
  std::vector<double> sorted(env);
  std::sort(sorted.begin(), sorted.end());
  const double loud =
      0.25 * (sorted[static_cast<std::size_t>(0.95 * static_cast<double>(n - 1))] + mean) - mean;
  const auto half_win = static_cast<std::ptrdiff_t>(std::lround(0.25 * ct.period_s / kf.window_s));
  const double duration = kf.t_s.back() + 0.5 * kf.window_s;
  auto window_at = [&](double t) {
    return static_cast<std::ptrdiff_t>(std::floor(t / kf.window_s));
  };
  std::vector<double> onsets;
  for (double t = t0 - ct.period_s; t < duration; t += ct.period_s) {
    const std::ptrdiff_t c = window_at(t);
    std::ptrdiff_t best_i = -1;
    double best_d = -1e300;
    for (std::ptrdiff_t i = std::max<std::ptrdiff_t>(0, c - half_win);
         i < std::min<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(n) - 1, c + half_win); ++i) {
      const double d = env[static_cast<std::size_t>(i) + 1] - env[static_cast<std::size_t>(i)];
      if (d > best_d) {
        best_d = d;
        best_i = i;
      }
    }
    if (best_i >= 0) onsets.push_back(static_cast<double>(best_i + 1) * kf.window_s);
  }
  for (std::size_t k = 0; k + 1 < onsets.size(); ++k) {
    const double a = onsets[k], b = onsets[k + 1];
    if (a < 0 || b > duration + 1e-12 || b - a < 0.5 * ct.period_s) continue;
    // Active: some window in the cycle is loud.
    bool active = false;
    for (std::ptrdiff_t i = window_at(a); i < window_at(b) && i < static_cast<std::ptrdiff_t>(n);
         ++i) {
      if (env[static_cast<std::size_t>(i)] > loud) active = true;
    }
    if (!active) continue;
    ct.start_s.push_back(a);
    ct.end_s.push_back(b);
  }
  if (ct.start_s.empty()) {
    throw Error("a cycle period was found but no whole active cycle lies in the signal");
  }
  double sum = 0;
  for (std::size_t k = 0; k < ct.start_s.size(); ++k) sum += ct.end_s[k] - ct.start_s[k];
  ct.period_s = sum / static_cast<double>(ct.start_s.size());
  return ct;
}

namespace {

// The ranges' findings: how many cycles look new, worn or neither, and one flag per zone and
// half of the cut whose k_f leaves the new tool's range in some cycle.
void range_flags(MonitorReport& r) {
  for (const auto& c : r.cycles) {
    r.cycles_new += c.tool_state == "new" ? 1 : 0;
    r.cycles_worn += c.tool_state == "worn" ? 1 : 0;
    r.cycles_neither += c.tool_state == "neither" ? 1 : 0;
  }
  const int judged = r.cycles_new + r.cycles_worn + r.cycles_neither;
  if (judged == 0) return;
  for (int zone = 2; zone <= 3; ++zone) {
    for (int half = 1; half <= 2; ++half) {
      int cycles = 0, outside = 0, worn = 0, first = -1;
      double sum = 0;
      for (std::size_t k = 0; k < r.cycles.size(); ++k) {
        for (const auto& j : r.cycles[k].judged) {
          if (j.zone != zone || j.half != half) continue;
          ++cycles;
          if (j.in_new) continue;
          ++outside;
          worn += j.in_worn ? 1 : 0;
          sum += j.k_f;
          if (first < 0) first = static_cast<int>(k);
        }
      }
      if (outside == 0) continue;
      const KfRange nr = pivkin2025_kf_range(zone, half, false);
      const KfRange wr = pivkin2025_kf_range(zone, half, true);
      r.flags.push_back(fmt::format(
          "{} half: k_f outside the new tool's {:.2f}-{:.2f} (Pivkin 2025 Fig. 21) in {} of {} "
          "cycles (mean {:.3f} there, first in cycle {}); inside the worn tool's {:.2f}-{:.2f} "
          "(Fig. 24) in {} of them",
          kf_cell_name(zone, half), nr.lo, nr.hi, outside, cycles, sum / outside, first, wr.lo,
          wr.hi, worn));
    }
  }
  if (r.cycles_worn + r.cycles_neither > 0) {
    r.flags.push_back(fmt::format(
        "tool state by Pivkin 2025's k_f ranges: new in {}, worn in {}, neither in {} of {} "
        "cycles",
        r.cycles_new, r.cycles_worn, r.cycles_neither, judged));
  }
}

}  // namespace

MonitorReport analyze_signal(const Signal& s, const MonitorSettings& m, const Job* job,
                             double start_s) {
  MonitorReport r;
  r.kf = kf_series(s, m, true);
  if (r.kf.t_s.size() < 4) {
    throw InputError(fmt::format("the signal holds {} windows of {:g} s: too short to monitor",
                                 r.kf.t_s.size(), m.window_s));
  }
  const auto bins = static_cast<std::size_t>(m.phase_bins);
  if (job != nullptr) {
    r.timing = cycles_from_job(*job, start_s, s.duration_s());
    r.model = model_profile(*job, m.phase_bins);
  } else {
    r.timing = cycles_from_signal(r.kf, 0.02, 20.0);
    if (!r.timing.note.empty()) r.warnings.push_back(r.timing.note);
  }
  // Per cycle: windows whose centre falls in it, by phase bin.
  std::size_t w = 0;
  for (std::size_t k = 0; k < r.timing.start_s.size(); ++k) {
    CycleResult cr;
    cr.start_s = r.timing.start_s[k];
    cr.end_s = r.timing.end_s[k];
    std::vector<double> sum(bins, 0.0), cnt(bins, 0.0);
    double env_max = 0;
    std::vector<std::pair<std::size_t, std::size_t>> in;  // (window, bin)
    while (w < r.kf.t_s.size() && r.kf.t_s[w] < cr.start_s) ++w;
    for (std::size_t i = w; i < r.kf.t_s.size() && r.kf.t_s[i] < cr.end_s; ++i) {
      if (!std::isfinite(r.kf.k_f[i])) continue;
      const double ph = (r.kf.t_s[i] - cr.start_s) / (cr.end_s - cr.start_s);
      const auto b = std::min(bins - 1, static_cast<std::size_t>(ph * static_cast<double>(bins)));
      in.emplace_back(i, b);
      sum[b] += r.kf.k_f[i];
      cnt[b] += 1;
      env_max = std::max(env_max, std::hypot(r.kf.rms_low[i], r.kf.rms_high[i]));
    }
    for (std::size_t b = 0; b < bins; ++b)
      cr.k_f_profile.push_back(cnt[b] > 0 ? sum[b] / cnt[b] : kNaN);
    // The cutting part: the model's zones, or without a model the windows above a quarter of
    // the cycle's loudest.
    double s_all = 0, n_all = 0, s1 = 0, n1 = 0, s3 = 0, n3 = 0;
    double cell_sum[2][2] = {{0, 0}, {0, 0}}, cell_n[2][2] = {{0, 0}, {0, 0}};
    for (const auto& [i, b] : in) {
      const double kf = r.kf.k_f[i];
      const int zone = r.model ? r.model->zone[b] : -1;
      if (r.model && zone >= 2 && r.model->half[b] > 0) {
        cell_sum[zone - 2][r.model->half[b] - 1] += kf;
        cell_n[zone - 2][r.model->half[b] - 1] += 1;
      }
      const bool cutting =
          r.model ? zone > 0 : std::hypot(r.kf.rms_low[i], r.kf.rms_high[i]) >= 0.25 * env_max;
      if (!cutting) continue;
      s_all += kf;
      n_all += 1;
      if (zone == 1) {
        s1 += kf;
        n1 += 1;
      } else if (zone == 3) {
        s3 += kf;
        n3 += 1;
      }
    }
    cr.k_f_mean = n_all > 0 ? s_all / n_all : kNaN;
    if (n1 > 0) cr.k_f_czi = s1 / n1;
    if (n3 > 0) cr.k_f_cziii = s3 / n3;
    cr.ploughing = cr.k_f_czi && cr.k_f_cziii && *cr.k_f_czi > m.ploughing_ratio * *cr.k_f_cziii;
    if (r.model && m.criteria == KfCriteria::pivkin2025) {
      cr.judged = judge_kf(cell_sum, cell_n);
      cr.tool_state = kf_tool_state(cr.judged);
    }
    r.cycles.push_back(std::move(cr));
  }
  // Levels: the mean over cycles; wear against the first baseline_cycles.
  double sum = 0, cnt = 0;
  for (const auto& c : r.cycles) {
    if (std::isfinite(c.k_f_mean)) {
      sum += c.k_f_mean;
      cnt += 1;
    }
  }
  if (cnt > 0) {
    r.k_f_mean = sum / cnt;
  } else {
    double a = 0, b = 0;
    for (const double v : r.kf.k_f) {
      if (std::isfinite(v)) {
        a += v;
        b += 1;
      }
    }
    r.k_f_mean = b > 0 ? a / b : kNaN;
  }
  const auto nb = static_cast<std::size_t>(m.baseline_cycles);
  auto level = [&](std::size_t from, std::size_t to) {
    double a = 0, b = 0;
    for (std::size_t k = from; k < to; ++k) {
      if (std::isfinite(r.cycles[k].k_f_mean)) {
        a += r.cycles[k].k_f_mean;
        b += 1;
      }
    }
    return b > 0 ? a / b : kNaN;
  };
  int ploughing = 0;
  for (const auto& c : r.cycles) ploughing += c.ploughing ? 1 : 0;
  if (r.cycles.size() >= nb) {
    r.reference_k_f = level(0, nb);
    int worn = 0;
    for (auto& c : r.cycles) {
      c.wear = std::isfinite(c.k_f_mean) && c.k_f_mean > m.wear_ratio * r.reference_k_f;
      worn += c.wear ? 1 : 0;
    }
    if (r.cycles.size() >= 2 * nb) {
      const double last = level(r.cycles.size() - nb, r.cycles.size());
      r.wear_trend = last > m.wear_ratio * r.reference_k_f;
      if (r.wear_trend) {
        r.flags.push_back(fmt::format(
            "wear trend: the last {} cycles' k_f level {:.3f} is {:.2f} times the first {} "
            "cycles' {:.3f} (threshold {:g}); {} cycle(s) above it",
            nb, last, last / r.reference_k_f, nb, r.reference_k_f, m.wear_ratio, worn));
      }
    }
  }
  if (ploughing > 0) {
    r.flags.push_back(fmt::format(
        "ploughing suspected in {} of {} cycles: k_f in the CZI phases exceeds {:g} times its "
        "CZIII level",
        ploughing, r.cycles.size(), m.ploughing_ratio));
  }
  range_flags(r);
  return r;
}

}  // namespace trochomill

namespace trochomill {

LiveMonitor::LiveMonitor(double rate_hz, const MonitorSettings& m, const Job* job, double start_s)
    : m_(m), stream_(rate_hz, m) {
  if (job != nullptr) {
    for (const double b : planned_cycle_bounds(*job)) bounds_.push_back(start_s + b);
    ModelProfile mp = model_profile(*job, m.phase_bins);
    zone_ = std::move(mp.zone);
    half_ = std::move(mp.half);
  }
}

void LiveMonitor::push(const double* x, std::size_t n,
                       const std::function<void(const LiveWindow&)>& out) {
  stream_.push(x, n, [&](const KfStream::Window& w) {
    LiveWindow lw;
    lw.window = w;
    if (!bounds_.empty() && w.t_s >= bounds_.front() && w.t_s < bounds_.back()) {
      const auto it = std::upper_bound(bounds_.begin(), bounds_.end(), w.t_s);
      const auto k = static_cast<int>(it - bounds_.begin()) - 1;
      const auto uk = static_cast<std::size_t>(k);
      lw.cycle = k;
      lw.phase = (w.t_s - bounds_[uk]) / (bounds_[uk + 1] - bounds_[uk]);
      const auto bins = zone_.size();
      const std::size_t b =
          std::min(bins - 1, static_cast<std::size_t>(lw.phase * static_cast<double>(bins)));
      lw.zone = zone_[b];
      lw.half = half_[b];
    }
    // A cycle finished: its level joins the reference or is compared with it, and its zones
    // and halves are judged against the ranges.
    if (lw.cycle != cycle_) {
      if (cycle_ >= 0 && cycle_n_ > 0) {
        last_level_ = cycle_sum_ / cycle_n_;
        if (finished_ < m_.baseline_cycles) ref_sum_ += last_level_;
        ++finished_;
      }
      if (cycle_ >= 0 && m_.criteria == KfCriteria::pivkin2025) {
        const std::string state = kf_tool_state(judge_kf(cell_sum_, cell_n_));
        if (state == "worn" || state == "neither") lw.flags.push_back("ranges-" + state);
      }
      cycle_ = lw.cycle;
      cycle_sum_ = cycle_n_ = 0;
      for (auto& row : cell_sum_) row[0] = row[1] = 0;
      for (auto& row : cell_n_) row[0] = row[1] = 0;
    }
    if (lw.zone > 0 && std::isfinite(w.k_f)) {
      cycle_sum_ += w.k_f;
      cycle_n_ += 1;
      if (lw.zone >= 2 && lw.half > 0) {
        cell_sum_[lw.zone - 2][lw.half - 1] += w.k_f;
        cell_n_[lw.zone - 2][lw.half - 1] += 1;
      }
      if (lw.zone == 3) {
        cziii_sum_ += w.k_f;
        cziii_n_ += 1;
      }
      if (lw.zone == 1 && cziii_n_ >= 10 && w.k_f > m_.ploughing_ratio * cziii_sum_ / cziii_n_) {
        lw.flags.emplace_back("ploughing");
      }
    }
    if (finished_ > m_.baseline_cycles &&
        last_level_ > m_.wear_ratio * ref_sum_ / m_.baseline_cycles) {
      lw.flags.emplace_back("wear");
    }
    out(lw);
  });
}

}  // namespace trochomill
