// Benchmarks of the engagement kernel on the Wagih 2023 examples (20 mm slots, one sample
// per tooth pass, as the performance aim in docs/PERFORMANCE.md states).
#include <benchmark/benchmark.h>

#include <string>

#include "trochomill/analysis.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/force.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/report.hpp"
#include "trochomill/study.hpp"

namespace {

void BM_EngagementWagih(benchmark::State& state) {
  static const char* const kNames[] = {"trochoidal", "circular", "elliptical", "linear-elliptical"};
  const char* name = kNames[state.range(0)];
  const trochomill::Job job = trochomill::load_job(std::string(TROCHOMILL_SOURCE_DIR) +
                                                   "/examples/wagih2023/" + name + ".toml");
  const auto planned = trochomill::plan_path(job);
  std::size_t samples = 0;
  for (auto _ : state) {
    const auto e = trochomill::compute_engagement(planned.path, job);
    samples = e.samples.size();
    benchmark::DoNotOptimize(e.h_max_mm.data());
  }
  state.counters["samples"] = static_cast<double>(samples);
  state.SetLabel(name);
}
BENCHMARK(BM_EngagementWagih)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// The whole analysis (engagement, cycle, walls at path and tooth level, imprints, tooth
// chips) of one Wagih example; the aim in docs/PERFORMANCE.md is < 100 ms on one core.
void BM_AnalyzeWagih(benchmark::State& state) {
  static const char* const kNames[] = {"trochoidal", "circular", "elliptical", "linear-elliptical"};
  const char* name = kNames[state.range(0)];
  const trochomill::Job job = trochomill::load_job(std::string(TROCHOMILL_SOURCE_DIR) +
                                                   "/examples/wagih2023/" + name + ".toml");
  const auto planned = trochomill::plan_path(job);
  for (auto _ : state) {
    const auto m = trochomill::analyze_process(job, planned.path);
    benchmark::DoNotOptimize(m.h_max_mm);
  }
  state.SetLabel(name);
}
BENCHMARK(BM_AnalyzeWagih)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// `compare` of eight aspect ratios (the paper's parameter study) on all cores.
void BM_CompareEightAspectRatios(benchmark::State& state) {
  const std::string job =
      std::string(TROCHOMILL_SOURCE_DIR) + "/examples/wagih2023/elliptical.toml";
  const std::vector<trochomill::Vary> vary = {
      trochomill::parse_vary("path.aspect_ratio=0.5,0.6,0.7,0.8,0.9,1.0,1.1,1.2")};
  for (auto _ : state) {
    // As `compare` runs it: the file parsed once, every point analysed with its predicted force.
    const auto doc = trochomill::JobDocument::load(job);
    const auto pts = trochomill::run_compare(doc, {}, vary, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(pts.data());
  }
  state.SetLabel(state.range(0) == 0 ? "all cores" : "1 thread");
}
BENCHMARK(BM_CompareEightAspectRatios)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
