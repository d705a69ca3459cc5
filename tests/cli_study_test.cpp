// The CLI's studies: a sweep locks its output and --resume checks it, and a study whose every
// point failed fails.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/io.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::exit_code_of;
using test::run_cli;
using test::spawn_cli;

// Two sweeps of one output at once: the second refuses to start (the first holds the file's
// lock), where both once wrote the same rows; a file that holds a point twice is refused by
// --resume, where it was accepted.
TEST_F(Cli, ASweepLocksItsOutputAndResumeChecksIt) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const std::string csv = (dir_ / "sw.csv").string(), log = (dir_ / "log").string();
  const std::string tmp = dir_.string();
  const std::string study =
      " --vary path.step=0.5,0.55,0.6,0.65,0.7,0.75,0.8,0.85,0.9,0.95,1 "
      "--threads 1 --set slot.length=100 -o " +
      csv;
  const pid_t first = spawn_cli("sweep " + ex + study, log, tmp);
  ASSERT_GT(first, 0);
  // Waits (up to 60 s) for the first sweep's header: it holds the lock by then.
  for (int i = 0; i < 600 && !(std::filesystem::exists(csv) && std::filesystem::file_size(csv) > 0);
       ++i) {
    ::usleep(100000);
  }
  const CliResult second = run_cli("sweep " + ex + study + " --resume");
  EXPECT_EQ(second.code, 2) << second.out;
  EXPECT_NE(second.out.find("another sweep is writing it"), std::string::npos) << second.out;
  EXPECT_EQ(exit_code_of(first), 0) << read_file(log);
  // A point twice in the file: refused.
  const std::string text = read_file(csv);
  const auto second_line = text.find('\n') + 1;
  const std::string row = text.substr(second_line, text.find('\n', second_line) + 1 - second_line);
  std::ofstream(csv, std::ios::app) << row;
  const CliResult again = run_cli("sweep " + ex + study + " --resume");
  EXPECT_EQ(again.code, 2) << again.out;
  EXPECT_NE(again.out.find("point 0 is in it twice"), std::string::npos) << again.out;
}

// A study whose every point failed is a failed study (exit 2; report writes nothing); one
// whose points partly failed exits 0 and counts them on stderr. Each point's error names the
// option it came from (--vary, not --set).
TEST_F(Cli, AStudyWhoseEveryPointFailedFails) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const std::string csv = (dir_ / "sw.csv").string();
  CliResult r = run_cli("sweep " + ex + " --vary path.step=20,30 -o " + csv);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("every point failed (2 of 2"), std::string::npos) << r.out;
  std::filesystem::remove(csv);
  r = run_cli("sweep " + ex + " --vary path.step=1,30 --set slot.length=4 -o " + csv);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("1 of 2 points failed"), std::string::npos) << r.out;
  const std::string html = (dir_ / "r.html").string();
  r = run_cli("report " + ex + " --vary path.step=20,30 -o " + html);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("(the first: path.step: "), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(html));
  // A simulating sweep checks each point's memory estimate against its share of the limit
  // before it starts (it checked none).
  std::filesystem::remove(csv);
  r = run_cli("sweep " + test::example("bergmann2021/trochoidal.toml").string() +
              " --vary path.step=0.3,0.4 --eval simulate --cycles 3:4 --threads 2 "
              "--memory-limit 0.1 -o " +
              csv);
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("exceeds this point's share of the memory limit, 0.05 GB"),
            std::string::npos)
      << r.out;
  r = run_cli("compare " + ex + " --vary path.step=1,30 --set slot.length=4");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("compare: 1 of 2 points failed (the first: path.step: "), std::string::npos)
      << r.out;
}

// An option of the other kind of run is refused, not ignored: optimize's --pareto and
// --population with one goal, -o with several; report's --rate without --signal; compare's
// unknown key before any point runs.
TEST_F(Cli, OptionsThatDoNotApplyAreRefused) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const std::string one =
      "optimize " + ex + " --var path.step=0.5:1 --maximize cycle_mrr_mm3_per_min";
  CliResult r = run_cli(one + " --max-evals 10 -o - --pareto " + (dir_ / "p.csv").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--pareto is for several goals"), std::string::npos) << r.out;
  r = run_cli(one + " --max-evals 10 -o - --population 8");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--population is for several goals"), std::string::npos) << r.out;
  r = run_cli(one + " --minimize h_max_mm --max-evals 16 --pareto - -o " +
              (dir_ / "b.toml").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("-o is for one goal"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "b.toml"));
  r = run_cli("report " + ex + " --rate 1000 -o " + (dir_ / "r.html").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--rate requires --signal"), std::string::npos) << r.out;
  // A command whose SIGNAL is an optional positional keeps its reading options without it:
  // monitor --stream reads standard input with them.
  EXPECT_EQ(test::run_command("printf '0.1\\n0.2\\n' | " + std::string(TROCHOMILL_CLI) +
                              " monitor --stream --rate 40000 --format csv")
                .code,
            0);
  r = run_cli("compare " + ex + " --vary path.nope=1,2");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--vary path.nope: no such job key"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace trochomill
