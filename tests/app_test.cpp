// The application layer: windows, memory limits and feed targets as the CLI and the Python
// module resolve them, with the caller's option names in every message.
#include "trochomill/app.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"

using namespace trochomill;

namespace {

// A window by cycles is the cycle marks' times; by times it is the times; none is the path.
TEST(App, WindowsResolveToTheCyclesOrTheTimes) {
  const Job job = load_job(test::example("wagih2023/trochoidal.toml"));
  const ToolPath path = plan_path(job).path;
  const auto& marks = path.cycles();
  ASSERT_GT(marks.size(), 5u);
  WindowRequest r;
  r.cycles = std::pair{3LL, 5LL};
  const auto [a, b] = resolve_window(path, r);
  EXPECT_EQ(a, marks[3].start_time_s);
  EXPECT_EQ(b, marks[5].start_time_s);
  r.cycles = std::pair{0LL, static_cast<long long>(marks.size())};
  EXPECT_EQ(resolve_window(path, r).second, path.duration_s());  // the last runs to the end
  EXPECT_EQ(resolve_window(path, {}), (std::pair{0.0, path.duration_s()}));
  EXPECT_EQ(resolve_window(path, {std::nullopt, 2.0, 7.5}), (std::pair{2.0, 7.5}));
}

// The CLI's flag for each option the app layer names (its table, cli_option_name, is the
// CLI's own; this is the part the rules below use).
std::string cli_flag(std::string_view api) {
  if (api == "cycles") return "--cycles";
  if (api == "from_s") return "--from";
  if (api == "to_s") return "--to";
  if (api == "memory_limit_gb") return "--memory-limit";
  return std::string(api);
}
// The message of the InputError f throws as an adapter shows it ("no error" without one).
std::string shown(const std::function<void()>& f,
                  const std::function<std::string(std::string_view)>& name_of) {
  try {
    f();
  } catch (const InputError& e) {
    return e.message(name_of);
  }
  return "no error";
}

// Each broken rule names its option: Python's argument in what(), the CLI's flag through
// message() (one rule, each adapter's name).
TEST(App, WindowErrorsNameTheCallersOptions) {
  const Job job = load_job(test::example("wagih2023/trochoidal.toml"));
  const ToolPath path = plan_path(job).path;
  WindowRequest both;
  both.cycles = std::pair{1LL, 2LL};
  both.from_s = 1.0;
  EXPECT_EQ(shown([&] { (void)resolve_window(path, both); }, cli_flag),
            "give --cycles or --from/--to, not both");
  EXPECT_EQ(test::message_of([&] { (void)resolve_window(path, both); }),
            "give cycles or from_s/to_s, not both");
  WindowRequest huge;
  huge.cycles = std::pair{99999999999LL, 1LL};  // beyond int: refused before any narrowing
  EXPECT_NE(shown([&] { (void)resolve_window(path, huge); }, cli_flag)
                .find("--cycles '99999999999:1': need 0 <= A < B <= "),
            std::string::npos);
  EXPECT_EQ(shown(
                [&] {
                  (void)resolve_window(path, {std::nullopt, -1.0, {}});
                },
                cli_flag),
            "--from must be a finite time in [0, 1e9] s, got -1");
  EXPECT_NE(shown(
                [&] {
                  (void)resolve_window(path, {std::nullopt, 5.0, 5.0});
                },
                cli_flag)
                .find("--to must be after --from"),
            std::string::npos);
  EXPECT_EQ(parse_cycle_range("3:4"), (std::pair{3LL, 4LL}));
  for (const char* bad : {"3", "3:", ":4", "a:4", "3:4x", "3 :4"}) {
    EXPECT_EQ(shown([&] { (void)parse_cycle_range(bad); }, cli_flag),
              std::string("--cycles '") + bad + "': expected A:B, e.g. 3:4");
    EXPECT_EQ(test::message_of([&] { (void)parse_cycle_range(bad); }),
              std::string("cycles '") + bad + "': expected A:B, e.g. 3:4");
  }
}

// An option named in a message: what() and problems() read its API name (as Python users
// call it), message() each adapter's own name for it; a message without one is what() as it
// is, and a stray mark (a control character in a file's text) passes through unchanged.
TEST(App, MessagesNameOptionsByTheAdaptersNames) {
  const auto flag = [](std::string_view n) { return n == "rate_hz" ? "--rate" : std::string(n); };
  const InputError e(
      std::vector<std::string>{"a.f32: give " + option_name("rate_hz") + " (Hz)",
                               option_name("start_s") + " needs " + option_name("signal")});
  EXPECT_EQ(std::string(e.what()), "a.f32: give rate_hz (Hz)\nstart_s needs signal");
  EXPECT_EQ(e.problems(),
            (std::vector<std::string>{"a.f32: give rate_hz (Hz)", "start_s needs signal"}));
  EXPECT_EQ(e.message(flag), "a.f32: give --rate (Hz)\nstart_s needs signal");
  const Interrupted stop("interrupted: " + option_name("resume") + " continues");
  EXPECT_EQ(stop.message([](std::string_view n) { return "--" + std::string(n); }),
            "interrupted: --resume continues");
  const IoError plain("cannot write 'x'");
  EXPECT_EQ(plain.message(flag), "cannot write 'x'");
  EXPECT_EQ(render_options("a\x1e b", flag), "a\x1e b");
  EXPECT_EQ(render_options("a\x1f"
                           "b\x1e",
                           flag),
            "a\x1f"
            "b\x1e");
}

TEST(App, MemoryChecksNameTheLimitAndItsSource) {
  EXPECT_EQ(memory_limit_bytes(2.5), 2.5e9);
  EXPECT_EQ(memory_limit_bytes(std::nullopt), default_memory_limit_bytes());
  EXPECT_EQ(test::message_of([] { (void)memory_limit_bytes(0.0); }),
            "memory_limit_gb must be a finite number > 0 (GB), got 0");
  EXPECT_EQ(shown([] { (void)memory_limit_bytes(-1.0); }, cli_flag),
            "--memory-limit must be a finite number > 0 (GB), got -1");
  EXPECT_NO_THROW(check_memory("simulate", 1e9, 1.0, "coarser"));
  EXPECT_EQ(shown([] { check_memory("simulate", 3e9, 1.0, "coarser"); }, cli_flag),
            "simulate: estimated memory 3.00 GB exceeds the limit of 1.00 GB (--memory-limit): "
            "coarser; or raise --memory-limit");
  // A tiny limit reads in MB (it read "0.00 GB").
  EXPECT_EQ(test::message_of([] { check_memory("plan", 3e6, 0.0001, "x"); }),
            "plan: estimated memory 3.00 MB exceeds the limit of 0.10 MB (memory_limit_gb): x; or "
            "raise memory_limit_gb");
  EXPECT_NE(test::message_of([] {
              check_memory("plan", 1e18, std::nullopt, "x");
            }).find("(75 % of RAM): x; or raise memory_limit_gb"),
            std::string::npos);
}

// Given targets replace the job's; absent ones keep default_feed_targets'.
TEST(App, FeedTargetsGoOverTheJobs) {
  const Job job = load_job(test::example("wagih2023/trochoidal.toml"));
  const FeedTargets d = default_feed_targets(job);
  FeedTargetRequest r;
  r.h_max_mm = 0.05;
  r.max_feed_mm_per_min = 900;
  const FeedTargets t = feed_targets(job, r);
  EXPECT_EQ(t.h_max_mm, 0.05);
  EXPECT_EQ(t.max_feed_mm_per_min, 900);
  EXPECT_EQ(t.min_feed_mm_per_min, d.min_feed_mm_per_min);
  EXPECT_EQ(t.piece_mm, d.piece_mm);
  EXPECT_EQ(t.feed_step_percent, d.feed_step_percent);
}

}  // namespace
