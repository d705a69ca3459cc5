// The CLI end to end: exit codes (0 ok, 2 bad input, 1 runtime failure), atomic outputs
// (nothing written on failure), --set, --version, and check-gcode's JSON report.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "test_util.hpp"
#include "trochomill/io.hpp"

namespace trochomill {
namespace {

struct CliResult {
  int code;
  std::string out;
};

CliResult run_cli(const std::string& args) {
  const std::string cmd = std::string(TROCHOMILL_CLI) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (p != nullptr && std::fgets(buf.data(), buf.size(), p) != nullptr) out += buf.data();
  const int status = p != nullptr ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("trochomill_cli_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

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

TEST_F(Cli, SetOverridesAndBadInputExitsTwoWithoutOutput) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const auto out = (dir_ / "x.ngc").string();
  CliResult r = run_cli("plan " + ex + " -o " + out + " --set path.aspect_ratio=-1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--set path.aspect_ratio: must be > 0"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
  r = run_cli("plan " + ex + " -o " + out + " --set path.aspect_ratio=0.6");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(read_file(out).find("path.aspect_ratio = 0.6"), std::string::npos);
  r = run_cli("plan /nonexistent.toml -o " + out);
  EXPECT_EQ(r.code, 2) << r.out;
  r = run_cli("frobnicate");
  EXPECT_EQ(r.code, 2) << r.out;
  r = run_cli("plan " + ex);  // missing -o
  EXPECT_EQ(r.code, 2) << r.out;
}

TEST_F(Cli, RuntimeFailureExitsOne) {
  const auto ex = test::example("wagih2023/elliptical.toml").string();
  const CliResult r = run_cli("plan " + ex + " -o " + (dir_ / "no" / "such" / "dir.ngc").string());
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("does not exist"), std::string::npos) << r.out;
}

TEST_F(Cli, MalformedGcodeNamesLineAndColumn) {
  const auto f = (dir_ / "bad.ngc").string();
  write_file_atomic(f, "G0 X0 Y0 Z0\nG1 X5 F100\nG1 X1.2.3\n");
  const CliResult r = run_cli("check-gcode " + f);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find(f + ":3:8: unexpected character '.'"), std::string::npos) << r.out;
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

TEST_F(Cli, VersionAndHelp) {
  CliResult r = run_cli("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("trochomill 0."), std::string::npos);
  r = run_cli("plan --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--dialect"), std::string::npos);
}

}  // namespace
}  // namespace trochomill
