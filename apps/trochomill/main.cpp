// trochomill command-line interface: builds the app from the command groups (one file each,
// commands.hpp), runs the chosen command and maps failures to exit codes: 0 success, 2 bad
// input (arguments, job file, NC program, signal), 1 runtime failure, 130 interrupted (Ctrl-C), 143
// terminated (SIGTERM).
#include <fmt/format.h>
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/version.hpp"

namespace {
// The last word on stderr: a failure to print it (stderr on a full disk) changes nothing, it
// must not throw out of main.
void say(const std::string& text) noexcept {
  (void)!std::fwrite(text.data(), 1, text.size(), stderr);
}

// A first word that is no command: said so, with the nearest command when one is close.
bool unknown_command(CLI::App& app, const std::string& word) {
  if (word.empty() || word[0] == '-') return false;
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    if (sub->get_name() == word) return false;
    names.push_back(sub->get_name());
  }
  say("error: unknown command '" + word + "'" + trochomill::did_you_mean(word, names) + "\n");
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  namespace cli = trochomill::cli;
  int exit_code = 0;
  // glibc's malloc gives freed memory at the top of its heap back to the system past 128 kB
  // and maps blocks from 128 kB up as they are asked for, so a loop that allocates and frees
  // the same large buffers takes them back each time as fresh, zeroed pages. calibrate's
  // solver does so every evaluation (its Jacobian and the model's forces): 23.7 s of which
  // two thirds were page faults and zeroing, 7.8 s with the memory kept, the same peak
  // (docs/PERFORMANCE.md). Blocks up to 32 MB (glibc's largest) come from the heap, and up to
  // 1 GB of free heap is kept for the next allocation; the process's peak does not change.
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
  mallopt(M_TRIM_THRESHOLD, 1024 * 1024 * 1024);
  cli::install_interrupt_handler();
  try {
    CLI::App app{"trochomill: plan, analyse and simulate trochoidal slot milling"};
    app.set_version_flag("--version", std::string("trochomill ") + trochomill::kVersion);
    app.require_subcommand(1);
    cli::register_path_commands(app, exit_code);
    cli::register_geometry_commands(app, exit_code);
    cli::register_analysis_commands(app, exit_code);
    cli::register_mechanism_commands(app, exit_code);
    cli::register_simulation_commands(app, exit_code);
    cli::register_calibration_commands(app, exit_code);
    cli::register_signal_commands(app, exit_code);
    cli::register_tool_commands(app, exit_code);
    cli::register_surface_commands(app, exit_code);
    cli::register_study_commands(app, exit_code);
    cli::register_feed_commands(app, exit_code);
    cli::register_report_commands(app, exit_code, argc, argv);
    if (argc > 1 && unknown_command(app, argv[1])) return 2;
    try {
      app.parse(argc, argv);  // the chosen command runs in its callback
    } catch (const CLI::Success& e) {
      return app.exit(e);
    } catch (const CLI::ParseError& e) {
      app.exit(e);
      return 2;
    }
    return exit_code;
  } catch (const trochomill::Interrupted& e) {
    // The library's own message is "interrupted"; a command that stopped while writing says
    // what it wrote.
    const std::string what = cli::cli_message(e);
    say("\n" + (what == "interrupted" ? std::string("interrupted: nothing was written") : what) +
        "\n");
    return cli::interrupted_exit_code();
  } catch (const trochomill::InputError& e) {
    say("error: " + cli::cli_message(e) + "\n");
    return 2;
  } catch (const trochomill::Error& e) {
    say("error: " + cli::cli_message(e) + "\n");
    return 1;
  } catch (const std::exception& e) {
    say(std::string("error: ") + e.what() + "\n");
    return 1;
  }
}
