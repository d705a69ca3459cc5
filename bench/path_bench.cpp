// Benchmarks of the foundation: planning and writing a 100 mm elliptical slot (100 cycles),
// reading G-code (throughput in bytes per second), planning a slot along a 1 m curve and
// reading a 10 MB drawing.
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "trochomill/engagement.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/geometry/drawing.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/pocket.hpp"

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

// Plans the job with `plan` and writes its LinuxCNC program at each iteration; the counters
// are the plan's `count` (under `count_name`) and the program's size.
template <typename Plan, typename Count>
void plan_and_write(benchmark::State& state, const trochomill::Job& job, Plan plan,
                    const char* count_name, Count count) {
  trochomill::GcodeWriteOptions opt;
  opt.dialect = trochomill::Dialect::linuxcnc;
  std::size_t n = 0, bytes = 0;
  for (auto _ : state) {
    const auto p = plan(job);
    const std::string code = trochomill::write_gcode(job, p.path, opt);
    n = static_cast<std::size_t>(count(p));
    bytes = code.size();
    benchmark::DoNotOptimize(code.data());
  }
  state.counters[count_name] = static_cast<double>(n);
  state.counters["gcode_bytes"] = static_cast<double>(bytes);
}

void BM_PlanAndWriteEllipticalSlot100mm(benchmark::State& state) {
  plan_and_write(
      state, slot_job(100), [](const trochomill::Job& j) { return trochomill::plan_path(j); },
      "cycles", [](const trochomill::PlannedPath& p) { return p.info.cycles; });
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

// A slot along a 1 m centreline (bench/data/meander.dxf: five 160 mm legs, four U-turns of
// radius 20 mm), W 12, D 8, step 1 mm, 6 mm deep in three levels: planned with the engagement
// kernel judging the bends' steps, and written as G-code (its size in bytes), at the arc
// tolerance given in um (the default 1 um, and 10 um: a roughing tolerance).
void BM_PlanCurvedSlot1m(benchmark::State& state) {
  const double tolerance_mm = static_cast<double>(state.range(0)) * 1e-3;
  const std::string dir = std::string(TROCHOMILL_SOURCE_DIR) + "/bench/data/";
  std::string text = "[geometry]\nfile = \"" + dir +
                     "meander.dxf\"\n[tool]\ndiameter = 8.0\nteeth = 3\n[slot]\nalong = "
                     "\"MEANDER\"\nwidth = 12.0\ndepth = 6.0\nmax_step_down = 2.0\n[cutting]\n"
                     "feed_rate = 900.0\nspindle_speed = 6000.0\n[machine]\ndialect = "
                     "\"linuxcnc\"\narc_tolerance = " +
                     fmt::format("{}", tolerance_mm) +
                     "\n[path]\ntype = \"trochoidal\"\nstep = 1.0\nentry = \"helix\"\n";
  plan_and_write(
      state, trochomill::parse_job(text, dir + "meander.toml"),
      [](const trochomill::Job& j) { return trochomill::plan_slot(j); }, "cycles",
      [](const trochomill::PlannedPath& p) { return p.info.cycles; });
}
BENCHMARK(BM_PlanCurvedSlot1m)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond);

// Planning the example pocket (examples/pockets/plate.toml: 80 x 50 mm around two islands,
// 10 mm tool, 53 degrees, two levels and the finishing pass) and writing its program: what
// `plan` does, plan_pocket's proof by the engagement kernel included (and any plan it sends
// back).
void BM_PlanPocketPlate(benchmark::State& state) {
  plan_and_write(
      state,
      trochomill::load_job(std::string(TROCHOMILL_SOURCE_DIR) + "/examples/pockets/plate.toml"),
      [](const trochomill::Job& j) { return trochomill::plan_pocket(j); }, "passes",
      [](const trochomill::PlannedPocket& p) { return p.info.passes; });
}
BENCHMARK(BM_PlanPocketPlate)->Unit(benchmark::kMillisecond);

// The medial axis of a perforated plate: a W x 0.6 W mm rectangle less circular holes of
// radius 4 mm at a 20 mm pitch (W = 60, 120, 240 mm: 6, 24, 84 holes), shrunk by a 10 mm
// tool's radius and 0.2 mm of stock (offset_region: Clipper's chords within 1 um), sampled
// 0.05 mm apart: what a pocket with many islands asks of it.
void BM_MedialAxisPerforated(benchmark::State& state) {
  using trochomill::Contour;
  const double W = static_cast<double>(state.range(0)), H = 0.6 * W;
  std::vector<Contour> region{Contour::polyline({{0, 0}, {W, 0}, {W, H}, {0, H}}, true)};
  for (double x = 10; x < W; x += 20) {
    for (double y = 10; y < H; y += 20) {
      region.push_back(Contour::circle({x, y}, 4).reversed());
    }
  }
  // The tool centre's region of a 10 mm tool with 0.2 mm of stock (Clipper's chords), as the
  // pocket planner asks.
  region = trochomill::offset_region(region, -5.2, 1e-3);
  std::size_t samples = 0;
  for (auto _ : state) {
    const auto axis = trochomill::medial_axis(region, 120, 0.05);
    samples = 0;
    for (const auto& b : axis) samples += b.points.size();
    benchmark::DoNotOptimize(samples);
  }
  state.counters["samples"] = static_cast<double>(samples);
  state.counters["contours"] = static_cast<double>(region.size());
}
BENCHMARK(BM_MedialAxisPerforated)->Arg(60)->Arg(120)->Arg(240)->Unit(benchmark::kMillisecond);

// Reading a 10 MB DXF: 100,000 polylines of four lines and a bulge each (R12 text, written
// here), chained into closed contours.
void BM_ReadDxf10MB(benchmark::State& state) {
  const std::string file =
      (std::filesystem::temp_directory_path() / "trochomill-bench-10mb.dxf").string();
  {
    std::string t =
        "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\n"
        "ENTITIES\n";
    for (int k = 0; t.size() < 10'000'000; ++k) {
      const double x = (k % 300) * 10.0, y = (k / 300) * 10.0;
      t += fmt::format(
          "0\nLWPOLYLINE\n8\nL{}\n90\n4\n70\n1\n10\n{}\n20\n{}\n10\n{}\n20\n{}\n42\n0.25\n10\n{}\n"
          "20\n{}\n10\n{}\n20\n{}\n",
          k % 7, x, y, x + 6, y, x + 6, y + 6, x, y + 6);
    }
    t += "0\nENDSEC\n0\nEOF\n";
    std::ofstream(file, std::ios::binary) << t;
    state.counters["bytes"] = static_cast<double>(t.size());
  }
  std::size_t contours = 0;
  for (auto _ : state) {
    const auto d = trochomill::read_drawing(file, trochomill::DrawingOptions{});
    contours = d.contours.size();
    benchmark::DoNotOptimize(contours);
  }
  state.counters["contours"] = static_cast<double>(contours);
  std::filesystem::remove(file);
}
BENCHMARK(BM_ReadDxf10MB)->Unit(benchmark::kMillisecond);
