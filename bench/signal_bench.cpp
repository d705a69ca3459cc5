// Benchmarks of the vibroacoustic monitor: 10 s of one 100 kHz channel through the
// default bands (2-5 kHz and 8-13 kHz, order 4): causal filtering, the offline zero-phase k_f
// series and the live stream. Real-time factor = signal seconds / wall seconds, reported as
// the counter `x_real_time`. The data: white noise from a fixed seed, or the raw float32
// file named by TROCHOMILL_BENCH_SIGNAL (scripts/bench-scipy-sosfilt passes the very data
// it gives scipy.signal.sosfilt).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <random>
#include <string>

#include "trochomill/signal.hpp"

namespace {

const trochomill::Signal& data() {
  static const trochomill::Signal s = [] {
    trochomill::Signal x;
    x.rate_hz = 100000;
    if (const char* path = std::getenv("TROCHOMILL_BENCH_SIGNAL")) {
      trochomill::SignalReadOptions o;
      o.format = trochomill::SampleFormat::f32;
      o.rate_hz = 100000;
      return trochomill::read_signal(path, o);
    }
    x.samples.resize(1000000);
    std::mt19937 rng(11);
    std::normal_distribution<double> g(0.0, 1.0);
    for (double& v : x.samples) v = g(rng);
    return x;
  }();
  return s;
}

void report(benchmark::State& state) {
  const double seconds = data().duration_s() * static_cast<double>(state.iterations());
  state.counters["x_real_time"] = benchmark::Counter(seconds, benchmark::Counter::kIsRate);
}

// Both bands, causal (what scipy.signal.sosfilt does twice).
void BM_SosfiltTwoBands(benchmark::State& state) {
  const trochomill::MonitorSettings m;
  const auto lo = trochomill::butter_bandpass(m.order, m.low_min_hz, m.low_max_hz, 100000);
  const auto hi = trochomill::butter_bandpass(m.order, m.high_min_hz, m.high_max_hz, 100000);
  for (auto _ : state) {
    const auto a = trochomill::sosfilt(lo, data().samples);
    const auto b = trochomill::sosfilt(hi, data().samples);
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(b.data());
  }
  report(state);
}
BENCHMARK(BM_SosfiltTwoBands)->Unit(benchmark::kMillisecond);

// Both bands, zero-phase (scipy.signal.sosfiltfilt twice).
void BM_SosfiltfiltTwoBands(benchmark::State& state) {
  const trochomill::MonitorSettings m;
  const auto lo = trochomill::butter_bandpass(m.order, m.low_min_hz, m.low_max_hz, 100000);
  const auto hi = trochomill::butter_bandpass(m.order, m.high_min_hz, m.high_max_hz, 100000);
  for (auto _ : state) {
    const auto a = trochomill::sosfiltfilt(lo, data().samples);
    const auto b = trochomill::sosfiltfilt(hi, data().samples);
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(b.data());
  }
  report(state);
}
BENCHMARK(BM_SosfiltfiltTwoBands)->Unit(benchmark::kMillisecond);

// The offline monitor's k_f series (zero-phase filters, RMS windows).
void BM_KfSeriesOffline(benchmark::State& state) {
  const trochomill::MonitorSettings m;
  for (auto _ : state) {
    const auto k = trochomill::kf_series(data(), m, true);
    benchmark::DoNotOptimize(k.k_f.data());
  }
  report(state);
}
BENCHMARK(BM_KfSeriesOffline)->Unit(benchmark::kMillisecond);

// Live: the stream fed in blocks of 1024 samples (as from a sound card).
void BM_KfStreamLive(benchmark::State& state) {
  const trochomill::MonitorSettings m;
  for (auto _ : state) {
    trochomill::KfStream stream(100000, m);
    double last = 0;
    const auto& x = data().samples;
    for (std::size_t i = 0; i < x.size(); i += 1024) {
      stream.push(x.data() + i, std::min<std::size_t>(1024, x.size() - i),
                  [&](const trochomill::KfStream::Window& w) { last = w.k_f; });
    }
    benchmark::DoNotOptimize(last);
  }
  report(state);
}
BENCHMARK(BM_KfStreamLive)->Unit(benchmark::kMillisecond);

}  // namespace
