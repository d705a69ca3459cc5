// The CLI's analysis commands: analyze (of a placed program, of a program without a cycle,
// its JSON and CSV, bad input), compare's grid, mechanism and recommend.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::first_line_of;
using test::run_cli;

// A program placed anywhere in the workpiece analyses as the slot it cuts when the job places
// it the same way; a program written for other keys draws a warning naming each key.
TEST_F(Cli, PlacedProgramAnalysesLikeThePlainOneAndHeaderMismatchesWarn) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const std::string place =
      " --set slot.origin_x=-250.5 --set slot.origin_y=40 --set slot.angle=90";
  const auto plain = (dir_ / "plain.ngc").string(), placed = (dir_ / "placed.ngc").string();
  ASSERT_EQ(run_cli("plan " + ex + " -o " + plain).code, 0);
  ASSERT_EQ(run_cli("plan " + ex + " -o " + placed + place).code, 0);
  const CliResult a = run_cli("analyze " + ex + " --gcode " + plain + " --json -");
  const CliResult b = run_cli("analyze " + ex + " --gcode " + placed + place + " --json -");
  ASSERT_EQ(a.code, 0) << a.out;
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_EQ(b.out.find("warning"), std::string::npos) << b.out;
  const auto ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out);
  // A quarter turn and a move on the 1e-4 mm grid commute with the program's rounding: the
  // turned-back program is the plain one to the reader's arithmetic (1e-9 relative).
  for (const char* k : {"cycle_mrr_mm3_per_min", "h_max_mm", "cycle_h_max_mm",
                        "engagement_angle_max_deg", "machining_time_s", "waviness_left_mm"}) {
    ASSERT_TRUE(ja.contains(k)) << k;
    EXPECT_NEAR(jb[k].get<double>(), ja[k].get<double>(), 1e-9 * std::abs(ja[k].get<double>()))
        << k;
  }
  // The placed program with the plain job: both placement keys are named.
  const CliResult c =
      run_cli("analyze " + ex + " --gcode " + placed + " --json " + (dir_ / "c.json").string());
  EXPECT_NE(c.out.find("warning: " + placed + " was written with slot.angle = 90"),
            std::string::npos)
      << c.out;
  EXPECT_NE(c.out.find("slot.origin_x = -250.5"), std::string::npos) << c.out;
  // A different feed in the job than in the program is named with both values.
  const CliResult d = run_cli("analyze " + ex + " --gcode " + plain +
                              " --set cutting.feed_rate=900 --json " + (dir_ / "d.json").string());
  EXPECT_NE(d.out.find("cutting.feed_rate = 600.0, the job has 900"), std::string::npos) << d.out;
}

// A program without a steady cycle (a full slot, then a 1 mm side pass) is summarised by the
// whole program: h_max is the slot's full chip f_z (R >= W/2 and the tool fully engaged: the
// chip is f_z at the slot's centre line), the cycle figures are null, the text says so.
TEST_F(Cli, AnalyzeSummarisesAProgramWithoutACycleByTheWholeProgram) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const auto f = (dir_ / "slot_then_side.ngc").string();
  // Slot frame: along +Y, x = 0 its centre line; the job's 10 mm tool, 4 teeth, 600 mm/min at
  // 2000 rpm (f_z = 0.075 mm) in its 20 x 20 mm slot, 6 mm deep: a full pass down the middle
  // (10 mm wide), then one 1 mm to the side.
  write_file_atomic(f,
                    "G21 G17 G90 G94\nG0 X0 Y-6 Z5\nG1 Z-6 F600\nG1 Y26\nG0 Z5\nG0 X1 Y-6\n"
                    "G1 Z-6\nG1 Y26\nG0 Z5\nM2\n");
  const CliResult r = run_cli("analyze " + ex + " --gcode " + f + " --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["periodic"].get<bool>());
  // The full slot's chip: f_z where the tooth crosses the feed direction (within the kernel's
  // sampling, 1e-9 relative: the chip of a circle translated by f_z at its apex is f_z).
  EXPECT_NEAR(j["h_max_mm"].get<double>(), 0.075, 0.075 * 1e-6);
  // Full engagement: the half circle ahead and the two slivers the last tooth pass (f_z back)
  // left, 180 + 2 asin(f_z / 2R) degrees (1e-9 deg: exact arcs).
  EXPECT_NEAR(j["engagement_angle_max_deg"].get<double>(),
              180.0 + 2 * std::asin(0.075 / 10.0) * 180.0 / kPi, 1e-9);
  // Removed: (10 + 1) mm x 20 mm x 6 mm. The swept-rate integral over tooth-pass samples
  // (rectangle rule, the entry and exit arcs included) is within 1e-3 of it.
  EXPECT_NEAR(j["removed_volume_mm3"].get<double>(), 1320.0, 1320.0 * 1e-3);
  EXPECT_NEAR(j["mrr_total_mm3_per_min"].get<double>(),
              j["removed_volume_mm3"].get<double>() / j["machining_time_s"].get<double>() * 60.0,
              1e-9);
  for (const char* key : {"cycle_time_s", "cycle_h_max_mm", "cycle_mrr_mm3_per_min",
                          "waviness_left_mm", "performance_index", "cycle_h_max_per_tooth_mm"}) {
    EXPECT_TRUE(j[key].is_null()) << key;
  }
  // Where: the full slot's block (line 4); the descent (line 3) is the entry, and the full
  // slot runs on 32 mm from it, farther than a tool diameter, so it is no part of the entry.
  const std::string at4 = f + ":4";
  EXPECT_EQ(j["h_max_at_line"], at4);
  EXPECT_EQ(j["h_max_after_entry_at_line"], at4);
  EXPECT_EQ(j["engagement_max_at_line"], at4);
  EXPECT_EQ(j["engagement_max_after_entry_at_line"], at4);
  EXPECT_NEAR(j["h_max_after_entry_mm"].get<double>(), 0.075, 0.075 * 1e-6);
  EXPECT_EQ(j["engagement_max_after_entry_deg"].get<double>(),
            j["engagement_angle_max_deg"].get<double>());
  const CliResult t = run_cli("analyze " + ex + " --gcode " + f);
  ASSERT_EQ(t.code, 0) << t.out;
  EXPECT_NE(t.out.find("h_max                0.075 mm"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("h_max at             " + at4 + " (0.000, "), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("steady cycle         none"), std::string::npos) << t.out;
  // A planned job has no lines to name.
  const CliResult planned = run_cli("analyze " + ex + " --json -");
  ASSERT_EQ(planned.code, 0) << planned.out;
  EXPECT_TRUE(nlohmann::json::parse(planned.out)["h_max_at_line"].is_null());
}

// LinuxCNC's arcspiral.ngc (an inch spiral of R-word arcs, 2.54 mm deep) has no steady cycle
// and its window touches no slot wall: analyze gives the whole program's figures and null
// walls (it stopped with "wall profile: no cutting sample within R", exit 2). Skipped where
// LinuxCNC's sample programs are not installed.
TEST_F(Cli, AnalyzeOfAProgramWithoutWallsGivesTheWholeProgram) {
  const std::string spiral = "/usr/share/linuxcnc/ncfiles/arcspiral.ngc";
  if (!std::filesystem::exists(spiral)) GTEST_SKIP() << spiral << " is not installed";
  const auto ex = test::example("wagih2023/trochoidal.toml").string();
  const CliResult r = run_cli("analyze " + ex + " --gcode " + spiral + " --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["periodic"].get<bool>());
  EXPECT_TRUE(j["waviness_left_mm"].is_null());
  EXPECT_TRUE(j["wall_peak_y_mm"].is_null());
  EXPECT_GT(j["h_max_mm"].get<double>(), 0.0);
  EXPECT_GT(j["removed_volume_mm3"].get<double>(), 0.0);
  EXPECT_EQ(j["h_max_at_line"].get<std::string>().rfind(spiral + ":", 0), 0u);
}

// A slot along a contour written with its helix entry and read back: the largest chip
// outside the entries is the planned path's (whose entry ends at its first cycle mark; the
// program's at the moves within a tool diameter of the helix), within 1 % (the program's
// 4-decimal coordinates), and the block named is a motion block of the program.
TEST_F(Cli, AnalyzeNamesTheBlockOfTheLargestChipOutsideTheEntries) {
  const auto ex = test::example("curves/bend.toml").string();
  const auto ngc = (dir_ / "bend.ngc").string();
  ASSERT_EQ(run_cli("plan " + ex + " -o " + ngc).code, 0);
  const CliResult planned = run_cli("analyze " + ex + " --json -");
  const CliResult read = run_cli("analyze " + ex + " --gcode " + ngc + " --json -");
  ASSERT_EQ(planned.code, 0) << planned.out;
  ASSERT_EQ(read.code, 0) << read.out;
  const auto p = nlohmann::json::parse(planned.out), r = nlohmann::json::parse(read.out);
  const double hp = p["h_max_after_entry_mm"].get<double>();
  EXPECT_NEAR(r["h_max_after_entry_mm"].get<double>(), hp, 0.01 * hp);
  EXPECT_LT(hp, p["h_max_mm"].get<double>());  // the entry's chip is the larger here
  const std::string where = r["h_max_after_entry_at_line"].get<std::string>();
  ASSERT_EQ(where.rfind(ngc + ":", 0), 0u) << where;
  const int line = std::stoi(where.substr(ngc.size() + 1));
  std::ifstream in(ngc);
  std::string text;
  for (int k = 0; k < line && std::getline(in, text); ++k) {
  }
  EXPECT_TRUE(text.rfind("G1", 0) == 0 || text.rfind("G2", 0) == 0 || text.rfind("G3", 0) == 0 ||
              text.rfind("X", 0) == 0 || text.rfind("Y", 0) == 0)
      << line << ": " << text;
}

// analyze: the JSON has every metric key, consistent with itself; the CSV has one
// row per sample; --gcode gives the same cycle as the job.
TEST_F(Cli, AnalyzeJsonAndCsv) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const auto csv = (dir_ / "series.csv").string();
  const CliResult r = run_cli("analyze " + ex + " --json - --csv " + csv);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key :
       {"path_length_mm", "machining_time_s", "mrr_total_mm3_per_min", "feed_per_tooth_mm",
        "h_max_mm", "t_h_max_s", "engagement_angle_max_deg", "cycle_path_length_mm", "cycle_time_s",
        "cycle_cutting_time_s", "cycle_cooling_time_s", "cycle_mrr_mm3_per_min", "cycle_h_max_mm",
        "cycle_t_h_max_s", "cycle_engagement_angle_max_deg", "waviness_left_mm",
        "waviness_right_mm", "waviness_left_tooth_mm", "waviness_right_tooth_mm"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j[key].is_number()) << key;
  }
  EXPECT_TRUE(j["periodic"].get<bool>());
  // The program's largest chip is at least the cycle's (it includes the cycle).
  EXPECT_GE(j["h_max_mm"].get<double>(), j["cycle_h_max_mm"].get<double>());
  // Cycle time = cycle length / feed (600 mm/min); MRR = W s a_p / T_c.
  EXPECT_NEAR(j["cycle_time_s"].get<double>(), j["cycle_path_length_mm"].get<double>() / 10.0,
              1e-9);
  EXPECT_NEAR(j["cycle_mrr_mm3_per_min"].get<double>(),
              20.0 * 1.0 * 6.0 / j["cycle_time_s"].get<double>() * 60.0, 1e-6);
  // The example's [material] (p20-kienzle from the library) gives the predicted force, and
  // with it the performance index (its value: Forces.PerformanceIndex...).
  EXPECT_GT(j["cycle_force_max_predicted_n"].get<double>(), 0);
  EXPECT_GT(j["performance_index"].get<double>(), 0);
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(
      line.rfind("t_s,x_mm,y_mm,z_mm,engaged_arcs_deg,engagement_deg,h_max_mm,teeth_in_cut", 0),
      0u);
  std::size_t rows = 0;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, j["samples"].get<std::size_t>());

  const auto ngc = (dir_ / "e.ngc").string();
  ASSERT_EQ(run_cli("plan " + ex + " -o " + ngc + " --tolerance 0.0001").code, 0);
  const CliResult g = run_cli("analyze " + ex + " --gcode " + ngc + " --json -");
  ASSERT_EQ(g.code, 0) << g.out;
  const auto k = nlohmann::json::parse(g.out);
  EXPECT_NEAR(k["cycle_time_s"].get<double>(), j["cycle_time_s"].get<double>(), 1e-4);
}

TEST_F(Cli, AnalyzeBadInput) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const auto out = (dir_ / "m.json").string();
  CliResult r = run_cli("analyze " + ex + " --set measured.force_max=-3 --json " + out);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("force_max"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
  r = run_cli("analyze " + ex + " --set analysis.steps_per_tooth=0");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("steps_per_tooth"), std::string::npos) << r.out;
  r = run_cli("analyze " + ex + " --gcode " + (dir_ / "missing.ngc").string());
  EXPECT_NE(r.code, 0);
  EXPECT_FALSE(std::filesystem::exists(out));
}

// compare: a grid of 2 x 2 points, the same numbers whatever the thread count, one row
// per point in the CSV, and a failing point reported without stopping the others.
TEST_F(Cli, CompareGrid) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const auto j1 = (dir_ / "a.json").string(), j2 = (dir_ / "b.json").string();
  const auto csv = (dir_ / "a.csv").string();
  const std::string grid =
      " --vary path.aspect_ratio=0.8,1.2 --vary path.step=0.8,1.0 --set slot.length=8";
  CliResult r = run_cli("compare " + ex + grid + " --threads 1 --json " + j1 + " --csv " + csv);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("path.aspect_ratio"), std::string::npos) << r.out;
  r = run_cli("compare " + ex + grid + " --threads 2 --json " + j2);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(read_file(j1), read_file(j2));  // deterministic whatever the thread count
  const auto j = nlohmann::json::parse(read_file(j1));
  ASSERT_EQ(j["points"].size(), 4u);
  EXPECT_EQ(j["points"][1]["set"]["path.aspect_ratio"], "0.8");
  EXPECT_EQ(j["points"][1]["set"]["path.step"], "1.0");
  // A longer cycle (r_e 1.2) removes less per minute at the same step.
  EXPECT_GT(j["points"][0]["metrics"]["cycle_mrr_mm3_per_min"].get<double>(),
            j["points"][2]["metrics"]["cycle_mrr_mm3_per_min"].get<double>());
  std::ifstream in(csv);
  std::string line;
  std::size_t rows = 0;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 5u);
  r = run_cli("compare " + ex + " --vary path.step=1.0,-1");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("failed at path.step=-1"), std::string::npos) << r.out;
  r = run_cli("compare " + ex + " --vary path.step");
  EXPECT_EQ(r.code, 2) << r.out;
  r = run_cli("compare " + ex + " --vary path.step=-1,-2");
  EXPECT_EQ(r.code, 2) << r.out;
}

// mechanism and recommend: JSON with the zone shares (summing to 1), min_step_mm, CSV
// curves; a family the model cannot describe is bad input.
TEST_F(Cli, MechanismAndRecommend) {
  const auto ex = test::example("pivkin2025/trochoidal.toml").string();
  CliResult r = run_cli("mechanism " + ex + " --set mechanism.points=360 --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  const double sum = j["zone_share"]["CZI"].get<double>() + j["zone_share"]["CZII"].get<double>() +
                     j["zone_share"]["CZIII"].get<double>();
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_EQ(j["h_mm"].size(), 360u);
  const auto csv = (dir_ / "m.csv").string();
  ASSERT_EQ(run_cli("mechanism " + ex + " --set mechanism.points=360 --csv " + csv).code, 0);
  EXPECT_EQ(first_line_of(csv).rfind("theta_deg,t_s,h_mm,psi_deg", 0), 0u);
  r = run_cli("recommend " + ex + " --set mechanism.points=360 --share 0.5 --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["min_step_mm"].get<double>(), 0.0);
  EXPECT_GE(j["zone_share"]["CZIII"].get<double>(), 0.5);
  r = run_cli("mechanism " + test::example("wagih2023/circular.toml").string());
  EXPECT_EQ(r.code, 2) << r.out;
  r = run_cli("recommend " + ex + " --share 1.5");
  EXPECT_EQ(r.code, 2) << r.out;
  // The published model: selectable on the command line and in the job; the same keys.
  r = run_cli("mechanism " + ex + " --model pivkin2025 --set mechanism.points=360 --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["model"], "pivkin2025");
  EXPECT_GT(j["h_max_mm"].get<double>(), 0.0);
  r = run_cli("recommend " + ex + " --set mechanism.model=pivkin2025 --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(r.out)["model"], "pivkin2025");
  r = run_cli("mechanism " + ex + " --model magic");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("pivkin2025"), std::string::npos) << r.out;  // lists what is allowed
}

}  // namespace
}  // namespace trochomill
