// sweep: a grid (--vary) and/or a space-filling sample (--range, --samples) of job keys, each
// point evaluated with analyze, mechanism, forces or simulate, one CSV row per point appended
// as points finish; --resume continues a stopped run.
#include <fmt/format.h>

#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/study.hpp"

namespace trochomill::cli {

void register_study_commands(CLI::App& app, int& exit_code) {
  struct Args {
    JobArgs job;
    std::vector<std::string> vary, range;
    std::size_t samples = 0;
    std::string sampler = "sobol", eval = "analyze", output, json, cycles;
    std::uint64_t seed = 1;
    int threads = 0;
    bool resume = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "sweep", "evaluate a grid or a space-filling sample of job variants, one CSV row per point");
  add_job_args(cmd, a->job);
  cmd->add_option("--vary", a->vary,
                  "section.key=v1,v2,... (repeatable: several give a grid, the first slowest)");
  cmd->add_option("--range", a->range,
                  "section.key=lo:hi, a number key sampled over [lo, hi] (repeatable: one "
                  "dimension each; integer keys rounded)");
  cmd->add_option("--samples", a->samples, "points of the sample over the ranges")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1000000}));
  cmd->add_option("--sampler", a->sampler,
                  "sobol (Sobol's sequence, the default) or lhs (Latin hypercube, --seed)");
  cmd->add_option("--seed", a->seed, "seed of the Latin hypercube's permutations");
  cmd->add_option("--eval", a->eval,
                  "what each point runs: analyze (default), mechanism, forces (fast chips) or "
                  "simulate");
  cmd->add_option("--cycles", a->cycles,
                  "forces and simulate: the window A:B of trochoid cycles (default: the steady "
                  "cycle)");
  cmd->add_option("-o,--output", a->output, "the results, CSV (appended as points finish)")
      ->required();
  cmd->add_option("--json", a->json,
                  "also write the whole table as JSON at the end (- for stdout)");
  cmd->add_option("--threads", a->threads, "points evaluated at once (0: all cores)")
      ->check(CLI::Range(0, 4096));
  cmd->add_flag("--resume", a->resume,
                "continue the sweep in OUTPUT: its rows stay, only the points missing run");
  cmd->final_callback([a, &exit_code] {
    if (a->output == "-") throw InputError("sweep: -o needs a file (rows are appended to it)");
    check_outputs({&a->json}, {&a->job.file, &a->output});
    check_outputs({&a->output}, {&a->job.file});
    std::vector<Vary> grid;
    for (const auto& v : a->vary) grid.push_back(parse_vary(v));
    std::vector<SweepRange> ranges;
    for (const auto& r : a->range) ranges.push_back(parse_range(r));
    const SweepPlan plan = plan_sweep(grid, ranges, a->samples, parse_sampler(a->sampler), a->seed);
    SweepOptions o;
    o.eval = parse_sweep_eval(a->eval);
    o.threads = a->threads;
    if (!a->cycles.empty()) {
      if (o.eval != SweepEval::forces && o.eval != SweepEval::simulate) {
        throw InputError("sweep: --cycles is for --eval forces or simulate");
      }
      const auto colon = a->cycles.find(':');
      char* e1 = nullptr;
      char* e2 = nullptr;
      const std::string s1 = a->cycles.substr(0, colon);
      const std::string s2 = colon == std::string::npos ? "" : a->cycles.substr(colon + 1);
      const long c1 = std::strtol(s1.c_str(), &e1, 10), c2 = std::strtol(s2.c_str(), &e2, 10);
      if (colon == std::string::npos || s1.empty() || s2.empty() || *e1 || *e2 || c1 < 0 ||
          c2 <= c1 || c2 > 100000) {
        throw InputError(fmt::format("--cycles '{}': expected A:B with 0 <= A < B", a->cycles));
      }
      o.cycles = std::pair<int, int>{static_cast<int>(c1), static_cast<int>(c2)};
    }
    const JobDocument doc = JobDocument::load(a->job.file);
    const std::vector<Override> base = a->job.overrides();
    (void)doc.build(base);  // a bad base job is bad input (exit 2)
    const GuardedRun run(true);
    const std::size_t n = run_sweep(doc, base, plan, o, a->output, a->resume, run.hooks());
    run.done();
    const SweepTable t = read_sweep_csv(a->output);
    std::size_t failed = 0;
    for (const auto& row : t.rows) failed += row[1 + plan.keys.size()] == "0" ? 1 : 0;
    if (!a->json.empty()) emit(a->json, sweep_json(t));
    if (a->json != "-") {
      fmt::print("{}: {} points ({} run now, {} failed) -> {}\n", a->job.file, plan.points.size(),
                 n, failed, a->output);
    }
    run.finish("interrupted: the rows written stay; --resume continues");
    exit_code = 0;
  });
}

}  // namespace trochomill::cli
