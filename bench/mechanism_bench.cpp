// Benchmarks of the mechanism model: one cycle at 3600 points, and the step
// recommendation, on the Pivkin 2025 example.
#include <benchmark/benchmark.h>

#include <string>

#include "trochomill/job.hpp"
#include "trochomill/mechanism.hpp"

namespace {

trochomill::Job pivkin() {
  return trochomill::load_job(std::string(TROCHOMILL_SOURCE_DIR) +
                              "/examples/pivkin2025/trochoidal.toml");
}

void BM_MechanismCycle3600(benchmark::State& state) {
  const trochomill::Job job = pivkin();
  trochomill::MechanismSettings st = job.mechanism;
  st.points = 3600;
  for (auto _ : state) {
    const auto c = trochomill::mechanism_curve(job, st);
    benchmark::DoNotOptimize(c.h_mm.data());
  }
}
BENCHMARK(BM_MechanismCycle3600)->Unit(benchmark::kMillisecond);

// The same on Wagih 2023's elliptical example (W 20, D 10: a/R = 1, aspect ratio 0.8).
void BM_MechanismCycle3600Wagih(benchmark::State& state) {
  const trochomill::Job job = trochomill::load_job(std::string(TROCHOMILL_SOURCE_DIR) +
                                                   "/examples/wagih2023/elliptical.toml");
  trochomill::MechanismSettings st = job.mechanism;
  st.points = 3600;
  for (auto _ : state) {
    const auto c = trochomill::mechanism_curve(job, st);
    benchmark::DoNotOptimize(c.h_mm.data());
  }
}
BENCHMARK(BM_MechanismCycle3600Wagih)->Unit(benchmark::kMillisecond);

void BM_MechanismCycle3600Pivkin(benchmark::State& state) {
  const trochomill::Job job = pivkin();
  trochomill::MechanismSettings st = job.mechanism;
  st.points = 3600;
  st.model = trochomill::ChipModel::pivkin2025;
  for (auto _ : state) {
    const auto c = trochomill::mechanism_curve(job, st);
    benchmark::DoNotOptimize(c.h_mm.data());
  }
}
BENCHMARK(BM_MechanismCycle3600Pivkin)->Unit(benchmark::kMillisecond);

void BM_RecommendStep(benchmark::State& state) {
  const trochomill::Job job = pivkin();
  const trochomill::MechanismSettings st = job.mechanism;
  for (auto _ : state) {
    const auto r = trochomill::recommend(job, st, false, false);
    benchmark::DoNotOptimize(r.value);
  }
}
BENCHMARK(BM_RecommendStep)->Unit(benchmark::kMillisecond);

void BM_RecommendStepPivkin(benchmark::State& state) {
  const trochomill::Job job = pivkin();
  trochomill::MechanismSettings st = job.mechanism;
  st.model = trochomill::ChipModel::pivkin2025;
  for (auto _ : state) {
    const auto r = trochomill::recommend(job, st, false, false);
    benchmark::DoNotOptimize(r.value);
  }
}
BENCHMARK(BM_RecommendStepPivkin)->Unit(benchmark::kMillisecond);

}  // namespace
