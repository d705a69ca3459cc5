// Job files: the shipped examples load with the values the papers give, overrides apply,
// and every bad job in tests/data/bad_jobs gives the message its first line expects.
#include "trochomill/job.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"

namespace trochomill {
namespace {

TEST(Job, WagihExampleLoadsTable1) {
  const Job j = load_job(test::example("wagih2023/elliptical.toml"));
  EXPECT_EQ(j.tool.diameter_mm, 10.0);
  EXPECT_EQ(j.tool.teeth, 4);
  EXPECT_EQ(j.slot.width_mm, 20.0);
  EXPECT_EQ(j.path.type, PathType::elliptical);
  EXPECT_EQ(j.path.aspect_ratio, 0.8);
  EXPECT_EQ(j.cutting.feed_rate_mm_per_min, 600.0);
  EXPECT_EQ(j.cutting.spindle_speed_rpm, 2000.0);
  // f_z = f_r / (n Z) = 600 / 8000: exact in binary to one rounding.
  EXPECT_NEAR(j.cutting.feed_per_tooth_mm, 0.075, 1e-15);
  // v_c = pi D n / 1000.
  EXPECT_NEAR(j.cutting.cutting_speed_m_per_min, M_PI * 10 * 2000 / 1000, 1e-12);
  ASSERT_EQ(j.tool.tooth_angles_deg.size(), 4u);
  EXPECT_EQ(j.tool.tooth_angles_deg[1], 90.0);
}

TEST(Job, PivkinDerivesSpindleAndFeedFromCuttingSpeed) {
  const Job j = load_job(test::example("pivkin2025/trochoidal.toml"));
  // n = 1000 v_c / (pi D) = 300000 / (12 pi) = 7957.747 rpm (the paper rounds to 7961).
  EXPECT_NEAR(j.cutting.spindle_speed_rpm, 300000.0 / (12.0 * M_PI), 1e-9);
  // f_r = f_z Z n = 0.03 * 4 * 7957.747 = 954.93 mm/min (the paper: 955).
  EXPECT_NEAR(j.cutting.feed_rate_mm_per_min, 0.12 * 300000.0 / (12.0 * M_PI), 1e-9);
  EXPECT_NEAR(j.cutting.feed_per_tooth_mm, 0.03, 1e-15);
}

TEST(Job, EveryExampleLoads) {
  for (const auto& dir : {"wagih2023", "bergmann2021", "pivkin2025"}) {
    for (const auto& f : test::files_in(test::example(dir), ".toml")) {
      EXPECT_NO_THROW((void)load_job(f)) << f;
    }
  }
}

TEST(Job, OverridesReplaceAndAddKeys) {
  const Job j = load_job(
      test::example("wagih2023/elliptical.toml"),
      {parse_override("path.aspect_ratio=0.6"), parse_override("path.type = linear-elliptical"),
       parse_override("path.linear_distance=0.75"),
       parse_override("tool.tooth_angles=[0, 80, 180, 260]")});
  EXPECT_EQ(j.path.aspect_ratio, 0.6);
  EXPECT_EQ(j.path.type, PathType::linear_elliptical);
  EXPECT_EQ(j.path.linear_distance_mm, 0.75);
  EXPECT_EQ(j.tool.tooth_angles_deg[1], 80.0);
}

TEST(Job, OverrideErrorsNameTheOverride) {
  try {
    (void)load_job(test::example("wagih2023/elliptical.toml"), {parse_override("path.step=-1")});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("path.step: must be > 0 mm, got -1"), std::string::npos)
        << e.what();
  }
  try {
    (void)load_job(test::example("wagih2023/elliptical.toml"), {parse_override("path.stepp=1")});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("path.stepp: unknown key [path] stepp; did you "
                                         "mean 'step'?"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW((void)parse_override("path.step"), InputError);
  EXPECT_THROW((void)parse_override("step=1"), InputError);
  EXPECT_THROW((void)parse_override("path.step="), InputError);
}

TEST(Job, AllProblemsAreReportedTogether) {
  try {
    (void)parse_job("[tool]\ndiameter = -1\nteeth = 0\n[slot]\nwidth = 1\n", "multi.toml");
    FAIL();
  } catch (const InputError& e) {
    // diameter, teeth, slot length, slot depth, path type, path step (the default type is
    // trochoidal, which needs one), feed, speed: 8 problems.
    EXPECT_EQ(e.problems().size(), 8u) << e.what();
  }
}

TEST(Job, MissingFileIsInputError) {
  EXPECT_THROW((void)load_job("/nonexistent/job.toml"), InputError);
}

// Data-driven: each file's first line is "# expect: <message>", which must appear in the
// error (prefixed by the file name, so line:column are checked where given).
TEST(Job, BadJobFilesGiveTheExpectedMessage) {
  const auto files = test::files_in(test::source_dir() / "tests/data/bad_jobs", ".toml");
  ASSERT_GE(files.size(), 15u);
  for (const auto& f : files) {
    const std::string expect = test::first_line(f).substr(std::string("# expect: ").size());
    try {
      (void)load_job(f);
      ADD_FAILURE() << f << ": loaded without error, expected: " << expect;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos)
          << f << "\n  expected: " << expect << "\n  got: " << e.what();
      EXPECT_NE(std::string(e.what()).find(f.string()), std::string::npos)
          << "message must name the file: " << e.what();
    }
  }
}

TEST(Io, AtomicWriteReplacesAndLeavesNoTemporaries) {
  const auto dir = std::filesystem::temp_directory_path() / "trochomill_io_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  write_file_atomic(dir / "a.txt", "first");
  write_file_atomic(dir / "a.txt", "second");
  EXPECT_EQ(read_file(dir / "a.txt"), "second");
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
  EXPECT_THROW(write_file_atomic(dir / "missing" / "b.txt", "x"), IoError);
  // A writer that fails half-way leaves neither the target nor its temporary file.
  EXPECT_THROW(write_file_atomic(dir / "c.bin",
                                 [](const std::filesystem::path& tmp) {
                                   write_file_atomic(tmp, "half");
                                   throw IoError("disk full");
                                 }),
               IoError);
  EXPECT_FALSE(std::filesystem::exists(dir / "c.bin"));
  files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(dir);
}

// The one CSV reader: columns by name in any order, ';' and quotes, a header detected when
// the first field is not a number, and every error at file:line:column.
TEST(Io, CsvReaderSelectsColumnsAndLocatesErrors) {
  CsvOptions named;
  named.columns = {"fz", "t"};
  named.detect_separator = true;
  const CsvTable t = parse_csv("# comment\n\"t\"; fx; fz\n0.5;1;2\n\n1.5;3;4\r\n", "f.csv", named);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[1], (std::vector<double>{4, 1.5}));
  EXPECT_EQ(t.line_of_row[1], 5u);
  try {
    (void)parse_csv("t,fz\n0,1\n1,x\n", "f.csv", CsvOptions{{"fz"}, false, true});
    ADD_FAILURE() << "a word in a number column was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "f.csv:3:2: 'x' in column 'fz' is not a number");
  }
  EXPECT_THROW((void)parse_csv("a,b\n1,2\n", "f.csv", CsvOptions{{"c"}, false, true}), InputError);
  const CsvTable plain = parse_csv("1, 2\n3, 4\n", "g.csv");  // no header
  EXPECT_TRUE(plain.header.empty());
  EXPECT_EQ(plain.rows.size(), 2u);
  EXPECT_THROW((void)parse_csv("1,2\n3\n", "g.csv"), InputError);  // ragged
  EXPECT_THROW((void)parse_csv("1,inf\n", "g.csv"), InputError);   // not finite
  EXPECT_EQ(split_trimmed(" a, b ,,c"), (std::vector<std::string>{"a", "b", "", "c"}));
}

// One parsed document builds many jobs: each with its own overrides, each message still at
// the file's line and column; settings-only overrides refuse the job's own sections.
TEST(Job, OneDocumentBuildsManyJobs) {
  const JobDocument doc = JobDocument::load(test::example("wagih2023/elliptical.toml"));
  EXPECT_EQ(doc.build({parse_override("path.aspect_ratio=0.6")}).path.aspect_ratio, 0.6);
  EXPECT_EQ(doc.build({parse_override("path.aspect_ratio=1.2")}).path.aspect_ratio, 1.2);
  EXPECT_EQ(doc.build().path.aspect_ratio, 0.8);
  try {
    (void)doc.build({parse_override("slot.width=5")});
    ADD_FAILURE() << "a slot narrower than the tool was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("slot.width"), std::string::npos) << e.what();
  }
  Job defaults;
  apply_overrides(defaults, {Override{"monitor.order", "6", "--order"}});
  EXPECT_EQ(defaults.monitor.order, 6);
  EXPECT_THROW(apply_overrides(defaults, {parse_override("tool.diameter=3")}), InputError);
  EXPECT_THROW(apply_overrides(defaults, {parse_override("monitor.low_max=100")}), InputError);
}

}  // namespace
}  // namespace trochomill

namespace trochomill {
namespace {

// The user guide's key reference is the schema's own text (scripts/update-key-reference
// writes it): a key added, removed or changed in the schema and not in the guide fails here.
TEST(Job, UserGuideKeyReferenceMatchesTheSchema) {
  const std::string guide = read_file(test::source_dir() / "docs/user-guide.md");
  const std::string begin = "<!-- keys:begin -->\n", end = "<!-- keys:end -->";
  const auto a = guide.find(begin), b = guide.find(end);
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  EXPECT_EQ(guide.substr(a + begin.size(), b - a - begin.size()), job_keys_markdown())
      << "run scripts/update-key-reference";
}

// Every key the schema lists is read: a document setting one key to a wrong type names that
// key (a key in the table but not read would pass silently), and the defaults shown are the
// struct's.
TEST(Job, EverySchemaKeyIsReadAndItsDefaultIsTheStructs) {
  const std::string base = read_file(test::example("wagih2023/trochoidal.toml"));
  for (const JobKey& k : job_keys()) {
    const std::string key = k.section + "." + k.key;
    try {
      (void)parse_job(base, "job.toml", {Override{key, "{ a = 1 }", {}}});
      ADD_FAILURE() << key << ": a table value was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(k.key), std::string::npos) << key << ": " << e.what();
    }
  }
  // Defaults come from the settings structs, whatever the module.
  std::map<std::string, std::string> shown;
  for (const JobKey& k : job_keys()) shown[k.section + "." + k.key] = k.default_text;
  EXPECT_EQ(shown["machine.safe_z"], "5");
  EXPECT_EQ(shown["monitor.window"], "0.005");
  EXPECT_EQ(shown["mechanism.model"], "exact");
  EXPECT_EQ(shown["simulation.steps_per_rev"], "600");
  EXPECT_EQ(shown["tool.diameter"], "required");
}

}  // namespace
}  // namespace trochomill
