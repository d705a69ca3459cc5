// Synthetic vibroacoustic signal whose band energies follow a chosen k_f profile through each
// trochoid cycle of the job's planned program (include/trochomill/signal.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/path.hpp"
#include "trochomill/signal.hpp"

namespace trochomill {

namespace {

// Unit-RMS band noise: white Gaussian noise through the band filter, after a warm-up the
// filter's transient needs, scaled to RMS 1.
std::vector<double> band_noise(std::size_t n, const Sos& sos, double rate_hz, std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const auto warm = static_cast<std::size_t>(0.05 * rate_hz);
  std::vector<double> x(n + warm);
  for (double& v : x) v = g(rng);
  SosFilter f(sos);
  f.process(x.data(), x.data(), x.size());
  x.erase(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(warm));
  double ss = 0;
  for (const double v : x) ss += v * v;
  const double rms = std::sqrt(ss / static_cast<double>(n));
  for (double& v : x) v /= rms;
  return x;
}

}  // namespace

Signal synth_signal(const Job& job, const MonitorSettings& m, const SynthOptions& o,
                    int* cycles_covered) {
  // Each broken rule by itself, with the value that broke it.
  std::vector<std::string> problems;
  const auto need = [&](bool ok, std::string what) {
    if (!ok) problems.push_back("synth-signal: " + std::move(what));
  };
  need(o.rate_hz > 0, fmt::format("rate must be > 0 Hz, got {}", o.rate_hz));
  need(o.cycles >= 1, fmt::format("cycles must be >= 1, got {}", o.cycles));
  need(o.lead_s >= 0, fmt::format("lead must be >= 0 s, got {}", o.lead_s));
  need(o.noise >= 0, fmt::format("noise must be >= 0, got {}", o.noise));
  need(o.idle >= 0, fmt::format("idle must be >= 0, got {}", o.idle));
  need(o.kf_czi > 0 && o.kf_czii > 0 && o.kf_cziii > 0,
       fmt::format("k_f values must be > 0, got {}, {}, {}", o.kf_czi, o.kf_czii, o.kf_cziii));
  need(o.kf_czii_down.value_or(1) > 0 && o.kf_cziii_down.value_or(1) > 0,
       fmt::format("down-cut k_f values must be > 0, got {}, {}", o.kf_czii_down.value_or(1),
                   o.kf_cziii_down.value_or(1)));
  need(o.wear_drift > -1, fmt::format("wear drift must be > -1, got {}", o.wear_drift));
  if (!problems.empty()) throw InputError(problems);
  validate(m, o.rate_hz);
  const std::vector<double> starts = planned_cycle_bounds(job);
  const std::size_t ncyc =
      std::min<std::size_t>(static_cast<std::size_t>(o.cycles), starts.size() - 1);
  if (cycles_covered != nullptr) *cycles_covered = static_cast<int>(ncyc);
  const double t_end = o.lead_s + starts[ncyc];
  if (!(t_end * o.rate_hz < 4e9)) {
    throw InputError(fmt::format("synth-signal: {:.4g} s at {:g} Hz is more than 4e9 samples",
                                 t_end, o.rate_hz));
  }
  const MechanismSettings& st = job.mechanism;
  const MechanismCurve c = mechanism_curve(job, st);
  const ZoneSummary zs = summarize_zones(c, st, false);

  Signal s;
  s.rate_hz = o.rate_hz;
  const auto n = static_cast<std::size_t>(std::ceil(t_end * o.rate_hz));
  std::mt19937 rng(o.seed);
  const std::vector<double> nl = band_noise(
      n, butter_bandpass(m.order, m.low_min_hz, m.low_max_hz, o.rate_hz), o.rate_hz, rng);
  const std::vector<double> nh = band_noise(
      n, butter_bandpass(m.order, m.high_min_hz, m.high_max_hz, o.rate_hz), o.rate_hz, rng);
  std::normal_distribution<double> g(0.0, 1.0);
  s.samples.resize(n);
  std::size_t cyc = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / o.rate_hz, tp = t - o.lead_s;
    while (cyc < ncyc && tp >= starts[cyc + 1]) ++cyc;
    double amp = o.idle, k = 1.0;
    if (cyc < ncyc && tp >= starts[cyc]) {
      // The model's zone at this phase of the cycle.
      const double ph = (tp - starts[cyc]) / (starts[cyc + 1] - starts[cyc]);
      const auto it = std::upper_bound(c.t_s.begin(), c.t_s.end(), ph * c.cycle_time_s);
      const auto j = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - c.t_s.begin() - 1));
      const bool down = cut_half(ph * c.cycle_time_s, c.zone[j], zs.cutting_start_s,
                                 zs.cutting_span_s, c.cycle_time_s) == 2;
      switch (c.zone[j]) {
        case 1:
          amp = 1, k = o.kf_czi;
          break;
        case 2:
          amp = 1, k = down ? o.kf_czii_down.value_or(o.kf_czii) : o.kf_czii;
          break;
        case 3:
          amp = 1, k = down ? o.kf_cziii_down.value_or(o.kf_cziii) : o.kf_cziii;
          break;
        default:
          break;
      }
    }
    // Wear: k_f grows linearly from the first cycle's start to the last one's end.
    const double t0 = o.lead_s + starts[0];
    k *= 1 + o.wear_drift * std::clamp((t - t0) / (t_end - t0), 0.0, 1.0);
    s.samples[i] = amp * (k * nl[i] + nh[i]) / std::sqrt(0.5 * (1 + k * k)) + o.noise * g(rng);
  }
  return s;
}

double synth_signal_memory_bytes(const Job& job, const SynthOptions& o) {
  const std::vector<double> starts = planned_cycle_bounds(job);
  const std::size_t ncyc =
      std::min<std::size_t>(static_cast<std::size_t>(std::max(o.cycles, 0)), starts.size() - 1);
  const double samples = (o.lead_s + starts[ncyc]) * o.rate_hz;
  // The signal and its two noise bands (8 bytes each) and the WAV's float32 (4): 28 bytes a
  // sample (measured: 23.7 at 2.6 M samples); and the process (20 MB).
  return process_base_bytes() + 28.0 * samples;
}

}  // namespace trochomill
