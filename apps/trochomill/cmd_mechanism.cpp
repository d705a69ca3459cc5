// mechanism and recommend: Pivkin 2025's cutting mechanism over a trochoid cycle, and the
// smallest step (or feed per tooth) that keeps a share of the cut in CZIII.
#include <fmt/format.h>

#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/report/mechanism.hpp"

namespace trochomill::cli {
namespace {

void add_mechanism_aliases(CLI::App* cmd, JobArgs& job) {
  add_key_alias(cmd, job, "--model", "mechanism.model", "chip model: exact or pivkin2025");
  add_key_alias(cmd, job, "--wear", "tool.flank_wear",
                "flank wear VB_B, mm (classify with the wear-corrected K_re)");
}

}  // namespace

void register_mechanism_commands(CLI::App& app, int& exit_code) {
  // mechanism
  {
    struct Args {
      JobArgs job;
      std::string json, csv;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "mechanism", "chip thickness, K_re and cutting-mechanism zones over a trochoid cycle");
    add_job_args(cmd, a->job);
    add_mechanism_aliases(cmd, a->job);
    cmd->add_option("--json", a->json, "write curves and zone summary as JSON (- for stdout)");
    cmd->add_option("--csv", a->csv, "write the curves as CSV (- for stdout)");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json, &a->csv}, {&a->job.file});
      const Job job = a->job.load();
      const MechanismSettings& st = job.mechanism;
      const bool use_wear = job.tool.flank_wear_mm > 0;
      const MechanismCurve c = mechanism_curve(job, st, use_wear);
      const ZoneSummary z = summarize_zones(c, st, use_wear);
      if (!a->json.empty()) emit(a->json, mechanism_json(job, st, c, z, use_wear));
      if (!a->csv.empty()) emit(a->csv, mechanism_csv(c));
      if (summary_to_stdout({&a->json, &a->csv})) {
        fmt::print("{}", mechanism_text(a->job.file, job, st, c, z, use_wear));
      }
      exit_code = 0;
    });
  }
  // recommend
  {
    struct Args {
      JobArgs job;
      std::string json;
      bool feed = false;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("recommend",
                                   "smallest trochoid step (or feed per tooth) for a CZIII share");
    add_job_args(cmd, a->job);
    add_mechanism_aliases(cmd, a->job);
    add_key_alias(cmd, a->job, "--share", "mechanism.share",
                  "required CZIII share, 0..1, of the cutting part or the cycle (--share-of)");
    add_key_alias(cmd, a->job, "--share-of", "mechanism.share_of",
                  "what the share is of: cutting (the time in the cut) or cycle (cooling "
                  "included)");
    add_key_alias(cmd, a->job, "--criterion", "mechanism.criterion",
                  "what the step must do: cziii (--share of CZIII, the default) or plunger "
                  "(at most --plunger-share of the cut's first half in CZI: Pivkin 2025)");
    add_key_alias(cmd, a->job, "--plunger-share", "mechanism.plunger_share",
                  "criterion plunger: the largest CZI share of the cut's first half, 0..1 "
                  "(default 0.2)");
    cmd->add_flag("--feed", a->feed, "recommend the feed per tooth at the job's step instead");
    cmd->add_option("--json", a->json, "write the recommendation as JSON (- for stdout)");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json}, {&a->job.file});
      const Job job = a->job.load();
      const bool use_wear = job.tool.flank_wear_mm > 0;
      const Recommendation r = recommend(job, job.mechanism, use_wear, a->feed);
      if (!a->json.empty()) emit(a->json, recommendation_json(job, job.mechanism, r, a->feed));
      if (a->json != "-") fmt::print("{}\n", r.explanation);
      exit_code = 0;
    });
  }
}

}  // namespace trochomill::cli
