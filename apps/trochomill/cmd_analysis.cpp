// analyze and compare: the process metrics of a slot program, and a parameter study over a
// grid of job variants.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/app.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report.hpp"
#include "trochomill/study.hpp"

namespace trochomill::cli {

void register_analysis_commands(CLI::App& app, int& exit_code) {
  // analyze
  {
    struct Args {
      JobArgs job;
      std::string gcode, json, csv;
      std::optional<double> memory_gb;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "analyze", "engagement, chip thickness, times, MRR, waviness of a slot program");
    add_job_args(cmd, a->job);
    add_stock_mesh_alias(cmd, a->job);
    add_memory_limit(cmd, a->memory_gb);
    cmd->add_option("--gcode", a->gcode, "analyse this NC program instead of the planned path");
    cmd->add_option("--json", a->json, "write the metrics as JSON (- for stdout)");
    cmd->add_option("--csv", a->csv, "write the time series as CSV (- for stdout)");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json, &a->csv}, {&a->job.file, &a->gcode});
      const Job job = a->job.load();
      GcodeProgram lines;
      // A pocket's own plan (proven as `plan` proves it) is kept for its summary below.
      std::optional<PlannedPocket> pocket;
      if (job.pocket.defined() && a->gcode.empty()) pocket = plan_pocket(job);
      const ToolPath path = pocket ? pocket->path : job_path(job, a->gcode, a->memory_gb, &lines);
      check_memory("analyze", estimate_analysis_memory(job, path), a->memory_gb,
                   fmt::format("{:.0f} s of program at {:g} rpm, {} samples per tooth pass: "
                               "lower [analysis] steps_per_tooth or analyse a shorter program",
                               path.duration_s(), job.cutting.spindle_speed_rpm,
                               job.analysis.steps_per_tooth));
      const GuardedRun run(true);
      ProcessMetrics m = analyze_with_forces(job, path, run.hooks());
      run.done();
      name_program_lines(m, lines);
      if (!a->json.empty()) emit(a->json, metrics_json(job, m));
      if (!a->csv.empty()) emit(a->csv, series_csv(m.series));
      if (summary_to_stdout({&a->json, &a->csv})) {
        fmt::print("{}", metrics_text(a->job.file, a->gcode, job, m));
        // A pocket's own plan: the target's proof from this analysis's series (the clearing
        // outside its entries, apart from the finishing pass), as `plan` prints it.
        if (pocket)
          fmt::print("{}", pocket_summary(pocket->info, prove_pocket(pocket->info, m.series)));
      }
      run.finish("interrupted: the outputs were written in full");
      exit_code = 0;
    });
  }
  // compare
  {
    struct Args {
      JobArgs job;
      std::vector<std::string> vary;
      std::string json, csv;
      int threads = 0;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("compare", "analyse a grid of job variants in parallel");
    add_job_args(cmd, a->job);
    cmd->add_option("--vary", a->vary,
                    "section.key=v1,v2,... (repeatable: several give a grid), e.g. "
                    "path.aspect_ratio=0.8,1.0,1.2")
        ->required();
    cmd->add_option("--json", a->json, "write the study as JSON (- for stdout)");
    cmd->add_option("--csv", a->csv, "write the study as CSV (- for stdout)");
    cmd->add_option("--threads", a->threads, "worker threads (0: all cores)")
        ->check(CLI::NonNegativeNumber);
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json, &a->csv}, {&a->job.file});
      const std::vector<Override> base = a->job.overrides();
      std::vector<Vary> varies;
      for (const auto& v : a->vary) varies.push_back(parse_vary_flag(v));
      const JobDocument doc = JobDocument::load(a->job.file);
      (void)doc.build(base);  // a bad base job is bad input (exit 2)
      const GuardedRun run(true);
      const auto points = run_compare(doc, base, varies, a->threads, run.hooks());
      run.done();
      if (!a->json.empty()) emit(a->json, study_json(varies, points));
      if (!a->csv.empty()) emit(a->csv, study_csv(varies, points));
      if (summary_to_stdout({&a->json, &a->csv})) fmt::print("{}", study_table(varies, points));
      run.finish("interrupted: the outputs were written in full");
      if (std::none_of(points.begin(), points.end(), [](const StudyPoint& p) { return p.ok; })) {
        throw InputError("compare: every point of the grid failed (see the table)");
      }
      print_failed_points("compare", points);
      exit_code = 0;
    });
  }
}

}  // namespace trochomill::cli
