// Formatting of paths and NC programs: sampled trajectories and `check-gcode`'s report
// (report.hpp).
#include <fmt/format.h>

#include <iterator>
#include <nlohmann/json.hpp>

#include "trochomill/report/path.hpp"

namespace trochomill {

void write_path_samples_csv(const PathSamples& s, const ToothTracks& tr,
                            const std::function<void(std::string_view)>& sink,
                            const RunHooks& hooks) {
  std::string out = "t_s,s_mm,x_mm,y_mm,z_mm,tx,ty,tz,curvature_per_mm,segment";
  for (int k = 0; k < tr.teeth; ++k)
    out += fmt::format(",tooth{0}_x_mm,tooth{0}_y_mm,tooth{0}_z_mm", k);
  out += '\n';
  hooks.begin("writing CSV");
  for (std::size_t i = 0; i < s.size(); ++i) {
    hooks.step(i, s.size());
    fmt::format_to(std::back_inserter(out),
                   "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{}", s.t_s[i],
                   s.s_mm[i], s.x_mm[i], s.y_mm[i], s.z_mm[i], s.tx[i], s.ty[i], s.tz[i],
                   s.curvature_per_mm[i], s.segment[i]);
    for (int k = 0; k < tr.teeth; ++k) {
      fmt::format_to(std::back_inserter(out), ",{:.9g},{:.9g},{:.9g}", tr.x_mm[k][i], tr.y_mm[k][i],
                     tr.z_mm[k][i]);
    }
    out += '\n';
    if (out.size() >= (1u << 20)) {
      sink(out);
      out.clear();
    }
  }
  sink(out);
}

std::string path_samples_csv(const PathSamples& s, const ToothTracks& tr) {
  std::string all;
  write_path_samples_csv(s, tr, [&](std::string_view piece) { all += piece; });
  return all;
}

std::string gcode_check_json(const std::string& file, const GcodeProgram& prog,
                             double time_with_acceleration_s) {
  const PathSummary sum = prog.path.empty() ? prog.summary : summarize(prog.path);
  const Box3& b = sum.box;
  // The axes besides X Y Z the program moves: each one's range (A B C degrees, U V W mm).
  nlohmann::json extra = nlohmann::json::object();
  for (const char c : prog.info.extra_axes) {
    const auto k = static_cast<std::size_t>(std::string_view("ABCUVW").find(c));
    const std::string unit = k < 3 ? "deg" : "mm";
    extra[std::string(1, c)] = {{"min_" + unit, prog.info.extra_min[k]},
                                {"max_" + unit, prog.info.extra_max[k]}};
  }
  nlohmann::json j = {
      {"file", file},
      {"lines", prog.info.lines},
      {"motion_blocks", prog.info.motion_blocks},
      {"blocks_executed", prog.info.blocks_executed},
      {"warnings", prog.info.warnings},
      {"segments", sum.segments},
      {"path_length_mm", sum.length_mm},
      {"feed_length_mm", sum.feed_length_mm},
      {"time_s", sum.duration_s},
      {"time_with_acceleration_s", time_with_acceleration_s},
      {"bbox_min_mm", {b.lo.x(), b.lo.y(), b.lo.z()}},
      {"bbox_max_mm", {b.hi.x(), b.hi.y(), b.hi.z()}},
      {"feed_min_mm_per_min", prog.info.min_feed_mm_per_min},
      {"feed_max_mm_per_min", prog.info.max_feed_mm_per_min},
      {"spindle_max_rpm", prog.info.max_spindle_rpm},
  };
  if (!prog.info.extra_axes.empty()) {
    j["extra_axes"] = extra;
    j["extra_axes_only_time_s"] = prog.info.extra_only_time_s;
  }
  return j.dump(2) + "\n";
}

std::string gcode_check_text(const std::string& file, const GcodeProgram& prog,
                             double time_with_acceleration_s, double max_acceleration_mm_per_s2) {
  const PathSummary sum = prog.path.empty() ? prog.summary : summarize(prog.path);
  const Box3& b = sum.box;
  std::string out = fmt::format("{}: {} lines, {} blocks run, {} segments\n", file, prog.info.lines,
                                prog.info.blocks_executed, sum.segments);
  out += fmt::format("  path length   {:.4f} mm ({:.4f} mm at feed)\n", sum.length_mm,
                     sum.feed_length_mm);
  out += fmt::format("  time          {:.4f} s at programmed feed", sum.duration_s);
  if (max_acceleration_mm_per_s2 > 0) {
    out += fmt::format(", {:.4f} s with {:g} mm/s^2", time_with_acceleration_s,
                       max_acceleration_mm_per_s2);
  }
  if (sum.segments == 0) {
    out += "\n  bounding box  none (no motion)\n";
  } else {
    out += fmt::format(
        "\n  bounding box  x [{:.4f}, {:.4f}]  y [{:.4f}, {:.4f}]  z [{:.4f}, {:.4f}] mm\n",
        b.lo.x(), b.hi.x(), b.lo.y(), b.hi.y(), b.lo.z(), b.hi.z());
  }
  out += fmt::format("  feed          {:g} to {:g} mm/min, spindle up to {:g} rpm\n",
                     prog.info.min_feed_mm_per_min, prog.info.max_feed_mm_per_min,
                     prog.info.max_spindle_rpm);
  if (!prog.info.extra_axes.empty()) {
    out += "  other axes   ";
    for (const char c : prog.info.extra_axes) {
      const auto k = static_cast<std::size_t>(std::string_view("ABCUVW").find(c));
      out += fmt::format(" {} [{:.4f}, {:.4f}] {}", c, prog.info.extra_min[k],
                         prog.info.extra_max[k], k < 3 ? "deg" : "mm");
    }
    out += fmt::format("; {:.4f} s of feed moves of these alone (not in the time above)\n",
                       prog.info.extra_only_time_s);
  }
  return out;
}

std::string pocket_json(const PocketInfo& info, const PocketProof& proof, const ToolPath& program,
                        const Machine& machine, std::size_t program_lines) {
  const auto at = [](const Vec3& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); };
  const auto name_or_null = [](const std::string& name) {
    return name.empty() ? nlohmann::json(nullptr) : nlohmann::json(name);
  };
  const auto leftovers = [](const std::vector<PocketLeftover>& list) {
    nlohmann::json out = nlohmann::json::array();
    for (const PocketLeftover& l : list) {
      out.push_back({{"area_mm2", l.area_mm2}, {"at_mm", {l.at_mm.x(), l.at_mm.y()}}});
    }
    return out;
  };
  const nlohmann::json j = {
      {"parts", info.parts},
      {"levels", info.levels},
      {"plans", info.plans},
      {"passes_by_level", info.passes_by_level},
      {"clearing_length_by_level_mm", info.clearing_length_by_level_mm},
      {"rest_cleared_by_level_mm2", info.rest_cleared_by_level_mm2},
      {"passes_per_level", info.passes},
      {"channels_per_level", info.channels},
      {"channel_width_mm", info.channel_width_mm},
      {"channels_left_mm2", info.channels_left_mm2},
      {"channel_family", name_or_null(info.channel_family)},
      {"channel_family_length_mm", info.channel_family_mm},
      {"channel_loops_length_mm", info.channel_loops_mm + info.channel_unheld_mm},
      {"channel_unheld_length_mm", info.channel_unheld_mm},
      {"channel_family_dropped", name_or_null(info.channel_family_dropped)},
      {"links_down_per_level", info.links_down},
      {"lifts_per_level", info.lifts},
      {"clearing_length_per_level_mm", info.clearing_length_mm},
      {"air_length_per_level_mm", info.air_length_mm},
      {"entries_per_level",
       {{"helix", info.helix_entries}, {"hole", info.hole_entries}, {"open", info.open_entries}}},
      {"open_mm2", info.open_mm2},
      {"open_mm2_by_level", info.open_mm2_by_level},
      {"rest_tool_diameter_mm", info.rest_tool_diameter_mm},
      {"rest_cleared_mm2", info.rest_cleared_mm2},
      {"target_engagement_deg", info.target_engagement_deg},
      {"planned_max_engagement_deg", info.planned_max_engagement_deg},
      {"aim_margin_deg", info.aim_margin_deg},
      {"replans", info.replans},
      {"first_proof_max_engagement_deg", info.first_proof_max_deg},
      {"proven", info.proven},
      {"clearing_max_engagement_deg", proof.clearing_max_engagement_deg},
      {"clearing_max_at_mm", at(proof.clearing_max_at_mm)},
      {"clearing_max_chip_mm", proof.clearing_max_chip_mm},
      {"clearing_share_above_target", proof.clearing_share_above_target},
      {"link_feed_max_engagement_deg", proof.air_max_engagement_deg},
      {"link_feed_max_chip_mm", proof.air_max_chip_mm},
      {"link_feed_removed_mm3", proof.air_removed_mm3},
      {"finish_max_engagement_deg", proof.finish_max_engagement_deg},
      {"finish_max_at_mm", at(proof.finish_max_at_mm)},
      {"finish_max_chip_mm", proof.finish_max_chip_mm},
      {"unreachable", leftovers(info.unreachable)},
      {"slotted_by_finish", leftovers(info.slotted)},
      {"cusps_mm2", info.cusps_mm2},
      {"left_for_finish_mm2", info.left_for_finish_mm2},
      {"path_length_mm", program.length_mm()},
      {"machining_time_s", program.duration_s()},
      {"machining_time_accel_s", estimate_time_s(program, machine)},
      {"program_lines", program_lines},
  };
  return j.dump(2) + "\n";
}

std::string pocket_summary(const PocketInfo& info, const PocketProof& proof) {
  std::string out;
  if (info.plans > 1 && info.passes_by_level.size() == static_cast<std::size_t>(info.levels)) {
    // The levels' plans differ (rest_of, a [stock] mesh): each level's passes, the rest the
    // deepest's.
    std::string passes, clearing;
    for (std::size_t k = 0; k < info.passes_by_level.size(); ++k) {
      passes += fmt::format("{}{}", k > 0 ? ", " : "", info.passes_by_level[k]);
      clearing += fmt::format("{}{:.1f}", k > 0 ? ", " : "", info.clearing_length_by_level_mm[k]);
    }
    out = fmt::format(
        "pocket: {} part{}, {} levels, by level from the top {} clearing passes and {} mm of "
        "clearing; the deepest level {} links staying down, {} lifts, {:.1f} mm through cleared "
        "area at the link feed\n",
        info.parts, info.parts == 1 ? "" : "s", info.levels, passes, clearing, info.links_down,
        info.lifts, info.air_length_mm);
  } else {
    out = fmt::format(
        "pocket: {} part{}, {} level{}, {} clearing passes a level ({} links staying down, {} "
        "lifts), {:.1f} mm of clearing and {:.1f} mm through cleared area at the link feed a "
        "level\n",
        info.parts, info.parts == 1 ? "" : "s", info.levels, info.levels == 1 ? "" : "s",
        info.passes, info.links_down, info.lifts, info.clearing_length_mm, info.air_length_mm);
  }
  if (info.channels > 0 && info.channel_family.empty()) {
    out += fmt::format(
        "  {} channel{} (narrower than {:g} mm) cleared by trochoidal loops along the medial axis "
        "a level\n",
        info.channels, info.channels == 1 ? "" : "s", info.channel_width_mm);
  } else if (info.channels > 0) {
    out += fmt::format(
        "  {} channel{} (narrower than {:g} mm) cleared along the medial axis a level: {:.1f} mm "
        "of it by {} cycles, {:.1f} mm by circular loops at the channels' ends{}\n",
        info.channels, info.channels == 1 ? "" : "s", info.channel_width_mm, info.channel_family_mm,
        info.channel_family, info.channel_loops_mm,
        info.channel_unheld_mm > 0
            ? fmt::format(", {:.1f} mm by circular loops where no {} cycle held the target",
                          info.channel_unheld_mm, info.channel_family)
            : "");
  }
  if (!info.channel_family_dropped.empty()) {
    out += fmt::format(
        "  warning: no plan with {} cycles in the channels held the target by the kernel ({:.4g} "
        "degrees at best): the channels are cleared by circular loops instead\n",
        info.channel_family_dropped, info.channel_family_dropped_deg);
  }
  if (info.channels_left_mm2 > 0) {
    out += fmt::format(
        "  warning: {:.4g} mm^2 of channels no trochoid could enter from cleared area is left to "
        "the finishing pass\n",
        info.channels_left_mm2);
  }
  if (info.rest_tool_diameter_mm > 0) {
    std::string by_level;
    for (std::size_t k = 0; k < info.rest_cleared_by_level_mm2.size(); ++k) {
      by_level += fmt::format("{}{:.1f}", k > 0 ? ", " : "", info.rest_cleared_by_level_mm2[k]);
    }
    out += info.rest_cleared_by_level_mm2.size() > 1
               ? fmt::format(
                     "  rest machining after a {:g} mm tool: at the levels from the top {} mm^2 "
                     "of this tool's area it had cleared; the passes cut what it left\n",
                     info.rest_tool_diameter_mm, by_level)
               : fmt::format(
                     "  rest machining after a {:g} mm tool: {:.1f} mm^2 of this tool's area it "
                     "had cleared; the passes cut what it left\n",
                     info.rest_tool_diameter_mm, info.rest_cleared_mm2);
  }
  if (info.hole_entries > 0 || info.open_mm2 > 0) {
    out += fmt::format(
        "  entries a level: {} by helix, {} straight down a pre-drilled hole, {} from above "
        "where nothing stands{}\n",
        info.helix_entries, info.hole_entries, info.open_entries,
        info.open_mm2 > 0 ? fmt::format(" (beside the stock: {:.1f} mm^2 of its area at the "
                                        "deepest level is air)",
                                        info.open_mm2)
                          : "");
  }
  if (!info.open_mm2_by_level.empty()) {
    std::string areas;
    for (const double a : info.open_mm2_by_level) {
      areas += fmt::format("{}{:.1f}", areas.empty() ? "" : ", ", a);
    }
    out += fmt::format(
        "  the [stock] mesh: air at the levels from the top {} mm^2 of the area the clearing "
        "covers (entered from above where the tool's disc is clear); {} plan{} for {} level{}\n",
        areas, info.plans, info.plans == 1 ? "" : "s", info.levels, info.levels == 1 ? "" : "s");
  }
  out += fmt::format(
      "  engagement target {:.4g} degrees; the planner's largest at its points {:.4g} degrees\n",
      info.target_engagement_deg, info.planned_max_engagement_deg);
  const auto at = [](const Vec3& p) {
    return fmt::format("({:.3f}, {:.3f}, {:.3f})", p.x(), p.y(), p.z());
  };
  if (info.finish_first_segment == 0) {
    out += "  no clearing: every part is too narrow for it (the finishing pass cuts them)\n";
  } else {
    out += fmt::format(
        "  the kernel on the program: clearing (entries excepted) engagement max {:.4g} degrees "
        "at {}, chip max {:.5f} mm, {:.3g} % of its cutting above the target\n",
        proof.clearing_max_engagement_deg, at(proof.clearing_max_at_mm), proof.clearing_max_chip_mm,
        100 * proof.clearing_share_above_target);
  }
  if (info.replans > 0 && info.proven) {
    out += fmt::format(
        "  the kernel found {:.4g} degrees at {} on the first plan, above the target + {:g} %: "
        "planned {} more time{}, the last with the steps' aim {:.4g} degrees below the target\n",
        info.first_proof_max_deg, at(info.first_proof_at_mm), 100 * kProofTolerance, info.replans,
        info.replans == 1 ? "" : "s", info.aim_margin_deg);
  } else if (!info.proven) {
    // Above f_z = 0.02 R the planner's discs a tooth apart, not the margin, are what fails
    // (docs/models.md, "Pockets": where no replan holds).
    const std::string why =
        info.tooth_advance_share > kPocketToothShare
            ? fmt::format(
                  "; the feed per tooth is {:.2g} of the tool's radius, above the {:g} up to "
                  "which the planner's model of the teeth held a 53 degree target on the test "
                  "pockets: a lower feed rate ({:.2g} times the [cutting] one there) may hold "
                  "it where a lower target does not",
                  info.tooth_advance_share, kPocketToothShare,
                  kPocketToothShare / info.tooth_advance_share)
            : std::string();
    out += fmt::format(
        "  warning: the kernel finds the clearing's engagement above the target + {:g} % on "
        "every plan tried (the first and {} more, the steps' aim 0.5 degrees lower each time): "
        "{:.4g} degrees at {} in this one, the least; a target {:.2g} degrees lower may hold "
        "(the proof then holds the program to that target){} (plan --strict writes no such "
        "program)\n",
        100 * kProofTolerance, info.replans, proof.clearing_max_engagement_deg,
        at(proof.clearing_max_at_mm),
        proof.clearing_max_engagement_deg - info.target_engagement_deg, why);
  }
  if ((info.air_length_mm > 0 || info.links_down > 0) && !(proof.air_max_engagement_deg > 0)) {
    out +=
        "  the kernel on the program: moves at the link feed (through cleared area) touch no "
        "stock\n";
  } else if (info.air_length_mm > 0 || info.links_down > 0) {
    out += fmt::format(
        "  the kernel on the program: moves at the link feed (through cleared area) remove "
        "{:.3g} mm^3 in all: chip max {:.5f} mm, engagement max {:.4g} degrees at {} (the feed "
        "marks such moves leave, a tooth's advance at that feed apart, and the tips of cusps "
        "narrower than a graze)\n",
        proof.air_removed_mm3, proof.air_max_chip_mm, proof.air_max_engagement_deg,
        at(proof.air_max_at_mm));
  }
  if (proof.finish_max_engagement_deg > 0) {
    out += fmt::format(
        "  the kernel on the program: finishing pass engagement max {:.4g} degrees at {}, chip "
        "max {:.5f} mm (where it meets what the clearing left: inside corners, parts narrower "
        "than the tool)\n",
        proof.finish_max_engagement_deg, at(proof.finish_max_at_mm), proof.finish_max_chip_mm);
  }
  for (const PocketLeftover& l : info.slotted) {
    out += fmt::format(
        "  warning: about {:.4g} mm^2 near ({:.3f}, {:.3f}) is barely wider than the tool with the "
        "stock to leave (by less than R / 10): no loop holds the target there; the finishing pass "
        "cuts it as a slot, level by level (from the cleared area, else ramped down along its "
        "contour)\n",
        l.area_mm2, l.at_mm.x(), l.at_mm.y());
  }
  for (const PocketLeftover& l : info.unreachable) {
    out += fmt::format(
        "  warning: {:.4g} mm^2 about ({:.3f}, {:.3f}) is narrower than the tool with the stock "
        "to leave: no path reaches it\n",
        l.area_mm2, l.at_mm.x(), l.at_mm.y());
  }
  if (info.cusps_mm2 > 0) {
    out += fmt::format("  inside corners' cusps (radius R + stock): {:.4g} mm^2 in all\n",
                       info.cusps_mm2);
  }
  if (info.left_for_finish_mm2 > 0) {
    out += fmt::format(
        "  {:.4g} mm^2 within reach is left to the finishing pass (where the clearing could not "
        "go on within the target: inside corners, the ends of narrow parts)\n",
        info.left_for_finish_mm2);
  }
  return out;
}

}  // namespace trochomill
