// What every command of the CLI shares: the job argument with `--set` (and the flags that are
// aliases of job keys), output emission ("-" is stdout), the time window of a path, signal
// input options, and the guarded long run (memory check, Ctrl-C, progress bar). Each command
// group registers its commands on the app in its own file (commands.hpp); main.cpp dispatches
// and maps errors to exit codes.
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/analysis.hpp"
#include "trochomill/app.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/progress.hpp"
#include "trochomill/signal.hpp"

namespace trochomill::cli {

/// A command's job: the file, its `--set` overrides, and alias flags that set job keys.
struct JobArgs {
  std::string file;
  std::vector<std::string> sets;
  /// A flag given that sets a job key, applied after the --set overrides.
  struct Alias {
    std::string flag, key, value;
  };
  std::vector<Alias> aliases;
  [[nodiscard]] std::vector<Override> overrides() const;
  [[nodiscard]] Job load() const;
};
/// A value-list flag (`--vary key=v1,v2,...`) parsed by the library, its errors named by the
/// flag (the library's name only the text).
[[nodiscard]] Vary parse_vary_flag(const std::string& text);
/// The CLI's flag for an option the library names by its API name (option_name in
/// trochomill/error.hpp): rate_hz is --rate, parts is --with; a name the CLI has no flag for
/// stays as it is.
[[nodiscard]] std::string cli_option_name(std::string_view api_name);
/// An error's message as the CLI shows it: each option it names by its flag.
[[nodiscard]] std::string cli_message(const Error& e);
/// Adds JOB (required) and --set to a command.
void add_job_args(CLI::App* cmd, JobArgs& a);
/// A flag that is an alias of a job key: `--flag VALUE` is `--set key=VALUE`, validated by the
/// job schema alone (the message names the flag's key).
void add_key_alias(CLI::App* cmd, JobArgs& a, const std::string& flag, const std::string& key,
                   const std::string& help);
/// --stock FILE: a pocket's stock as a closed mesh, the job key stock.mesh with the file
/// taken from the current folder (the key's own value is relative to the job file).
void add_stock_mesh_alias(CLI::App* cmd, JobArgs& a);
/// A flag without a value that sets a key to `value` (e.g. --chords: machine.arc_output=chords).
void add_key_flag(CLI::App* cmd, JobArgs& a, const std::string& flag, const std::string& key,
                  const std::string& value, const std::string& help);

/// A numeric flag's check: a finite number in [lo, hi] (CLI11's NonNegativeNumber and Range
/// let "nan" through). The message names the range; bad input exits 2.
[[nodiscard]] CLI::Validator finite_in(double lo, double hi);
/// > lo (open at lo), finite, at most hi.
[[nodiscard]] CLI::Validator finite_above(double lo, double hi);

/// A binary output whose writer needs a seekable file (libsndfile, assimp): written atomically
/// to `target`, or for "-" to a temporary file `extension` that is then copied to stdout.
void emit_file(const std::string& target, const std::string& extension,
               const std::function<void(const std::filesystem::path&)>& writer);
/// The lower-case extension of an output path (".wav").
[[nodiscard]] std::string lower_extension(const std::string& path);
/// The job's planned path, or the NC program's when one is given (turned into the slot frame
/// by the job's placement; a warning on stderr for each header key that disagrees).
/// `memory_gb`: the command's --memory-limit (a quarter of it for the program's path as read).
/// `lines`: receives the program's line table (segment_lines, source_files: the path's
/// segments keep their order in the slot frame), to name the block of a move.
[[nodiscard]] ToolPath job_path(const Job& job, const std::string& gcode_file,
                                std::optional<double> memory_gb = std::nullopt,
                                GcodeProgram* lines = nullptr);

/// Checks a command's outputs before any work: none is one of the inputs (`plan -o job.toml`
/// would overwrite the job), none is a directory, each one's directory exists. "-" (stdout)
/// and empty (not asked for) pass. Throws InputError naming the output (IoError for a missing
/// directory, as the write would).
void check_outputs(std::initializer_list<const std::string*> outputs,
                   std::initializer_list<const std::string*> inputs);
/// The same for an output directory (`simulate --out`): it is a directory or does not exist.
void check_output_dir(const std::string& dir, const std::string& option);

/// Writes text to a file atomically, or to stdout for "-".
void emit(const std::string& target, const std::string& text);
/// The same for text made piece by piece: `produce` hands each piece to the sink it is given
/// (a file of any size without holding it in memory).
void emit_stream(const std::string& target,
                 const std::function<void(const std::function<void(std::string_view)>&)>& produce);
/// True when the summary goes to stdout: no output option writes to "-".
[[nodiscard]] bool summary_to_stdout(std::initializer_list<const std::string*> outputs);

/// A time window: --cycles A:B or --from/--to (s), or the whole path.
struct WindowArgs {
  std::string cycles;
  std::optional<double> from_s, to_s;
  [[nodiscard]] bool given() const { return !cycles.empty() || from_s || to_s; }
  [[nodiscard]] std::pair<double, double> resolve(const ToolPath& path) const;
};
void add_window_args(CLI::App* cmd, WindowArgs& w, const std::string& what);

/// The feed schedule's flags (plan --feed-schedule, optimize-feed): the chip target, the
/// removal cap and the feed limits over the job's [machine] ones.
struct FeedTargetArgs {
  std::optional<double> h_max_mm, mrr_mm3_per_min, min_feed, max_feed, air_feed, h_axial_max_mm;
  double feed_step_percent = FeedTargets{}.feed_step_percent;
  double piece_mm = FeedTargets{}.piece_mm;
  /// The job's targets (default_feed_targets) with the flags given over them.
  [[nodiscard]] FeedTargets resolve(const Job& job) const;
};
inline constexpr std::array<const char*, 7> kFeedTargetFlags = {
    "--h-max", "--mrr", "--min-feed", "--max-feed", "--air-feed", "--feed-step", "--piece"};
void add_feed_target_args(CLI::App* cmd, FeedTargetArgs& a);

/// Signal-reading options shared by monitor and spectrum.
struct SignalArgs {
  std::string file;
  std::optional<double> rate;
  std::string format = "auto";
  int channel = 0;
  [[nodiscard]] Signal read() const;
};
/// The signal file as `name` (a positional SIGNAL, or an option such as --signal), and its
/// reading options.
void add_signal_args(CLI::App* cmd, SignalArgs& a, bool required,
                     const std::string& name = "SIGNAL");

/// "LO:HI" in Hz (0 < LO < HI). Throws InputError naming the option.
[[nodiscard]] std::pair<double, double> parse_band(const std::string& opt, const std::string& text);

/// Ctrl-C for the whole process (main installs it first). Outside a GuardedRun it removes
/// the temporary file of any output being written and ends the process (exit 130); inside one
/// it raises the flag the library polls, and a second Ctrl-C ends the process as outside.
/// SIGTERM is handled the same way, with exit 143.
void install_interrupt_handler();
/// The exit status of a run the user stopped: 130 for Ctrl-C, 143 for SIGTERM.
[[nodiscard]] int interrupted_exit_code();

/// A long run: Ctrl-C raises the flag its hooks carry (the library stops at the next check) and
/// a progress bar with the phase's name and ETA is shown on a terminal.
class GuardedRun {
 public:
  /// `progress`: show a bar when stderr is a terminal.
  explicit GuardedRun(bool progress);
  ~GuardedRun();
  GuardedRun(const GuardedRun&) = delete;
  GuardedRun& operator=(const GuardedRun&) = delete;
  /// Hooks for the library: the Ctrl-C flag, the phase and progress callbacks (empty when no
  /// bar is shown).
  [[nodiscard]] RunHooks hooks() const;
  /// Clears the bar's line.
  void done() const;
  /// Throws Interrupted when Ctrl-C came during the run (`what` says what was written): the
  /// last statement of a command, so a Ctrl-C that came while its outputs were written (or
  /// that stopped a simulation, whose partial results are written) ends it with 130.
  void finish(const char* what) const;

 private:
  struct Bar;
  std::shared_ptr<Bar> bar_;
};
/// A study's points that failed, counted on stderr with the first one's error (nothing when
/// none failed).
void print_failed_points(const char* command, const std::vector<StudyPoint>& points);
/// Adds --memory-limit (GB).
void add_memory_limit(CLI::App* cmd, std::optional<double>& limit_gb);

}  // namespace trochomill::cli
