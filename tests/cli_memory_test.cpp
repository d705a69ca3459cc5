// The CLI's memory: every command's estimate against the peak it then uses, simulate's at
// several resolutions, and a program without end stopped by the memory its path takes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "test_util.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::run_cli;

// Peak resident memory of one run of the CLI (MB): wait4 gives that child's own maxrss.
double peak_mb_of(const std::string& args) {
  std::vector<std::string> words = {TROCHOMILL_CLI};
  std::istringstream in(args);
  for (std::string w; in >> w;) words.push_back(w);
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return 0;
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << args;
  return static_cast<double>(ru.ru_maxrss) / 1024.0;  // KB on Linux
}

double estimate_gb_of(const std::string& args) {
  // --memory-limit 1e-6 GB refuses every run and prints the estimate.
  const CliResult r = run_cli(args + " --memory-limit 0.000001");
  EXPECT_EQ(r.code, 2) << r.out;
  const auto at = r.out.find("estimated memory ");
  EXPECT_NE(at, std::string::npos) << r.out;
  if (at == std::string::npos) return 0.0;
  char* end = nullptr;
  const double v = std::strtod(r.out.c_str() + at + 17, &end);
  // memory_text: GB, or MB / kB for small sizes.
  const std::string unit(end, std::min<std::size_t>(3, std::strlen(end)));
  return unit == " MB" ? v / 1e3 : unit == " kB" ? v / 1e6 : v;
}

// Every command that can be asked for too much estimates its memory before it allocates,
// refuses past --memory-limit with the numbers and what to change, and the estimate is
// within a factor of 2 of the peak it then uses. The estimate is printed to 0.01 GB, so the
// runs are sized to a hundred MB or more.
TEST_F(Cli, MemoryEstimatesMatchThePeak) {
#if defined(TROCHOMILL_SANITIZED)
  GTEST_SKIP() << "AddressSanitizer's shadow memory and redzones are not in the estimate";
#endif
  const auto w = test::example("wagih2023/trochoidal.toml").string();
  const auto p = test::example("pivkin2025/trochoidal.toml").string();
  const auto b = test::example("bergmann2021/trochoidal.toml").string();
  const auto out = (dir_ / "o").string();
  const std::vector<std::string> runs = {
      "plan " + w + " -o " + out + ".ngc --set slot.length=1000 --set path.step=0.01",
      "path " + w + " --dt 5e-5",
      "analyze " + w + " --set analysis.steps_per_tooth=16 --set slot.length=60 --json " + out +
          ".json",
      "synth-signal " + p + " -o " + out + ".wav --cycles 60 --rate 200000",
      "calibrate " + b + " --measured " + out + "-f.csv --fast --json " + out + "-c.json",
  };
  // The record calibrate fits: 4 s of the fast model's forces.
  ASSERT_EQ(run_cli("forces " + b + " --fast --from 20 --to 24 --csv " + out + "-f.csv").code, 0);
  for (const std::string& args : runs) {
    const double est_mb = 1000.0 * estimate_gb_of(args);
    const double peak_mb = peak_mb_of(args);
    EXPECT_GT(peak_mb, 100.0) << args;  // large enough for the 10 MB print resolution
    EXPECT_LE(est_mb, 2 * peak_mb) << args;
    EXPECT_GE(est_mb, 0.5 * peak_mb) << args;
  }
}

// The memory simulate estimates before it starts (and refuses past --memory-limit) is the
// memory it then uses: within a factor of 2 of the process's measured peak (VmHWM) at every
// resolution, with and without the HDF5 chip map; and the refusal names the numbers.
TEST_F(Cli, SimulateMemoryEstimateMatchesThePeak) {
#if defined(TROCHOMILL_SANITIZED)
  GTEST_SKIP() << "AddressSanitizer's shadow memory and redzones are not in the estimate";
#endif
  const auto ex = test::example("wagih2023/trochoidal.toml").string();
  struct Case {
    const char* resolution;
    bool out;
  };
  for (const Case c :
       {Case{"0.2", false}, Case{"0.1", false}, Case{"0.05", false}, Case{"0.2", true}}) {
    const auto json = (dir_ / "s.json").string();
    const std::string out = c.out ? " --out " + (dir_ / "out").string() : "";
    const CliResult r = run_cli("simulate " + ex +
                                " --from 10 --to 10.5 --set simulation.resolution=" + c.resolution +
                                " --json " + json + out);
    ASSERT_EQ(r.code, 0) << r.out;
    std::ifstream in(json);
    const auto j = nlohmann::json::parse(in);
    const double est = j["memory_estimate_mb"].get<double>(),
                 peak = j["memory_peak_mb"].get<double>();
    EXPECT_GT(peak, 0.0);
    EXPECT_LE(est, 2 * peak) << c.resolution << (c.out ? " with HDF5" : "");
    EXPECT_GE(est, 0.5 * peak) << c.resolution << (c.out ? " with HDF5" : "");
    std::filesystem::remove_all(dir_ / "out");
  }
  const CliResult refused = run_cli("simulate " + ex + " --from 10 --to 10.5 --memory-limit 0.01");
  EXPECT_EQ(refused.code, 2) << refused.out;
  EXPECT_NE(refused.out.find("exceeds the limit of 0.01 GB (--memory-limit)"), std::string::npos)
      << refused.out;
}

// A program that loops without end is stopped by the memory its path takes while it is read
// (a quarter of --memory-limit), exit 2 naming the line, in every command that keeps the path
// (it once grew until std::bad_alloc, several GB); check-gcode streams it to its block limit.
TEST_F(Cli, AnEndlessProgramStopsEveryCommandThatReadsIt) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const std::string ngc = (dir_ / "endless.ngc").string();
  std::ofstream(ngc) << "G21 G90\nF600\n#1=0\no100 while [1]\nG1 X[#1] Y0 Z-1\n"
                        "#1=[#1+0.001]\no100 endwhile\nM2\n";
  const std::string limit = " --memory-limit 0.2";
  for (const std::string& cmd :
       {"analyze " + ex + " --gcode " + ngc, "path " + ex + " --gcode " + ngc + " --csv /dev/null",
        "simulate " + ex + " --gcode " + ngc, "forces " + ex + " --fast --gcode " + ngc,
        "optimize-feed " + ngc + " --job " + ex + " -o " + (dir_ / "o.ngc").string()}) {
    const CliResult r = run_cli(cmd + limit);
    EXPECT_EQ(r.code, 2) << cmd << "\n" << r.out;
    EXPECT_NE(r.out.find("endless.ngc:5: the program's path holds"), std::string::npos)
        << cmd << "\n"
        << r.out;
    EXPECT_NE(r.out.find("loop without end"), std::string::npos) << cmd;
  }
  // At a 2 GB limit the path may take 0.5 GB: the process's peak stays below that plus the
  // program's own 60-90 MB (it once reached 1.5 times the share: the path's buffer doubled
  // after the check, and the old and new buffers were held at once). ru_maxrss is in kB and
  // covers every child waited for (the five above peak below 0.2 GB).
  const CliResult big = run_cli("analyze " + ex + " --gcode " + ngc + " --memory-limit 2");
  EXPECT_EQ(big.code, 2) << big.out;
  EXPECT_NE(big.out.find("loop without end"), std::string::npos) << big.out;
#if !defined(TROCHOMILL_SANITIZED)  // AddressSanitizer keeps freed memory in quarantine
  rusage use{};
  ASSERT_EQ(getrusage(RUSAGE_CHILDREN, &use), 0);
  EXPECT_LT(static_cast<double>(use.ru_maxrss) * 1024, 0.5e9 + 0.15e9);
#endif
}

}  // namespace
}  // namespace trochomill
