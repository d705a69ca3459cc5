// The CLI end to end: exit codes (0 ok, 2 bad input, 1 runtime failure), atomic outputs
// (nothing written on failure), --set, --version, and check-gcode's JSON report.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>

#include "test_util.hpp"
#include "trochomill/io.hpp"
#include "trochomill/job.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/surface.hpp"
#include "trochomill/units.hpp"

extern char** environ;

namespace trochomill {
namespace {

struct CliResult {
  int code;
  std::string out;
};

// A shell command's exit status and standard output.
CliResult run_command(const std::string& cmd) {
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (p != nullptr && std::fgets(buf.data(), buf.size(), p) != nullptr) out += buf.data();
  const int status = p != nullptr ? pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// The CLI with these arguments, stderr merged into the output.
CliResult run_cli(const std::string& args) {
  return run_command(std::string(TROCHOMILL_CLI) + " " + args + " 2>&1");
}

std::string first_line_of(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    // The process id keeps two suites running at once (a build and a sanitizer build) apart.
    dir_ = std::filesystem::temp_directory_path() /
           ("trochomill_cli_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

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
  const CliResult t = run_cli("analyze " + ex + " --gcode " + f);
  ASSERT_EQ(t.code, 0) << t.out;
  EXPECT_NE(t.out.find("h_max                0.07500 mm"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("steady cycle         none"), std::string::npos) << t.out;
}

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

// Flags that only set job keys are aliases of --set: validated by the schema, named in the
// message as the flag with its key, recorded in the program's header like any override.
TEST_F(Cli, KeyAliasesAreValidatedByTheSchema) {
  const std::string ex = test::example("pivkin2025/trochoidal.toml").string();
  CliResult r = run_cli("recommend " + ex + " --share 1.5");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--share (mechanism.share): must be in (0, 1] fraction, got 1.5"),
            std::string::npos)
      << r.out;
  r = run_cli("mechanism " + ex + " --model magic");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--model (mechanism.model): 'magic' is not one of exact | pivkin2025"),
            std::string::npos)
      << r.out;
  // Without a job file the monitor's flags set the default [monitor] settings, checked alike.
  r = run_cli("monitor x.wav --order 0");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--order (monitor.order): must be an integer in [1, 12], got 0"),
            std::string::npos)
      << r.out;
  const std::string ngc = (dir_ / "f.nc").string();
  r = run_cli("plan " + test::example("wagih2023/elliptical.toml").string() + " -o " + ngc +
              " --dialect fanuc --chords");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string code = read_file(ngc);
  EXPECT_NE(code.find("(machine.dialect = \"fanuc\")"), std::string::npos);
  EXPECT_NE(code.find("(machine.arc_output = \"chords\")"), std::string::npos);
  EXPECT_EQ(code.find("\nG2 "), std::string::npos);  // chords only: no arc blocks
  EXPECT_EQ(code.find("\nG3 "), std::string::npos);
  // `keys` lists the schema: every section, each key once.
  r = run_cli("keys --json");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.size(), job_keys().size());
}

// Numeric flags are finite and within a range the command can use: nan, a negative cut-off
// or a zero rapid rate are bad input (exit 2) naming the flag, never a silent run.
TEST_F(Cli, NumericFlagsAreFiniteAndInRange) {
  const std::string wagih = test::example("wagih2023/elliptical.toml").string();
  const std::string bergmann = test::example("bergmann2021/trochoidal.toml").string();
  const std::string ngc = (dir_ / "e.ngc").string();
  ASSERT_EQ(run_cli("plan " + wagih + " -o " + ngc).code, 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"check-gcode " + ngc + " --max-acceleration nan", "--max-acceleration: must be a finite"},
      {"check-gcode " + ngc + " --rapid-rate 0", "--rapid-rate: must be a finite number in (0"},
      {"forces " + bergmann + " --fast --from nan", "--from: must be a finite"},
      {"calibrate " + bergmann + " --measured x.csv --cutoff -5", "--cutoff: must be a finite"},
      {"calibrate " + bergmann + " --measured x.csv --max-shift nan", "--max-shift: must be"},
      {"synth-signal " + wagih + " -o x.wav --rate 1e9", "--rate: must be a finite number"},
      {"path " + wagih + " --dt inf", "--dt: must be a finite"},
      {"check-gcode " + ngc + " --g28 nan,0,0", "--g28: must be a finite number"},
      {"check-gcode " + ngc + " --g30 0,inf,0", "--g30: must be a finite number"},
      {"sweep " + wagih + " --vary path.step=1,2 -o s.csv --memory-limit 0",
       "--memory-limit: must be a finite number in (0"},
      {"optimize " + wagih + " --var path.step=2:1 --maximize h_max_mm -o b.toml",
       "--var 'path.step=2:1': expected section.key=lo:hi"},
  };
  for (const auto& [args, message] : cases) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(message), std::string::npos) << args << "\n" << r.out;
  }
}

// Messages say what the user typed: an unknown section from --set names the override (not
// line 0:0), a huge --cycles is echoed as typed, an output the writer cannot honour is refused,
// and a synthetic signal says how many cycles it covers.
TEST_F(Cli, MessagesNameWhatWasTyped) {
  const std::string wagih = test::example("wagih2023/trochoidal.toml").string();
  CliResult r =
      run_cli("plan " + wagih + " -o " + (dir_ / "x.ngc").string() + " --set unknown.key=1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--set unknown.key: unknown section [unknown]"), std::string::npos) << r.out;
  r = run_cli("simulate " + wagih + " --cycles 99999999999:1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--cycles '99999999999:1': need 0 <= A < B <= 20"), std::string::npos)
      << r.out;
  const std::string pivkin = test::example("pivkin2025/trochoidal.toml").string();
  r = run_cli("synth-signal " + pivkin + " -o " + (dir_ / "x.flac").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("synth-signal writes WAV"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.flac"));
  r = run_cli("synth-signal " + pivkin + " -o " + (dir_ / "x.wav").string() +
              " --rate 40000 --cycles 50");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("28 cycles (all the program has; 50 asked for)"), std::string::npos)
      << r.out;
}

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

TEST_F(Cli, VersionAndHelp) {
  CliResult r = run_cli("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("trochomill 0."), std::string::npos);
  r = run_cli("plan --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--dialect"), std::string::npos);
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
  EXPECT_TRUE(j["performance_index"].is_null());
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

// 0.1 s at 48 kHz of 3162 Hz and 10198 Hz tones as raw little-endian float32.
void tmill_signal_file(const std::filesystem::path& p) {
  std::ofstream f(p, std::ios::binary);
  for (int i = 0; i < 4800; ++i) {
    const double t = i / 48000.0;
    const auto v = static_cast<float>(0.7 * std::sin(2 * M_PI * 3162.3 * t) +
                                      0.4 * std::sin(2 * M_PI * 10198 * t));
    f.write(reinterpret_cast<const char*>(&v), sizeof v);  // x86-64 and arm64: little-endian
  }
}

// monitor, synth-signal, spectrum: a synthetic recording round trip with the required JSON
// keys, the live stream (one JSON line per window, equal to the library's causal series),
// and bad input (exit 2).
// A recording without a period (a flat line, white noise) is still a result: the k_f series
// and its mean, no cycles, a warning saying why, exit 0.
TEST_F(Cli, MonitorWithoutAPeriodReportsTheSeries) {
  const auto flat = (dir_ / "flat.f32").string(), noise = (dir_ / "noise.s16").string();
  {
    std::ofstream f(flat, std::ios::binary);
    const std::vector<float> zeros(200000, 0.0f);  // 2 s at 100 kHz
    f.write(reinterpret_cast<const char*>(zeros.data()),
            static_cast<std::streamsize>(zeros.size() * sizeof(float)));
    std::ofstream n(noise, std::ios::binary);
    std::uint32_t state = 12345;  // a fixed LCG: white noise, the same every run
    for (int i = 0; i < 200000; ++i) {
      state = state * 1664525u + 1013904223u;
      const auto v = static_cast<std::int16_t>(static_cast<std::int32_t>(state >> 16) - 32768);
      n.write(reinterpret_cast<const char*>(&v), sizeof v);
    }
  }
  const CliResult a = run_cli("monitor " + flat + " --rate 100000 --json -");
  ASSERT_EQ(a.code, 0) << a.out;
  EXPECT_NE(a.out.find("warning: the signal"), std::string::npos) << a.out;
  const auto ja = nlohmann::json::parse(a.out.substr(a.out.find('{')));
  EXPECT_EQ(ja["cycles"].get<int>(), 0);
  EXPECT_TRUE(ja["k_f_mean"].is_null());  // 0 / 0 in every window: no level to report
  EXPECT_EQ(ja["warnings"].size(), 1u);

  const auto csv = (dir_ / "noise.csv").string();
  const CliResult b = run_cli("monitor " + noise + " --rate 100000 --json - --csv " + csv);
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_NE(b.out.find("warning: no cycle period stands out"), std::string::npos) << b.out;
  const auto jb = nlohmann::json::parse(b.out.substr(b.out.find('{')));
  EXPECT_EQ(jb["cycles"].get<int>(), 0);
  // White noise has a flat spectrum: the band RMS ratio is sqrt of the bandwidth ratio,
  // sqrt(3000 / 5000) = 0.775 for the default bands (2-5 kHz over 8-13 kHz); within 10 %
  // for the filters' skirts and the estimate's spread over 0.4 M samples.
  EXPECT_NEAR(jb["k_f_mean"].get<double>(), std::sqrt(3000.0 / 5000.0), 0.08);
  std::ifstream in(csv);
  std::size_t rows = 0;
  for (std::string line; std::getline(in, line);) ++rows;
  EXPECT_GT(rows, 10u);  // the per-window series is written
}

TEST_F(Cli, MonitorSynthAndSpectrum) {
  const auto ex = test::example("pivkin2025/trochoidal.toml").string();
  const auto wav = (dir_ / "s.wav").string();
  CliResult r = run_cli("synth-signal " + ex + " -o " + wav + " --cycles 4 --rate 48000");
  ASSERT_EQ(r.code, 0) << r.out;
  r = run_cli("monitor " + wav + " --job " + ex + " --start 0.1 --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["cycles"], 4);
  EXPECT_EQ(j["k_f_per_cycle"].size(), 4u);
  EXPECT_GT(j["k_f_mean"].get<double>(), 0.9);
  EXPECT_LT(j["k_f_mean"].get<double>(), 1.3);
  EXPECT_TRUE(j["flags"].is_array());
  EXPECT_EQ(j["cycle_source"], "job");
  r = run_cli("monitor " + wav + " --json -");  // cycles from the signal alone
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(r.out)["cycle_source"], "signal");
  r = run_cli("spectrum " + wav + " --nfft 1024 --csv -");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.rfind("f_hz,psd_per_hz\n", 0), 0u);

  // Live: raw float32 on stdin, 0.1 s of a tone pair at 48 kHz: 20 windows of 5 ms.
  tmill_signal_file(dir_ / "x.f32");
  r = run_cli("monitor --stream --rate 48000 < " + (dir_ / "x.f32").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<nlohmann::json> lines;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(lines.size(), 20u);
  const Signal sig = read_signal((dir_ / "x.f32").string(), [] {
    SignalReadOptions o;
    o.rate_hz = 48000;
    return o;
  }());
  const KfSeries causal = kf_series(sig, MonitorSettings{}, false);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    EXPECT_NEAR(lines[i]["k_f"].get<double>(), causal.k_f[i], 1e-12 * causal.k_f[i]);
  }

  // Bad input.
  EXPECT_EQ(run_cli("monitor " + (dir_ / "x.f32").string()).code, 2);  // no rate
  EXPECT_EQ(run_cli("monitor " + wav + " --low 5000:2000").code, 2);
  EXPECT_EQ(run_cli("monitor " + wav + " --high 8000:30000").code, 2);  // above Nyquist
  EXPECT_EQ(run_cli("monitor " + (dir_ / "none.wav").string()).code, 2);
  {
    std::ofstream t(dir_ / "t.f32", std::ios::binary);
    t.write("abcde", 5);
  }
  r = run_cli("monitor --stream --rate 48000 < " + (dir_ / "t.f32").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("truncated"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad.wav"));
  EXPECT_EQ(
      run_cli("synth-signal " + ex + " -o " + (dir_ / "bad.wav").string() + " --rate -5").code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad.wav"));
}

}  // namespace
}  // namespace trochomill

namespace trochomill {
namespace {

// simulate on a steady cycle of Wagih's trochoid (coarse: 0.1 mm dexels, 60 steps per
// revolution): the JSON keys with their values' invariants (the three boards remove
// the same volume within the boundary bound: 2 x 50 mm of wall x 6 mm x d / 2), every output
// file written and readable, and bad input refused with exit 2 naming the option.
// The memory simulate estimates before it starts (and refuses past --memory-limit) is the
// memory it then uses: within a factor of 2 of the process's measured peak (VmHWM) at every
// resolution, with and without the HDF5 chip map; and the refusal names the numbers.
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
  return at == std::string::npos ? 0.0 : std::strtod(r.out.c_str() + at + 17, nullptr);
}

// Every command that can be asked for too much estimates its memory before it allocates,
// refuses past --memory-limit with the numbers and what to change, and the estimate is
// within a factor of 2 of the peak it then uses. The estimate is printed to 0.01 GB, so the
// runs are sized to a hundred MB or more.
TEST_F(Cli, MemoryEstimatesMatchThePeak) {
#if defined(__SANITIZE_ADDRESS__)
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

TEST_F(Cli, SimulateMemoryEstimateMatchesThePeak) {
#if defined(__SANITIZE_ADDRESS__)
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

// Starts the CLI with `args` (split at blanks), stdout and stderr to `log`, TMPDIR `tmp`.
pid_t spawn_cli(const std::string& args, const std::string& log, const std::string& tmp) {
  std::vector<std::string> words{TROCHOMILL_CLI};
  std::istringstream in(args);
  for (std::string w; in >> w;) words.push_back(w);
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_s{"TMPDIR=" + tmp};
  for (char** e = environ; *e != nullptr; ++e) {
    if (std::strncmp(*e, "TMPDIR=", 7) != 0) env_s.emplace_back(*e);
  }
  std::vector<char*> envp;
  for (auto& e : env_s) envp.push_back(e.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  return rc == 0 ? pid : -1;
}

int exit_code_of(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
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
}

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
  EXPECT_NE(r.out.find("--vary (path.step)"), std::string::npos) << r.out;
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
  EXPECT_NE(r.out.find("compare: 1 of 2 points failed (the first: --vary (path.step)"),
            std::string::npos)
      << r.out;
}

// Messages a new user met: a mistyped command is named with the nearest one; a binary file
// given as a table is said to be one (its bytes were echoed back); a G28 position must be a
// number; every job key a command's help names ("[section] key" or "section.key") exists.
TEST_F(Cli, MessagesNameWhatIsWrong) {
  CliResult r = run_cli("simulte x");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("unknown command 'simulte'; did you mean 'simulate'?"), std::string::npos)
      << r.out;
  const std::string ex = test::example("wagih2023/trochoidal.toml");
  r = run_cli("calibrate " + ex + " --measured " + std::string(TROCHOMILL_CLI));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find(":1:1: byte 0x7f is not text"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("ELF"), std::string::npos) << r.out;
  const std::string ngc = (dir_ / "g.ngc").string();
  std::ofstream(ngc) << "G28\nM2\n";
  EXPECT_EQ(run_cli("check-gcode " + ngc + " --g28 nan,0,0").code, 2);
  // The keys, and every key named in a help text.
  const auto keys = nlohmann::json::parse(run_cli("keys --json").out);
  std::set<std::string> names, sections;
  for (const auto& k : keys) {
    names.insert(k["section"].get<std::string>() + "." + k["key"].get<std::string>());
    sections.insert(k["section"].get<std::string>());
  }
  const std::string top = run_cli("--help").out;
  // (No std::regex: GCC 12 warns inside it under the sanitizers.)
  const auto is_word = [](char c) {
    return std::islower(static_cast<unsigned char>(c)) != 0 || c == '_' ||
           std::isdigit(static_cast<unsigned char>(c)) != 0;
  };
  // Each "[section] key" and "section.key" of a text: (section, key) pairs.
  const auto named_keys = [&](const std::string& text) {
    std::vector<std::pair<std::string, std::string>> out;
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '[') {
        std::size_t j = i + 1;
        while (j < text.size() && is_word(text[j])) ++j;
        if (j + 2 < text.size() && text[j] == ']' && text[j + 1] == ' ' && j > i + 1) {
          std::size_t k = j + 2;
          while (k < text.size() && is_word(text[k])) ++k;
          if (k > j + 2)
            out.emplace_back(text.substr(i + 1, j - i - 1), text.substr(j + 2, k - j - 2));
        }
      } else if (text[i] == '.' && i > 0 && is_word(text[i - 1]) && i + 1 < text.size() &&
                 is_word(text[i + 1])) {
        std::size_t s = i;
        while (s > 0 && is_word(text[s - 1])) --s;
        std::size_t e = i + 1;
        while (e < text.size() && is_word(text[e])) ++e;
        out.emplace_back(text.substr(s, i - s), text.substr(i + 1, e - i - 1));
      }
    }
    return out;
  };
  std::size_t commands = 0;
  const std::string list = top.substr(top.find("Subcommands:"));
  std::istringstream lines(list);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("  ", 0) != 0 || line.size() < 3 ||
        !std::islower(static_cast<unsigned char>(line[2]))) {
      continue;
    }
    const std::string cmd = line.substr(2, line.find(' ', 2) - 2);
    const std::string help = run_cli(cmd + " --help").out;
    ++commands;
    for (const auto& [section, key] : named_keys(help)) {
      // Phrases such as "[stock] box" or "[machine] limits" name a section, not a key.
      static const std::set<std::string> phrases = {"box", "limits", "block", "settings"};
      if (sections.count(section) == 0 || phrases.count(key) > 0) continue;
      EXPECT_TRUE(names.count(section + "." + key) > 0)
          << cmd << " --help names " << section << "." << key << ", no such key";
    }
  }
  EXPECT_GT(commands, 15u);
}

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
  // texture reads the folder's walls (at the middle level, each wall material side up).
  const CliResult tex = run_cli("texture " + out + " --lambda-c 0.8 --json -");
  ASSERT_EQ(tex.code, 0) << tex.out;
  const auto tj = nlohmann::json::parse(tex.out)["surfaces"];
  // The floor, cut across the slot in this window: an end mill without axial runout leaves it
  // flat (every Z ray ends at the tool's bottom), so Sa and Sz are 0 to rounding.
  ASSERT_TRUE(std::filesystem::exists(std::filesystem::path(out) / "floor.x3p"));
  ASSERT_EQ(tj.size(), 3u);
  EXPECT_EQ(tj[2]["surface"], "floor");
  EXPECT_EQ(tj[2]["kind"], "areal");
  EXPECT_LT(tj[2]["sl"]["sa_mm"].get<double>(), 1e-12);
  EXPECT_LT(tj[2]["sl"]["sz_mm"].get<double>(), 1e-12);
  EXPECT_EQ(tj[2]["sl"]["sku"].get<double>(), 0.0);  // no shape: not a ratio of rounding errors
  EXPECT_TRUE(tj[2]["sl"]["sal_mm"].is_null());
  EXPECT_TRUE(tj[2]["sl"]["flat"].get<bool>());
  EXPECT_EQ(tj[0]["surface"], "left");
  EXPECT_NE(tj[0]["description"].get<std::string>().find("simulated left wall at z = "),
            std::string::npos);
  EXPECT_GT(tj[1]["ra_mm"].get<double>(), 0.0);

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
  const CliResult nm =
      run_cli("forces " + test::example("wagih2023/elliptical.toml").string() + " --fast");
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

namespace trochomill {
namespace {

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
