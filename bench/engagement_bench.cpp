// Benchmarks of the engagement kernel on the Wagih 2023 examples (20 mm slots, one sample
// per tooth pass, as the performance aim in docs/PERFORMANCE.md states).
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <string>

#include "trochomill/analysis.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/force.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/report.hpp"
#include "trochomill/study.hpp"
#include "trochomill/surface.hpp"
#include "trochomill/units.hpp"

namespace {

// The four Wagih 2023 examples, by the benchmarks' first argument.
const char* const kWagihNames[] = {"trochoidal", "circular", "elliptical", "linear-elliptical"};
trochomill::Job wagih_job(const char* name) {
  return trochomill::load_job(std::string(TROCHOMILL_SOURCE_DIR) + "/examples/wagih2023/" + name +
                              ".toml");
}

void BM_EngagementWagih(benchmark::State& state) {
  const char* name = kWagihNames[state.range(0)];
  const trochomill::Job job = wagih_job(name);
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

// The whole analysis (engagement, cycle, walls at path and tooth level, imprints, tooth
// chips, the predicted floor) of one Wagih example.
void BM_AnalyzeWagih(benchmark::State& state) {
  const char* name = kWagihNames[state.range(0)];
  const trochomill::Job job = wagih_job(name);
  const auto planned = trochomill::plan_path(job);
  for (auto _ : state) {
    const auto m = trochomill::analyze_process(job, planned.path);
    benchmark::DoNotOptimize(m.h_max_mm);
  }
  state.SetLabel(name);
}
BENCHMARK(BM_AnalyzeWagih)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

// The same without the predicted floor (the parts a study of the cycle's or the walls'
// metrics asks for: analysis.hpp AnalysisParts), and the steady cycle alone (a simulation's
// window).
void BM_AnalyzeWagihParts(benchmark::State& state) {
  const char* name = kWagihNames[state.range(0)];
  const trochomill::Job job = wagih_job(name);
  const auto planned = trochomill::plan_path(job);
  trochomill::AnalysisParts parts = trochomill::AnalysisParts::cycle_only();
  parts.walls = state.range(1) == 1;
  for (auto _ : state) {
    const auto m = trochomill::analyze_process(job, planned.path, {}, parts);
    benchmark::DoNotOptimize(m.h_max_mm);
  }
  state.SetLabel(fmt::format("{}, {}", name, parts.walls ? "no floor" : "cycle only"));
}
BENCHMARK(BM_AnalyzeWagihParts)->ArgsProduct({{0, 1, 2, 3}, {0, 1}})->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// The predicted floor alone: the end edges' passes over the whole elliptical program along the
// slot's middle (x = 0), 1.75 mm at 0.5 um (the 0.25 mm cut-off's traverse), on one thread
// (analyze runs the three lines in parallel).
void BM_FloorProfileWagih(benchmark::State& state) {
  const trochomill::Job job = wagih_job("elliptical");
  const auto planned = trochomill::plan_path(job);
  const trochomill::PathSamples s =
      trochomill::sample_by_time(planned.path, trochomill::tooth_period_s(job.tool, job.cutting));
  const double omega = -trochomill::rpm_to_rad_per_s(job.cutting.spindle_speed_rpm);
  const double mid = 0.5 * job.slot.length_mm;
  for (auto _ : state) {
    const auto f = trochomill::floor_profile(s, job.tool, omega, 0.0, mid - 0.875, 0.0005, 3501);
    benchmark::DoNotOptimize(f.z_mm.data());
  }
}
BENCHMARK(BM_FloorProfileWagih)->Unit(benchmark::kMillisecond);

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
