// JSON, CSV and table output of the analysis, and the parameter study (see report.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string_view>

#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/report/analysis.hpp"
#include "trochomill/report/job.hpp"
#include "trochomill/report/texture.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// The scalar metrics every output shares: JSON key (with unit), getter, and whether it
// describes the steady cycle (null, NaN in tables, for a program without one).
struct Scalar {
  const char* key;
  std::function<double(const ProcessMetrics&)> get;
  bool cycle = false;
};

// The texture keys of the walls (left and right) and of the floor's middle, and how to read
// one from a ProfileTexture.
struct TextureKey {
  const char* left;
  const char* right;
  const char* floor;
  double (*get)(const ProfileTexture&);
};
const TextureKey kTextureKeys[] = {
    {"ra_left_mm", "ra_right_mm", "ra_floor_mm",
     [](const ProfileTexture& t) { return t.roughness.ra_mm; }},
    {"rz_left_mm", "rz_right_mm", "rz_floor_mm",
     [](const ProfileTexture& t) { return t.roughness.rz_mm; }},
    {"wa_left_mm", "wa_right_mm", "wa_floor_mm", [](const ProfileTexture& t) { return t.wa_mm; }},
    {"wt_left_mm", "wt_right_mm", "wt_floor_mm", [](const ProfileTexture& t) { return t.wt_mm; }},
    {"lambda_c_left_mm", "lambda_c_right_mm", "lambda_c_floor_mm",
     [](const ProfileTexture& t) { return t.cutoff_mm; }},
};

const std::vector<Scalar>& scalars() {
  static const std::vector<Scalar> s = [] {
    // The whole program's figures first, then the steady cycle's (cycle_*), then the walls
    // (the steady state's, so null without a cycle too).
    std::vector<Scalar> v = {
        {"path_length_mm", [](const ProcessMetrics& m) { return m.path_length_mm; }},
        {"feed_length_mm", [](const ProcessMetrics& m) { return m.feed_length_mm; }},
        {"machining_time_s", [](const ProcessMetrics& m) { return m.machining_time_s; }},
        {"machining_time_with_acceleration_s",
         [](const ProcessMetrics& m) { return m.machining_time_accel_s; }},
        {"cutting_time_total_s", [](const ProcessMetrics& m) { return m.cutting_time_total_s; }},
        {"slot_volume_mm3", [](const ProcessMetrics& m) { return m.slot_volume_mm3; }},
        {"removed_volume_mm3", [](const ProcessMetrics& m) { return m.removed_volume_mm3; }},
        {"mrr_total_mm3_per_min", [](const ProcessMetrics& m) { return m.mrr_total_mm3_per_min; }},
        {"feed_per_tooth_mm", [](const ProcessMetrics& m) { return m.feed_per_tooth_mm; }},
        {"h_max_mm", [](const ProcessMetrics& m) { return m.h_max_slot_mm; }},
        {"t_h_max_s", [](const ProcessMetrics& m) { return m.t_h_max_slot_s; }},
        {"engagement_angle_max_deg",
         [](const ProcessMetrics& m) { return m.engagement_angle_max_slot_deg; }},
        {"cycle_start_s", [](const ProcessMetrics& m) { return m.cycle_start_s; }, true},
        {"cycle_time_s", [](const ProcessMetrics& m) { return m.cycle_time_s; }, true},
        {"cycle_path_length_mm", [](const ProcessMetrics& m) { return m.path_length_per_cycle_mm; },
         true},
        {"cycle_cutting_time_s", [](const ProcessMetrics& m) { return m.cutting_time_s; }, true},
        {"cycle_cooling_time_s", [](const ProcessMetrics& m) { return m.cooling_time_s; }, true},
        {"cycle_mrr_mm3_per_min", [](const ProcessMetrics& m) { return m.mrr_mm3_per_min; }, true},
        {"cycle_mrr_swept_mm3_per_min",
         [](const ProcessMetrics& m) { return m.mrr_swept_mm3_per_min; }, true},
        {"cycle_h_max_mm", [](const ProcessMetrics& m) { return m.h_max_mm; }, true},
        {"cycle_t_h_max_s", [](const ProcessMetrics& m) { return m.t_h_max_s; }, true},
        {"cycle_h_max_tooth_mm", [](const ProcessMetrics& m) { return m.h_max_tooth_mm; }, true},
        {"cycle_chip_translation_error_mm",
         [](const ProcessMetrics& m) { return m.chip_translation_error_mm; }, true},
        {"cycle_engagement_angle_max_deg",
         [](const ProcessMetrics& m) { return m.engagement_angle_max_deg; }, true},
        {"cycle_axial_depth_mm", [](const ProcessMetrics& m) { return m.axial_depth_mm; }, true},
        {"cycle_force_max_predicted_n",
         [](const ProcessMetrics& m) { return m.force_max_predicted_n.value_or(std::nan("")); },
         true},
        {"waviness_left_mm", [](const ProcessMetrics& m) { return m.walls_path.left.waviness_mm; },
         true},
        {"waviness_right_mm",
         [](const ProcessMetrics& m) { return m.walls_path.right.waviness_mm; }, true},
        {"waviness_left_tooth_mm",
         [](const ProcessMetrics& m) { return m.walls_tooth.left.waviness_mm; }, true},
        {"waviness_right_tooth_mm",
         [](const ProcessMetrics& m) { return m.walls_tooth.right.waviness_mm; }, true},
        {"performance_index",
         [](const ProcessMetrics& m) { return m.performance_index.value_or(std::nan("")); }, true},
    };
    // NaN (JSON null) without a tooth-level wall.
    for (const TextureKey& k : kTextureKeys) {
      v.push_back({k.left,
                   [get = k.get](const ProcessMetrics& m) {
                     return m.texture_left ? get(*m.texture_left) : std::nan("");
                   },
                   true});
      v.push_back({k.right,
                   [get = k.get](const ProcessMetrics& m) {
                     return m.texture_right ? get(*m.texture_right) : std::nan("");
                   },
                   true});
    }
    // The floor's texture (whole program): the middle's, and Ra beside each wall. NaN where
    // too little of the line was cut.
    auto floor = [](std::size_t k, double (*get)(const ProfileTexture&)) {
      return [k, get](const ProcessMetrics& m) {
        return m.texture_floor[k] ? get(*m.texture_floor[k]) : std::nan("");
      };
    };
    for (const TextureKey& k : kTextureKeys) v.push_back({k.floor, floor(1, k.get)});
    v.push_back({"ra_floor_left_mm", floor(0, kTextureKeys[0].get)});
    v.push_back({"ra_floor_right_mm", floor(2, kTextureKeys[0].get)});
    return v;
  }();
  return s;
}

// The columns of a study's table (a subset, in reading order).
const std::vector<const char*>& table_columns() {
  static const std::vector<const char*> c = {"cycle_time_s",
                                             "cycle_cooling_time_s",
                                             "cycle_mrr_mm3_per_min",
                                             "mrr_total_mm3_per_min",
                                             "cycle_h_max_mm",
                                             "cycle_t_h_max_s",
                                             "cycle_engagement_angle_max_deg",
                                             "waviness_left_mm",
                                             "waviness_right_mm",
                                             "waviness_left_tooth_mm",
                                             "waviness_right_tooth_mm",
                                             "machining_time_s"};
  return c;
}

double scalar(const ProcessMetrics& m, const std::string& key) {
  for (const auto& s : scalars()) {
    if (key == s.key) return s.cycle && !m.periodic ? std::nan("") : s.get(m);
  }
  throw Error("unknown metric " + key);
}

// The part of the analysis one top-level key of metrics_json needs (nested keys by their
// first part).
AnalysisParts part_of(std::string_view key) {
  key = key.substr(0, key.find('.'));
  AnalysisParts p = AnalysisParts::cycle_only();
  const auto is = [&](std::string_view k) { return key == k; };
  if (is("cycle_force_max_predicted_n")) {
    p.force = true;
  } else if (is("performance_index")) {  // F_R,max, the walls' Ra and waviness
    p.walls = p.force = true;
  } else if (key.find("floor") != std::string_view::npos) {
    p.walls = p.floor = true;
  } else if (key.rfind("waviness_", 0) == 0 || is("wall_peak_y_mm") || is("cycle_h_max_tooth_mm") ||
             is("cycle_h_max_per_tooth_mm") || is("cycle_chip_translation_error_mm") ||
             is("bottom_imprint")) {
    p.walls = true;
  } else {
    for (const TextureKey& k : kTextureKeys) p.walls = p.walls || is(k.left) || is(k.right);
  }
  return p;
}

nlohmann::json metrics_object(const ProcessMetrics& m) {
  // A figure that is not there (no cycle, no tooth-level wall, no force model) is null.
  nlohmann::json j = nlohmann::json::object();
  for (const auto& s : scalars()) {
    const double v = s.cycle && !m.periodic ? std::nan("") : s.get(m);
    j[s.key] = std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v);
  }
  j["periodic"] = m.periodic;
  j["cycle_h_max_per_tooth_mm"] =
      m.periodic ? nlohmann::json(m.h_max_per_tooth_mm) : nlohmann::json(nullptr);
  j["bottom_imprint"] = {{"x_mm", m.imprint.x_mm},
                         {"crossings_per_mm", m.imprint.crossings_per_mm}};
  j["wall_peak_y_mm"] = m.periodic ? nlohmann::json{{"left", m.walls_path.left.peak_y_mm},
                                                    {"right", m.walls_path.right.peak_y_mm}}
                                   : nlohmann::json(nullptr);
  j["performance_index_note"] =
      m.periodic || !m.performance_index_note.empty()
          ? m.performance_index_note
          : std::string(
                "no steady cycle (the program is not periodic): Wagih's index "
                "compares one cycle's removal rate");
  j["samples"] = m.series.samples.size();
  // The figures of a part not computed are not there.
  if (!m.parts.all()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (!m.parts.has(part_of(it.key()))) *it = nullptr;
    }
  }
  return j;
}

}  // namespace

AnalysisParts analysis_parts_for(const std::vector<std::string>& metric_keys) {
  AnalysisParts p = AnalysisParts::cycle_only();
  for (const std::string& k : metric_keys) p |= part_of(k);
  return p;
}

std::string metrics_json(const Job& job, const ProcessMetrics& m) {
  nlohmann::json j = metrics_object(m);
  j["job"] = {{"source", job.source},
              {"path_type", to_string(job.path.type)},
              {"step_mm", job.path.step_mm},
              {"tool_diameter_mm", job.tool.diameter_mm},
              {"teeth", job.tool.teeth},
              {"slot_width_mm", job.slot.width_mm},
              {"slot_length_mm", job.slot.length_mm},
              {"slot_depth_mm", job.slot.depth_mm},
              {"feed_rate_mm_per_min", feed_rate_mm_per_min(job)},
              {"spindle_speed_rpm", spindle_speed_rpm(job)}};
  if (job.slot.curved()) j["job"]["slot_along"] = job.slot.along;
  if (job.pocket.defined()) {
    // A pocket has no slot and no step: its layer, depth and the channels' family instead (a
    // pocket job's [path] type is its channels', not the program's).
    nlohmann::json& jj = j["job"];
    for (const char* k : {"step_mm", "slot_width_mm", "slot_length_mm", "slot_depth_mm"}) {
      jj.erase(k);
    }
    jj["path_type"] = "pocket";
    jj["pocket_boundary"] = job.pocket.boundary;
    jj["pocket_depth_mm"] = job.pocket.depth_mm;
    // (null: the circular loops, as `plan --json` has it)
    jj["channel_family"] = job.pocket.channel_family
                               ? nlohmann::json(std::string(to_string(*job.pocket.channel_family)))
                               : nlohmann::json(nullptr);
  }
  // Where the largest chip is (the tool centre, mm), and the largest after the entry.
  const auto point = [](const Vec3& p) { return nlohmann::json::array({p.x(), p.y(), p.z()}); };
  j["h_max_at_mm"] = point(m.h_max_slot_at_mm);
  j["h_max_after_entry_mm"] = m.h_max_after_entry_mm;
  j["h_max_after_entry_at_mm"] = point(m.h_max_after_entry_at_mm);
  j["engagement_max_at_mm"] = point(m.engagement_max_slot_at_mm);
  j["engagement_max_after_entry_deg"] = m.engagement_max_after_entry_deg;
  j["engagement_max_after_entry_at_mm"] = point(m.engagement_max_after_entry_at_mm);
  j["h_axial_max_mm"] = m.h_axial_max_mm;
  j["h_axial_max_at_mm"] = point(m.h_axial_max_at_mm);
  j["descents_into_stock"] = m.descents_into_stock;
  // And, for a program read from a file, the blocks that made those moves ("file:line").
  const auto source = [](const std::string& s) {
    return s.empty() ? nlohmann::json(nullptr) : nlohmann::json(s);
  };
  j["h_max_at_line"] = source(m.h_max_slot_source);
  j["h_max_after_entry_at_line"] = source(m.h_max_after_entry_source);
  j["engagement_max_at_line"] = source(m.engagement_max_slot_source);
  j["engagement_max_after_entry_at_line"] = source(m.engagement_max_after_entry_source);
  j["h_axial_max_at_line"] = source(m.h_axial_max_source);
  return j.dump(2) + "\n";
}

std::string figure_text(double v, int digits) {
  if (!std::isfinite(v)) return "-";
  if (v == 0) return "0";
  const int d = std::clamp(digits, 1, 17);
  // The magnitude's exact decimal digits (40 after the first: a tie at `d` digits has a short
  // exact expansion, so a "5" followed by zeros here is one), rounded half up in magnitude as
  // ECMAScript's toPrecision and toExponential round (printf rounds a tie to even).
  const std::string e = fmt::format("{:.40e}", std::abs(v));
  const std::string mantissa = e.substr(0, 1) + e.substr(2, 40);
  int exponent = std::atoi(e.c_str() + e.find('e') + 1);
  std::string kept = mantissa.substr(0, static_cast<std::size_t>(d));
  if (mantissa[static_cast<std::size_t>(d)] >= '5') {
    int i = d - 1;
    while (i >= 0 && kept[static_cast<std::size_t>(i)] == '9')
      kept[static_cast<std::size_t>(i--)] = '0';
    if (i < 0) {
      kept.insert(kept.begin(), '1');
      kept.pop_back();
      ++exponent;
    } else {
      ++kept[static_cast<std::size_t>(i)];
    }
  }
  const std::string sign = v < 0 ? "-" : "";
  const std::string point = kept.size() > 1 ? "." + kept.substr(1) : "";
  const double a = std::abs(v);
  if (a >= 1e6 || a < 1e-4) {  // the page's exponent form, "1.235e+6"
    return fmt::format("{}{}{}e{}{}", sign, kept.substr(0, 1), point, exponent < 0 ? '-' : '+',
                       std::abs(exponent));
  }
  // The shortest text of the rounded value (as the page's String(Number(...))).
  const double r =
      std::strtod(fmt::format("{}{}e{}", kept.substr(0, 1), point, exponent).c_str(), nullptr);
  return sign + fmt::format("{}", r);
}

std::string metrics_text(const std::string& job_file, const std::string& gcode, const Job& job,
                         const ProcessMetrics& m) {
  const auto f = [](double v) { return figure_text(v); };
  const std::string what = job.pocket.defined()
                               ? fmt::format("pocket of layer '{}'", job.pocket.boundary)
                           : job.slot.width_mm > 0 ? std::string(to_string(job.path.type))
                                                   : std::string("program");
  std::string out =
      fmt::format("{}: {}{}\n", job_file, what, gcode.empty() ? "" : " (from " + gcode + ")");
  out += fmt::format("  machining time       {} s ({} s with acceleration), path {} mm\n",
                     f(m.machining_time_s), f(m.machining_time_accel_s), f(m.path_length_mm));
  // The whole program, then the steady cycle where there is one.
  out += fmt::format("  MRR                  {} mm^3/min over the program ({} mm^3 removed)\n",
                     f(m.mrr_total_mm3_per_min), f(m.removed_volume_mm3));
  out += fmt::format("  h_max                {} mm at {} s (f_z {} mm)\n", f(m.h_max_slot_mm),
                     f(m.t_h_max_slot_s), f(m.feed_per_tooth_mm));
  out += fmt::format("  engagement max       {} deg\n", f(m.engagement_angle_max_slot_deg));
  // Where a figure is: a place on the part, to the thousandth of a mm (a position, not a
  // figure: 4 significant digits would round 123.456 mm to 0.04 mm).
  const auto xyz = [](const Vec3& p) {
    return fmt::format("({:.3f}, {:.3f}, {:.3f})", p.x(), p.y(), p.z());
  };
  // The end edges' chip: the descent per tooth where the end face cuts (docs/models.md
  // section 7).
  if (m.descents_into_stock > 0) {
    out += fmt::format(
        "  axial chip max       {} mm at {}{} ({} descent{} into stock)\n", f(m.h_axial_max_mm),
        m.h_axial_max_source.empty() ? "" : m.h_axial_max_source + " ", xyz(m.h_axial_max_at_mm),
        m.descents_into_stock, m.descents_into_stock == 1 ? "" : "s");
  } else {
    out += "  axial chip max       0 mm (no descent into stock)\n";
  }
  if (!m.h_max_slot_source.empty() && m.engagement_angle_max_slot_deg > 0) {
    // A program read from a file: the blocks of the largest chip and engagement (none where
    // the flutes never cut: a drilling program).
    out += fmt::format("  h_max at             {} {}; after the entry {} mm at {} {}\n",
                       m.h_max_slot_source, xyz(m.h_max_slot_at_mm), f(m.h_max_after_entry_mm),
                       m.h_max_after_entry_source, xyz(m.h_max_after_entry_at_mm));
    out += fmt::format("  engagement max at    {} {}; after the entry {} deg at {} {}\n",
                       m.engagement_max_slot_source, xyz(m.engagement_max_slot_at_mm),
                       f(m.engagement_max_after_entry_deg), m.engagement_max_after_entry_source,
                       xyz(m.engagement_max_after_entry_at_mm));
  }
  if (job.slot.curved()) {
    out += fmt::format(
        "  {:<21}h_max {} mm at ({:.3f}, {:.3f}); after the entry {} mm at ({:.3f}, {:.3f})\n",
        fmt::format("along '{}'", job.slot.along), f(m.h_max_slot_mm), m.h_max_slot_at_mm.x(),
        m.h_max_slot_at_mm.y(), f(m.h_max_after_entry_mm), m.h_max_after_entry_at_mm.x(),
        m.h_max_after_entry_at_mm.y());
    out +=
        "  steady cycle         none (a slot along a curve: each cycle's step follows the "
        "bend): whole-program figures only\n";
    return out;
  }
  const auto um = [&](double mm) { return f(1000 * mm); };
  if (m.texture_floor[1]) {
    const auto ra = [&](std::size_t k) {
      return m.texture_floor[k] ? um(m.texture_floor[k]->roughness.ra_mm) : std::string("-");
    };
    out += fmt::format(
        "  floor texture        Ra {} um, Rz {} um, Wt {} um in the middle (lambda_c {} mm); Ra "
        "{} / {} um beside the left / right wall (end edges' dish {} deg)\n",
        ra(1), um(m.texture_floor[1]->roughness.rz_mm), um(m.texture_floor[1]->wt_mm),
        f(m.texture_floor[1]->cutoff_mm), ra(0), ra(2), f(job.tool.dish_angle_deg));
  }
  if (!m.periodic) {
    out += m.performance_index_note.empty()
               ? std::string(
                     "  steady cycle         none (the path does not repeat with the "
                     "step): whole-program figures only\n")
               : "  steady cycle         none: " + m.performance_index_note + "\n";
    return out;
  }
  out += fmt::format("  steady cycle         {} s, {} mm; cutting {} s, cooling {} s\n",
                     f(m.cycle_time_s), f(m.path_length_per_cycle_mm), f(m.cutting_time_s),
                     f(m.cooling_time_s));
  out += fmt::format("    MRR                {} mm^3/min\n", f(m.mrr_mm3_per_min));
  out += fmt::format("    h_max              {} mm at {} s after cutting starts\n", f(m.h_max_mm),
                     f(m.t_h_max_s));
  out += fmt::format("    engagement max     {} deg\n", f(m.engagement_angle_max_deg));
  out += fmt::format(
      "  wall waviness        left {} mm, right {} mm (path); left {} mm, right {} mm (tooth)\n",
      f(m.walls_path.left.waviness_mm), f(m.walls_path.right.waviness_mm),
      f(m.walls_tooth.left.waviness_mm), f(m.walls_tooth.right.waviness_mm));
  if (m.texture_left && m.texture_right) {
    out += fmt::format(
        "  wall texture         Ra {} / {} um, Rz {} / {} um, Wt {} / {} um (left / right, "
        "lambda_c {} / {} mm)\n",
        um(m.texture_left->roughness.ra_mm), um(m.texture_right->roughness.ra_mm),
        um(m.texture_left->roughness.rz_mm), um(m.texture_right->roughness.rz_mm),
        um(m.texture_left->wt_mm), um(m.texture_right->wt_mm), f(m.texture_left->cutoff_mm),
        f(m.texture_right->cutoff_mm));
  }
  if (m.force_max_predicted_n) {
    out += fmt::format("  F_R,max predicted    {} N over the cycle ([material] {}{})\n",
                       f(*m.force_max_predicted_n), to_string(*job.material.model),
                       job.material.name.empty() ? "" : ", " + job.material.name);
  }
  if (m.performance_index)
    out += fmt::format("  performance index    {}\n", f(*m.performance_index));
  return out;
}

std::string series_csv(const EngagementSeries& e) {
  const PathSamples& s = e.samples;
  std::string out =
      "t_s,x_mm,y_mm,z_mm,engaged_arcs_deg,engagement_deg,h_max_mm,teeth_in_cut,"
      "mrr_mm3_per_min,axial_chip_mm\n";
  out.reserve(s.size() * 96);
  for (std::size_t i = 0; i < s.size(); ++i) {
    std::string arcs;
    for (const auto& a : e.arcs[i]) {
      if (!arcs.empty()) arcs += ';';
      fmt::format_to(std::back_inserter(arcs), "{:.4f}:{:.4f}", rad_to_deg(a.start_rad),
                     rad_to_deg(a.end_rad));
    }
    fmt::format_to(
        std::back_inserter(out), "{:.6f},{:.6f},{:.6f},{:.6f},{},{:.4f},{:.7f},{},{:.3f},{:.7f}\n",
        s.t_s[i], s.x_mm[i], s.y_mm[i], s.z_mm[i], arcs, rad_to_deg(e.engagement_angle_rad[i]),
        e.h_max_mm[i], e.teeth_in_cut[i], e.removal_rate_mm3_per_s[i] * 60.0, e.axial_chip_mm[i]);
  }
  return out;
}

std::string study_table(const std::vector<Vary>& varies, const std::vector<StudyPoint>& points) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> head;
  for (const auto& v : varies) head.push_back(v.key);
  std::vector<const char*> columns = table_columns();
  // Predicted force and performance index when a force model ran (analyze and compare fill
  // them from [material]).
  for (const auto& p : points) {
    if (p.ok && p.metrics.force_max_predicted_n) {
      columns.push_back("cycle_force_max_predicted_n");
      columns.push_back("performance_index");
      break;
    }
  }
  for (const char* c : columns) head.push_back(c);
  rows.push_back(head);
  for (const auto& p : points) {
    std::vector<std::string> r;
    for (std::size_t k = 0; k < varies.size(); ++k) {
      r.push_back(p.overrides[p.overrides.size() - varies.size() + k].value);
    }
    for (const char* c : columns) {
      const double v = p.ok ? scalar(p.metrics, c) : std::nan("");
      r.push_back(std::isfinite(v) ? fmt::format("{:.5g}", v) : "-");
    }
    rows.push_back(r);
  }
  std::vector<std::size_t> width(head.size(), 0);
  for (const auto& r : rows) {
    for (std::size_t k = 0; k < r.size(); ++k) width[k] = std::max(width[k], r[k].size());
  }
  std::string out;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t k = 0; k < rows[i].size(); ++k) {
      out += k == 0 ? fmt::format("{:<{}}", rows[i][k], width[k])
                    : fmt::format("  {:>{}}", rows[i][k], width[k]);
    }
    out += '\n';
  }
  for (const auto& p : points) {
    if (!p.ok) {
      std::string at;
      for (const auto& o : p.overrides) at += " " + o.key + "=" + o.value;
      out += fmt::format("failed at{}: {}\n", at, p.error);
    }
  }
  return out;
}

std::string study_json(const std::vector<Vary>& varies, const std::vector<StudyPoint>& points) {
  nlohmann::json j;
  j["vary"] = nlohmann::json::array();
  for (const auto& v : varies) j["vary"].push_back({{"key", v.key}, {"values", v.values}});
  j["points"] = nlohmann::json::array();
  for (const auto& p : points) {
    nlohmann::json o;
    nlohmann::json set = nlohmann::json::object();
    for (std::size_t k = 0; k < varies.size(); ++k) {
      set[varies[k].key] = p.overrides[p.overrides.size() - varies.size() + k].value;
    }
    o["set"] = set;
    o["ok"] = p.ok;
    if (p.ok) {
      o["metrics"] = metrics_object(p.metrics);
    } else {
      o["error"] = p.error;
    }
    j["points"].push_back(o);
  }
  return j.dump(2) + "\n";
}

std::string study_csv(const std::vector<Vary>& varies, const std::vector<StudyPoint>& points) {
  std::string out;
  for (const auto& v : varies) out += v.key + ",";
  out += "ok";
  for (const auto& s : scalars()) out += std::string(",") + s.key;
  out += '\n';
  for (const auto& p : points) {
    for (std::size_t k = 0; k < varies.size(); ++k) {
      const std::string& val = p.overrides[p.overrides.size() - varies.size() + k].value;
      out += (val.find(',') != std::string::npos ? "\"" + val + "\"" : val) + ",";
    }
    out += p.ok ? "1" : "0";
    for (const auto& s : scalars()) {
      const double v = p.ok ? s.get(p.metrics) : std::nan("");
      out += std::isfinite(v) ? fmt::format(",{:.9g}", v) : ",";
    }
    out += '\n';
  }
  return out;
}

std::string job_keys_text() {
  std::size_t w = 0;
  for (const JobKey& k : job_keys()) w = std::max(w, k.section.size() + 1 + k.key.size());
  std::string out;
  for (const JobKey& k : job_keys()) {
    out += fmt::format("{:<{}}  {}{}, {}; default {}\n    {}\n", k.section + "." + k.key, w, k.type,
                       k.unit.empty() ? "" : " (" + k.unit + ")", k.allowed, k.default_text, k.doc);
  }
  return out;
}

std::string job_keys_json() {
  nlohmann::json j = nlohmann::json::array();
  for (const JobKey& k : job_keys()) {
    j.push_back({{"section", k.section},
                 {"key", k.key},
                 {"type", k.type},
                 {"unit", k.unit},
                 {"allowed", k.allowed},
                 {"default", k.default_text},
                 {"doc", k.doc}});
  }
  return j.dump(2) + "\n";
}

namespace {

nlohmann::json areal_json(const ArealParameters& p, bool lengths) {
  nlohmann::json j = {{"sa_mm", p.sa_mm},       {"sq_mm", p.sq_mm},
                      {"ssk", p.ssk},           {"sku", p.sku},
                      {"sp_mm", p.sp_mm},       {"sv_mm", p.sv_mm},
                      {"sz_mm", p.sz_mm},       {"sdr_percent", p.sdr_percent},
                      {"area_mm2", p.area_mm2}, {"flat", p.flat}};
  if (lengths) {
    j["sal_mm"] = p.sal_mm ? nlohmann::json(*p.sal_mm) : nlohmann::json(nullptr);
    j["str"] = p.str ? nlohmann::json(*p.str) : nlohmann::json(nullptr);
  }
  return j;
}

}  // namespace

std::string texture_json(const std::string& source, const std::vector<TextureEntry>& entries) {
  nlohmann::json surfaces = nlohmann::json::array();
  bool profiles = false, areal = false;
  for (const TextureEntry& e : entries) {
    if (e.areal) {
      areal = true;
      const ArealTexture& t = *e.areal;
      surfaces.push_back(
          {{"surface", e.surface},
           {"kind", "areal"},
           {"description", e.description},
           {"s_filter_mm", t.s_mm > 0 ? nlohmann::json(t.s_mm) : nlohmann::json(nullptr)},
           {"l_filter_mm", t.l_mm},
           {"l_filter_source", t.l_source},
           {"form", form_removal_name(t.form)},
           {"form_degree", t.degree},
           {"sl", areal_json(t.sl, true)},
           {"sf", areal_json(t.sf, false)}});
      if (e.comparison) {
        const SurfaceComparison& c = *e.comparison;
        surfaces.back()["comparison"] = {{"against", e.against},
                                         {"shift_x_mm", c.shift_x_mm},
                                         {"shift_y_mm", c.shift_y_mm},
                                         {"offset_mm", c.offset_mm},
                                         {"tilt_x", c.tilt_x},
                                         {"tilt_y", c.tilt_y},
                                         {"correlation", c.correlation},
                                         {"overlap_mm2", c.overlap_mm2},
                                         {"points", c.points},
                                         {"rms_difference_mm", c.rms_difference_mm},
                                         {"max_difference_mm", c.max_difference_mm},
                                         {"measured", areal_json(c.measured, false)},
                                         {"predicted", areal_json(c.predicted, false)}};
      }
      continue;
    }
    profiles = true;
    const ProfileParameters& r = e.texture.roughness;
    surfaces.push_back(
        {{"surface", e.surface},
         {"kind", "profile"},
         {"description", e.description},
         {"lambda_c_mm", e.texture.cutoff_mm},
         {"lambda_c_source", e.texture.cutoff_source},
         {"lambda_s_mm", e.texture.lambda_s_mm > 0 ? nlohmann::json(e.texture.lambda_s_mm)
                                                   : nlohmann::json(nullptr)},
         {"mean_line", e.texture.robust ? "robust Gaussian regression (ISO 16610-31)"
                                        : "Gaussian (ISO 16610-21)"},
         {"ra_mm", r.ra_mm},
         {"rq_mm", r.rq_mm},
         {"rsk", r.rsk},
         {"rku", r.rku},
         {"rp_mm", r.rp_mm},
         {"rv_mm", r.rv_mm},
         {"rz_mm", r.rz_mm},
         {"rt_mm", r.rt_mm},
         {"rsm_mm", r.rsm_mm},
         {"profile_elements", r.elements},
         {"wa_mm", e.texture.wa_mm},
         {"wt_mm", e.texture.wt_mm},
         {"evaluation_length_mm", r.evaluation_length_mm},
         {"sections", r.sections}});
  }
  std::string standards;
  if (profiles) standards = "ISO 16610-21 Gaussian filter, ISO 21920-2 parameters";
  if (areal) {
    standards += std::string(profiles ? "; " : "") +
                 "ISO 16610-61 areal Gaussian filter, ISO 25178-2 parameters";
  }
  const nlohmann::json j = {{"source", source}, {"standards", standards}, {"surfaces", surfaces}};
  return j.dump(2) + "\n";
}

std::string texture_text(const std::string& source, const std::vector<TextureEntry>& entries) {
  std::string out = fmt::format("{}:\n", source);
  for (const TextureEntry& e : entries) {
    if (e.areal) {
      const ArealTexture& t = *e.areal;
      const ArealParameters& p = t.sl;
      out += fmt::format(
          "  {}: {}\n    S-filter {}, F-operator {}{}, L-filter {:g} mm ({}), {:.4g} mm^2\n"
          "    Sa {:.4f} um  Sq {:.4f} um  Sz {:.4f} um  Sp {:.4f} um  Sv {:.4f} um\n"
          "    Ssk {:.3f}  Sku {:.3f}  Sdr {:.4f} %  Sal {}  Str {}\n"
          "    S-F surface: Sa {:.4f} um  Sq {:.4f} um  Sz {:.4f} um\n",
          e.surface, e.description, t.s_mm > 0 ? fmt::format("{:g} mm", t.s_mm) : "none",
          form_removal_name(t.form),
          t.form == FormRemoval::polynomial ? fmt::format(" (degree {})", t.degree) : "", t.l_mm,
          t.l_source, p.area_mm2, 1000 * p.sa_mm, 1000 * p.sq_mm, 1000 * p.sz_mm, 1000 * p.sp_mm,
          1000 * p.sv_mm, p.ssk, p.sku, p.sdr_percent,
          p.sal_mm
              ? fmt::format("{:.4f} mm", *p.sal_mm)
              : std::string(p.flat ? "- (flat to rounding)" : "- (no decay to 0.2 within the map)"),
          p.str ? fmt::format("{:.3f}", *p.str) : std::string(p.flat ? "-" : "- (directional)"),
          1000 * t.sf.sa_mm, 1000 * t.sf.sq_mm, 1000 * t.sf.sz_mm);
      if (e.comparison) {
        const SurfaceComparison& c = *e.comparison;
        out += fmt::format(
            "    against {}: shift ({:.4f}, {:.4f}) mm, offset {:.4f} um, tilt ({:.3g}, {:.3g}), "
            "correlation {:.4f}\n"
            "      over {:.4g} mm^2 ({} points): difference rms {:.4f} um, max {:.4f} um; Sa "
            "{:.4f} um measured, {:.4f} um predicted\n",
            e.against, c.shift_x_mm, c.shift_y_mm, 1000 * c.offset_mm, c.tilt_x, c.tilt_y,
            c.correlation, c.overlap_mm2, c.points, 1000 * c.rms_difference_mm,
            1000 * c.max_difference_mm, 1000 * c.measured.sa_mm, 1000 * c.predicted.sa_mm);
      }
      continue;
    }
    const ProfileParameters& r = e.texture.roughness;
    out += fmt::format(
        "  {}: {}\n    lambda_c {:g} mm ({}){}{}, {} x {:g} mm\n"
        "    Ra {:.4f} um  Rq {:.4f} um  Rz {:.4f} um  Rt {:.4f} um  Rp {:.4f} um  Rv {:.4f} um\n"
        "    Rsk {:.3f}  Rku {:.3f}  RSm {:.4f} mm ({} elements)  Wa {:.4f} um  Wt {:.4f} um\n",
        e.surface, e.description, e.texture.cutoff_mm, e.texture.cutoff_source,
        e.texture.lambda_s_mm > 0 ? fmt::format(", lambda_s {:g} mm", e.texture.lambda_s_mm) : "",
        e.texture.robust ? ", robust mean line" : "", r.sections,
        r.evaluation_length_mm / r.sections, 1000 * r.ra_mm, 1000 * r.rq_mm, 1000 * r.rz_mm,
        1000 * r.rt_mm, 1000 * r.rp_mm, 1000 * r.rv_mm, r.rsk, r.rku, r.rsm_mm, r.elements,
        1000 * e.texture.wa_mm, 1000 * e.texture.wt_mm);
  }
  return out;
}

}  // namespace trochomill
