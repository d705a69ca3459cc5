// The CLI's surface and tool commands: texture of a CSV profile, a job and X3P files (with
// bad input), insert and topography.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/io.hpp"
#include "trochomill/texture.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::first_line_of;
using test::run_cli;

// texture: a measured CSV profile (heights in um) of a short sinusoid on a long one gives the
// closed forms (Ra = 2A/pi to 1e-4, the long wave's Wt = 2B T(4 mm) to 1e-3, RSm the short
// wavelength), the same numbers as the library on the same samples; a job's walls are
// analyze's; bad columns, units and sources exit 2 naming them.
TEST_F(Cli, TextureOfAProfileAJobAndBadInput) {
  const auto csv = (dir_ / "p.csv").string();
  {
    std::ofstream out(csv);
    out << "x_mm,z_um\n";
    for (int i = 0; i <= 16000; ++i) {
      const double x = 0.00025 * i;
      char line[64];
      std::snprintf(line, sizeof line, "%.6f,%.9f\n", x,
                    2 * std::sin(2 * std::numbers::pi * x / 0.05) +
                        0.5 * std::sin(2 * std::numbers::pi * x / 4));
      out << line;
    }
  }
  const CliResult r = run_cli("texture " + csv + " --z-unit um --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out)["surfaces"][0];
  EXPECT_EQ(j["lambda_c_mm"].get<double>(), 0.8);
  EXPECT_NEAR(j["ra_mm"].get<double>(), 2 * 0.002 / std::numbers::pi, 1e-4 * 0.002);
  EXPECT_NEAR(j["rsm_mm"].get<double>(), 0.05, 1e-4);
  EXPECT_NEAR(j["wt_mm"].get<double>(), 2 * 0.0005 * gaussian_transmission(4.0, 0.8), 1e-3 * 0.001);
  const auto ex = test::example("wagih2023/trochoidal.toml").string();
  const CliResult t = run_cli("texture " + ex + " --json -");
  ASSERT_EQ(t.code, 0) << t.out;
  const CliResult an = run_cli("analyze " + ex + " --json -");
  ASSERT_EQ(an.code, 0) << an.out;
  const auto tj = nlohmann::json::parse(t.out)["surfaces"];
  const auto aj = nlohmann::json::parse(an.out);
  EXPECT_EQ(tj[0]["ra_mm"].get<double>(), aj["ra_left_mm"].get<double>());
  EXPECT_EQ(tj[1]["rz_mm"].get<double>(), aj["rz_right_mm"].get<double>());
  // A job's floor runs its simulation window: an ideal flat end mill (no corner radius, no
  // axial runout) leaves a plane floor, so every height is the plane to rounding ("flat",
  // Sa below 1e-12 mm); a coarse simulation (0.05 mm dexels, 60 steps a revolution) keeps
  // the test short. The window is named.
  const CliResult fl = run_cli("texture " + ex +
                               " --surface floor --cycles 4:5 --lambda-c 0.5 --set "
                               "simulation.resolution=0.05 --set simulation.steps_per_rev=60 "
                               "--json -");
  ASSERT_EQ(fl.code, 0) << fl.out;
  const auto fj = nlohmann::json::parse(fl.out)["surfaces"];
  ASSERT_EQ(fj.size(), 1u);
  EXPECT_EQ(fj[0]["surface"], "floor");
  EXPECT_EQ(fj[0]["kind"], "areal");
  EXPECT_TRUE(fj[0]["sf"]["flat"].get<bool>());
  EXPECT_LT(fj[0]["sf"]["sa_mm"].get<double>(), 1e-12);
  EXPECT_NE(fj[0]["description"].get<std::string>().find("simulated, 0.05 mm dexels, t "),
            std::string::npos)
      << fj[0]["description"];
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {csv + " --cycles 1:2", "choose the simulation window of a job's floor"},
           {csv + " --columns x_mm,height", "no column 'height'"},
           {csv + " --z-unit nm", "--z-unit 'nm': mm or um"},
           {csv + " --surface top", "--surface 'top'"},
           {(dir_ / "x.dat").string(), "is not a folder written by simulate --out"},
           {csv + " --lambda-c 500", "shorter --lambda-c"}}) {
    const CliResult b = run_cli("texture " + args);
    EXPECT_EQ(b.code, 2) << args << "\n" << b.out;
    EXPECT_NE(b.out.find(says), std::string::npos) << b.out;
  }
}

// texture of X3P files: a surface z = A sin(2 pi x / 0.02) sampled 40 times a period, with a
// tilt the plane takes out, filtered with lambda_s 0.002 mm (transmitting the wave at T =
// exp(-pi (alpha 0.002 / 0.02)^2)) and lambda_c 0.08 mm (passing 1.5e-5 of it to the mean
// surface): Sa = T A (2/N) cot(pi/N) (the mean of |sin| over N samples a period) and Sq =
// T A / sqrt 2, to 2e-3 (the renormalised mean surface within a cut-off of the map's ends
// carries a little of the wave); the F-operator and filters asked for are stated. A profile
// X3P is a profile (Ra of 400 samples a period to 1e-5); malformed files and options exit 2
// naming them.
TEST_F(Cli, TextureOfX3pSurfacesAndProfiles) {
  const double A = 0.001;
  HeightMap m;
  m.nx = 4000, m.ny = 400, m.dx_mm = m.dy_mm = 0.0005;
  for (std::size_t r = 0; r < m.ny; ++r) {
    for (std::size_t c = 0; c < m.nx; ++c) {
      m.z_mm.push_back(A * std::sin(2 * std::numbers::pi * static_cast<double>(c) / 40) +
                       0.01 * static_cast<double>(r) * m.dy_mm);
    }
  }
  const auto x3p = (dir_ / "s.x3p").string();
  write_x3p(x3p, m);
  const CliResult r = run_cli("texture " + x3p + " --lambda-c 0.08 --lambda-s 0.002 --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  const auto s = j["surfaces"][0];
  EXPECT_EQ(s["kind"], "areal");
  EXPECT_EQ(s["l_filter_mm"].get<double>(), 0.08);
  EXPECT_EQ(s["s_filter_mm"].get<double>(), 0.002);
  EXPECT_EQ(s["form"], "plane");
  const double keep = gaussian_transmission(0.02, 0.002);
  const double mean_abs = 2.0 / 40 / std::tan(std::numbers::pi / 40);
  EXPECT_NEAR(s["sl"]["sa_mm"].get<double>() / (A * keep * mean_abs), 1.0, 2e-3);
  EXPECT_NEAR(s["sl"]["sq_mm"].get<double>() / (A * keep / std::sqrt(2.0)), 1.0, 2e-3);
  EXPECT_NE(j["standards"].get<std::string>().find("ISO 25178-2"), std::string::npos);

  HeightMap prf;
  prf.nx = 32000, prf.ny = 1, prf.dx_mm = prf.dy_mm = 0.000125;
  for (std::size_t c = 0; c < prf.nx; ++c) {
    prf.z_mm.push_back(A * std::sin(2 * std::numbers::pi * static_cast<double>(c) / 400));
  }
  const auto px = (dir_ / "p.x3p").string();
  write_x3p(px, prf);
  const CliResult p = run_cli("texture " + px + " --json -");
  ASSERT_EQ(p.code, 0) << p.out;
  const auto pj = nlohmann::json::parse(p.out)["surfaces"][0];
  EXPECT_EQ(pj["kind"], "profile");
  EXPECT_NEAR(pj["ra_mm"].get<double>() / (A * 2.0 / 400 / std::tan(std::numbers::pi / 400)), 1.0,
              1e-5);

  // --against: a predicted surface and the "measured" one, the same shape moved by (0.05,
  // 0.03) mm and set 1 um higher: the comparison finds the shift, the offset, and no
  // difference left (to rounding).
  const auto f = [](double x, double y) {
    return 0.003 * std::sin(2 * std::numbers::pi * (x / 0.37 + y / 0.91)) +
           0.002 * std::cos(2 * std::numbers::pi * (x / 0.23 - y / 0.41));
  };
  HeightMap pred, meas;
  pred.nx = meas.nx = 200, pred.ny = meas.ny = 150;
  pred.dx_mm = pred.dy_mm = meas.dx_mm = meas.dy_mm = 0.01;
  for (std::size_t row = 0; row < 150; ++row) {
    for (std::size_t c = 0; c < 200; ++c) {
      const double x = static_cast<double>(c) * 0.01, y = static_cast<double>(row) * 0.01;
      pred.z_mm.push_back(f(x, y));
      meas.z_mm.push_back(f(x - 0.05, y - 0.03) + 0.001);
    }
  }
  const auto pp = (dir_ / "pred.x3p").string(), mp = (dir_ / "meas.x3p").string();
  write_x3p(pp, pred);
  write_x3p(mp, meas);
  const CliResult cmp = run_cli("texture " + mp + " --against " + pp + " --lambda-c 0.25 --json -");
  ASSERT_EQ(cmp.code, 0) << cmp.out;
  const auto cj = nlohmann::json::parse(cmp.out)["surfaces"][0]["comparison"];
  EXPECT_NEAR(cj["shift_x_mm"].get<double>(), 0.05, 1e-12);
  EXPECT_NEAR(cj["shift_y_mm"].get<double>(), 0.03, 1e-12);
  EXPECT_LT(cj["rms_difference_mm"].get<double>(), 1e-12);
  EXPECT_EQ(cj["against"].get<std::string>(), pp);

  write_file_atomic(dir_ / "bad.x3p", "PK not really");
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {(dir_ / "bad.x3p").string(), "not an X3P file"},
           {x3p + " --form cubic", "--form 'cubic': plane, polynomial or none"},
           {x3p + " --form polynomial --degree 8", "degree must be 1 to 6"},
           {x3p + " --lambda-c 0.5", "longer than the map's shorter side"},
           {x3p + " --memory-limit 0.01", "the memory limit"},
           {px + " --against " + x3p, "--against compares areal surfaces"},
           {x3p + " --against " + (dir_ / "p.csv").string(), "an X3P file or a folder"},
           {test::example("wagih2023/trochoidal.toml").string() +
                " --surface floor --memory-limit 0.001",
            "texture: estimated memory"}}) {
    const CliResult b = run_cli("texture " + args);
    EXPECT_EQ(b.code, 2) << args << "\n" << b.out;
    EXPECT_NE(b.out.find(says), std::string::npos) << args << "\n" << b.out;
  }
}

// insert writes a synthetic mesh the topography command samples back; the JSON names its
// statistics; a job without topography and no --mesh is bad input.
TEST_F(Cli, InsertAndTopography) {
  const auto ex = test::example("bergmann2021/trochoidal.toml").string();
  const auto mesh = (dir_ / "worn.obj").string();
  const CliResult w = run_cli("insert " + ex + " -o " + mesh + " --vb 0.1 --sections 60");
  ASSERT_EQ(w.code, 0) << w.out;
  ASSERT_TRUE(std::filesystem::exists(mesh));
  const CliResult t = run_cli("topography " + ex + " --mesh " + mesh + " --json - --csv " +
                              (dir_ / "grid.csv").string());
  ASSERT_EQ(t.code, 0) << t.out;
  const auto j = nlohmann::json::parse(t.out);
  EXPECT_GT(j["points"].get<int>(), 1000);
  EXPECT_LT(j["facets_kept"].get<int>(), j["facets_total"].get<int>());
  // The land (0.1 - 0.02 mm) + hone quarter (0.0314) + rake (0.18) on every segment.
  for (const auto& sgm : j["per_segment"]) {
    EXPECT_NEAR(sgm["profile_length_mm"].get<double>(), 0.08 + 0.0314 + 0.18, 2e-3);
    EXPECT_NEAR(sgm["outer_facet_angle_deg"].get<double>(), 90.0, 1.0);
  }
  EXPECT_EQ(first_line_of((dir_ / "grid.csv").string()).rfind("kappa,tau,s_mm", 0), 0u);
  // The example's own wear states: state 1 is the worn insert (its land at 90 degrees).
  const CliResult st = run_cli("topography " + ex + " --set topography.state=1 --json -");
  ASSERT_EQ(st.code, 0) << st.out;
  EXPECT_NEAR(
      nlohmann::json::parse(st.out)["per_segment"][10]["outer_facet_angle_deg"].get<double>(), 90.0,
      1.0);
  // A job without [topography] and no --mesh is bad input.
  EXPECT_EQ(run_cli("topography " + test::example("wagih2023/trochoidal.toml").string()).code, 2);
  EXPECT_EQ(run_cli("insert " + ex + " -o " + (dir_ / "x.xyz").string()).code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.xyz"));
}

}  // namespace
}  // namespace trochomill
