// Benchmarks of the force models and the wear topography:
//  - Force/FastWagihSlot: fast-mode forces (analytic chips, 96 steps per revolution) of the
//    whole Wagih trochoidal slot with the al7075-t6 linear coefficients (aim < 200 ms); the
//    machine's cores, as the CLI runs it.
//  - Force/Calibrate1s20kHz: calibration of k_c, k_n, m and the radial runout on 1 s of
//    20 kHz three-axis forces (Bergmann's case, generated with the paper's coefficients and
//    3 N noise; untimed) with the fast chip source (aim < 10 s).
//  - Topography/RbfFit100k: the cubic RBF (partition of unity) through 100,000 scattered
//    points (a Kronecker sequence, so scripts/bench-scipy-rbf feeds scipy the same points) and
//    its evaluation at 10,000 points (aim: fit < 10 s); counter: the largest error.
//  - Topography/SampleInsert: a synthetic insert mesh of ~100,000 visible points sampled into
//    the edge grid (culling, RBF, profiles).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <string>

#include "trochomill/force.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/topography.hpp"

namespace {

using namespace trochomill;

std::string example(const char* name) {
  return std::string(TROCHOMILL_SOURCE_DIR) + "/examples/" + name;
}

void ForceFastWagihSlot(benchmark::State& state) {
  const Job job = load_job(example("wagih2023/trochoidal.toml"),
                           {parse_override("material.name=al7075-t6-linear")});
  const ToolPath path = plan_path(job).path;
  std::size_t steps = 0;
  for (auto _ : state) {
    const JobForces f = job_forces(job, path, 0.0, path.duration_s(), true);
    steps = f.series.size();
    benchmark::DoNotOptimize(f.summary.f_resultant_max_n);
  }
  state.counters["steps"] = static_cast<double>(steps);
}
BENCHMARK(ForceFastWagihSlot)->Name("Force/FastWagihSlot")->Unit(benchmark::kMillisecond);

void ForceCalibrate(benchmark::State& state) {
  const Job truth = load_job(example("bergmann2021/trochoidal.toml"),
                             {parse_override("forces.fast_steps_per_rev=1000")});
  const ToolPath path = plan_path(truth).path;
  const auto [c0, c1] = cycle_window(path, 3, 4);
  const double t0 = job_forces(truth, path, c0, c1, true).summary.t_resultant_max_s - 0.5;
  const JobForces gen = job_forces(truth, path, t0, t0 + 1.0, true);
  MeasuredForces meas;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 3.0);
  const auto& ts = gen.series.t_s;
  for (double t = ts.front(); t < ts.back(); t += 5e-5) {
    const auto j = static_cast<std::size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin());
    const double f = (t - ts[j - 1]) / (ts[j] - ts[j - 1]);
    const auto at = [&](const std::vector<double>& y) { return y[j - 1] + f * (y[j] - y[j - 1]); };
    meas.t_s.push_back(t + 0.0073);
    meas.fx_n.push_back(at(gen.series.fx_n) + noise(rng));
    meas.fy_n.push_back(at(gen.series.fy_n) + noise(rng));
    meas.fz_n.push_back(at(gen.series.fz_n) + noise(rng));
  }
  const Job start =
      load_job(example("bergmann2021/trochoidal.toml"),
               {parse_override("material.k_c=1500"), parse_override("material.k_n=300"),
                parse_override("material.m=0.2"), parse_override("tool.runout_radial=0.005")});
  CalibrationOptions o;
  o.fit = {"k_c", "k_n", "m", "runout_radial"};
  o.fast = true;
  o.from_s = t0, o.to_s = t0 + 1.0;
  o.max_shift_s = 0.02;
  double kc = 0;
  int iterations = 0;
  for (auto _ : state) {
    const CalibrationResult r = calibrate_forces(start, path, meas, o);
    kc = r.material.k_c;
    iterations = r.iterations;
  }
  state.counters["samples"] = static_cast<double>(meas.t_s.size());
  state.counters["k_c_error_pct"] = 100 * (kc - 1926.08) / 1926.08;
  state.counters["iterations"] = iterations;
}
BENCHMARK(ForceCalibrate)->Name("Force/Calibrate1s20kHz")->Unit(benchmark::kMillisecond);

// The Kronecker sequence u = 2 frac(i a1), v = frac(i a2) (a1, a2 from the plastic number),
// and a smooth surface of 0.1 mm amplitude: the same in scripts/bench-scipy-rbf.
double surface(double u, double v) {
  return 0.05 * std::sin(2 * u) * std::cos(3 * v) + 0.02 * u * u - 0.01 * v;
}
void kronecker(int n, std::vector<std::array<double, 2>>& pts, std::vector<double>& val) {
  const double g = 1.32471795724474602596, a1 = 1 / g, a2 = 1 / (g * g);
  for (int i = 1; i <= n; ++i) {
    const double u = 2 * std::fmod(0.5 + a1 * i, 1.0), v = std::fmod(0.5 + a2 * i, 1.0);
    pts.push_back({u, v});
    val.push_back(surface(u, v));
  }
}

void TopographyRbfFit(benchmark::State& state) {
  std::vector<std::array<double, 2>> pts;
  std::vector<double> val;
  kronecker(static_cast<int>(state.range(0)), pts, val);
  double worst = 0;
  for (auto _ : state) {
    const CubicRbf rbf(pts, val);
    worst = 0;
    for (int i = 0; i < 10000; ++i) {
      const double u = 0.1 + 1.8 * ((i * 0.6180339887) - std::floor(i * 0.6180339887));
      const double v = 0.1 + 0.8 * ((i * 0.7548776662) - std::floor(i * 0.7548776662));
      worst = std::max(worst, std::abs(rbf(u, v) - surface(u, v)));
    }
  }
  state.counters["max_error_mm"] = worst;
}
BENCHMARK(TopographyRbfFit)->Name("Topography/RbfFit")->Arg(100000)->Unit(benchmark::kMillisecond);

void TopographySampleInsert(benchmark::State& state) {
  SimTool tool;
  tool.radius_mm = 8, tool.corner_radius_mm = 0.8, tool.flute_length_mm = 6;
  tool.segment_mm = 0.05, tool.sub_segments = 5;
  SyntheticInsert s;
  s.vb_mm = 0.15;
  s.sections = 1100, s.profile_points = 200;
  const Mesh m = synthetic_insert(tool, s);
  std::size_t points = 0;
  for (auto _ : state) {
    EdgeTopography info;
    const EdgeGrid g = sample_topography(m, tool, 0.2, &info);
    points = info.points;
    benchmark::DoNotOptimize(g.cells.data());
  }
  state.counters["points"] = static_cast<double>(points);
}
BENCHMARK(TopographySampleInsert)->Name("Topography/SampleInsert")->Unit(benchmark::kMillisecond);

}  // namespace
