// optimize-feed: chip-load feed scheduling of any NC program the reader accepts, the program
// rewritten with nothing changed but its feeds (feed.hpp).
#include <fmt/format.h>

#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/feed.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report.hpp"

namespace trochomill::cli {

void register_feed_commands(CLI::App& app, int& exit_code) {
  struct Args {
    std::string program, out, json, html;
    std::vector<std::string> includes;
    std::optional<double> force_n, power_w, torque_nm, memory_gb;
    std::string engine = "kernel", stock;
    std::optional<int> rounds;
    JobArgs job;
    FeedTargetArgs targets;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "optimize-feed",
      "rewrite the feeds of an NC program so every piece cuts the target chip (within the "
      "removal cap and the machine's feed limits), nothing else changed");
  cmd->add_option("PROGRAM", a->program, "NC program (G-code) to optimise")->required();
  cmd->add_option("--job", a->job.file,
                  "job file (TOML): tool, stock (the slot), cutting conditions, [machine] limits")
      ->required();
  cmd->add_option("--set", a->job.sets,
                  "override a job key: section.key=value (repeatable), e.g. machine.max_feed=3000")
      ->take_all();
  cmd->add_option("-o,--output", a->out, "the rewritten program (- for stdout)")->required();
  cmd->add_option("--json", a->json, "write the summary as JSON (- for stdout)");
  cmd->add_option("--html", a->html,
                  "the HTML report of the rewritten program, with feed, chip and force along "
                  "the program before and after");
  cmd->add_option("-I,--include", a->includes,
                  "folder searched for o<name> call's name.ngc (repeatable; the program's own "
                  "folder is searched first)")
      ->check(CLI::ExistingDirectory);
  add_feed_target_args(cmd, a->targets);
  cmd->add_option("--force", a->force_n,
                  "cap on the resultant cutting force, N (the job's [material] model)")
      ->check(finite_above(0, 1e7));
  cmd->add_option("--power", a->power_w, "cap on the spindle power, W ([material] model)")
      ->check(finite_above(0, 1e8));
  cmd->add_option("--torque", a->torque_nm, "cap on the spindle torque, N m ([material] model)")
      ->check(finite_above(0, 1e6));
  cmd->add_option("--engine", a->engine,
                  "where the chips come from: kernel (the exact engagement, 2.5D programs: "
                  "constant-Z levels with plunges, ramps and helices between them) or sim (the "
                  "tri-dexel simulation at [simulation] resolution and steps_per_rev: any "
                  "3D motion)")
      ->check(CLI::IsMember({"kernel", "sim"}));
  cmd->add_option("--stock", a->stock,
                  "the stock as a closed mesh (STL, PLY or OBJ; mm, the program's frame) "
                  "instead of the job's [stock] box")
      ->check(CLI::ExistingFile);
  cmd->add_option("--rounds", a->rounds,
                  "rounds of evaluation and rescaling (default 12; each evaluates the whole "
                  "program: with --engine sim a whole simulation)")
      ->check(CLI::Range(1, 100));
  add_memory_limit(cmd, a->memory_gb);
  cmd->final_callback([a, &exit_code] {
    check_outputs({&a->out, &a->json, &a->html}, {&a->program, &a->job.file, &a->stock});
    if (!a->json.empty() && a->json == a->out) {
      throw InputError("--json and --output are the same file: give each its own");
    }
    const Job job = a->job.load();
    FeedOptimizeOptions opt;
    opt.targets = a->targets.resolve(job);
    opt.force_n = a->force_n;
    opt.power_w = a->power_w;
    opt.torque_nm = a->torque_nm;
    opt.read = gcode_options(job.machine).read;
    opt.engine = a->engine == "sim" ? FeedEngine::sim : FeedEngine::kernel;
    if (!a->stock.empty()) opt.stock_mesh = std::make_shared<const Mesh>(read_mesh(a->stock));
    if (a->rounds) opt.targets.iterations = *a->rounds;
    opt.memory_limit_bytes = memory_limit_bytes(a->memory_gb);
    opt.read.max_path_bytes = kPathShareOfMemory * opt.memory_limit_bytes;
    for (const auto& d : a->includes) opt.read.include_dirs.emplace_back(d);
    const std::string text = read_text_file(a->program);
    const GuardedRun run(true);
    FeedOptimizeResult r = optimize_feed(job, text, a->program, opt, run.hooks());
    std::string page;
    if (!a->html.empty()) {
      // The rewritten program's report (in the slot frame of the job's placement), with the
      // before/after part.
      GcodeReadOptions ro = opt.read;
      ro.cancel = [hooks = run.hooks()] { return hooks.cancelled(); };
      const ToolPath path = to_slot_frame(read_gcode(r.text, a->out, ro).path, slot_placement(job));
      ReportRequest rq;
      rq.job_file = a->job.file;
      rq.gcode_file = a->out;
      rq.job_text = read_text_file(a->job.file);
      rq.overrides = a->job.overrides();
      rq.command = "trochomill optimize-feed " + a->program;
      ReportData d = build_report(job, path, rq, run.hooks());
      d.feed = r;
      page = report_html(d, run.hooks());
    }
    run.done();
    run.finish("interrupted: nothing was written");
    for (const std::string& w : r.warnings) fmt::print(stderr, "warning: {}\n", w);
    emit(a->out, r.text);
    if (!a->json.empty()) emit(a->json, feed_summary_json(r));
    if (!a->html.empty()) emit(a->html, page);
    const std::string summary = feed_summary_text(r);
    fmt::print(summary_to_stdout({&a->out, &a->json}) ? stdout : stderr, "{}", summary);
    exit_code = 0;
  });
}

}  // namespace trochomill::cli
