// The CLI's simulation commands: simulate's --out folder and outputs, forces, calibrate and
// materials.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::first_line_of;
using test::run_cli;

// simulate --out makes its folder as mkdir does: a missing parent is bad input (exit 2), and
// nothing is made (a mistyped path once made every folder on it silently).
TEST_F(Cli, SimulateOutMakesOnlyTheLastFolder) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const CliResult r =
      run_cli("simulate " + ex + " --cycles 3:4 --out " + (dir_ / "a" / "b" / "c").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("its parent"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "a"));
}

// simulate on a steady cycle of Wagih's trochoid (coarse: 0.1 mm dexels, 60 steps per
// revolution): the JSON keys with their values' invariants (the three boards remove
// the same volume within the boundary bound: 2 x 50 mm of wall x 6 mm x d / 2), every output
// file written and readable, and bad input refused with exit 2 naming the option.
TEST_F(Cli, SimulateWritesItsOutputs) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const std::string out = (dir_ / "sim").string();
  const std::string common =
      " --set simulation.resolution=0.1 --set simulation.steps_per_rev=60 --set slot.length=8";
  const CliResult r = run_cli("simulate " + ex + " --cycles 3:4 --json - --out " + out + common);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"removed_volume_mm3", "h_max_mm", "steps", "dexel_updates", "wall_time_s",
                          "complete", "memory_estimate_mb"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_TRUE(j["complete"].get<bool>());
  EXPECT_GT(j["steps"].get<int>(), 1000);
  // f_z = 600 / (2000 * 4) = 0.075 mm: the chip stays near it (feed marks, the wedge's width).
  EXPECT_GT(j["h_max_mm"].get<double>(), 0.03);
  EXPECT_LT(j["h_max_mm"].get<double>(), 0.075 * 1.1);
  const auto by = j["removed_volume_by_board_mm3"];
  for (int b = 0; b < 2; ++b) {
    EXPECT_NEAR(by[b].get<double>(), by[2].get<double>(), 100 * 6 * 0.1 / 2);
  }
  for (const char* f :
       {"series.csv", "chips.h5", "walls.csv", "floor.csv", "surface.stl", "floor.x3p"}) {
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(out) / f)) << f;
  }
  EXPECT_EQ(first_line_of(out + "/walls.csv"), "y_mm,z_mm,left_x_mm,right_x_mm");
  const ChipMapData m = read_chip_map_h5(std::filesystem::path(out) / "chips.h5");
  EXPECT_EQ(m.t_s.size(), j["steps"].get<std::size_t>());
  EXPECT_EQ(m.teeth, 4u);
  // texture reads the folder's floor. Its walls are refused: the slot is 8 mm long and 20 mm
  // wide, all round end and no finished wall (texture measured the round end as a wall).
  const CliResult walls = run_cli("texture " + out + " --surface walls");
  EXPECT_EQ(walls.code, 2) << walls.out;
  EXPECT_NE(walls.out.find("/walls.csv: the left wall at z = "), std::string::npos) << walls.out;
  EXPECT_NE(walls.out.find("is all front arc"), std::string::npos) << walls.out;
  const CliResult tex = run_cli("texture " + out + " --surface floor --json -");
  ASSERT_EQ(tex.code, 0) << tex.out;
  const auto tj = nlohmann::json::parse(tex.out)["surfaces"];
  // The floor, cut across the slot in this window: an end mill without axial runout leaves it
  // flat (every Z ray ends at the tool's bottom), so Sa and Sz are 0 to rounding.
  ASSERT_TRUE(std::filesystem::exists(std::filesystem::path(out) / "floor.x3p"));
  ASSERT_EQ(tj.size(), 1u);
  EXPECT_EQ(tj[0]["surface"], "floor");
  EXPECT_EQ(tj[0]["kind"], "areal");
  EXPECT_LT(tj[0]["sl"]["sa_mm"].get<double>(), 1e-12);
  EXPECT_LT(tj[0]["sl"]["sz_mm"].get<double>(), 1e-12);
  EXPECT_EQ(tj[0]["sl"]["sku"].get<double>(), 0.0);  // no shape: not a ratio of rounding errors
  EXPECT_TRUE(tj[0]["sl"]["sal_mm"].is_null());
  EXPECT_TRUE(tj[0]["sl"]["flat"].get<bool>());

  CliResult bad = run_cli("simulate " + ex + " --cycles 5:2" + common);
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--cycles"), std::string::npos) << bad.out;
  bad = run_cli("simulate " + ex + " --cycles 3:4 --memory-limit 0.000001" + common);
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--memory-limit"), std::string::npos) << bad.out;
  bad = run_cli("simulate " + ex + " --cycles 3:4 --set simulation.threads=-1" + common);
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("threads"), std::string::npos) << bad.out;
}

// forces: the JSON keys the issue names; the CSV it writes is read by calibrate as it is and
// gives back the coefficients that made it (the same chip source, noise-free: within 0.5 %,
// the interpolation bound of force_test's round trip); materials lists the library; analyze
// fills the performance index from the predicted force; bad input exits 2.
TEST_F(Cli, ForcesCalibrateAndMaterials) {
  const auto ex = test::example("bergmann2021/trochoidal.toml").string();
  const auto csv = (dir_ / "f.csv").string();
  const CliResult f = run_cli("forces " + ex +
                              " --fast --from 134.0 --to 135.0 --set forces.fast_steps_per_rev=1000"
                              " --csv " +
                              csv + " --json -");
  ASSERT_EQ(f.code, 0) << f.out;
  const auto j = nlohmann::json::parse(f.out);
  for (const char* k : {"f_resultant_max_n", "f_x_max_n", "f_y_max_n", "f_z_max_n", "torque_max_nm",
                        "power_max_w"}) {
    ASSERT_TRUE(j.contains(k)) << k;
    EXPECT_GT(j[k].get<double>(), 0.0) << k;
  }
  // F_R,max >= each component's maximum, and power = torque * omega at the same step.
  EXPECT_GE(j["f_resultant_max_n"].get<double>(), j["f_x_max_n"].get<double>());
  EXPECT_EQ(first_line_of(csv).rfind("t_s,f_x_n,f_y_n,f_z_n,f_resultant_n,torque_nm,power_w", 0),
            0u);
  const CliResult c = run_cli("calibrate " + ex + " --measured " + csv +
                              " --fast --fit k_c,k_n,m --set material.k_c=1500 --set material.m=0.2"
                              " --json -");
  ASSERT_EQ(c.code, 0) << c.out;
  const auto cj = nlohmann::json::parse(c.out);
  EXPECT_NEAR(cj["k_c"].get<double>(), 1926.08, 0.005 * 1926.08);
  EXPECT_NEAR(cj["k_n"].get<double>(), 502.64, 0.005 * 502.64);
  EXPECT_NEAR(cj["m"].get<double>(), 0.28, 0.005 * 0.28);
  EXPECT_GT(cj["r2"].get<double>(), 0.999);
  EXPECT_TRUE(cj.contains("rmse_n"));
  EXPECT_TRUE(cj["ci95"].contains("k_c"));
  // The human form prints the [material] block.
  const auto block = (dir_ / "material.toml").string();
  const CliResult h =
      run_cli("calibrate " + ex + " --measured " + csv + " --fast --fit k_c --write " + block);
  ASSERT_EQ(h.code, 0) << h.out;
  EXPECT_NE(h.out.find("[material]"), std::string::npos) << h.out;
  EXPECT_EQ(first_line_of(block), "[material]");
  // materials
  const CliResult m = run_cli("materials");
  ASSERT_EQ(m.code, 0) << m.out;
  EXPECT_NE(m.out.find("inconel718-bergmann2021"), std::string::npos);
  EXPECT_NE(m.out.find("1926.08"), std::string::npos);
  // Bad input: no measurement, an unknown parameter, a bad column list, no material.
  EXPECT_EQ(run_cli("calibrate " + ex).code, 2);
  EXPECT_EQ(run_cli("calibrate " + ex + " --measured " + csv + " --fast --fit k_x").code, 2);
  EXPECT_EQ(run_cli("calibrate " + ex + " --measured " + csv + " --columns a,b").code, 2);
  const CliResult nm = run_cli("forces " + test::example("curves/bend.toml").string() + " --fast");
  EXPECT_EQ(nm.code, 2) << nm.out;
  EXPECT_NE(nm.out.find("[material]"), std::string::npos) << nm.out;
  // analyze: PI from the predicted force when [material] is given and roughness measured.
  const CliResult a = run_cli("analyze " + test::example("wagih2023/elliptical.toml").string() +
                              " --set material.name=al7075-t6-linear --set "
                              "measured.roughness_ra=0.8 --json -");
  ASSERT_EQ(a.code, 0) << a.out;
  const auto aj = nlohmann::json::parse(a.out);
  ASSERT_TRUE(aj["cycle_force_max_predicted_n"].is_number()) << a.out;
  ASSERT_TRUE(aj["performance_index"].is_number()) << a.out;
  EXPECT_NE(aj["performance_index_note"].get<std::string>().find("predicted"), std::string::npos);
}

}  // namespace
}  // namespace trochomill
