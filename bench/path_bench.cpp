// Benchmarks of the foundation: planning and writing a 100 mm elliptical slot (100 cycles),
// and reading G-code (throughput in bytes per second).
#include <benchmark/benchmark.h>

#include <string>

#include "trochomill/gcode.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"

namespace {

trochomill::Job slot_job(double length_mm) {
  using trochomill::parse_override;
  return trochomill::load_job(
      std::string(TROCHOMILL_SOURCE_DIR) + "/examples/wagih2023/elliptical.toml",
      {parse_override("slot.length=" + std::to_string(length_mm))});
}

void BM_PlanEllipticalSlot100mm(benchmark::State& state) {
  const trochomill::Job job = slot_job(100);
  for (auto _ : state) {
    auto p = trochomill::plan_path(job);
    benchmark::DoNotOptimize(p.path.length_mm());
  }
}
BENCHMARK(BM_PlanEllipticalSlot100mm)->Unit(benchmark::kMillisecond);

void BM_PlanAndWriteEllipticalSlot100mm(benchmark::State& state) {
  const trochomill::Job job = slot_job(100);
  trochomill::GcodeWriteOptions opt;
  opt.dialect = trochomill::Dialect::linuxcnc;
  std::size_t cycles = 0, bytes = 0;
  for (auto _ : state) {
    const auto p = trochomill::plan_path(job);
    const std::string code = trochomill::write_gcode(job, p.path, opt);
    cycles = static_cast<std::size_t>(p.info.cycles);
    bytes = code.size();
    benchmark::DoNotOptimize(code.data());
  }
  state.counters["cycles"] = static_cast<double>(cycles);
  state.counters["gcode_bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_PlanAndWriteEllipticalSlot100mm)->Unit(benchmark::kMillisecond);

void BM_ReadGcode(benchmark::State& state) {
  // A long program: the 100 mm slot as chords (mostly G1) and as biarcs (mostly G2/G3).
  const trochomill::Job job = slot_job(100);
  const auto p = trochomill::plan_path(job);
  trochomill::GcodeWriteOptions opt;
  opt.arc_output = state.range(0) ? trochomill::ArcOutput::chords : trochomill::ArcOutput::arcs;
  opt.tolerance_mm = 0.0001;
  const std::string code = trochomill::write_gcode(job, p.path, opt);
  for (auto _ : state) {
    auto prog = trochomill::read_gcode(code, "bench.ngc");
    benchmark::DoNotOptimize(prog.path.length_mm());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(code.size()));
  state.SetLabel(state.range(0) ? "G1 chords" : "G2/G3 biarcs");
}
BENCHMARK(BM_ReadGcode)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
