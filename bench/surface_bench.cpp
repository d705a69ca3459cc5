// Surface texture: the areal texture of a 4096 x 4096 map (S-filter, plane, L-filter, the
// ISO 25178-2 parameters with Sal and Str) and the profile parameters of 10^6 points.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "trochomill/surface.hpp"

namespace {

using namespace trochomill;

// A milled-looking map: feed marks along x, a waviness along y, noise; 1 um spacing.
HeightMap milled_map(std::size_t n) {
  HeightMap m;
  m.nx = m.ny = n;
  m.dx_mm = m.dy_mm = 0.001;
  m.z_mm.resize(n * n);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 2e-4);
  for (std::size_t r = 0; r < n; ++r) {
    for (std::size_t c = 0; c < n; ++c) {
      const double x = static_cast<double>(c) * m.dx_mm, y = static_cast<double>(r) * m.dy_mm;
      m.z_mm[r * n + c] = 0.002 * std::cos(2 * M_PI * x / 0.08) +
                          0.004 * std::sin(2 * M_PI * y / 1.3) + 0.0005 * x + noise(rng);
    }
  }
  return m;
}

void SurfaceArealTexture(benchmark::State& state) {
  const HeightMap m = milled_map(static_cast<std::size_t>(state.range(0)));
  ArealFilterOptions o;
  o.s_mm = 0.0025;  // ISO 3274's lambda_s for lambda_c 0.8 mm
  o.l_mm = 0.8;
  for (auto _ : state) {
    const ArealTexture t = areal_texture(m, o);
    benchmark::DoNotOptimize(t.sl.sa_mm);
  }
  state.counters["points"] = static_cast<double>(m.z_mm.size());
}
BENCHMARK(SurfaceArealTexture)
    ->Name("Surface/ArealTexture")
    ->Arg(4096)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void SurfaceArealFilter(benchmark::State& state) {
  const HeightMap m = milled_map(4096);
  const double lc = static_cast<double>(state.range(0)) / 1000;  // um to mm
  for (auto _ : state) {
    const HeightMap f = gaussian_filter_areal(m, lc);
    benchmark::DoNotOptimize(f.z_mm.data());
  }
}
BENCHMARK(SurfaceArealFilter)
    ->Name("Surface/ArealFilter4096")
    ->Arg(25)
    ->Arg(800)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void SurfaceArealParameters(benchmark::State& state) {
  const HeightMap m = milled_map(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    const ArealParameters p = areal_parameters(m, state.range(1) != 0);
    benchmark::DoNotOptimize(p.sa_mm);
  }
}
BENCHMARK(SurfaceArealParameters)
    ->Name("Surface/ArealParameters")
    ->Args({4096, 0})
    ->Args({4096, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void SurfaceProfileParameters(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<double> z(n);
  std::mt19937_64 rng(2);
  std::normal_distribution<double> noise(0.0, 2e-4);
  for (std::size_t i = 0; i < n; ++i) {
    z[i] = 0.002 * std::cos(2 * M_PI * static_cast<double>(i) * 0.0005 / 0.08) + noise(rng);
  }
  for (auto _ : state) {
    const ProfileParameters p = profile_parameters(z, 0.0005);
    benchmark::DoNotOptimize(p.ra_mm);
  }
}
BENCHMARK(SurfaceProfileParameters)
    ->Name("Surface/ProfileParameters")
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);

}  // namespace
