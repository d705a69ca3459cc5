// The CLI's shared pieces (cli_common.hpp).
#include "cli_common.hpp"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "trochomill/app.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/study.hpp"

namespace trochomill::cli {

namespace {

CLI::Validator finite_check(double lo, double hi, bool open_lo) {
  const std::string what =
      fmt::format("a finite number {}", open_lo ? fmt::format("in ({:g}, {:g}]", lo, hi)
                                                : fmt::format("in [{:g}, {:g}]", lo, hi));
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        const bool ok = end != text.c_str() && *end == '\0' && std::isfinite(v) &&
                        (open_lo ? v > lo : v >= lo) && v <= hi;
        return ok ? std::string() : fmt::format("must be {}, got '{}'", what, text);
      },
      what);
}

}  // namespace

CLI::Validator finite_in(double lo, double hi) { return finite_check(lo, hi, false); }
CLI::Validator finite_above(double lo, double hi) { return finite_check(lo, hi, true); }

namespace {
// Runs a library parser of a flag's text; its errors (which name the text, not the flag) are
// given the flag in front.
template <class Parse>
auto with_flag(const std::string& flag, Parse&& parse) {
  try {
    return parse();
  } catch (const InputError& e) {
    std::vector<std::string> problems;
    for (const auto& p : e.problems()) problems.push_back(flag + " " + p);
    throw InputError(problems);
  }
}
}  // namespace

std::string cli_option_name(std::string_view api_name) {
  // The library's (and Python's) name of each option the CLI has a flag for, and the flag.
  static const std::map<std::string, std::string, std::less<>> flags = {
      {"cycles", "--cycles"},
      {"engine", "--engine"},
      {"eval", "--eval"},
      {"fit", "--fit"},
      {"format", "--format"},
      {"from_s", "--from"},
      {"l_mm", "--lambda-c"},
      {"lambda_c_mm", "--lambda-c"},
      {"lambda_s_mm", "--lambda-s"},
      {"max_blocks", "--max-blocks"},
      {"max_evaluations", "--max-evals"},
      {"maximize", "--maximize"},
      {"measured_t_s", "--measured"},
      {"memory_limit_gb", "--memory-limit"},
      {"max_feed_mm_per_min", "--max-feed"},
      {"h_axial_max_mm", "--h-axial-max"},
      {"min_feed_mm_per_min", "--min-feed"},
      {"minimize", "--minimize"},
      {"model", "--model"},
      {"parts", "--with"},
      {"ranges", "--range"},
      {"rate_hz", "--rate"},
      {"resume", "--resume"},
      {"samples", "--samples"},
      {"sampler", "--sampler"},
      {"signal", "--signal"},
      {"start_s", "--start"},
      {"stream", "--stream"},
      {"subject_to", "--subject-to"},
      {"to_s", "--to"},
      {"variables", "--var"},
      {"vary", "--vary"},
  };
  const auto it = flags.find(api_name);
  return it == flags.end() ? std::string(api_name) : it->second;
}

std::string cli_message(const Error& e) { return e.message(cli_option_name); }

Vary parse_vary_flag(const std::string& text) {
  return with_flag("--vary", [&] { return parse_vary(text); });
}

std::vector<Override> JobArgs::overrides() const {
  std::vector<Override> ov;
  for (const auto& s : sets) {
    Override o = with_flag("--set", [&] { return parse_override(s); });
    o.origin = "--set " + o.key;  // the schema's messages name the flag and the key
    ov.push_back(std::move(o));
  }
  for (const Alias& a : aliases)
    ov.push_back(Override{a.key, a.value, fmt::format("{} ({})", a.flag, a.key)});
  return ov;
}

Job JobArgs::load() const {
  Job job = load_job(file, overrides());
  attach_rest_stock(job);  // [pocket] rest_of: the earlier program's stock, read once
  if (job.geometry.units.rfind("unitless (read as mm)", 0) == 0) {
    fmt::print(stderr,
               "warning: {} gives no unit (no $INSUNITS, or 0): its numbers are read as mm; if "
               "it was drawn in another, say which with [geometry] units (mm, cm, m, in or ft)\n",
               job.geometry.file);
  }
  return job;
}

void add_job_args(CLI::App* cmd, JobArgs& a) {
  cmd->add_option("JOB", a.file, "job file (TOML)")->required();
  cmd->add_option("--set", a.sets,
                  "override a job key: section.key=value (repeatable), e.g. path.step=0.8")
      ->take_all();
}

void add_key_alias(CLI::App* cmd, JobArgs& a, const std::string& flag, const std::string& key,
                   const std::string& help) {
  cmd->add_option_function<std::string>(
      flag,
      [&a, flag, key](const std::string& v) {
        a.aliases.push_back({flag, key, v});
      },
      fmt::format("{} (the job key {}: --set {}=VALUE)", help, key, key));
}

void add_stock_mesh_alias(CLI::App* cmd, JobArgs& a) {
  cmd->add_option_function<std::string>(
      "--stock",
      [&a](const std::string& v) {
        // A TOML basic string of the absolute path: backslashes and quotes escaped.
        std::string quoted = "\"";
        for (const char c : std::filesystem::absolute(v).string()) {
          if (c == '\\' || c == '"') quoted += '\\';
          quoted += c;
        }
        a.aliases.push_back({"--stock", "stock.mesh", quoted + "\""});
      },
      "a pocket's stock as a closed mesh: STL, PLY or OBJ, mm, the drawing's frame (the job "
      "key stock.mesh, the file relative to the current folder)");
}

void add_key_flag(CLI::App* cmd, JobArgs& a, const std::string& flag, const std::string& key,
                  const std::string& value, const std::string& help) {
  cmd->add_flag_callback(
      flag,
      [&a, flag, key, value] {
        a.aliases.push_back({flag, key, value});
      },
      fmt::format("{} (--set {}={})", help, key, value));
}

FeedTargets FeedTargetArgs::resolve(const Job& job) const {
  return feed_targets(job, {h_max_mm, mrr_mm3_per_min, feed_step_percent, piece_mm, min_feed,
                            max_feed, air_feed, h_axial_max_mm});
}

void add_feed_target_args(CLI::App* cmd, FeedTargetArgs& a) {
  cmd->add_option("--h-max", a.h_max_mm,
                  "target largest chip, mm (default: the job's feed per tooth)")
      ->check(finite_above(0, 100));
  cmd->add_option("--h-axial-max", a.h_axial_max_mm,
                  "largest axial chip of a descent (its descent per tooth where the end face "
                  "cuts), mm; a faster descent is slowed to it (default: the target chip)")
      ->check(finite_above(0, 100));
  cmd->add_option("--mrr", a.mrr_mm3_per_min,
                  "cap on the removal rate, mm^3/min (the swept area times the slot depth)")
      ->check(finite_above(0, 1e9));
  cmd->add_option("--min-feed", a.min_feed,
                  "slowest scheduled feed, mm/min (default: machine.min_feed, else a tenth of "
                  "the job's feed)")
      ->check(finite_above(0, 1e6));
  cmd->add_option("--max-feed", a.max_feed,
                  "fastest scheduled feed, mm/min (default: machine.max_feed, else three times "
                  "the job's feed)")
      ->check(finite_above(0, 1e6));
  cmd->add_option("--air-feed", a.air_feed,
                  "feed where the tool cuts nothing, mm/min (default: machine.air_feed, else "
                  "the max feed)")
      ->check(finite_in(0, 1e6));
  cmd->add_option("--feed-step", a.feed_step_percent,
                  "neighbouring pieces within this percent share the slower feed")
      ->capture_default_str()
      ->check(finite_in(0, 100));
  cmd->add_option("--piece", a.piece_mm, "the longest piece fed alone, mm (at least 0.01)")
      ->capture_default_str()
      ->check(finite_in(0.01, 1e3));
}

ToolPath job_path(const Job& job, const std::string& gcode_file, std::optional<double> memory_gb,
                  GcodeProgram* lines) {
  if (gcode_file.empty()) return plan_job(job).path;
  GcodeReadOptions ro = gcode_options(job.machine).read;
  // Reading leaves the most of the memory to the work on the path (samples, chips).
  ro.max_path_bytes = kPathShareOfMemory * memory_limit_bytes(memory_gb);
  ro.missing_tool_diameter_mm = job.tool.diameter_mm;
  GcodeProgram prog = read_gcode_file(gcode_file, ro);
  if (prog.path.empty()) {
    throw InputError(fmt::format(
        "{}: the program has no motion (no G0/G1/G2/G3 moves): there is nothing to analyse",
        gcode_file));
  }
  for (const std::string& w : prog.info.warnings) fmt::print(stderr, "warning: {}\n", w);
  if (lines != nullptr) {
    lines->segment_lines = std::move(prog.segment_lines);
    lines->source_files = std::move(prog.source_files);
  }
  const std::vector<std::string> differ = header_mismatches(job, prog, gcode_file);
  for (const std::string& w : differ) fmt::print(stderr, "warning: {}\n", w);
  if (!differ.empty()) {
    fmt::print(stderr,
               "warning: the results are for the program as the job describes the tool, slot "
               "and placement; run with the job the program was written for\n");
  }
  // A program is in the workpiece; the models work in the slot frame of the job's placement.
  return to_slot_frame(prog.path, slot_placement(job));
}

void check_outputs(std::initializer_list<const std::string*> outputs,
                   std::initializer_list<const std::string*> inputs) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const std::string* o : outputs) {
    if (o->empty() || *o == "-") continue;
    const fs::path out = fs::weakly_canonical(*o, ec);
    for (const std::string* in : inputs) {
      if (in->empty() || *in == "-") continue;
      if (fs::weakly_canonical(*in, ec) == out) {
        throw InputError(
            fmt::format("output '{}' is the input '{}': choose another output file", *o, *in));
      }
    }
    if (fs::is_directory(*o, ec)) {
      throw InputError(fmt::format("output '{}' is a directory: give a file name", *o));
    }
    const fs::path dir = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (!fs::is_directory(dir, ec)) {  // a file-system failure, as writing would find it
      throw IoError(
          fmt::format("cannot write '{}': directory '{}' does not exist", *o, dir.string()));
    }
  }
}

void check_output_dir(const std::string& dir, const std::string& option) {
  std::error_code ec;
  if (!dir.empty() && std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec)) {
    throw InputError(fmt::format("{} '{}' exists and is not a directory", option, dir));
  }
}

namespace {
// A failed write to standard output (a full disk behind `>`, a closed pipe) is a failed write.
void check_stdout(bool ok) {
  if (!ok || std::fflush(stdout) != 0 || std::ferror(stdout) != 0) {
    throw IoError(fmt::format("cannot write to standard output: {}", std::strerror(errno)));
  }
}
}  // namespace

void emit(const std::string& target, const std::string& text) {
  if (target == "-") {
    check_stdout(std::fwrite(text.data(), 1, text.size(), stdout) == text.size());
  } else {
    write_file_atomic(target, text);
  }
}

void emit_stream(const std::string& target,
                 const std::function<void(const std::function<void(std::string_view)>&)>& produce) {
  if (target == "-") {
    produce([](std::string_view piece) {
      if (std::fwrite(piece.data(), 1, piece.size(), stdout) != piece.size()) check_stdout(false);
    });
    check_stdout(true);
    return;
  }
  write_text_atomic(target, produce);
}

void emit_file(const std::string& target, const std::string& extension,
               const std::function<void(const std::filesystem::path&)>& writer) {
  if (target != "-") {
    write_file_atomic(target, writer);
    return;
  }
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() /
      fmt::format("trochomill-{}{}", static_cast<long>(::getpid()), extension);
  const PendingFile pending(tmp);
  std::string bytes;
  try {
    writer(tmp);
    bytes = read_file(tmp);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  std::filesystem::remove(tmp);
  emit("-", bytes);
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool summary_to_stdout(std::initializer_list<const std::string*> outputs) {
  return std::none_of(outputs.begin(), outputs.end(),
                      [](const std::string* o) { return *o == "-"; });
}

std::pair<double, double> WindowArgs::resolve(const ToolPath& path) const {
  WindowRequest r;
  if (!cycles.empty()) r.cycles = parse_cycle_range(cycles);
  r.from_s = from_s;
  r.to_s = to_s;
  return resolve_window(path, r);
}

void add_window_args(CLI::App* cmd, WindowArgs& w, const std::string& what) {
  cmd->add_option("--from", w.from_s, what + " start, s of programmed time (default 0)")
      ->check(finite_in(0, 1e9));
  cmd->add_option("--to", w.to_s, what + " end, s (default: the path's end)")
      ->check(finite_in(0, 1e9));
  cmd->add_option("--cycles", w.cycles,
                  "A:B: trochoid cycles A (inclusive) to B (exclusive), from 0");
}

Signal SignalArgs::read() const {
  SignalReadOptions o;
  o.format = parse_sample_format(format);
  o.rate_hz = rate;
  o.channel = channel;
  return read_signal(file, o);
}

void add_signal_args(CLI::App* cmd, SignalArgs& a, bool required, const std::string& name) {
  auto* o = cmd->add_option(name, a.file,
                            "WAV/FLAC/AIFF (libsndfile), CSV, raw .f32/.s16 (- for stdin, raw)");
  if (required) o->required();
  auto* rate =
      cmd->add_option("--rate", a.rate, "sample rate, Hz (raw data, CSV without a time column)")
          ->check(finite_above(0, 1e8));
  auto* format =
      cmd->add_option("--format", a.format, "auto, wav, csv, f32 or s16 (default: by extension)");
  auto* channel = cmd->add_option("--channel", a.channel, "0-based channel (or CSV data column)")
                      ->check(CLI::NonNegativeNumber);
  // A signal given by an option (report's --signal): its reading options are refused without
  // it. (A command's optional positional SIGNAL is not: monitor --stream reads standard input
  // with them.)
  if (!required && name.rfind("--", 0) == 0) {
    for (CLI::Option* x : {rate, format, channel}) x->needs(o);
  }
}

std::pair<double, double> parse_band(const std::string& opt, const std::string& text) {
  const auto colon = text.find(':');
  char* e1 = nullptr;
  char* e2 = nullptr;
  const std::string a = text.substr(0, colon),
                    b = colon == std::string::npos ? "" : text.substr(colon + 1);
  const double lo = std::strtod(a.c_str(), &e1), hi = std::strtod(b.c_str(), &e2);
  if (colon == std::string::npos || a.empty() || b.empty() || *e1 != '\0' || *e2 != '\0' ||
      !(lo > 0 && hi > lo)) {
    throw InputError(fmt::format(
        "{} '{}': expected LOW:HIGH in Hz with 0 < LOW < HIGH, e.g. 2000:5000", opt, text));
  }
  return {lo, hi};
}

namespace {

std::atomic<bool> g_interrupted{false};
std::atomic<int> g_guarded{0};  // GuardedRuns alive (the library polls g_interrupted)
std::atomic<int> g_signal{0};   // the first stopping signal (SIGINT, SIGTERM)

void on_interrupt(int sig) {
  int none = 0;
  g_signal.compare_exchange_strong(none, sig);
  if (g_guarded.load() > 0 && !g_interrupted.exchange(true)) return;  // the library stops
  remove_pending_files();
  static const char msg[] = "\ninterrupted\n";
  static const char term[] = "\nterminated\n";
  if (sig == SIGTERM) {
    (void)!::write(STDERR_FILENO, term, sizeof term - 1);
  } else {
    (void)!::write(STDERR_FILENO, msg, sizeof msg - 1);
  }
  ::_exit(128 + sig);
}

}  // namespace

int interrupted_exit_code() {
  const int sig = g_signal.load();
  return 128 + (sig != 0 ? sig : SIGINT);
}

void install_interrupt_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);  // the same, exit 143 (a batch system's stop, `kill`)
  // A write past the file size limit (ulimit -f) fails with EFBIG and is reported as any
  // failed write, instead of the signal ending the process with a half-written output.
  std::signal(SIGXFSZ, SIG_IGN);
}

struct GuardedRun::Bar {
  bool shown = false;
  std::string label;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now(), last{};
};

GuardedRun::GuardedRun(bool progress) : bar_(std::make_shared<Bar>()) {
  bar_->shown = progress && isatty(STDERR_FILENO) != 0;
  g_interrupted.store(false);
  g_guarded.fetch_add(1);
}

GuardedRun::~GuardedRun() { g_guarded.fetch_sub(1); }

RunHooks GuardedRun::hooks() const {
  RunHooks h;
  h.cancel = &g_interrupted;
  if (!bar_->shown) return h;
  h.phase = [bar = bar_](std::string_view name) {
    bar->label = std::string(name);
    bar->start = std::chrono::steady_clock::now();
    bar->last = {};
  };
  h.progress = [bar = bar_](std::size_t done, std::size_t total) {
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - bar->last < std::chrono::milliseconds(100)) return;
    bar->last = now;
    const double f =
        static_cast<double>(done) / static_cast<double>(std::max<std::size_t>(1, total));
    const double el = std::chrono::duration<double>(now - bar->start).count();
    const int w = 30, filled = static_cast<int>(std::clamp(f, 0.0, 1.0) * w);
    // The ETA once a little of the phase is done (before, it says nothing).
    const std::string eta =
        f >= 0.01 || (f > 0 && el > 2) ? fmt::format("{:.0f} s", el * (1 - f) / f) : "?";
    fmt::print(stderr, "\r{:<26.26} [{}{}] {:5.1f} %  ETA {}   ", bar->label,
               std::string(static_cast<std::size_t>(filled), '#'),
               std::string(static_cast<std::size_t>(w - filled), '.'), 100 * f, eta);
  };
  return h;
}

void GuardedRun::done() const {
  if (bar_->shown) fmt::print(stderr, "\r{}\r", std::string(78, ' '));
}

void GuardedRun::finish(const char* what) const {
  if (g_interrupted.load()) throw Interrupted(what);
}

void print_failed_points(const char* command, const std::vector<StudyPoint>& points) {
  std::size_t failed = 0;
  const StudyPoint* first = nullptr;
  for (const StudyPoint& p : points) {
    if (p.ok) continue;
    if (failed++ == 0) first = &p;
  }
  if (failed == 0) return;
  fmt::print(stderr, "{}: {} of {} points failed (the first: {})\n", command, failed, points.size(),
             first->error);
}

void add_memory_limit(CLI::App* cmd, std::optional<double>& limit_gb) {
  cmd->add_option("--memory-limit", limit_gb,
                  "refuse to start above this estimate, GB (default: 75 % of RAM)")
      ->check(finite_above(0, 1e6));
}

}  // namespace trochomill::cli
