// Benchmarks of the tri-dexel simulation, one thread each (the boards run in
// parallel in the CLI; here the per-core rate is measured):
//  - Sim/WagihCycleWindow: 0.1 s of a steady trochoid cycle (Wagih's example, 6 mm deep,
//    35 degree helix, 0.02 mm dexels, 600 steps per revolution) after the envelope pre-roll
//    and a revolution with the teeth (untimed); counters: dexel updates per second
//    (subtractions that removed material) and steps per second.
//  - Sim/BergmannEnvelope: the envelope sweep of the first 10 s of the Bergmann case at
//    0.01 mm.
// The whole Bergmann arc at the paper's resolution is timed by scripts/bench-bergmann-arc.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <string>

#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/sim.hpp"

namespace {

using namespace trochomill;

std::string example(const char* name) {
  return std::string(TROCHOMILL_SOURCE_DIR) + "/examples/" + name;
}

void SimWagihCycleWindow(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const Job job = load_job(example("wagih2023/trochoidal.toml"),
                           {parse_override("simulation.resolution=0.02"),
                            parse_override("simulation.steps_per_rev=600")});
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 3, 4);
  const SimTool tool = sim_tool(job, job.simulation);
  double updates = 0, steps = 0;
  for (auto _ : state) {
    state.PauseTiming();
    TriDexel work(job_stock(job), job.simulation.resolution_mm);
    (void)sweep_envelope(path, tool, work, 0, from + 0.47);
    SimControl lead;
    lead.envelope_before = true;
    (void)simulate(path, tool, job.simulation, work, from + 0.47, from + 0.5, lead);
    state.ResumeTiming();
    const SimResult r = simulate(path, tool, job.simulation, work, from + 0.5, from + 0.6);
    updates += static_cast<double>(r.dexel_updates);
    steps += static_cast<double>(r.steps.size());
  }
  state.counters["dexel_updates_per_s"] = benchmark::Counter(updates, benchmark::Counter::kIsRate);
  state.counters["steps_per_s"] = benchmark::Counter(steps, benchmark::Counter::kIsRate);
}
BENCHMARK(SimWagihCycleWindow)->Unit(benchmark::kMillisecond);

void SimBergmannEnvelope(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const Job job = load_job(example("bergmann2021/trochoidal.toml"),
                           {parse_override("simulation.resolution=0.01")});
  const ToolPath path = plan_path(job).path;
  const SimTool tool = sim_tool(job, job.simulation);
  for (auto _ : state) {
    TriDexel work(job_stock(job), job.simulation.resolution_mm);
    benchmark::DoNotOptimize(sweep_envelope(path, tool, work, 0, 10.0));
  }
}
BENCHMARK(SimBergmannEnvelope)->Unit(benchmark::kMillisecond);

}  // namespace
