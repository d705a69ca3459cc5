// The CLI's exit codes (0 ok, 2 bad input, 1 runtime failure) and its messages: --set and
// bad input exit 2 without output, flags that alias job keys and numeric flags are checked,
// messages name what was typed and what is wrong, --version and --help.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/io.hpp"
#include "trochomill/job.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::run_cli;

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

// The library names an option as its API does (rate_hz, parts, lambda_c_mm); the CLI shows
// its flag for it, in the message's place, in every kind of message (bad input, a note of an
// interrupted run is tested in Cli.ASweepLocksItsOutputAndResumeChecksIt).
TEST_F(Cli, LibraryOptionsAreNamedByTheirFlags) {
  const std::string wagih = test::example("wagih2023/trochoidal.toml").string();
  const std::string raw = (dir_ / "a.f32").string();
  { std::ofstream(raw, std::ios::binary) << std::string(400, '\0'); }
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"spectrum " + raw, "a.f32: raw samples carry no rate: give --rate (Hz)"},
      {"report " + wagih + " -o r.html --with plots", "report: --with 'plots': unknown item"},
      {"report " + wagih + " -o r.html --signal " + raw + " --rate 1000",
       "report: --signal needs --start T"},
      {"sweep " + wagih + " --range path.type=1:2 --samples 2 -o s.csv",
       "--range path.type: the key is choice, not a number (give its values with --vary)"},
      {"optimize " + wagih + " --var path.step=0.5:1 --maximize mrr -o b.toml",
       "--maximize mrr: not a metric of --eval analyze"},
      {"optimize " + wagih +
           " --var path.step=0.5:1 --var path.step=0.6:1 --maximize h_max_mm -o b.toml",
       "--var path.step: given twice"},
  };
  for (const auto& [args, message] : cases) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(message), std::string::npos) << args << "\n" << r.out;
    EXPECT_EQ(r.out.find('\x1e'), std::string::npos) << args;  // no mark left
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

TEST_F(Cli, VersionAndHelp) {
  CliResult r = run_cli("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("trochomill 0."), std::string::npos);
  r = run_cli("plan --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--dialect"), std::string::npos);
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

}  // namespace
}  // namespace trochomill
