// The simulation's outputs: the machined slot read off each board (walls and floor), the chip
// map through HDF5, the surface's STL, and the output set written whole, streamed or kept.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sim_util.hpp"
#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report/sim.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"
#include "trochomill/texture.hpp"

namespace trochomill {
namespace {

using test::end_mill;
using test::line_path;
using test::same_entry;
using test::small_wagih_job;

// A straight full slot (a_p 1 mm, R 5 mm, f_z 0.2 mm) read off each board: the X board's walls
// lie at x = +-R less at most the feed marks' depth f_z^2 / 8R (1e-3 mm) on the rows the tool
// passed; the Z and Y boards place the wall between their last cut ray and their first uncut
// one, so within one spacing of it; the Z board's floor is the tip height z = -1 (exact: the
// ray is cut from the tip up) and the X board is cut at every level above it and at none below.
TEST(Sim, TheThreeBoardsAgreeOnTheMachinedSlot) {
  const double d = 0.05, R = 5, fz = 0.2;
  const Box3 box{{-8, -10, -2}, {8, 10, 0}};
  TriDexel work(box, d);
  SimSettings s;
  s.steps_per_rev = 60;
  const SimTool tool = end_mill(0);
  const ToolPath p = line_path(0, -16, 16, -1, fz * 2 * 3000);
  (void)simulate(p, tool, s, work, 0, p.duration_s());
  const auto walls = wall_profiles(work, 0.0, 20);
  int rows = 0;
  for (const WallPoint& w : walls) {
    if (w.y_mm < -9 || w.y_mm > 9) continue;
    EXPECT_GT(w.z_mm, -1.0) << "cut below the tip";
    EXPECT_NEAR(w.left_x_mm, -R, fz * fz / (8 * R) + 1e-9) << w.y_mm << " " << w.z_mm;
    EXPECT_NEAR(w.right_x_mm, R, fz * fz / (8 * R) + 1e-9) << w.y_mm << " " << w.z_mm;
    ++rows;
  }
  EXPECT_GT(rows, 1000);
  // Z board: the floor profile across the slot at y = 0.
  const auto floor = floor_profiles(work, 400);
  int checked = 0;
  for (const FloorPoint& f : floor) {
    if (std::abs(f.y_mm - 0.025) > 1e-9) continue;
    if (std::abs(f.x_mm) < R - d) {
      EXPECT_DOUBLE_EQ(f.z_mm, -1.0) << f.x_mm;
    }
    if (std::abs(f.x_mm) > R + d) {
      EXPECT_DOUBLE_EQ(f.z_mm, 0.0) << f.x_mm;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 320);
  // Y board (rays along y at (z, x)): at mid-depth, cut within the walls, whole outside.
  const DexelBoard& yb = work.boards[1];
  const int zl = static_cast<int>((-0.5 - box.lo[2]) / d);
  for (int j = 0; j < yb.count_v(); ++j) {
    const double x = yb.v_of(j);
    double len = 0;
    for (const Interval& v : yb.intervals(zl, j)) len += v.hi - v.lo;
    if (std::abs(x) < R - d) {
      EXPECT_NEAR(len, 0.0, 1e-9) << x;
    }
    if (std::abs(x) > R + d) {
      EXPECT_NEAR(len, 20.0, 1e-9) << x;
    }
  }
}

// The chip map through HDF5 and back: every value identical (float32 stored as float32).
TEST(Sim, ChipMapHdf5RoundTrip) {
  const Box3 box{{-8, -10, -2}, {8, 10, 0}};
  TriDexel work(box, 0.1);
  SimSettings s;
  s.steps_per_rev = 60;
  const SimTool tool = end_mill(30);
  const ToolPath p = line_path(0, -14, -6, -1, 0.1 * 2 * 3000);
  const SimResult r = simulate(p, tool, s, work, 0, p.duration_s());
  const ChipMapData m = chip_map_data(r, tool, s);
  ASSERT_EQ(m.h_mm.size(), r.steps.size() * 2 * static_cast<std::size_t>(r.segments_per_tooth));
  std::size_t nonzero = 0;
  for (const float v : m.h_mm) nonzero += v > 0 ? 1 : 0;
  EXPECT_EQ(nonzero, r.chip_map.size());
  const auto file = std::filesystem::temp_directory_path() / "trochomill_chips_test.h5";
  write_chip_map_h5(file, m);
  // The same map writes the same bytes (no time stamps in the file), a second later too.
  const auto file2 = std::filesystem::temp_directory_path() / "trochomill_chips_test2.h5";
  sleep(1);
  write_chip_map_h5(file2, m);
  EXPECT_EQ(test::read_file(file), test::read_file(file2));
  // Written from the result itself, made dense a block of 1024 steps at a time (the run has
  // more than two blocks): the same bytes as from the whole dense map.
  ASSERT_GT(r.steps.size(), 2048u);
  write_chip_map_h5(file2, r, tool, s);
  EXPECT_EQ(test::read_file(file), test::read_file(file2));
  std::filesystem::remove(file2);
  const ChipMapData back = read_chip_map_h5(file);
  std::filesystem::remove(file);
  EXPECT_EQ(back.teeth, 2u);
  EXPECT_EQ(back.segments_per_tooth, m.segments_per_tooth);
  EXPECT_EQ(back.steps_per_rev, 60);
  EXPECT_TRUE(back.complete);
  EXPECT_EQ(back.t_s, m.t_s);
  EXPECT_EQ(back.tip_mm, m.tip_mm);
  EXPECT_EQ(back.removed_mm3, m.removed_mm3);
  EXPECT_EQ(back.h_mm, m.h_mm);
  EXPECT_EQ(back.w_mm, m.w_mm);
  EXPECT_EQ(back.v_mm3, m.v_mm3);
  EXPECT_EQ(back.segment_height_mm, m.segment_height_mm);
  EXPECT_THROW((void)read_chip_map_h5(file), Error);  // gone: a clear error, no crash
}

// The machined surface's STL is a closed solid: every edge is shared by exactly two
// triangles, and its volume by the divergence theorem equals the height field's integral
// (trapezoidal over the grid cells, which the two triangles per cell integrate exactly) to
// float precision (1e-6 relative: the STL stores float32).
TEST(Sim, SurfaceStlIsAClosedSolidOfTheHeightFieldsVolume) {
  const Box3 box{{-8, -10, -2}, {8, 10, 0}};
  TriDexel work(box, 0.1);
  SimSettings s;
  s.steps_per_rev = 60;
  SimTool tool = end_mill(0);
  tool.corner_radius_mm = 1;
  const ToolPath p = line_path(0, -16, 4, -1, 0.2 * 2 * 3000);
  (void)simulate(p, tool, s, work, 0, p.duration_s());
  const HeightField f = surface_height_field(work, 0.2);
  const std::string stl = height_field_stl(f);
  std::uint32_t n = 0;
  std::memcpy(&n, stl.data() + 80, 4);
  ASSERT_EQ(stl.size(), 84u + 50u * n);
  std::map<std::array<float, 6>, int> edges;
  double vol = 0;
  for (std::uint32_t t = 0; t < n; ++t) {
    float v[12];
    std::memcpy(v, stl.data() + 84 + 50 * t, 48);
    const float* a = v + 3;
    const float* b = v + 6;
    const float* c = v + 9;
    vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
            a[2] * (b[0] * c[1] - b[1] * c[0])) /
           6.0;
    for (const auto& [p0, p1] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
      std::array<float, 6> key{p0[0], p0[1], p0[2], p1[0], p1[1], p1[2]};
      std::array<float, 6> rev{p1[0], p1[1], p1[2], p0[0], p0[1], p0[2]};
      ++edges[std::min(key, rev)];
    }
  }
  for (const auto& [e, k] : edges) ASSERT_EQ(k, 2);
  const std::size_t nc = f.x_mm_of_column.size(), nr = f.y_mm_of_row.size();
  double want = 0;
  for (std::size_t a = 0; a + 1 < nc; ++a) {
    for (std::size_t b = 0; b + 1 < nr; ++b) {
      const double dx = f.x_mm_of_column[a + 1] - f.x_mm_of_column[a];
      const double dy = f.y_mm_of_row[b + 1] - f.y_mm_of_row[b];
      // Two triangles on the diagonal (a, b)-(a+1, b+1): their integral.
      const double z0 = f.z_mm[a * nr + b], z2 = f.z_mm[(a + 1) * nr + b + 1];
      const double z1 = f.z_mm[(a + 1) * nr + b], z3 = f.z_mm[a * nr + b + 1];
      want += dx * dy * ((z0 + z1 + z2) / 6 + (z0 + z2 + z3) / 6 - f.bottom_mm);
    }
  }
  EXPECT_NEAR(vol, want, 1e-6 * std::abs(want) + 1e-3);
  // And the slot is in it: the machined volume (stock less the solid) is near the slot's.
  EXPECT_GT(box.volume_mm3() - want, 100.0);
}

// simulate's --out is written as one set: cancelled between files, the folder holds none of
// this run's files (an earlier run's stay as they were) and no staging folder; not cancelled,
// all six replace the earlier ones.
TEST(Sim, OutputsAreWrittenAsOneSet) {
  const Job job = small_wagih_job();
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 2, 3);
  const JobSimulation js = simulate_job(job, path, from, to);
  const auto dir =
      std::filesystem::temp_directory_path() / ("trochomill_outputs_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  write_file_atomic(dir / "series.csv", "an earlier run\n");
  const auto entries = [&] {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      names.push_back(e.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  };
  std::atomic<bool> stop{false};
  RunHooks hooks;
  hooks.cancel = &stop;
  std::vector<std::string> phases;
  hooks.phase = [&](std::string_view name) { phases.emplace_back(name); };
  // The floor: cut across the slot in this window (floor.x3p is then the sixth file).
  const double half =
      0.5 * job.slot.width_mm - job.tool.corner_radius_mm - job.simulation.resolution_mm;
  const HeightMap floor = floor_height_map(*js.work, -half, half, -0.5 * job.slot.depth_mm);
  EXPECT_GE(floor.nx, 2u);
  hooks.progress = [&](std::size_t done, std::size_t total) {
    EXPECT_EQ(total, 6u);
    if (done == 3) stop = true;  // after three of the six files
  };
  EXPECT_THROW((void)write_simulation_outputs(dir, job, js, std::nullopt, hooks), Interrupted);
  EXPECT_EQ(phases, std::vector<std::string>{"writing outputs"});
  EXPECT_EQ(entries(), std::vector<std::string>{"series.csv"});
  EXPECT_EQ(read_file(dir / "series.csv"), "an earlier run\n");

  stop = false;
  hooks.progress = {};
  EXPECT_EQ(write_simulation_outputs(dir, job, js, std::nullopt, hooks), "");
  EXPECT_EQ(entries(), (std::vector<std::string>{"chips.h5", "floor.csv", "floor.x3p", "series.csv",
                                                 "surface.stl", "walls.csv"}));
  // floor.x3p holds the floor: the same heights (to one rounding, mm to m and back).
  const HeightMap back = read_x3p(dir / "floor.x3p");
  ASSERT_EQ(back.z_mm.size(), floor.z_mm.size());
  for (std::size_t i = 0; i < floor.z_mm.size(); ++i) {
    ASSERT_NEAR(back.z_mm[i], floor.z_mm[i], 2.3e-16 * std::abs(floor.z_mm[i]));
  }
  EXPECT_NE(read_file(dir / "series.csv"), "an earlier run\n");
  std::filesystem::remove_all(dir);
}

// A simulation whose records go to a sink and are not kept hands the sink exactly the records a
// kept run holds (every field bit for bit, each step's chip entries in order), keeps none, and
// counts the same steps and h_max. The outputs streamed into SimulationOutputs as the steps come
// are the bytes write_simulation_outputs writes from the kept run.
TEST(Sim, StreamedRecordsAreTheKeptOnes) {
  const Job job = small_wagih_job();
  const ToolPath path = plan_path(job).path;
  const auto [from, to] = cycle_window(path, 2, 3);
  const JobSimulation kept = simulate_job(job, path, from, to);
  struct Collect final : SimSink {
    void take(const SimStep& st, std::span<const ChipEntry> chips) override {
      for (const ChipEntry& c : chips) EXPECT_EQ(c.step, steps.size());
      steps.push_back(st);
      entries.insert(entries.end(), chips.begin(), chips.end());
    }
    std::vector<SimStep> steps;
    std::vector<ChipEntry> entries;
  } got;
  SimControl c;
  c.keep_records = false;
  c.sink = &got;
  const JobSimulation streamed = simulate_job(job, path, from, to, c);
  const SimResult &k = kept.result, &r = streamed.result;
  EXPECT_TRUE(r.steps.empty());
  EXPECT_TRUE(r.chip_map.empty());
  ASSERT_GT(k.steps.size(), 1000u);
  ASSERT_GT(k.chip_map.size(), 1000u);
  EXPECT_EQ(k.step_count, k.steps.size());
  EXPECT_EQ(r.step_count, k.steps.size());
  double h_max = 0;
  for (const SimStep& st : k.steps) h_max = std::max(h_max, st.h_max_mm);
  EXPECT_GT(h_max, 0.0);
  EXPECT_EQ(k.h_max_mm, h_max);
  EXPECT_EQ(r.h_max_mm, h_max);
  EXPECT_EQ(r.removed_by_board_mm3, k.removed_by_board_mm3);
  EXPECT_EQ(r.dexel_updates, k.dexel_updates);
  ASSERT_EQ(got.steps.size(), k.steps.size());
  for (std::size_t n = 0; n < k.steps.size(); ++n) {
    const SimStep &a = got.steps[n], &b = k.steps[n];
    ASSERT_EQ(a.t_s, b.t_s) << n;
    ASSERT_EQ(a.tip_mm, b.tip_mm) << n;
    ASSERT_EQ(a.removed_mm3, b.removed_mm3) << n;
    ASSERT_EQ(a.h_max_mm, b.h_max_mm) << n;
    ASSERT_EQ(a.h_mean_mm, b.h_mean_mm) << n;
    ASSERT_EQ(a.engaged_segments, b.engaged_segments) << n;
  }
  ASSERT_EQ(got.entries.size(), k.chip_map.size());
  for (std::size_t q = 0; q < k.chip_map.size(); ++q) {
    ASSERT_TRUE(same_entry(got.entries[q], k.chip_map[q])) << q;
  }

  const auto base =
      std::filesystem::temp_directory_path() / ("trochomill_stream_" + std::to_string(::getpid()));
  std::filesystem::remove_all(base);
  std::filesystem::create_directory(base);  // the outputs make only their own folder
  const std::string note = write_simulation_outputs(base / "kept", job, kept, std::nullopt);
  SimulationOutputs out(base / "streamed", job);
  c.sink = &out;
  const JobSimulation js = simulate_job(job, path, from, to, c);
  EXPECT_EQ(out.finish(js, std::nullopt), note);
  for (const char* f : {"series.csv", "chips.h5", "walls.csv", "floor.csv", "surface.stl"}) {
    const std::string a = test::read_file(base / "kept" / f);
    EXPECT_GT(a.size(), 1000u) << f;
    EXPECT_TRUE(a == test::read_file(base / "streamed" / f)) << f;
  }
  const ChipMapData m = read_chip_map_h5(base / "streamed" / "chips.h5");
  EXPECT_EQ(m.t_s.size(), k.steps.size());
  EXPECT_TRUE(m.complete);
  std::filesystem::remove_all(base);
}

}  // namespace
}  // namespace trochomill
