// Benchmarks of the tri-dexel simulation, one thread each (the boards run in
// parallel in the CLI; here the per-core rate is measured):
//  - Sim/WagihCycleWindow: 0.1 s of a steady trochoid cycle (Wagih's example, 6 mm deep,
//    35 degree helix, 0.02 mm dexels, 600 steps per revolution) after the envelope pre-roll
//    and a revolution with the teeth (untimed), continuing that revolution's call (its
//    SimCarry: the annulus searched from the first step); counters: dexel updates per second
//    (subtractions that removed material) and steps per second.
//  - Sim/BergmannEnvelope: the envelope sweep of the first 10 s of the Bergmann case at
//    0.01 mm.
//  - Sim/NaiveDexelSubtraction: the yardstick for the window's update rate, measured in the
//    same run: a plain dexel kernel (a vector of intervals per ray) taking 16 million cuts
//    that each remove material, sweeping the rays in order as a tool's pass does; counter:
//    subtractions per second. The ratio of the window's rate to it is comparable across
//    machines.
// The whole Bergmann arc at the paper's resolution is timed by scripts/bench-bergmann-arc.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"

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
    const SimCarry carry =
        simulate(path, tool, job.simulation, work, from + 0.47, from + 0.5, lead).carry;
    SimControl window;
    window.after = &carry;  // the window continues the lead revolution, as the CLI's does
    state.ResumeTiming();
    const SimResult r = simulate(path, tool, job.simulation, work, from + 0.5, from + 0.6, window);
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

void SimNaiveDexelSubtraction(benchmark::State& state) {
  // 256 x 256 rays along x over [0, 100] mm, up to 8 intervals each inline; each pass cuts
  // every ray once, a 1/32 mm slice a little further along than the pass before (each cut
  // removes material, as the window's counted updates do); a quarter of the rays are split in
  // two first so that the interval counts vary.
  struct Iv {
    double lo, hi;
  };
  struct Ray {
    Iv v[8];
    int n = 0;
  };
  constexpr int kRays = 256 * 256;
  double cuts = 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<Ray> rays(kRays);
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(2, 98);
    for (Ray& r : rays) r.v[0] = {0.0, 100.0}, r.n = 1;
    for (int k = 0; k < kRays / 4; ++k) {
      Ray& r = rays[static_cast<std::size_t>(rng()) % kRays];
      const double a = u(rng);
      if (r.n == 1) r.v[0] = {0.0, a - 0.5}, r.v[1] = {a + 0.5, 100.0}, r.n = 2;
    }
    state.ResumeTiming();
    std::size_t removed = 0;
    for (int pass = 0; pass < 256; ++pass) {
      const double a = 30.0 + pass / 32.0, b = a + 1 / 32.0;  // exact in binary: no slivers
      for (Ray& r : rays) {
        // The naive subtraction: every interval against (a, b), the pieces left kept in order.
        Iv out[8];
        int m = 0;
        bool hit = false;
        for (int q = 0; q < r.n; ++q) {
          const Iv v = r.v[q];
          if (v.hi <= a || v.lo >= b) {
            if (m < 8) out[m++] = v;
            continue;
          }
          hit = true;
          if (v.lo < a && m < 8) out[m++] = {v.lo, a};
          if (v.hi > b && m < 8) out[m++] = {b, v.hi};
        }
        removed += hit ? 1 : 0;
        std::copy(out, out + m, r.v);
        r.n = m;
      }
    }
    benchmark::DoNotOptimize(removed);
    cuts += static_cast<double>(removed);
  }
  state.counters["subtractions_per_s"] = benchmark::Counter(cuts, benchmark::Counter::kIsRate);
}
BENCHMARK(SimNaiveDexelSubtraction)->Unit(benchmark::kMillisecond);

}  // namespace
