// sweep: a grid (--vary) and/or a space-filling sample (--range, --samples) of job keys, each
// point evaluated with analyze, mechanism, forces or simulate, one CSV row per point appended
// as points finish; --resume continues a stopped run. optimize: the best variant under
// constraints (NLopt), or the Pareto set of several objectives (pagmo).
#include <fmt/format.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report.hpp"
#include "trochomill/study.hpp"

namespace trochomill::cli {
namespace {

// Why an optimisation found nothing: the points failed (the first one's error), or none held
// the constraints.
std::string no_feasible_point(const OptimizeResult& r) {
  if (r.failed == r.evaluations && r.failed > 0) {
    return fmt::format("optimize: every one of the {} points evaluated failed (the first: {})",
                       r.evaluations, r.first_error);
  }
  return fmt::format(
      "optimize: no feasible point in {} evaluations ({} failed): loosen the constraints or "
      "widen the variables",
      r.evaluations, r.failed);
}

}  // namespace
namespace {

// "A:B" trochoid cycles for forces and simulate.
std::pair<int, int> parse_cycles(const std::string& text) {
  const auto colon = text.find(':');
  char* e1 = nullptr;
  char* e2 = nullptr;
  const std::string s1 = text.substr(0, colon);
  const std::string s2 = colon == std::string::npos ? "" : text.substr(colon + 1);
  const long c1 = std::strtol(s1.c_str(), &e1, 10), c2 = std::strtol(s2.c_str(), &e2, 10);
  if (colon == std::string::npos || s1.empty() || s2.empty() || *e1 || *e2 || c1 < 0 || c2 <= c1 ||
      c2 > 100000) {
    throw InputError(fmt::format("--cycles '{}': expected A:B with 0 <= A < B", text));
  }
  return {static_cast<int>(c1), static_cast<int>(c2)};
}

}  // namespace

void register_study_commands(CLI::App& app, int& exit_code) {
  // sweep
  {
    struct Args {
      JobArgs job;
      std::vector<std::string> vary, range;
      std::size_t samples = 0;
      std::string sampler = "sobol", eval = "analyze", output, json, cycles;
      std::uint64_t seed = 1;
      int threads = 0;
      bool resume = false;
      std::optional<double> memory_gb;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "sweep",
        "evaluate a grid or a space-filling sample of job variants, one CSV row per point");
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
    add_memory_limit(cmd, a->memory_gb);
    cmd->final_callback([a, &exit_code] {
      if (a->output == "-") throw InputError("sweep: -o needs a file (rows are appended to it)");
      check_outputs({&a->json}, {&a->job.file, &a->output});
      check_outputs({&a->output}, {&a->job.file});
      std::vector<Vary> grid;
      for (const auto& v : a->vary) grid.push_back(parse_vary_flag(v));
      std::vector<SweepRange> ranges;
      for (const auto& r : a->range) ranges.push_back(parse_range(r));
      const SweepPlan plan =
          plan_sweep(grid, ranges, a->samples, parse_sampler(a->sampler), a->seed);
      SweepOptions o;
      o.eval = parse_sweep_eval(a->eval);
      o.threads = a->threads;
      o.memory_limit_bytes = memory_limit_bytes(a->memory_gb);
      if (!a->cycles.empty()) {
        if (o.eval != SweepEval::forces && o.eval != SweepEval::simulate) {
          throw InputError("sweep: --cycles is for --eval forces or simulate");
        }
        o.cycles = parse_cycles(a->cycles);
      }
      const JobDocument doc = JobDocument::load(a->job.file);
      const std::vector<Override> base = a->job.overrides();
      (void)doc.build(base);  // a bad base job is bad input (exit 2)
      // Under mpirun the ranks share the points; rank 0 writes (a plain run is one rank).
      const Distributed world;
      const GuardedRun run(world.rank() == 0);
      const std::size_t n =
          run_sweep(doc, base, plan, o, a->output, a->resume, run.hooks(), &world);
      run.done();
      if (world.rank() != 0) {
        run.finish("interrupted");
        exit_code = 0;
        return;
      }
      const SweepTable t = read_sweep_csv(a->output);
      std::size_t failed = 0;
      std::string first_error;
      for (const auto& row : t.rows) {
        if (row[1 + plan.keys.size()] != "0") continue;
        if (failed++ == 0) first_error = row[2 + plan.keys.size()];
      }
      if (!a->json.empty()) emit(a->json, sweep_json(t));
      if (a->json != "-") {
        fmt::print("{}: {} points ({} run now, {} failed) -> {}\n", a->job.file, plan.points.size(),
                   n, failed, a->output);
      }
      run.finish("interrupted: the rows written stay; --resume continues");
      // Some points failed: said on stderr (exit 0); every point: a failed study (exit 2).
      if (failed > 0 && failed == t.rows.size()) {
        throw InputError(fmt::format("sweep: every point failed ({} of {}; the first: {})", failed,
                                     t.rows.size(), first_error));
      }
      if (failed > 0) {
        fmt::print(stderr, "sweep: {} of {} points failed (rows with ok = 0; the first: {})\n",
                   failed, t.rows.size(), first_error);
      }
      exit_code = 0;
    });
  }
  // optimize
  {
    struct Args {
      JobArgs job;
      std::vector<std::string> vars, maximize, minimize, subject_to;
      std::string eval = "analyze", cycles, output, pareto, json, html;
      int max_evals = 300, population = 24;
      std::uint64_t seed = 1;
      std::optional<double> memory_gb;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "optimize", "the best job variant under constraints, or the Pareto set of several goals");
    add_job_args(cmd, a->job);
    cmd->add_option("--var", a->vars,
                    "a variable: section.key=lo:hi (a number key) or section.key=a,b,... (a "
                    "choice, e.g. path.type=elliptical,linear-elliptical); repeatable")
        ->required();
    cmd->add_option("--maximize", a->maximize, "a metric to maximise (repeatable: a Pareto set)");
    cmd->add_option("--minimize", a->minimize, "a metric to minimise (repeatable: a Pareto set)");
    cmd->add_option("--subject-to", a->subject_to,
                    "a constraint METRIC<=VALUE or METRIC>=VALUE (repeatable), e.g. "
                    "h_max_mm<=0.05");
    cmd->add_option("--eval", a->eval, "analyze (default), mechanism, forces or simulate");
    add_memory_limit(cmd, a->memory_gb);
    cmd->add_option("--cycles", a->cycles, "forces and simulate: the window A:B of cycles");
    cmd->add_option("--max-evals", a->max_evals,
                    "evaluations per combination of choices (one goal) or in all (several)")
        ->check(CLI::Range(10, 1000000));
    cmd->add_option("--population", a->population, "NSGA-II's population (several goals)")
        ->check(CLI::Range(8, 100000));
    cmd->add_option("--seed", a->seed, "seed of the evolution (ISRES, NSGA-II)");
    cmd->add_option("-o,--output", a->output,
                    "one goal: the best job as TOML, ready for plan, - for stdout (required then)");
    cmd->add_option("--pareto", a->pareto,
                    "several goals: the Pareto set as CSV, - for stdout (required then)");
    cmd->add_option("--json", a->json, "the result as JSON (- for stdout)");
    cmd->add_option("--html", a->html,
                    "the HTML report of the best job (one goal) or of the job with the Pareto "
                    "set (several)");
    cmd->final_callback([a, cmd, &exit_code] {
      check_outputs({&a->output, &a->pareto, &a->json, &a->html}, {&a->job.file});
      std::vector<OptVariable> vars;
      for (const auto& v : a->vars) vars.push_back(parse_opt_variable(v));
      std::vector<Objective> goals;
      for (const auto& m : a->maximize) goals.push_back({m, true});
      for (const auto& m : a->minimize) goals.push_back({m, false});
      std::vector<Constraint> cons;
      for (const auto& c : a->subject_to) cons.push_back(parse_constraint(c));
      // Options of the other kind of run are refused, not ignored.
      for (const char* opt : {"--pareto", "--population"}) {
        if (goals.size() == 1 && cmd->count(opt) > 0) {
          throw InputError(fmt::format(
              "optimize: {} is for several goals (NSGA-II's Pareto set); one goal gives the best "
              "job (-o)",
              opt));
        }
      }
      if (goals.size() > 1 && cmd->count("--output") > 0) {
        throw InputError(
            "optimize: -o is for one goal (the best job); several goals give a Pareto set "
            "(--pareto)");
      }
      if (goals.size() == 1 && a->output.empty()) {
        throw InputError("optimize: -o FILE.toml is required (the best job is written there)");
      }
      if (goals.size() > 1 && a->pareto.empty()) {
        throw InputError(
            "optimize: several goals give a Pareto set: --pareto FILE.csv is required");
      }
      OptimizeOptions o;
      o.eval = parse_sweep_eval(a->eval);
      o.memory_limit_bytes = memory_limit_bytes(a->memory_gb);
      o.max_evaluations = a->max_evals;
      o.population = a->population;
      o.seed = a->seed;
      if (!a->cycles.empty()) {
        if (o.eval != SweepEval::forces && o.eval != SweepEval::simulate) {
          throw InputError("optimize: --cycles is for --eval forces or simulate");
        }
        o.cycles = parse_cycles(a->cycles);
      }
      const JobDocument doc = JobDocument::load(a->job.file);
      const std::vector<Override> base = a->job.overrides();
      (void)doc.build(base);
      // NLopt's methods are sequential: under mpirun rank 0 optimises, the others end at once.
      const Distributed world;
      if (world.rank() != 0) {
        exit_code = 0;
        return;
      }
      const GuardedRun run(true);
      const OptimizeResult r = optimize(doc, base, vars, goals, cons, o, run.hooks());
      run.done();
      const auto point_json = [&](const OptPoint& p) {
        nlohmann::json j = {{"metrics", p.metrics}};
        for (std::size_t k = 0; k < r.keys.size(); ++k) j["values"][r.keys[k]] = p.values[k];
        for (std::size_t c = 0; c < cons.size(); ++c) {
          const double v = p.metrics.at(cons[c].metric);
          j["margins"][a->subject_to[c]] = cons[c].upper ? cons[c].value - v : v - cons[c].value;
        }
        return j;
      };
      nlohmann::json out = {
          {"method", r.method}, {"evaluations", r.evaluations}, {"variables", r.keys}};
      std::vector<Override> best_overrides = base;
      if (goals.size() == 1) {
        if (!r.best) throw InputError(no_feasible_point(r));
        for (std::size_t k = 0; k < r.keys.size(); ++k) {
          best_overrides.push_back({r.keys[k], r.best->values[k], "--var"});
        }
        out["best"] = point_json(*r.best);
        const Job best = doc.build(best_overrides);
        emit(a->output, fmt::format("# The best variant of {} found by trochomill optimize ({} "
                                    "evaluations, {}).\n",
                                    a->job.file, r.evaluations, r.method) +
                            to_toml(best));
      } else {
        if (r.pareto.empty()) throw InputError(no_feasible_point(r));
        std::string csv;
        for (const auto& k : r.keys) csv += k + ",";
        for (std::size_t g = 0; g < goals.size(); ++g)
          csv += goals[g].metric + (g + 1 < goals.size() ? "," : "\n");
        out["pareto"] = nlohmann::json::array();
        for (const OptPoint& p : r.pareto) {
          for (const auto& v : p.values)
            csv += v.find(',') == std::string::npos ? v + "," : "\"" + v + "\",";
          for (std::size_t g = 0; g < goals.size(); ++g) {
            csv += fmt::format("{}{}", p.metrics.at(goals[g].metric),
                               g + 1 < goals.size() ? "," : "\n");
          }
          out["pareto"].push_back(point_json(p));
        }
        emit(a->pareto, csv);
      }
      if (!a->html.empty()) {
        // The best job's report, or the base job's with the Pareto set.
        Job job = doc.build(best_overrides);
        attach_rest_stock(job);
        ReportRequest rq;
        rq.job_file = a->job.file;
        rq.job_text = to_toml(job);
        rq.overrides = best_overrides;
        rq.command = "trochomill optimize " + a->job.file;
        ReportData d = build_report(job, plan_job(job).path, rq, run.hooks());
        if (goals.size() > 1) {
          ReportPareto p;
          p.keys = r.keys;
          for (const Objective& g : goals) {
            p.goals.push_back(g.metric);
            p.maximize.push_back(g.maximize);
          }
          for (const OptPoint& pt : r.pareto) {
            p.values.push_back(pt.values);
            std::vector<double> gv;
            for (const Objective& g : goals) gv.push_back(pt.metrics.at(g.metric));
            p.goal_values.push_back(std::move(gv));
          }
          d.pareto = std::move(p);
        }
        emit(a->html, report_html(d, run.hooks()));
      }
      if (!a->json.empty()) emit(a->json, out.dump(2) + "\n");
      // The summary line: on stdout, or on stderr when an output is standard output.
      const bool to_stdout =
          a->json == "-" || a->output == "-" || a->pareto == "-" || a->html == "-";
      {
        std::FILE* const sink = to_stdout ? stderr : stdout;
        if (r.best) {
          std::string line;
          for (std::size_t k = 0; k < r.keys.size(); ++k) {
            line += fmt::format("{}{} = {}", k ? ", " : "", r.keys[k], r.best->values[k]);
          }
          fmt::print(sink, "{}: best of {} evaluations: {}; {} = {:.6g} -> {}\n", a->job.file,
                     r.evaluations, line, goals[0].metric, r.best->metrics.at(goals[0].metric),
                     a->output);
        } else {
          fmt::print(sink, "{}: {} Pareto point{} of {} evaluations -> {}\n", a->job.file,
                     r.pareto.size(), r.pareto.size() == 1 ? "" : "s", r.evaluations, a->pareto);
        }
      }
      run.finish("interrupted");
      exit_code = 0;
    });
  }
}

}  // namespace trochomill::cli
