// The sweep: its samplers (Sobol's sequence, Latin hypercube), its plan, and runs that write,
// stop and resume the same file whatever the thread count.
#include "trochomill/study.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>

#include "test_util.hpp"
#include "trochomill/app.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report.hpp"

namespace trochomill {
namespace {

namespace fs = std::filesystem;

// compare's, sweep's and optimize's value lists: commas inside brackets and quotes kept.
TEST(Sweep, ParseVary) {
  const Vary v = parse_vary("path.aspect_ratio=0.5, 0.6 ,0.7");
  EXPECT_EQ(v.key, "path.aspect_ratio");
  ASSERT_EQ(v.values.size(), 3u);
  EXPECT_EQ(v.values[1], "0.6");
  const Vary t = parse_vary("tool.tooth_angles=[0, 90, 180, 270],[0, 95, 180, 275]");
  ASSERT_EQ(t.values.size(), 2u);
  EXPECT_EQ(t.values[1], "[0, 95, 180, 275]");
  const Vary q = parse_vary(R"(path.type="elliptical","linear-elliptical")");
  ASSERT_EQ(q.values.size(), 2u);
  EXPECT_THROW((void)parse_vary("path.step"), InputError);
  EXPECT_THROW((void)parse_vary("step=1,2"), InputError);
  EXPECT_THROW((void)parse_vary("path.step=1,,2"), InputError);
}

// scipy.stats.qmc.Sobol(d=3, scramble=False).random(5) (Joe and Kuo's directions) without its
// first point, the origin, which Boost's generator skips: exact binary fractions.
TEST(Sweep, SobolIsJoeAndKuosSequence) {
  const auto u = unit_samples(4, 3, Sampler::sobol, 0);
  const double want[4][3] = {
      {0.5, 0.5, 0.5}, {0.75, 0.25, 0.25}, {0.25, 0.75, 0.75}, {0.375, 0.375, 0.625}};
  for (int i = 0; i < 4; ++i) {
    for (int d = 0; d < 3; ++d) EXPECT_EQ(u[i][d], want[i][d]) << i << "," << d;
  }
}

// A Latin hypercube has exactly one sample in each of the N strata of every dimension, the
// same for a seed, another for another seed.
TEST(Sweep, LatinHypercubeFillsEveryStratumOnce) {
  const std::size_t n = 37;
  const auto a = unit_samples(n, 4, Sampler::lhs, 11);
  for (std::size_t d = 0; d < 4; ++d) {
    std::set<std::size_t> strata;
    for (const auto& p : a) {
      ASSERT_GE(p[d], 0.0);
      ASSERT_LT(p[d], 1.0);
      strata.insert(static_cast<std::size_t>(p[d] * static_cast<double>(n)));
    }
    EXPECT_EQ(strata.size(), n);
  }
  EXPECT_EQ(a, unit_samples(n, 4, Sampler::lhs, 11));
  EXPECT_NE(a, unit_samples(n, 4, Sampler::lhs, 12));
}

TEST(Sweep, PlanIsTheGridTimesTheSample) {
  const SweepPlan p = plan_sweep({parse_vary("path.aspect_ratio=0.8,1.0"),
                                  parse_vary("path.direction=\"climb\",\"conventional\"")},
                                 {parse_range("path.step=0.5:1.5"), parse_range("tool.teeth=2:6")},
                                 3, Sampler::sobol, 0);
  ASSERT_EQ(p.keys, (std::vector<std::string>{"path.aspect_ratio", "path.direction", "path.step",
                                              "tool.teeth"}));
  ASSERT_EQ(p.points.size(), 12u);
  // First key slowest; the sample innermost: step = 0.5 + u (Sobol 0.5, 0.75, 0.25); teeth
  // rounded from 2 + 4 u (0.5, 0.25, 0.75 -> 4, 3, 5).
  EXPECT_EQ(p.points[0], (std::vector<std::string>{"0.8", "\"climb\"", "1", "4"}));
  EXPECT_EQ(p.points[1], (std::vector<std::string>{"0.8", "\"climb\"", "1.25", "3"}));
  EXPECT_EQ(p.points[2], (std::vector<std::string>{"0.8", "\"climb\"", "0.75", "5"}));
  EXPECT_EQ(p.points[3][1], "\"conventional\"");
  EXPECT_EQ(p.points[6][0], "1.0");
  // Bad input names the option and the key.
  EXPECT_THROW((void)plan_sweep({parse_vary("path.nope=1,2")}, {}, 0, Sampler::sobol, 0),
               InputError);
  EXPECT_THROW((void)plan_sweep({parse_vary("path.step=1,2")}, {parse_range("path.step=1:2")}, 4,
                                Sampler::sobol, 0),
               InputError);
  EXPECT_THROW((void)plan_sweep({}, {parse_range("path.type=1:2")}, 4, Sampler::sobol, 0),
               InputError);
  EXPECT_THROW((void)plan_sweep({}, {parse_range("path.step=1:2")}, 0, Sampler::sobol, 0),
               InputError);
  EXPECT_THROW((void)parse_range("path.step=2:1"), InputError);
  EXPECT_THROW((void)parse_range("path.step=1:nan"), InputError);
  EXPECT_THROW((void)parse_sampler("halton"), InputError);
  EXPECT_THROW((void)parse_sweep_eval("optimize"), InputError);
}

class SweepRun : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("trochomill-sweep-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// Each row holds what `compare` gives the same point (the same evaluation, printed in its
// shortest round-trip form: equal to the last bit); a point whose job is invalid records why and
// the sweep goes on.
TEST_F(SweepRun, RowsAreTheAnalysisOfEachPointAndFailuresAreRecorded) {
  const JobDocument doc = JobDocument::load(test::example("wagih2023/elliptical.toml"));
  const SweepPlan plan =
      plan_sweep({parse_vary("path.aspect_ratio=0.8,1.2"), parse_vary("path.step=1,-1")}, {}, 0,
                 Sampler::sobol, 0);
  const fs::path csv = dir_ / "a.csv";
  EXPECT_EQ(run_sweep(doc, {}, plan, SweepOptions{}, csv, false), 4u);
  const SweepTable t = read_sweep_csv(csv);
  ASSERT_EQ(t.rows.size(), 4u);
  const auto col = [&t](const std::string& name) {
    return static_cast<std::size_t>(std::find(t.columns.begin(), t.columns.end(), name) -
                                    t.columns.begin());
  };
  const std::vector<Vary> varies = {parse_vary("path.aspect_ratio=0.8,1.2")};
  const auto study = nlohmann::json::parse(study_json(varies, run_compare(doc, {}, varies, 1)));
  for (const std::size_t row : {0u, 2u}) {
    EXPECT_EQ(t.rows[row][col("ok")], "1");
    const auto& m = study["points"][row / 2]["metrics"];
    for (const char* k : {"h_max_mm", "cycle_mrr_mm3_per_min", "waviness_left_mm"}) {
      EXPECT_EQ(std::stod(t.rows[row][col(k)]), m[k].get<double>()) << k;
    }
  }
  for (const std::size_t row : {1u, 3u}) {
    EXPECT_EQ(t.rows[row][col("ok")], "0");
    EXPECT_NE(t.rows[row][col("error")].find("path.step"), std::string::npos)
        << t.rows[row][col("error")];
    EXPECT_EQ(t.rows[row][col("h_max_mm")], "");
  }
  // An existing file is refused without --resume.
  EXPECT_THROW((void)run_sweep(doc, {}, plan, SweepOptions{}, csv, false), InputError);
}

// compare is the sweep's engine kept in memory: a key the schema does not have, or one given
// twice, is refused before any point runs (it failed point by point); the grid's order is
// the plan's; a point that fails records why. The report's study refuses a grid whose every
// point failed, in Python as in the CLI (report_data, the layer both call).
TEST(Compare, KeysAreCheckedFirstAndEveryFailureIsRecorded) {
  const JobDocument doc = JobDocument::load(test::example("wagih2023/elliptical.toml"));
  EXPECT_THROW((void)run_compare(doc, {}, {parse_vary("path.nope=1,2")}, 1), InputError);
  EXPECT_THROW(
      (void)run_compare(doc, {}, {parse_vary("path.step=1,2"), parse_vary("path.step=3")}, 1),
      InputError);
  EXPECT_THROW((void)run_compare(doc, {}, {}, 1), InputError);
  // A key without values (Python builds its lists itself) is refused; it crashed the plan.
  EXPECT_THROW((void)run_compare(doc, {}, {Vary{"path.step", {}}}, 1), InputError);
  const std::vector<Override> base = {{"slot.length", "4", ""}};
  const std::vector<Vary> varies = {parse_vary("path.step=1,-1"),
                                    parse_vary("path.aspect_ratio=0.8,1.2")};
  const std::vector<StudyPoint> points = run_compare(doc, base, varies, 2);
  const SweepPlan plan = plan_sweep(varies, {}, 0, Sampler::sobol, 0);
  ASSERT_EQ(points.size(), plan.points.size());
  for (std::size_t p = 0; p < points.size(); ++p) {
    ASSERT_EQ(points[p].overrides.size(), 3u);
    EXPECT_EQ(points[p].overrides[0].key, "slot.length");
    EXPECT_EQ(points[p].overrides[1].value, plan.points[p][0]);
    EXPECT_EQ(points[p].overrides[2].value, plan.points[p][1]);
    EXPECT_EQ(points[p].ok, plan.points[p][0] == "1") << points[p].error;
    if (points[p].ok) {
      EXPECT_GT(points[p].metrics.h_max_mm, 0);
    } else {
      EXPECT_NE(points[p].error.find("path.step"), std::string::npos);
    }
  }
  Job job = doc.build(base);
  ReportRequest r;
  r.overrides = {{"slot.length", "4", ""}, {"path.step", "-1", ""}};
  r.varies = {parse_vary("path.aspect_ratio=0.8,1.2")};
  r.document = &doc;
  try {
    (void)report_data(job, plan_job(job).path, r);
    ADD_FAILURE() << "a study of failures was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("every point of the study failed"), std::string::npos)
        << e.what();
  }
}

// A run stopped after two rows and in the middle of the third resumes to the same file; one
// and two threads write the same bytes.
TEST_F(SweepRun, ResumeAfterAKillAndAnyThreadCountGiveTheSameFile) {
  const JobDocument doc = JobDocument::load(test::example("pivkin2025/trochoidal.toml"));
  const SweepPlan plan = plan_sweep(
      {}, {parse_range("path.step=0.05:0.2"), parse_range("cutting.feed_per_tooth=0.02:0.08")}, 6,
      Sampler::lhs, 5);
  SweepOptions o;
  o.eval = SweepEval::mechanism;
  o.threads = 1;
  const fs::path one = dir_ / "one.csv", two = dir_ / "two.csv";
  ASSERT_EQ(run_sweep(doc, {}, plan, o, one, false), 6u);
  o.threads = 2;
  ASSERT_EQ(run_sweep(doc, {}, plan, o, two, false), 6u);
  const std::string full = read_text_file(one);
  EXPECT_EQ(full, read_text_file(two));
  // The header, two rows and half of the third: what a kill during that write could leave.
  std::size_t cut = 0;
  for (int lines = 0; lines < 3; ++lines) cut = full.find('\n', cut) + 1;
  const std::size_t half = cut + (full.find('\n', cut) - cut) / 2;
  const fs::path resumed = dir_ / "resumed.csv";
  write_file_atomic(resumed, full.substr(0, half));
  EXPECT_EQ(run_sweep(doc, {}, plan, o, resumed, true), 4u);
  EXPECT_EQ(read_text_file(resumed), full);
  // Resuming a finished sweep runs nothing; another sweep's file is refused.
  EXPECT_EQ(run_sweep(doc, {}, plan, o, resumed, true), 0u);
  const SweepPlan other = plan_sweep(
      {}, {parse_range("path.step=0.05:0.3"), parse_range("cutting.feed_per_tooth=0.02:0.08")}, 6,
      Sampler::lhs, 5);
  EXPECT_THROW((void)run_sweep(doc, {}, other, o, resumed, true), InputError);
  o.eval = SweepEval::analyze;
  EXPECT_THROW((void)run_sweep(doc, {}, plan, o, resumed, true), InputError);
}

}  // namespace
}  // namespace trochomill

namespace trochomill {
namespace {

// A problem with a closed-form answer from trochomill's own metrics: a full-width straight
// slot (the linear family) cuts a chip h_max = f_z = F / (Z n) and removes faster the faster
// it feeds, so the largest removal rate with h_max <= 0.05 mm over F in [100, 2000] mm/min and
// n in [1000, 3000] rpm is at n = 3000, F = 0.05 * 4 * 3000 = 600 mm/min. The optimiser finds
// it within 0.5 %, and the analysis of the job it returns holds the constraint.
TEST(Optimize, FindsTheLargestFeedWhoseChipStaysBelowTheLimit) {
#if defined(TROCHOMILL_SANITIZED)
  // 140 s under the sanitizers (100 analyses to converge): the Release suite checks the
  // optimum; the sanitizers see optimize's code in the other Optimize.* tests.
  GTEST_SKIP() << "the optimum is checked in the Release suite";
#endif
  const JobDocument doc = JobDocument::load(test::example("wagih2023/trochoidal.toml"));
  const std::vector<Override> base = {{"path.type", "\"linear\"", ""}};
  OptimizeOptions o;
  o.max_evaluations = 100;
  const OptimizeResult r =
      optimize(doc, base,
               {parse_opt_variable("cutting.feed_rate=100:2000"),
                parse_opt_variable("cutting.spindle_speed=1000:3000")},
               {{"mrr_total_mm3_per_min", true}}, {parse_constraint("h_max_mm<=0.05")}, o);
  ASSERT_TRUE(r.best);
  const double feed = std::stod(r.best->values[0]), rpm = std::stod(r.best->values[1]);
  EXPECT_NEAR(feed, 600.0, 0.005 * 600.0);
  EXPECT_NEAR(rpm, 3000.0, 0.005 * 3000.0);
  EXPECT_LE(r.evaluations, 100u);
  // Settings as a control takes them: the feed to 0.001 mm/min, the speed to 0.1 rpm (no
  // 600.30000000000004 in best.toml).
  for (const auto& [value, places] :
       {std::pair{r.best->values[0], 3u}, std::pair{r.best->values[1], 1u}}) {
    const auto dot = value.find('.');
    EXPECT_TRUE(dot == std::string::npos || value.size() - dot - 1 <= places) << value;
  }
  std::vector<Override> best = base;
  best.push_back({"cutting.feed_rate", r.best->values[0], ""});
  best.push_back({"cutting.spindle_speed", r.best->values[1], ""});
  const Job job = doc.build(best);
  const ProcessMetrics m = analyze_with_forces(job, plan_path(job).path);
  EXPECT_LE(m.h_max_slot_mm, 0.05 * (1 + 1e-9));
  // The job written for it reads back as the same job.
  const Job again = parse_job(to_toml(job), "best.toml");
  EXPECT_EQ(again.flat_keys, job.flat_keys);
}

// A study computes only the analysis's parts its metrics need (the floor is about half of
// analyze): every metric comes out the same to the bit with its parts as with all, and a part
// left out gives no figures (not zeros).
TEST(Optimize, EveryMetricIsTheSameWithOnlyTheAnalysisPartsItNeeds) {
  const Job job = load_job(test::example("wagih2023/elliptical.toml"));
  const auto full = point_metrics(job, SweepEval::analyze, std::nullopt);
  ASSERT_TRUE(full.count("ra_floor_mm") && full.count("waviness_left_tooth_mm") &&
              full.count("cycle_force_max_predicted_n") && full.count("performance_index"));
  EXPECT_EQ(analysis_parts_for({"h_max_mm", "cycle_mrr_mm3_per_min", "cycle_time_s"}),
            AnalysisParts::cycle_only());
  EXPECT_EQ(analysis_parts_for({"ra_floor_left_mm"}), (AnalysisParts{true, true, false}));
  EXPECT_EQ(analysis_parts_for({"wall_peak_y_mm.left"}), (AnalysisParts{true, false, false}));
  EXPECT_EQ(analysis_parts_for({"performance_index"}), (AnalysisParts{true, false, true}));
  EXPECT_EQ(analysis_parts_for({"cycle_force_max_predicted_n"}),
            (AnalysisParts{false, false, true}));
  std::map<std::tuple<bool, bool, bool>, std::map<std::string, double>> by_parts;
  for (const std::string& key : metric_names(job, SweepEval::analyze)) {
    const AnalysisParts p = analysis_parts_for({key});
    auto [it, fresh] = by_parts.try_emplace({p.walls, p.floor, p.force});
    if (fresh) it->second = point_metrics(job, SweepEval::analyze, std::nullopt, {}, 0, p);
    const auto& some = it->second;
    ASSERT_EQ(some.count(key), full.count(key)) << key;
    if (full.count(key)) {
      EXPECT_EQ(some.at(key), full.at(key)) << key;  // exact: the same code on the same input
    }
  }
  const auto cycle = by_parts.at({false, false, false});
  for (const char* key : {"waviness_left_mm", "ra_left_mm", "ra_floor_mm", "performance_index",
                          "cycle_force_max_predicted_n", "cycle_h_max_tooth_mm"}) {
    EXPECT_EQ(cycle.count(key), 0u) << key;
  }
}

// A range narrower than a setting's rounding (0.0001 mm) keeps its points inside it (they
// were rounded out of it and NLopt refused its own bounds); a study whose every point fails
// says the first point's error.
TEST(Optimize, ANarrowRangeStaysInsideAndFailuresAreSaid) {
  const JobDocument doc = JobDocument::load(test::example("wagih2023/trochoidal.toml"));
  OptimizeOptions o;
  o.max_evaluations = 10;
  const OptimizeResult r = optimize(doc, {}, {parse_opt_variable("path.step=0.50001:0.50002")},
                                    {{"cycle_mrr_mm3_per_min", true}}, {}, o);
  ASSERT_TRUE(r.best);
  const double step = std::stod(r.best->values[0]);
  EXPECT_GE(step, 0.50001);
  EXPECT_LE(step, 0.50002);
  // Searched on the cycle alone, reported with every metric (the floor's too).
  EXPECT_TRUE(r.best->metrics.count("waviness_left_tooth_mm"));
  EXPECT_TRUE(r.best->metrics.count("ra_floor_mm"));
  const OptimizeResult bad = optimize(doc, {}, {parse_opt_variable("path.aspect_ratio=1.1:1.2")},
                                      {{"cycle_mrr_mm3_per_min", true}}, {}, o);
  EXPECT_FALSE(bad.best);
  EXPECT_EQ(bad.failed, bad.evaluations);
  EXPECT_NE(bad.first_error.find("elliptical family"), std::string::npos) << bad.first_error;
}

// Two goals pulling apart (removal rate up, chip down): every point of the Pareto set is
// feasible and none dominates another.
TEST(Optimize, ParetoSetIsNonDominated) {
  const JobDocument doc = JobDocument::load(test::example("wagih2023/trochoidal.toml"));
  OptimizeOptions o;
  o.max_evaluations = 48;
  o.population = 8;
  const std::vector<Objective> goals = {{"mrr_total_mm3_per_min", true}, {"h_max_mm", false}};
  const OptimizeResult r = optimize(doc, {{"path.type", "\"linear\"", ""}},
                                    {parse_opt_variable("cutting.feed_rate=100:2000")}, goals,
                                    {parse_constraint("h_max_mm<=0.2")}, o);
  ASSERT_GE(r.pareto.size(), 5u);
  for (const OptPoint& a : r.pareto) {
    EXPECT_TRUE(a.feasible);
    EXPECT_LE(a.metrics.at("h_max_mm"), 0.2 * (1 + 1e-9));
    for (const OptPoint& b : r.pareto) {
      const bool dominates =
          b.metrics.at("mrr_total_mm3_per_min") >= a.metrics.at("mrr_total_mm3_per_min") &&
          b.metrics.at("h_max_mm") <= a.metrics.at("h_max_mm") &&
          (b.metrics.at("mrr_total_mm3_per_min") > a.metrics.at("mrr_total_mm3_per_min") ||
           b.metrics.at("h_max_mm") < a.metrics.at("h_max_mm"));
      EXPECT_FALSE(dominates) << b.values[0] << " dominates " << a.values[0];
    }
  }
}

TEST(Optimize, BadVariablesMetricsAndConstraintsAreRefused) {
  EXPECT_THROW((void)parse_constraint("h_max_mm<0.05"), InputError);
  EXPECT_THROW((void)parse_constraint("h_max_mm<=abc"), InputError);
  EXPECT_THROW((void)parse_opt_variable("path.type=1:2"), InputError);
  EXPECT_THROW((void)parse_opt_variable("path.type=elliptical"), InputError);
  EXPECT_THROW((void)parse_opt_variable("path.nope=1:2"), InputError);
  const JobDocument doc = JobDocument::load(test::example("wagih2023/trochoidal.toml"));
  try {
    (void)optimize(doc, {}, {parse_opt_variable("path.step=0.5:1.5")}, {{"mrr", true}}, {},
                   OptimizeOptions{});
    FAIL() << "an unknown metric was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("maximize mrr: not a metric of eval analyze"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace trochomill
