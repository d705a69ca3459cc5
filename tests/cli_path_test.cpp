// The CLI's path commands: plan (with a feed schedule) writes G-code that check-gcode reads,
// check-gcode takes the machine from a job, path's CSV, and optimize-feed with a stock mesh.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/io.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::run_cli;

// plan --feed-schedule: the same path (length to the writer's rounding) at varying feeds,
// faster than at the constant one, read back by check-gcode; its options need the flag.
TEST_F(Cli, PlanWithAFeedScheduleWritesTheSamePathFaster) {
  const auto ex = test::example("wagih2023/trochoidal.toml").string();
  const auto plain = (dir_ / "plain.ngc").string(), fast = (dir_ / "fast.ngc").string();
  ASSERT_EQ(run_cli("plan " + ex + " -o " + plain).code, 0);
  const CliResult r = run_cli("plan " + ex + " -o " + fast + " --feed-schedule --max-feed 1500");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("feed schedule: h_max 0.07500 ->"), std::string::npos) << r.out;
  const auto a = nlohmann::json::parse(run_cli("check-gcode " + plain + " --json -").out);
  const auto b = nlohmann::json::parse(run_cli("check-gcode " + fast + " --json -").out);
  // The writer rounds to 1e-4 mm (4 decimals): lengths agree within 1e-4 relative.
  EXPECT_NEAR(b["path_length_mm"].get<double>(), a["path_length_mm"].get<double>(),
              1e-4 * a["path_length_mm"].get<double>());
  EXPECT_LT(b["time_s"].get<double>(), 0.7 * a["time_s"].get<double>());
  EXPECT_LE(b["feed_max_mm_per_min"].get<double>(), 1500.0);
  EXPECT_GE(b["feed_min_mm_per_min"].get<double>(), 60.0);
  const CliResult e = run_cli("plan " + ex + " -o " + fast + " --max-feed 900");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.out.find("--max-feed is an option of --feed-schedule"), std::string::npos) << e.out;
}

TEST_F(Cli, PlanWritesGcodeThatCheckGcodeReads) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const auto out = (dir_ / "e.ngc").string();
  const CliResult r = run_cli("plan " + ex + " -o " + out + " --dialect linuxcnc");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("elliptical"), std::string::npos);
  const CliResult c = run_cli("check-gcode " + out + " --json -");
  ASSERT_EQ(c.code, 0) << c.out;
  const auto j = nlohmann::json::parse(c.out);
  EXPECT_GT(j["path_length_mm"].get<double>(), 500.0);
  // The tool centre stays within |x| <= a = 5 mm and reaches the slot depth.
  EXPECT_NEAR(j["bbox_min_mm"][0].get<double>(), -5.0, 1e-4);
  EXPECT_NEAR(j["bbox_max_mm"][0].get<double>(), 5.0, 1e-4);
  EXPECT_NEAR(j["bbox_min_mm"][2].get<double>(), -6.0, 1e-12);
  EXPECT_EQ(j["spindle_max_rpm"].get<double>(), 2000.0);
}

// plan --json of a pocket: the plan's figures and the kernel's proof, the same numbers the
// summary prints (to its 4 significant digits); with --json - only the JSON on stdout (the
// summary on stderr); refused for a slot, and with -o - too.
TEST_F(Cli, PlanJsonGivesAPocketsProof) {
  const auto ex = test::example("pockets/plate.toml").string();
  const auto out = (dir_ / "p.ngc").string(), js = (dir_ / "p.json").string();
  const CliResult r = run_cli("plan " + ex + " -o " + out + " --json " + js);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(test::read_file(js));
  EXPECT_EQ(j["target_engagement_deg"].get<double>(), 53.0);
  EXPECT_EQ(j["levels"].get<int>(), 2);
  EXPECT_EQ(j["plans"].get<int>(), 1);
  EXPECT_TRUE(j["proven"].get<bool>());
  const double eng = j["clearing_max_engagement_deg"].get<double>();
  EXPECT_LE(eng, 53 * 1.02);
  EXPECT_GT(eng, 45);
  EXPECT_NE(
      r.out.find(fmt::format("clearing (entries excepted) engagement max {:.4g} degrees", eng)),
      std::string::npos)
      << r.out;
  EXPECT_EQ(j["clearing_max_at_mm"].size(), 3u);
  // The program's figures, as the summary's last line says them (3 decimals) and as written.
  EXPECT_NE(r.out.find(fmt::format(
                "path {:.3f} mm, time {:.3f} s ({:.3f} s with acceleration), {} lines",
                j["path_length_mm"].get<double>(), j["machining_time_s"].get<double>(),
                j["machining_time_accel_s"].get<double>(), j["program_lines"].get<long>())),
            std::string::npos)
      << r.out;
  const std::string program = test::read_file(out);
  EXPECT_EQ(j["program_lines"].get<long>(), std::count(program.begin(), program.end(), '\n'));
  ASSERT_EQ(j["unreachable"].size(), 1u);  // the 96 mm^2 beside the block island
  EXPECT_NEAR(j["unreachable"][0]["area_mm2"].get<double>(), 96.11, 0.01);
  // analyze --json of the program names a pocket as one: no slot, no step, no slot family.
  const CliResult a = test::run_command(std::string(TROCHOMILL_CLI) + " analyze " + ex +
                                        " --gcode " + out + " --json - 2>/dev/null");
  ASSERT_EQ(a.code, 0) << a.out;
  const auto aj = nlohmann::json::parse(a.out)["job"];
  EXPECT_EQ(aj["path_type"], "pocket");
  EXPECT_EQ(aj["pocket_boundary"], "POCKET");
  EXPECT_EQ(aj["pocket_depth_mm"].get<double>(), 6.0);
  EXPECT_TRUE(aj["channel_family"].is_null());
  EXPECT_FALSE(aj.contains("slot_width_mm"));
  EXPECT_FALSE(aj.contains("step_mm"));
  // To stdout: the JSON alone.
  const CliResult o = test::run_command(std::string(TROCHOMILL_CLI) + " plan " + ex + " -o " + out +
                                        " --json - 2>/dev/null");
  ASSERT_EQ(o.code, 0);
  EXPECT_EQ(nlohmann::json::parse(o.out), j);
  const CliResult both = run_cli("plan " + ex + " -o - --json -");
  EXPECT_EQ(both.code, 2);
  EXPECT_NE(both.out.find("-o - and --json -: both to stdout"), std::string::npos) << both.out;
  const CliResult slot = run_cli("plan " + test::example("wagih2023/trochoidal.toml").string() +
                                 " -o " + out + " --json " + js);
  EXPECT_EQ(slot.code, 2);
  EXPECT_NE(slot.out.find("--json: the plan's JSON is a pocket's"), std::string::npos) << slot.out;
}

// plan --strict: a pocket whose proof fails on every plan is not written (exit 1); the
// warning without it says why: the plate's pocket at a tenth with a 1 mm tool at 0.025 mm a
// tooth (f_z / R = 0.05) reaches 55.1 degrees for 53 (docs/models.md: up to 0.02 R the plans
// hold, 53.7 degrees at 0.01 and 0.02 R). A proven pocket writes as before; a slot refuses it.
TEST_F(Cli, PlanStrictWritesNoPocketItsProofFails) {
  const auto job = (dir_ / "small.toml").string(), out = (dir_ / "small.ngc").string();
  {
    std::ofstream f(job);
    f << "[geometry]\nfile = \"" << (test::source_dir() / "tests/data/dxf/pockets.dxf").string()
      << "\"\n[pocket]\nboundary = \"SMALL\"\nislands = \"SMALLI\"\ndepth = 1.0\n"
         "max_step_down = 1.0\nstock_to_leave = 0.02\nmax_engagement = 53.0\n[tool]\n"
         "diameter = 1.0\nteeth = 3\n[cutting]\nfeed_rate = 600.0\nspindle_speed = 8000.0\n";
  }
  const CliResult loose = run_cli("plan " + job + " -o " + out);
  ASSERT_EQ(loose.code, 0) << loose.out;
  EXPECT_NE(loose.out.find("the feed per tooth is 0.05 of the tool's radius, above the 0.02 up "
                           "to which the planner's model of the teeth held a 53 degree target on "
                           "the test pockets: a lower feed rate (0.4 times the [cutting] one"),
            std::string::npos)
      << loose.out;
  std::filesystem::remove(out);
  const CliResult strict = run_cli("plan " + job + " --strict -o " + out);
  EXPECT_EQ(strict.code, 1) << strict.out;
  EXPECT_NE(strict.out.find("plan --strict: the kernel finds"), std::string::npos) << strict.out;
  EXPECT_NE(strict.out.find("nothing was written"), std::string::npos) << strict.out;
  EXPECT_FALSE(std::filesystem::exists(out));
  // A program already at -o is left, and said to be no program of this job.
  std::ofstream(out) << "(an earlier program)\n";
  const CliResult stale = run_cli("plan " + job + " --strict -o " + out);
  EXPECT_EQ(stale.code, 1);
  EXPECT_NE(stale.out.find("is an earlier program, not this job's"), std::string::npos)
      << stale.out;
  std::filesystem::remove(out);
  // At 0.005 mm a tooth (0.01 R) it holds, and --strict writes it.
  const CliResult slow = run_cli("plan " + job + " --strict --set cutting.feed_rate=120 -o " + out);
  EXPECT_EQ(slow.code, 0) << slow.out;
  EXPECT_TRUE(std::filesystem::exists(out));
  const CliResult slot = run_cli("plan " + test::example("wagih2023/trochoidal.toml").string() +
                                 " --strict -o " + out);
  EXPECT_EQ(slot.code, 2);
  EXPECT_NE(slot.out.find("--strict: the proof it asks for is a pocket's"), std::string::npos)
      << slot.out;
}

// A drawing without a unit ($INSUNITS absent: tests/data/dxf/r12-parts.dxf, an R12 file) is
// read as mm with a warning naming the key that says otherwise; [geometry] units = "in"
// reads it in inches: the corner its SLOT layer has at (30, 10) is then at (762, 254) mm.
TEST_F(Cli, AUnitlessDrawingIsReadAsMmWithAWarning) {
  const std::string drawing = (test::source_dir() / "tests/data/dxf/r12-parts.dxf").string();
  const auto pocket = (dir_ / "r12.toml").string(), slot = (dir_ / "r12-slot.toml").string();
  const auto out = (dir_ / "r12.ngc").string();
  const std::string tool =
      "[tool]\ndiameter = 6.0\nteeth = 3\n[cutting]\nfeed_rate = 600.0\nspindle_speed = "
      "6000.0\n";
  std::ofstream(pocket) << "[geometry]\nfile = \"" << drawing
                        << "\"\n[pocket]\nboundary = \"ISLAND\"\ndepth = 1.0\n"
                           "max_engagement = 50.0\n"
                        << tool;
  std::ofstream(slot) << "[geometry]\nfile = \"" << drawing
                      << "\"\n[slot]\nalong = \"SLOT\"\nwidth = 8.0\ndepth = 1.0\n[path]\n"
                         "type = \"trochoidal\"\nstep = 0.5\n"
                      << tool;
  const CliResult mm = run_cli("plan " + pocket + " -o " + out);
  ASSERT_EQ(mm.code, 0) << mm.out;
  EXPECT_NE(mm.out.find("r12-parts.dxf gives no unit (no $INSUNITS, or 0): its numbers are read "
                        "as mm; if it was drawn in another, say which with [geometry] units"),
            std::string::npos)
      << mm.out;
  const CliResult in_mm = run_cli("plan " + slot + " -o " + out);
  EXPECT_EQ(in_mm.code, 2);
  EXPECT_NE(in_mm.out.find("has a corner at (30.0000, 10.0000)"), std::string::npos) << in_mm.out;
  const CliResult in_in = run_cli("plan " + slot + " --set geometry.units='\"in\"' -o " + out);
  EXPECT_EQ(in_in.code, 2);
  EXPECT_NE(in_in.out.find("has a corner at (762.0000, 254.0000)"), std::string::npos) << in_in.out;
  EXPECT_EQ(in_in.out.find("gives no unit"), std::string::npos) << in_in.out;
  // check-drawing --units: the same for a drawing alone (the island's circle: 50.27 mm^2 as
  // mm, 25.4^2 times that in inches).
  const CliResult drawn = run_cli("check-drawing " + drawing + " --units in");
  EXPECT_EQ(drawn.code, 0) << drawn.out;
  EXPECT_NE(drawn.out.find("units: unitless (read as in: [geometry] units)"), std::string::npos)
      << drawn.out;
  // pi (4 x 25.4)^2 = 32429.2787 mm^2 (the circle of radius 4 units).
  EXPECT_NE(drawn.out.find("32429.2787"), std::string::npos) << drawn.out;
  EXPECT_EQ(run_cli("check-drawing " + drawing + " --units yd").code, 2);
}

// --stock FILE (plan, analyze, simulate, report): the job key stock.mesh, the file taken from
// the current folder. The plate with the cored blank given so plans as cored.toml (whose
// [stock] mesh is that file): the same moves, the core's air at the first level; a slot job
// refuses it, naming the flag and the key.
TEST_F(Cli, StockFlagIsTheStockMeshFromTheCurrentFolder) {
  const auto plate = test::example("pockets/plate.toml").string();
  const auto blank = std::filesystem::relative(test::example("pockets/cored-blank.stl")).string();
  const auto a = (dir_ / "a.ngc").string(), b = (dir_ / "b.ngc").string();
  const CliResult r = run_cli("plan " + plate + " --stock " + blank + " -o " + a);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("the [stock] mesh: air at the levels from the top 229.8, 0.0 mm^2"),
            std::string::npos)
      << r.out;
  ASSERT_EQ(run_cli("plan " + test::example("pockets/cored.toml").string() + " -o " + b).code, 0);
  const auto moves = [](const std::string& file) {
    std::string out;
    std::istringstream in(test::read_file(file));
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line[0] != '(') out += line + "\n";
    }
    return out;
  };
  EXPECT_EQ(moves(a), moves(b));
  const CliResult slot = run_cli("plan " + test::example("wagih2023/trochoidal.toml").string() +
                                 " --stock " + blank + " -o " + a);
  EXPECT_EQ(slot.code, 2);
  EXPECT_NE(slot.out.find("--stock (stock.mesh): is read by pocket jobs"), std::string::npos)
      << slot.out;
}

// check-gcode --job takes the machine from the job: its G55 origin, G28 position and tool
// table; a flag given overrides the job.
TEST_F(Cli, CheckGcodeTakesTheMachineFromAJob) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const auto tbl = (dir_ / "t.tbl").string();
  write_file_atomic(tbl, "T3 P3 Z40 D8\n");
  const auto f = (dir_ / "m.ngc").string();
  // In G55 (origin X100 in machine coordinates), the output frame G54 (origin 0): X5 in G55 is
  // X105 in G54; a G41 D3 circle of radius 20 run inside with tool 3 (8 mm) has radius 16.
  write_file_atomic(f,
                    "G21 G17 G90 G94\nG55 G0 X5 Y-20 Z2\nF300\nG41 D3\nG1 X5 Y0\n"
                    "G3 X5 Y0 I20 J0\nG40\nG1 X5 Y-20\nG28\nM2\n");
  const std::string sets =
      " --set machine.origin_g54=[0,0,0] --set machine.origin_g55=[100,0,0]"
      " --set machine.g28_position=[0,0,50] --set machine.tool_table=" +
      tbl;
  const CliResult r = run_cli("check-gcode " + f + " --json - --job " + ex + sets);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  // The circle's tool centre: x from 105 + 4 to 105 + 36 (16 mm about (125, 0)); G28 ends at
  // the machine's 0, 0, 50 (1e-9 mm: sums of the words).
  EXPECT_NEAR(j["bbox_max_mm"][0].get<double>(), 141.0, 1e-9);
  EXPECT_NEAR(j["bbox_max_mm"][2].get<double>(), 50.0, 1e-9);
  EXPECT_NEAR(j["bbox_min_mm"][0].get<double>(), 0.0, 1e-9);
  // The flag over the job: G55's origin given on the command line.
  const CliResult o =
      run_cli("check-gcode " + f + " --json - --job " + ex + sets + " --offset G55=200,0,0");
  ASSERT_EQ(o.code, 0) << o.out;
  EXPECT_NEAR(nlohmann::json::parse(o.out)["bbox_max_mm"][0].get<double>(), 241.0, 1e-9);
  // --set without --job is an error that says so.
  const CliResult e = run_cli("check-gcode " + f + " --set machine.dialect=fanuc");
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.out.find("--set needs --job"), std::string::npos) << e.out;
}

TEST_F(Cli, PathCsvHasToothTracks) {
  const auto ex = test::example("wagih2023/trochoidal.toml").string();
  const auto csv = (dir_ / "p.csv").string();
  const CliResult r = run_cli("path " + ex + " --csv " + csv + " --steps-per-rev 12");
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(csv);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("t_s,s_mm,x_mm,y_mm,z_mm", 0), 0u);
  EXPECT_NE(header.find("tooth3_y_mm"), std::string::npos);
  std::size_t rows = 0;
  for (std::string line; std::getline(in, line);) ++rows;
  // 12 samples per revolution at 2000 rpm: dt = 2.5 ms over the whole program.
  const double duration = 64.957;  // s, the planned program (checked to 1 ms below)
  EXPECT_NEAR(static_cast<double>(rows), duration / 0.0025, 2.0);
  EXPECT_EQ(run_cli("path " + ex + " --dt 0.1 --ds 0.1").code, 2);  // exclusive options
}

// optimize-feed's stock mesh: an STL box with --engine sim and with the kernel runs (the
// summary names the engine, the simulation's resolution; the output exists); with a face
// missing, exit 2 naming a line that crosses it an odd number of times, nothing written.
TEST_F(Cli, OptimizeFeedWithAStockMesh) {
  const auto job = (dir_ / "job.toml").string(), prog = (dir_ / "p.ngc").string(),
             stl = (dir_ / "stock.stl").string(), open_stl = (dir_ / "open.stl").string(),
             out = (dir_ / "out.ngc").string();
  std::ofstream(job) << "[tool]\ndiameter = 10\nteeth = 4\n[slot]\nwidth = 10\nlength = 20\n"
                        "depth = 3\n[path]\ntype = \"linear\"\nstep = 1\n"
                        "[cutting]\nfeed_rate = 600\nspindle_speed = 2000\n"
                        "[machine]\ndialect = \"linuxcnc\"\n[simulation]\nresolution = 0.1\n"
                        "steps_per_rev = 24\n";
  std::ofstream(prog) << "G21 G90 G17 G94\nG0 X0 Y-8 Z5\nG1 Z-1 F600\nG1 Y12\nG0 Z5\nM2\n";
  // An ASCII STL box x -8..8, y 0..10, z -3..0, two facets a face (outward).
  const double lo[3] = {-8, 0, -3}, hi[3] = {8, 10, 0};
  auto corner = [&](int k) {
    return std::to_string((k & 1) ? hi[0] : lo[0]) + " " + std::to_string((k & 2) ? hi[1] : lo[1]) +
           " " + std::to_string((k & 4) ? hi[2] : lo[2]);
  };
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  auto stl_text = [&](int skip) {
    std::string s = "solid stock\n";
    int n = 0;
    for (const auto& q : faces) {
      for (const auto& t : {std::array{q[0], q[1], q[2]}, std::array{q[0], q[2], q[3]}}) {
        if (n++ == skip) continue;
        s += "facet normal 0 0 0\nouter loop\n";
        for (const int k : t) s += "vertex " + corner(k) + "\n";
        s += "endloop\nendfacet\n";
      }
    }
    return s + "endsolid stock\n";
  };
  std::ofstream(stl) << stl_text(-1);
  std::ofstream(open_stl) << stl_text(0);
  const CliResult ok = run_cli("optimize-feed " + prog + " --job " + job + " -o " + out +
                               " --engine sim --stock " + stl + " --rounds 2");
  EXPECT_EQ(ok.code, 0) << ok.out;
  EXPECT_NE(ok.out.find("the tri-dexel simulation at 0.1 mm, 24 steps/rev"), std::string::npos)
      << ok.out;
  EXPECT_TRUE(std::filesystem::exists(out));
  std::filesystem::remove(out);
  const CliResult kernel =
      run_cli("optimize-feed " + prog + " --job " + job + " -o " + out + " --stock " + stl);
  EXPECT_EQ(kernel.code, 0) << kernel.out;
  EXPECT_NE(kernel.out.find("the exact engagement kernel"), std::string::npos) << kernel.out;
  std::filesystem::remove(out);
  for (const char* engine : {"kernel", "sim"}) {
    const CliResult open = run_cli("optimize-feed " + prog + " --job " + job + " -o " + out +
                                   " --engine " + engine + " --stock " + open_stl);
    EXPECT_EQ(open.code, 2) << engine << open.out;
    EXPECT_NE(open.out.find("not closed"), std::string::npos) << engine << open.out;
    EXPECT_FALSE(std::filesystem::exists(out)) << engine;
  }
}

}  // namespace
}  // namespace trochomill
