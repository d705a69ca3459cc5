// The CLI's outputs: links, pipes and inputs are never replaced, "-" is standard output for
// every output, and Ctrl-C (or SIGTERM) stops cleanly, leaving no half-written file.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/io.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::exit_code_of;
using test::run_cli;
using test::run_command;
using test::spawn_cli;

// Outputs: a link stays a link (its target is written), a FIFO stays a FIFO (written
// through), an output that is an input or lies in a missing directory is refused before any
// work, and nothing is half-written.
TEST_F(Cli, OutputsNeverReplaceLinksPipesOrInputs) {
  namespace fs = std::filesystem;
  const std::string job = (dir_ / "job.toml").string();
  fs::copy_file(test::example("wagih2023/elliptical.toml"), job);
  const std::string before = read_file(job);
  CliResult r = run_cli("plan " + job + " -o " + job);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("is the input"), std::string::npos) << r.out;
  EXPECT_EQ(read_file(job), before);  // the job is untouched
  // A symbolic link to a program: the link stays, the program it names is written.
  const fs::path real = dir_ / "real.ngc", link = dir_ / "link.ngc";
  { std::ofstream(real) << "old\n"; }
  fs::create_symlink(real, link);
  ASSERT_EQ(run_cli("plan " + job + " -o " + link.string()).code, 0);
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_GT(read_file(real).size(), 10000u);  // the program (about 40 kB), not "old"
  // A FIFO with a reader: written through, still a FIFO afterwards.
  const fs::path fifo = dir_ / "fifo", got = dir_ / "got.ngc";
  const std::string shell = "mkfifo " + fifo.string() + " && { cat " + fifo.string() + " > " +
                            got.string() + " & } && " + TROCHOMILL_CLI + " plan " + job + " -o " +
                            fifo.string() + " > /dev/null && wait";
  ASSERT_EQ(std::system(shell.c_str()), 0) << shell;
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_EQ(read_file(got), read_file(real));
  // Checked before the work: the JSON is not written when the CSV's directory is missing.
  r = run_cli("analyze " + job + " --json " + (dir_ / "a.json").string() + " --csv " +
              (dir_ / "nodir" / "a.csv").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("directory"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "a.json"));
}

// "-" is standard output for every output option, binary ones included; the summary then
// goes to stderr. An extension the writer cannot honour is refused before any work.
TEST_F(Cli, DashIsStdoutForBinaryOutputs) {
  const auto p = test::example("pivkin2025/trochoidal.toml").string();
  const auto wav = (dir_ / "s.wav").string(), stl = (dir_ / "i.stl").string();
  ASSERT_EQ(run_cli("synth-signal " + p + " --cycles 1 --rate 30000 -o " + wav).code, 0);
  ASSERT_EQ(run_cli("insert " + p + " --sections 4 --points 8 -o " + stl).code, 0);
  const std::string cli = TROCHOMILL_CLI;
  const auto wav2 = (dir_ / "s2.wav").string(), stl2 = (dir_ / "i2.stl").string();
  ASSERT_EQ(std::system((cli + " synth-signal " + p + " --cycles 1 --rate 30000 -o - > " + wav2 +
                         " 2>/dev/null")
                            .c_str()),
            0);
  ASSERT_EQ(std::system(
                (cli + " insert " + p + " --sections 4 --points 8 -o - > " + stl2 + " 2>/dev/null")
                    .c_str()),
            0);
  // The same bytes as the file (the WAV carries no time stamp: a run a second later is equal).
  EXPECT_EQ(read_file(wav2), read_file(wav));
  EXPECT_EQ(read_file(stl2), read_file(stl));
  const CliResult bad = run_cli("insert " + p + " -o " + (dir_ / "i.flac").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.out.find("insert writes .stl, .ply or .obj"), std::string::npos) << bad.out;
}

// `-` is standard output for optimize's -o and --pareto and calibrate's --write too (they
// once wrote a file named "-"), the summary line then on stderr; a failed write to standard
// output (a full disk behind it) exits 1.
TEST_F(Cli, DashIsStandardOutputEverywhere) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const std::string in_dir = "cd " + dir_.string() + " && ";
  const std::string cli = std::string(TROCHOMILL_CLI);
  const auto run_in_dir = [&](const std::string& args) {  // stdout alone, in dir_
    return run_command(in_dir + cli + " " + args + " 2>/dev/null");
  };
  const std::string var = " --var path.step=0.5:1 --maximize cycle_mrr_mm3_per_min";
  CliResult r = run_in_dir("optimize " + ex + var + " --max-evals 10 -o -");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("[path]"), std::string::npos) << r.out;   // the best job, as TOML
  EXPECT_EQ(r.out.find("best of"), std::string::npos) << r.out;  // the summary on stderr
  r = run_in_dir("optimize " + ex + var +
                 " --minimize h_max_mm --max-evals 20 --population 8 --pareto -");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("path.step,cycle_mrr_mm3_per_min,h_max_mm\n", 0), 0u) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "-"));
  EXPECT_EQ(run_cli("analyze " + ex + " --json - > /dev/full").code, 1);
}

// CPU seconds a process has used (utime + stime of /proc/PID/stat), -1 when it is gone.
double cpu_seconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(in, text)) return -1;
  // The fields after the command name (which may hold blanks) start past its ')'.
  std::istringstream rest(text.substr(text.rfind(')') + 2));
  std::string field;
  double ticks = 0;
  for (int k = 3; k <= 15 && rest >> field; ++k) {
    if (k == 14 || k == 15) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// Waits until a process has used `seconds` of CPU (up to 120 s of wall time): on a loaded or
// sanitizer machine a fixed sleep may end before the run has started.
void wait_for_cpu(pid_t pid, double seconds) {
  for (int i = 0; i < 2400; ++i) {
    const double c = cpu_seconds(pid);
    if (c < 0 || c >= seconds) return;
    ::usleep(50000);
  }
}

std::size_t files_in(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) n += e.exists() ? 1 : 0;
  return n;
}

// Ctrl-C: a long run stops at the library's next check (exit 130, SIGTERM 143); during output
// writing no
// half-written file is left, whether a long run was under way (the staging of --out) or not
// (the handler removes the temporary file and ends the process).
TEST_F(Cli, CtrlCStopsCleanlyAndLeavesNoHalfWrittenFile) {
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  const auto tmp = dir_ / "tmp";
  std::filesystem::create_directories(tmp);
  const std::string log = (dir_ / "log").string();
  // 1. Output to a FIFO nobody reads: the program is made in TMPDIR, then the copy into the
  // FIFO blocks in open(). Ctrl-C there removes the temporary file and exits 130.
  const std::string fifo = (dir_ / "fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  pid_t pid = spawn_cli("plan " + ex + " -o " + fifo, log, tmp.string());
  ASSERT_GT(pid, 0);
  // Waits (up to 60 s: sanitizer builds are slow) for the temporary file to be complete.
  for (int i = 0; i < 600 && files_in(tmp) == 0; ++i) ::usleep(100000);
  ASSERT_EQ(files_in(tmp), 1u);
  ::usleep(300000);  // the writer closes it, then blocks opening the FIFO
  ::kill(pid, SIGINT);
  EXPECT_EQ(exit_code_of(pid), 130) << read_file(log);
  EXPECT_EQ(files_in(tmp), 0u) << "the temporary program was left behind";
  EXPECT_NE(read_file(log).find("interrupted"), std::string::npos) << read_file(log);

  // 2. A simulation long enough to be interrupted (minutes), from the path's start (no
  // pre-roll: it records from its first step), Ctrl-C once it has used 2 s of CPU: the run
  // stops at the next step and writes what it computed, marked incomplete, exit 130. The
  // --out folder then holds the whole set of files and no staging folder.
  const auto out = dir_ / "sim";
  const std::string json = (dir_ / "s.json").string();
  pid = spawn_cli("simulate " + ex + " --from 0 --to 30 --set simulation.resolution=0.02 --json " +
                      json + " --out " + out.string(),
                  log, tmp.string());
  ASSERT_GT(pid, 0);
  wait_for_cpu(pid, 2.0);
  ::kill(pid, SIGINT);
  EXPECT_EQ(exit_code_of(pid), 130) << read_file(log);
  EXPECT_NE(read_file(log).find("interrupted: the outputs were written in full"), std::string::npos)
      << read_file(log);
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  EXPECT_FALSE(j["complete"].get<bool>());
  for (const char* f : {"series.csv", "chips.h5", "walls.csv", "floor.csv", "surface.stl"}) {
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  }
  // The series and the chip map were streamed as the steps came: every step computed is in
  // both, and the map says it is incomplete.
  const auto steps = j["steps"].get<std::size_t>();
  EXPECT_GT(steps, 0u);
  const std::string series = read_file(out / "series.csv");
  EXPECT_EQ(static_cast<std::size_t>(std::count(series.begin(), series.end(), '\n')), steps + 1);
  const ChipMapData map = read_chip_map_h5(out / "chips.h5");
  EXPECT_EQ(map.t_s.size(), steps);
  EXPECT_FALSE(map.complete);
  // floor.x3p too when the run got as far as cutting the floor across the slot; if not, the
  // note says why.
  const bool floor = std::filesystem::exists(out / "floor.x3p");
  EXPECT_EQ(files_in(out), floor ? 6u : 5u);
  if (!floor) {
    EXPECT_NE(read_file(log).find("floor.x3p not written"), std::string::npos) << read_file(log);
  }
  EXPECT_EQ(files_in(tmp), 0u);

  // 3. analyze of a long program (minutes), Ctrl-C once it has used 2 s of CPU (planning
  // the path takes a fraction of that, under the sanitizers too): exit 130, no output at all.
  const std::string ajson = (dir_ / "a.json").string();
  pid = spawn_cli(
      "analyze " + ex + " --set slot.length=2000 --set analysis.steps_per_tooth=8 --json " + ajson,
      log, tmp.string());
  ASSERT_GT(pid, 0);
  wait_for_cpu(pid, 2.0);
  ::kill(pid, SIGINT);
  EXPECT_EQ(exit_code_of(pid), 130) << read_file(log);
  EXPECT_NE(read_file(log).find("interrupted: nothing was written"), std::string::npos)
      << read_file(log);
  EXPECT_FALSE(std::filesystem::exists(ajson));
  EXPECT_EQ(files_in(dir_), 5u);  // tmp, log, fifo, sim, s.json

  // 4. optimize (one goal: NLopt) stops at its next evaluation, exit 130, nothing written
  // (Ctrl-C inside NLopt's callback once became "nlopt failure", exit 1).
  const std::string best = (dir_ / "best.toml").string();
  pid = spawn_cli("optimize " + test::example("wagih2023/elliptical.toml").string() +
                      " --var path.aspect_ratio=0.5:1.2 --var path.step=0.5:1.5 --maximize "
                      "cycle_mrr_mm3_per_min -o " +
                      best,
                  log, tmp.string());
  ASSERT_GT(pid, 0);
  wait_for_cpu(pid, 1.0);
  ::kill(pid, SIGINT);
  EXPECT_EQ(exit_code_of(pid), 130) << read_file(log);
  EXPECT_FALSE(std::filesystem::exists(best));

  // 5. SIGTERM (a batch system's stop, `kill`) is Ctrl-C with exit 143.
  pid = spawn_cli(
      "analyze " + ex + " --set slot.length=2000 --set analysis.steps_per_tooth=8 --json " + ajson,
      log, tmp.string());
  ASSERT_GT(pid, 0);
  wait_for_cpu(pid, 2.0);
  ::kill(pid, SIGTERM);
  EXPECT_EQ(exit_code_of(pid), 143) << read_file(log);
  EXPECT_FALSE(std::filesystem::exists(ajson));
  EXPECT_EQ(files_in(tmp), 0u);

  // 6. optimize-feed while it reads a program that loops without moving (the reader's block
  // limit would stop it after 200 million blocks, 20 s and more): Ctrl-C answered within a
  // second (the reader polls every 64k blocks, a few ms; it once read to the limit first).
  const std::string spin = (dir_ / "spin.ngc").string();
  std::ofstream(spin) << "G21 G90\n#1=0\no100 while [1]\n#1=[#1+1]\no100 endwhile\nM2\n";
  const std::string fed = (dir_ / "fed.ngc").string();
  pid = spawn_cli("optimize-feed " + spin + " --job " + ex + " -o " + fed, log, tmp.string());
  ASSERT_GT(pid, 0);
  wait_for_cpu(pid, 1.0);
  const auto asked = std::chrono::steady_clock::now();
  ::kill(pid, SIGINT);
  EXPECT_EQ(exit_code_of(pid), 130) << read_file(log);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count(), 1.0);
  EXPECT_FALSE(std::filesystem::exists(fed));
  EXPECT_EQ(files_in(tmp), 0u);
}

}  // namespace
}  // namespace trochomill
