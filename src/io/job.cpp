// Job file loading and validation (toml++). Every problem becomes one message naming the
// key with its file:line:column (or the --set override that supplied it) and what is
// allowed; all problems are collected and thrown together as one InputError.
#include "trochomill/job.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// The known keys of each section; anything else is reported with the closest suggestion.
const std::map<std::string, std::vector<std::string>>& known_keys() {
  static const std::map<std::string, std::vector<std::string>> keys = {
      {"tool",
       {"diameter", "teeth", "helix_angle", "corner_radius", "edge_radius", "flute_length",
        "runout_radial", "runout_axial", "runout_phase", "tooth_angles", "tool_number",
        "flank_wear", "type", "lead_angle", "insert_radial", "insert_axial"}},
      {"slot", {"width", "length", "depth"}},
      {"path",
       {"type", "step", "aspect_ratio", "linear_distance", "direction", "entry", "entry_radius",
        "entry_pitch", "entry_angle", "entry_feed", "clearance"}},
      {"cutting",
       {"feed_rate", "spindle_speed", "feed_per_tooth", "cutting_speed", "spindle_direction",
        "coolant"}},
      {"machine",
       {"dialect", "safe_z", "rapid_rate", "max_acceleration", "junction_deviation",
        "arc_tolerance", "arc_output", "program_number"}},
      {"measured", {"force_max", "roughness_ra", "waviness"}},
      {"analysis", {"steps_per_tooth", "imprint_points"}},
      {"mechanism", {"czi_max", "czii_max", "transition", "share", "model", "points"}},
      {"stock", {"min", "max"}},
      {"simulation",
       {"resolution", "steps_per_rev", "chip_sampling", "segment", "sub_segments", "threads"}},
      {"material",
       {"name", "model", "k_c", "k_n", "m", "m_n", "k_a", "m_a", "k_tc", "k_rc", "k_ac", "k_te",
        "k_re", "k_ae", "friction_angle", "source", "notes"}},
      {"forces", {"fast_steps_per_rev", "ploughing_angle"}},
      {"topography", {"files", "synthetic_vb", "state", "band", "rake", "clearance"}},
      {"monitor",
       {"low_min", "low_max", "high_min", "high_max", "order", "window", "baseline_cycles",
        "wear_ratio", "ploughing_ratio", "phase_bins"}},
  };
  return keys;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string suggestion(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  if (best_d <= limit) return fmt::format("; did you mean '{}'?", best);
  std::string all;
  for (const auto& c : candidates) all += (all.empty() ? "" : ", ") + c;
  return fmt::format(" (known: {})", all);
}

std::string fmt_num(double v) { return fmt::format("{:g}", v); }

struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_incl = true;
  bool hi_incl = true;
  [[nodiscard]] bool contains(double v) const {
    return (lo_incl ? v >= lo : v > lo) && (hi_incl ? v <= hi : v < hi);
  }
  [[nodiscard]] std::string describe() const {
    const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
    if (has_lo && has_hi) {
      return fmt::format("in {}{}, {}{}", lo_incl ? "[" : "(", fmt_num(lo), fmt_num(hi),
                         hi_incl ? "]" : ")");
    }
    if (has_lo) return fmt::format("{} {}", lo_incl ? ">=" : ">", fmt_num(lo));
    if (has_hi) return fmt::format("{} {}", hi_incl ? "<=" : "<", fmt_num(hi));
    return "finite";
  }
};
constexpr Range positive() { return Range{0.0, std::numeric_limits<double>::infinity(), false}; }
constexpr Range non_negative() { return Range{0.0}; }

class JobReader {
 public:
  JobReader(toml::table& root, std::string source, std::set<std::string> overridden)
      : root_(root), source_(std::move(source)), overridden_(std::move(overridden)) {}

  std::vector<std::string>& problems() { return problems_; }

  [[nodiscard]] std::string where(const std::string& section, const std::string& key,
                                  const toml::node* node) const {
    const std::string full = section + "." + key;
    if (overridden_.count(full)) return fmt::format("--set {}", full);
    if (node != nullptr && node->source().begin.line > 0) {
      return fmt::format("{}:{}:{}: [{}] {}", source_, node->source().begin.line,
                         node->source().begin.column, section, key);
    }
    return fmt::format("{}: [{}] {}", source_, section, key);
  }

  void problem(const std::string& section, const std::string& key, const std::string& what) {
    problems_.push_back(fmt::format("{}: {}", where(section, key, find(section, key)), what));
  }

  [[nodiscard]] const toml::node* find(const std::string& section, const std::string& key) const {
    const toml::table* t = root_[section].as_table();
    return t ? t->get(key) : nullptr;
  }
  [[nodiscard]] bool has(const std::string& section, const std::string& key) const {
    return find(section, key) != nullptr;
  }

  std::optional<double> number(const std::string& section, const std::string& key,
                               const std::string& unit, Range range,
                               std::optional<double> fallback = std::nullopt,
                               bool required = false) {
    const toml::node* n = find(section, key);
    if (n == nullptr) {
      if (required) {
        problems_.push_back(fmt::format("{}: missing required key [{}] {} ({}{})", source_, section,
                                        key, unit.empty() ? "number" : unit, range_hint(range)));
      }
      return fallback;
    }
    if (!n->is_number()) {
      problem(section, key,
              fmt::format("expected a number ({}), got {}", unit_or(unit), type_name(*n)));
      return fallback;
    }
    const double v = n->value<double>().value_or(0.0);
    if (!std::isfinite(v)) {
      problem(section, key, fmt::format("must be a finite number, got {}", fmt_num(v)));
      return fallback;
    }
    if (!range.contains(v)) {
      problem(section, key,
              fmt::format("must be {} {}, got {}", range.describe(), unit, fmt_num(v)));
      return fallback;
    }
    return v;
  }

  std::optional<int> integer(const std::string& section, const std::string& key, int lo, int hi,
                             std::optional<int> fallback = std::nullopt, bool required = false) {
    const toml::node* n = find(section, key);
    if (n == nullptr) {
      if (required) {
        problems_.push_back(fmt::format("{}: missing required key [{}] {} (integer in [{}, {}])",
                                        source_, section, key, lo, hi));
      }
      return fallback;
    }
    if (!n->is_integer()) {
      problem(section, key,
              fmt::format("expected an integer in [{}, {}], got {}", lo, hi, type_name(*n)));
      return fallback;
    }
    const int64_t v = n->value<int64_t>().value_or(0);
    if (v < lo || v > hi) {
      problem(section, key, fmt::format("must be an integer in [{}, {}], got {}", lo, hi, v));
      return fallback;
    }
    return static_cast<int>(v);
  }

  template <typename Enum>
  std::optional<Enum> choice(const std::string& section, const std::string& key,
                             const std::vector<std::pair<std::string, Enum>>& options,
                             std::optional<Enum> fallback, bool required = false) {
    std::string allowed;
    for (const auto& [name, value] : options) allowed += (allowed.empty() ? "" : " | ") + name;
    const toml::node* n = find(section, key);
    if (n == nullptr) {
      if (required) {
        problems_.push_back(
            fmt::format("{}: missing required key [{}] {} ({})", source_, section, key, allowed));
      }
      return fallback;
    }
    if (!n->is_string()) {
      problem(section, key,
              fmt::format("expected one of {} (a string), got {}", allowed, type_name(*n)));
      return fallback;
    }
    const std::string v = n->value<std::string>().value_or("");
    for (const auto& [name, value] : options) {
      if (name == v) return value;
    }
    std::vector<std::string> names;
    for (const auto& [name, value] : options) names.push_back(name);
    const std::string hint = suggestion(v, names);
    problem(section, key,
            fmt::format("'{}' is not one of {}{}", v, allowed,
                        hint.rfind("; did", 0) == 0 ? hint : std::string()));
    return fallback;
  }

  std::optional<std::string> string(const std::string& section, const std::string& key) {
    const toml::node* n = find(section, key);
    if (n == nullptr) return std::nullopt;
    if (!n->is_string()) {
      problem(section, key, fmt::format("expected a string, got {}", type_name(*n)));
      return std::nullopt;
    }
    return n->value<std::string>().value_or("");
  }

  std::optional<std::vector<std::string>> string_array(const std::string& section,
                                                       const std::string& key) {
    const toml::node* n = find(section, key);
    if (n == nullptr) return std::nullopt;
    const toml::array* arr = n->as_array();
    if (arr == nullptr) {
      problem(section, key, fmt::format("expected an array of strings, got {}", type_name(*n)));
      return std::nullopt;
    }
    std::vector<std::string> out;
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const toml::node& e = *arr->get(i);
      if (!e.is_string()) {
        problem(section, key, fmt::format("element {} must be a string, got {}", i, type_name(e)));
        return std::nullopt;
      }
      out.push_back(e.value<std::string>().value_or(""));
    }
    return out;
  }

  std::optional<std::vector<double>> number_array(const std::string& section,
                                                  const std::string& key, Range range) {
    const toml::node* n = find(section, key);
    if (n == nullptr) return std::nullopt;
    const toml::array* arr = n->as_array();
    if (arr == nullptr) {
      problem(section, key, fmt::format("expected an array of numbers, got {}", type_name(*n)));
      return std::nullopt;
    }
    std::vector<double> out;
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const toml::node& e = *arr->get(i);
      if (!e.is_number()) {
        problem(section, key, fmt::format("element {} must be a number, got {}", i, type_name(e)));
        return std::nullopt;
      }
      const double v = e.value<double>().value_or(0.0);
      if (!std::isfinite(v) || !range.contains(v)) {
        problem(section, key,
                fmt::format("element {} must be {}, got {}", i, range.describe(), fmt_num(v)));
        return std::nullopt;
      }
      out.push_back(v);
    }
    return out;
  }

  void check_unknown() {
    const auto& known = known_keys();
    std::vector<std::string> sections;
    for (const auto& [name, keys] : known) sections.push_back(name);
    for (auto&& [k, v] : root_) {
      const std::string section(k.str());
      const auto it = known.find(section);
      if (it == known.end()) {
        problems_.push_back(fmt::format("{}:{}:{}: unknown section [{}]{}", source_,
                                        k.source().begin.line, k.source().begin.column, section,
                                        suggestion(section, sections)));
        continue;
      }
      const toml::table* t = v.as_table();
      if (t == nullptr) {
        problems_.push_back(fmt::format("{}:{}:{}: '{}' must be a table [{}]", source_,
                                        k.source().begin.line, k.source().begin.column, section,
                                        section));
        continue;
      }
      for (auto&& [kk, vv] : *t) {
        const std::string key(kk.str());
        if (std::find(it->second.begin(), it->second.end(), key) == it->second.end()) {
          const std::string full = section + "." + key;
          const std::string loc = overridden_.count(full)
                                      ? fmt::format("--set {}", full)
                                      : fmt::format("{}:{}:{}", source_, kk.source().begin.line,
                                                    kk.source().begin.column);
          problems_.push_back(fmt::format("{}: unknown key [{}] {}{}", loc, section, key,
                                          suggestion(key, it->second)));
        }
      }
    }
  }

 private:
  static std::string unit_or(const std::string& unit) { return unit.empty() ? "number" : unit; }
  static std::string range_hint(const Range& r) {
    const std::string d = r.describe();
    return d == "finite" ? "" : ", " + d;
  }
  static std::string type_name(const toml::node& n) {
    switch (n.type()) {
      case toml::node_type::string:
        return "a string";
      case toml::node_type::integer:
        return "an integer";
      case toml::node_type::floating_point:
        return "a number";
      case toml::node_type::boolean:
        return "a boolean";
      case toml::node_type::array:
        return "an array";
      case toml::node_type::table:
        return "a table";
      default:
        return "a date/time";
    }
  }

  toml::table& root_;
  std::string source_;
  std::set<std::string> overridden_;
  std::vector<std::string> problems_;
};

void apply_override(toml::table& root, const Override& o) {
  const auto dot = o.key.find('.');
  const std::string section = o.key.substr(0, dot);
  const std::string key = o.key.substr(dot + 1);
  // The value in TOML syntax; when that does not parse, a bare word is taken as a string.
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + o.value);
  } catch (const toml::parse_error&) {
    parsed.insert_or_assign("v", o.value);
  }
  toml::node* existing = root.get(section);
  if (existing == nullptr) {
    root.insert_or_assign(section, toml::table{});
    existing = root.get(section);
  }
  toml::table* t = existing->as_table();
  if (t == nullptr) {
    throw InputError(fmt::format("--set {}: '{}' is not a table", o.key, section));
  }
  if (key.find('.') != std::string::npos) {
    throw InputError(
        fmt::format("--set {}: nested keys are not supported (use section.key)", o.key));
  }
  t->insert_or_assign(key, *parsed.get("v"));
}

// A value in TOML syntax; doubles in their shortest round-trip form (0.6, not 0.5999...).
std::string format_value(const toml::node& v) {
  if (v.is_floating_point()) {
    const double d = v.value<double>().value_or(0.0);
    std::string out = fmt::format("{}", d);
    if (std::isfinite(d) && out.find_first_of(".e") == std::string::npos) out += ".0";
    return out;
  }
  if (v.is_integer()) return fmt::format("{}", v.value<int64_t>().value_or(0));
  if (const toml::array* arr = v.as_array()) {
    std::string out = "[";
    for (std::size_t i = 0; i < arr->size(); ++i) {
      out += (i ? ", " : "") + format_value(*arr->get(i));
    }
    return out + "]";
  }
  if (v.is_table()) return "{...}";
  std::ostringstream ss;
  ss << toml::toml_formatter(v, toml::format_flags::none);
  return ss.str();
}

void flatten(const toml::table& root, std::vector<std::pair<std::string, std::string>>& out) {
  for (auto&& [k, v] : root) {
    if (const toml::table* t = v.as_table()) {
      for (auto&& [kk, vv] : *t) {
        out.emplace_back(std::string(k.str()) + "." + std::string(kk.str()), format_value(vv));
      }
    }
  }
}

// [material]: reads the keys present into m (absent keys keep m's values, so a job's keys
// override a library entry's).
void read_material_keys(JobReader& r, Material& m) {
  if (auto v = r.string("material", "source")) m.source = *v;
  if (auto v = r.string("material", "notes")) m.notes = *v;
  if (auto v = r.choice<ForceModel>("material", "model",
                                    {{"bergmann", ForceModel::bergmann},
                                     {"kienzle", ForceModel::kienzle},
                                     {"linear", ForceModel::linear}},
                                    std::nullopt)) {
    m.model = *v;
  }
  const auto num = [&](const char* key, const char* unit, Range range, double& dst) {
    if (auto v = r.number("material", key, unit, range)) dst = *v;
  };
  num("k_c", "N/mm^2", positive(), m.k_c);
  num("k_n", "N/mm^2", Range{}, m.k_n);
  num("m", "", Range{0.0, 1.0, true, false}, m.m);
  if (auto v = r.number("material", "m_n", "", Range{0.0, 1.0, true, false})) m.m_n = *v;
  num("k_a", "N/mm^2", Range{}, m.k_a);
  if (auto v = r.number("material", "m_a", "", Range{0.0, 1.0, true, false})) m.m_a = *v;
  num("k_tc", "N/mm^2", positive(), m.k_tc);
  num("k_rc", "N/mm^2", Range{}, m.k_rc);
  num("k_ac", "N/mm^2", Range{}, m.k_ac);
  num("k_te", "N/mm", Range{}, m.k_te);
  num("k_re", "N/mm", Range{}, m.k_re);
  num("k_ae", "N/mm", Range{}, m.k_ae);
}

// The coefficients a model needs are there, and the job gives none of another model's.
void check_material(JobReader& r, const Material& m) {
  static const std::vector<std::string> power_keys = {"k_c", "k_n", "m"};
  static const std::vector<std::string> kienzle_keys = {"m_n", "k_a", "m_a"};
  static const std::vector<std::string> linear_keys = {"k_tc", "k_rc", "k_ac",
                                                       "k_te", "k_re", "k_ae"};
  if (!m.model) {
    for (const auto* keys : {&power_keys, &kienzle_keys, &linear_keys}) {
      for (const auto& k : *keys) {
        if (r.has("material", k)) {
          r.problem("material", k, "give [material] model (bergmann | kienzle | linear) or name");
          return;
        }
      }
    }
    return;
  }
  const std::string model(to_string(*m.model));
  const auto foreign = [&](const std::vector<std::string>& keys, const char* owner) {
    for (const auto& k : keys) {
      if (r.has("material", k)) {
        r.problem("material", k,
                  fmt::format("belongs to the {} model, not to model = \"{}\"", owner, model));
      }
    }
  };
  if (*m.model == ForceModel::linear) {
    foreign(power_keys, "bergmann/kienzle");
    foreign(kienzle_keys, "kienzle");
    if (!(m.k_tc > 0)) {
      r.problem("material", "k_tc", "the linear model needs k_tc (N/mm^2, > 0)");
    }
    return;
  }
  foreign(linear_keys, "linear");
  if (*m.model == ForceModel::bergmann) foreign(kienzle_keys, "kienzle");
  if (!(m.k_c > 0)) {
    r.problem("material", "k_c", fmt::format("model = \"{}\" needs k_c (N/mm^2, > 0)", model));
  }
}

Material library_material(const std::string& name);

Job build_job(toml::table& root, std::string source, const std::set<std::string>& overridden) {
  JobReader r(root, source, overridden);
  Job job;
  job.source = source;
  // [tool]
  Tool& tool = job.tool;
  tool.diameter_mm = r.number("tool", "diameter", "mm", positive(), 0.0, true).value_or(0.0);
  tool.teeth = r.integer("tool", "teeth", 1, 64, 0, true).value_or(0);
  tool.helix_angle_deg =
      r.number("tool", "helix_angle", "degrees", Range{0, 90, true, false}, 0.0).value_or(0.0);
  tool.corner_radius_mm =
      r.number("tool", "corner_radius", "mm", non_negative(), 0.0).value_or(0.0);
  tool.edge_radius_mm = r.number("tool", "edge_radius", "mm", non_negative(), 0.0).value_or(0.0);
  tool.flute_length_mm = r.number("tool", "flute_length", "mm", non_negative(), 0.0).value_or(0.0);
  tool.runout_radial_mm =
      r.number("tool", "runout_radial", "mm", non_negative(), 0.0).value_or(0.0);
  tool.runout_axial_mm = r.number("tool", "runout_axial", "mm", non_negative(), 0.0).value_or(0.0);
  tool.runout_phase_deg =
      r.number("tool", "runout_phase", "degrees", Range{-360, 360}, 0.0).value_or(0.0);
  tool.tool_number = r.integer("tool", "tool_number", 0, 9999, 1).value_or(1);
  if (tool.diameter_mm > 0 && tool.corner_radius_mm > tool.radius_mm()) {
    r.problem("tool", "corner_radius",
              fmt::format("must be <= the tool radius ({} mm), got {}", fmt_num(tool.radius_mm()),
                          fmt_num(tool.corner_radius_mm)));
  }
  if (tool.diameter_mm > 0 && tool.edge_radius_mm >= 0.1 * tool.diameter_mm) {
    r.problem("tool", "edge_radius",
              fmt::format("must be < D/10 = {} mm (a cutting-edge rounding is micrometres), got {}",
                          fmt_num(0.1 * tool.diameter_mm), fmt_num(tool.edge_radius_mm)));
  }
  if (auto angles = r.number_array("tool", "tooth_angles", Range{0, 360, true, false})) {
    if (tool.teeth > 0 && static_cast<int>(angles->size()) != tool.teeth) {
      r.problem("tool", "tooth_angles",
                fmt::format("must list one angle per tooth ({} values for teeth = {}), got {}",
                            tool.teeth, tool.teeth, angles->size()));
    } else if (!std::is_sorted(angles->begin(), angles->end()) ||
               std::adjacent_find(angles->begin(), angles->end()) != angles->end()) {
      r.problem("tool", "tooth_angles", "must be strictly increasing degrees in [0, 360)");
    } else {
      tool.tooth_angles_deg = *angles;
    }
  }
  tool.type =
      r.choice<ToolType>("tool", "type",
                         {{"end_mill", ToolType::end_mill}, {"insert_mill", ToolType::insert_mill}},
                         ToolType::end_mill)
          .value_or(ToolType::end_mill);
  const auto lead = r.number("tool", "lead_angle", "degrees", Range{0, 90, false, true}, 90.0);
  if (lead) {
    if (tool.type != ToolType::insert_mill && *lead != 90.0) {
      r.problem("tool", "lead_angle",
                "applies to type = \"insert_mill\" (an end mill's flank is at 90 degrees)");
    } else {
      tool.lead_angle_deg = *lead;
    }
  }
  for (auto [key, dest] : {std::pair{"insert_radial", &tool.insert_radial_mm},
                           std::pair{"insert_axial", &tool.insert_axial_mm}}) {
    if (auto v = r.number_array("tool", key, Range{-1.0, 1.0})) {
      if (tool.type != ToolType::insert_mill) {
        r.problem("tool", key, "applies to type = \"insert_mill\"");
      } else if (tool.teeth > 0 && static_cast<int>(v->size()) != tool.teeth) {
        r.problem("tool", key,
                  fmt::format("must list one value (mm) per insert ({} for teeth = {}), got {}",
                              tool.teeth, tool.teeth, v->size()));
      } else {
        *dest = *v;
      }
    }
  }
  if (tool.tooth_angles_deg.empty() && tool.teeth > 0) {
    for (int k = 0; k < tool.teeth; ++k) tool.tooth_angles_deg.push_back(360.0 * k / tool.teeth);
  }

  // [slot]
  Slot& slot = job.slot;
  slot.width_mm = r.number("slot", "width", "mm", positive(), 0.0, true).value_or(0.0);
  slot.length_mm = r.number("slot", "length", "mm", positive(), 0.0, true).value_or(0.0);
  slot.depth_mm = r.number("slot", "depth", "mm", positive(), 0.0, true).value_or(0.0);

  // [path]
  PathSpec& path = job.path;
  path.type = r.choice<PathType>("path", "type",
                                 {{"linear", PathType::linear},
                                  {"trochoidal", PathType::trochoidal},
                                  {"circular", PathType::circular},
                                  {"elliptical", PathType::elliptical},
                                  {"linear-elliptical", PathType::linear_elliptical}},
                                 PathType::trochoidal, true)
                  .value_or(PathType::trochoidal);
  const bool trochoidal_family = path.type != PathType::linear;
  const bool needs_step = trochoidal_family || slot.width_mm > tool.diameter_mm;
  path.step_mm = r.number("path", "step", "mm", positive(), 0.0, needs_step).value_or(0.0);
  path.aspect_ratio = r.number("path", "aspect_ratio", "(b/a)", positive(), 1.0).value_or(1.0);
  path.linear_distance_mm =
      r.number("path", "linear_distance", "mm", non_negative(), 0.0).value_or(0.0);
  path.direction =
      r.choice<Direction>("path", "direction",
                          {{"climb", Direction::climb}, {"conventional", Direction::conventional}},
                          Direction::climb)
          .value_or(Direction::climb);
  path.entry = r.choice<EntryType>("path", "entry",
                                   {{"helix", EntryType::helix},
                                    {"ramp", EntryType::ramp},
                                    {"plunge", EntryType::plunge},
                                    {"outside", EntryType::outside}},
                                   EntryType::outside)
                   .value_or(EntryType::outside);
  path.entry_radius_mm = r.number("path", "entry_radius", "mm", non_negative(), 0.0).value_or(0.0);
  path.entry_pitch_mm =
      r.number("path", "entry_pitch", "mm per turn", positive(), 1.0).value_or(1.0);
  path.entry_angle_deg =
      r.number("path", "entry_angle", "degrees", Range{0, 90, false, false}, 3.0).value_or(3.0);
  path.entry_feed_mm_per_min =
      r.number("path", "entry_feed", "mm/min", non_negative(), 0.0).value_or(0.0);
  path.clearance_mm = r.number("path", "clearance", "mm", non_negative(), 1.0).value_or(1.0);

  // Geometry feasibility (only when the inputs themselves were valid).
  const double D = tool.diameter_mm, W = slot.width_mm;
  if (D > 0 && W > 0) {
    if (W < D) {
      r.problem("slot", "width",
                fmt::format("the slot ({} mm) is narrower than the tool ([tool] diameter = {} mm)",
                            fmt_num(W), fmt_num(D)));
    } else if (trochoidal_family && W <= D) {
      r.problem("slot", "width",
                fmt::format("a {} path needs a slot wider than the tool ([tool] diameter = {} mm); "
                            "use type = \"linear\" for W = D",
                            to_string(path.type), fmt_num(D)));
    }
    if (path.step_mm > 0 && path.step_mm >= D && needs_step) {
      r.problem("path", "step",
                fmt::format("must be smaller than the tool diameter ({} mm), got {}", fmt_num(D),
                            fmt_num(path.step_mm)));
    }
  }
  if (path.type == PathType::trochoidal && r.has("path", "aspect_ratio") &&
      path.aspect_ratio != 1.0) {
    r.problem("path", "aspect_ratio",
              "type = \"trochoidal\" is the elliptical family with aspect_ratio = 1; "
              "use type = \"elliptical\" for other aspect ratios");
  }

  // [cutting]: exactly one way to give each of feed and speed.
  Cutting& cut = job.cutting;
  const bool has_fr = r.has("cutting", "feed_rate"), has_fz = r.has("cutting", "feed_per_tooth");
  const bool has_n = r.has("cutting", "spindle_speed"), has_vc = r.has("cutting", "cutting_speed");
  const auto fr = r.number("cutting", "feed_rate", "mm/min", positive());
  const auto fz = r.number("cutting", "feed_per_tooth", "mm", positive());
  const auto n = r.number("cutting", "spindle_speed", "rpm", positive());
  const auto vc = r.number("cutting", "cutting_speed", "m/min", positive());
  if (has_fr && has_fz) {
    r.problem("cutting", "feed_per_tooth",
              "give either [cutting] feed_rate (mm/min) or feed_per_tooth (mm), not both");
  } else if (!has_fr && !has_fz) {
    r.problems().push_back(fmt::format(
        "{}: missing [cutting] feed_rate (mm/min) or feed_per_tooth (mm): give exactly one",
        source));
  }
  if (has_n && has_vc) {
    r.problem("cutting", "cutting_speed",
              "give either [cutting] spindle_speed (rpm) or cutting_speed (m/min), not both");
  } else if (!has_n && !has_vc) {
    r.problems().push_back(fmt::format(
        "{}: missing [cutting] spindle_speed (rpm) or cutting_speed (m/min): give exactly one",
        source));
  }
  if ((n || vc) && D > 0) {
    cut.spindle_speed_rpm = n ? *n : spindle_rpm_from_cutting_speed(*vc, D);
    cut.cutting_speed_m_per_min = cutting_speed_from_spindle_rpm(cut.spindle_speed_rpm, D);
    if ((fr || fz) && tool.teeth > 0) {
      cut.feed_rate_mm_per_min = fr ? *fr : *fz * tool.teeth * cut.spindle_speed_rpm;
      cut.feed_per_tooth_mm = cut.feed_rate_mm_per_min / (tool.teeth * cut.spindle_speed_rpm);
    }
  }
  cut.spindle_direction =
      r.choice<SpindleDirection>("cutting", "spindle_direction",
                                 {{"cw", SpindleDirection::cw}, {"ccw", SpindleDirection::ccw}},
                                 SpindleDirection::cw)
          .value_or(SpindleDirection::cw);
  cut.coolant =
      r.choice<Coolant>("cutting", "coolant",
                        {{"off", Coolant::off}, {"flood", Coolant::flood}, {"mist", Coolant::mist}},
                        Coolant::off)
          .value_or(Coolant::off);

  // [machine]
  Machine& m = job.machine;
  m.dialect = r.choice<Dialect>("machine", "dialect",
                                {{"linuxcnc", Dialect::linuxcnc},
                                 {"fanuc", Dialect::fanuc},
                                 {"sinumerik", Dialect::sinumerik},
                                 {"grbl", Dialect::grbl}},
                                Dialect::linuxcnc)
                  .value_or(Dialect::linuxcnc);
  m.safe_z_mm =
      r.number("machine", "safe_z", "mm above the top face", positive(), 5.0).value_or(5.0);
  m.rapid_rate_mm_per_min =
      r.number("machine", "rapid_rate", "mm/min", positive(), 10000.0).value_or(10000.0);
  m.max_acceleration_mm_per_s2 =
      r.number("machine", "max_acceleration", "mm/s^2", non_negative(), 0.0).value_or(0.0);
  m.junction_deviation_mm =
      r.number("machine", "junction_deviation", "mm", non_negative(), 0.01).value_or(0.01);
  m.arc_tolerance_mm =
      r.number("machine", "arc_tolerance", "mm", Range{1e-6, 1.0}, 0.001).value_or(0.001);
  m.arc_output = r.choice<ArcOutput>("machine", "arc_output",
                                     {{"arcs", ArcOutput::arcs}, {"chords", ArcOutput::chords}},
                                     ArcOutput::arcs)
                     .value_or(ArcOutput::arcs);
  m.program_number = r.integer("machine", "program_number", 1, 9999, 1000).value_or(1000);

  // [measured]: process results the user measured (or a later model fills in).
  job.measured.force_max_n = r.number("measured", "force_max", "N", positive());
  job.measured.roughness_ra_um = r.number("measured", "roughness_ra", "um", positive());
  job.measured.waviness_um = r.number("measured", "waviness", "um", positive());
  // [tool] flank_wear, [mechanism], [material] friction_angle (the rest of [material]
  // belongs to the force models)
  tool.flank_wear_mm = r.number("tool", "flank_wear", "mm", non_negative(), 0.0).value_or(0.0);
  MechanismJob& mj = job.mechanism;
  mj.czi_max_pct = r.number("mechanism", "czi_max", "% of r_e", positive(), 25.0).value_or(25.0);
  mj.czii_max_pct = r.number("mechanism", "czii_max", "% of r_e", positive(), 60.0).value_or(60.0);
  mj.transition_pct =
      r.number("mechanism", "transition", "% of r_e", positive(), 40.0).value_or(40.0);
  mj.share =
      r.number("mechanism", "share", "fraction", Range{0.0, 1.0, false, true}, 0.5).value_or(0.5);
  mj.model = r.choice<std::string>("mechanism", "model",
                                   {{"exact", "exact"}, {"pivkin2025", "pivkin2025"}}, "exact")
                 .value_or("exact");
  mj.points = r.integer("mechanism", "points", 36, 1000000, 3600).value_or(3600);
  mj.friction_angle_deg =
      r.number("material", "friction_angle", "degrees", Range{0.0, 90.0, false, false});
  if (mj.czii_max_pct <= mj.czi_max_pct) {
    r.problem("mechanism", "czii_max",
              fmt::format("must be greater than czi_max ({}), got {}", fmt_num(mj.czi_max_pct),
                          fmt_num(mj.czii_max_pct)));
  }
  // [monitor]
  MonitorSettings& mo = job.monitor;
  mo.low_min_hz = r.number("monitor", "low_min", "Hz", positive(), 2000.0).value_or(2000.0);
  mo.low_max_hz = r.number("monitor", "low_max", "Hz", positive(), 5000.0).value_or(5000.0);
  mo.high_min_hz = r.number("monitor", "high_min", "Hz", positive(), 8000.0).value_or(8000.0);
  mo.high_max_hz = r.number("monitor", "high_max", "Hz", positive(), 13000.0).value_or(13000.0);
  mo.order = r.integer("monitor", "order", 1, 12, 4).value_or(4);
  mo.window_s = r.number("monitor", "window", "s", Range{1e-5, 10.0}, 0.005).value_or(0.005);
  mo.baseline_cycles = r.integer("monitor", "baseline_cycles", 1, 1000, 3).value_or(3);
  mo.wear_ratio =
      r.number("monitor", "wear_ratio", "ratio", Range{1.0, 100.0, false, true}, 1.3).value_or(1.3);
  mo.ploughing_ratio =
      r.number("monitor", "ploughing_ratio", "ratio", Range{1.0, 100.0, false, true}, 1.15)
          .value_or(1.15);
  mo.phase_bins = r.integer("monitor", "phase_bins", 4, 10000, 50).value_or(50);
  if (mo.low_max_hz <= mo.low_min_hz) {
    r.problem("monitor", "low_max",
              fmt::format("must be greater than low_min ({} Hz), got {} Hz", fmt_num(mo.low_min_hz),
                          fmt_num(mo.low_max_hz)));
  }
  if (mo.high_max_hz <= mo.high_min_hz) {
    r.problem("monitor", "high_max",
              fmt::format("must be greater than high_min ({} Hz), got {} Hz",
                          fmt_num(mo.high_min_hz), fmt_num(mo.high_max_hz)));
  }
  // [simulation]
  SimSettings& si = job.simulation;
  si.resolution_mm =
      r.number("simulation", "resolution", "mm", Range{1e-4, 10.0}, 0.01).value_or(0.01);
  si.steps_per_rev = r.integer("simulation", "steps_per_rev", 8, 100000, 600).value_or(600);
  si.chip_sampling_mm =
      r.number("simulation", "chip_sampling", "mm", Range{1e-5, 1.0}, 0.001).value_or(0.001);
  si.segment_mm = r.number("simulation", "segment", "mm", Range{1e-3, 10.0}, 0.05).value_or(0.05);
  si.sub_segments = r.integer("simulation", "sub_segments", 1, 100, 5).value_or(5);
  si.threads = r.integer("simulation", "threads", 0, 1024, 0).value_or(0);
  // [stock]
  {
    const auto lo = r.number_array("stock", "min", Range{});
    const auto hi = r.number_array("stock", "max", Range{});
    if (lo.has_value() != hi.has_value()) {
      r.problem("stock", lo ? "max" : "min", "give both min and max ([x, y, z] in mm)");
    } else if (lo) {
      if (lo->size() != 3 || hi->size() != 3) {
        r.problem("stock", "min", "min and max must each be [x, y, z] in mm");
      } else if (!((*hi)[0] > (*lo)[0] && (*hi)[1] > (*lo)[1] && (*hi)[2] > (*lo)[2])) {
        r.problem("stock", "max", "every coordinate of max must exceed min's");
      } else {
        job.stock_min_mm = std::array<double, 3>{(*lo)[0], (*lo)[1], (*lo)[2]};
        job.stock_max_mm = std::array<double, 3>{(*hi)[0], (*hi)[1], (*hi)[2]};
      }
    }
  }
  // [analysis]
  job.analysis.steps_per_tooth = r.integer("analysis", "steps_per_tooth", 1, 64, 1).value_or(1);
  job.analysis.imprint_points = r.integer("analysis", "imprint_points", 3, 10001, 81).value_or(81);

  // [material]: a library entry by name, then the job's own keys over it.
  {
    Material& ma = job.material;
    if (auto name = r.string("material", "name")) {
      try {
        ma = library_material(*name);
      } catch (const InputError& e) {
        r.problem("material", "name", e.what());
      }
    }
    read_material_keys(r, ma);
    check_material(r, ma);
  }
  // [forces]
  job.forces.fast_steps_per_rev =
      r.integer("forces", "fast_steps_per_rev", 8, 100000, 96).value_or(96);
  job.forces.ploughing_angle_deg =
      r.number("forces", "ploughing_angle", "degrees", Range{0.0, 90.0, false, false}, 80.0)
          .value_or(80.0);
  // [topography]: file names relative to the job file's directory.
  {
    TopographySettings& tp = job.topography;
    if (auto files = r.string_array("topography", "files")) {
      const std::filesystem::path base = std::filesystem::path(source).parent_path();
      for (const auto& f : *files) {
        const std::filesystem::path fp(f);
        tp.files.push_back(fp.is_absolute() ? fp : base / fp);
      }
    }
    if (auto vb = r.number_array("topography", "synthetic_vb", Range{0.0, 2.0})) {
      tp.synthetic_vb_mm = *vb;
    }
    if (!tp.files.empty() && !tp.synthetic_vb_mm.empty()) {
      r.problem("topography", "synthetic_vb", "give files or synthetic_vb, not both");
    }
    tp.band_mm = r.number("topography", "band", "mm", Range{1e-3, 5.0}, 0.2).value_or(0.2);
    tp.rake_deg = r.number("topography", "rake", "degrees", Range{-30.0, 30.0}, 0.0).value_or(0.0);
    tp.clearance_deg =
        r.number("topography", "clearance", "degrees", Range{1.0, 30.0}, 7.0).value_or(7.0);
    const int states = static_cast<int>(tp.states());
    tp.state = r.integer("topography", "state", 0, std::max(0, states - 1), 0).value_or(0);
  }

  r.check_unknown();
  if (!r.problems().empty()) throw InputError(r.problems());
  flatten(root, job.flat_keys);
  return job;
}

}  // namespace

std::filesystem::path materials_dir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("TROCHOMILL_DATA"); env != nullptr && *env != '\0') {
    return fs::path(env) / "materials";
  }
#ifdef TROCHOMILL_SOURCE_DATA_DIR
  if (fs::is_directory(fs::path(TROCHOMILL_SOURCE_DATA_DIR) / "materials")) {
    return fs::path(TROCHOMILL_SOURCE_DATA_DIR) / "materials";
  }
#endif
#ifdef TROCHOMILL_INSTALL_DATA_DIR
  return fs::path(TROCHOMILL_INSTALL_DATA_DIR) / "materials";
#else
  return fs::path("data") / "materials";
#endif
}

std::vector<Material> material_library() {
  namespace fs = std::filesystem;
  const fs::path dir = materials_dir();
  if (!fs::is_directory(dir)) {
    throw InputError(fmt::format(
        "materials library not found at {} (set TROCHOMILL_DATA to the directory holding "
        "materials/)",
        dir.string()));
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".toml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<Material> out;
  for (const auto& f : files) {
    std::string text;
    try {
      text = read_file(f);
    } catch (const IoError& e) {
      throw InputError(e.what());
    }
    toml::table root;
    try {
      root = toml::parse(text, f.string());
    } catch (const toml::parse_error& e) {
      throw InputError(fmt::format("{}:{}:{}: TOML syntax error: {}", f.string(),
                                   e.source().begin.line, e.source().begin.column,
                                   e.description()));
    }
    JobReader r(root, f.string(), {});
    Material m;
    if (auto name = r.string("material", "name")) m.name = *name;
    if (m.name.empty()) r.problem("material", "name", "a library entry needs a name");
    read_material_keys(r, m);
    if (!m.model) r.problem("material", "model", "a library entry needs a model");
    check_material(r, m);
    if (m.source.empty()) r.problem("material", "source", "a library entry must cite its source");
    r.check_unknown();
    if (!r.problems().empty()) throw InputError(r.problems());
    out.push_back(std::move(m));
  }
  std::sort(out.begin(), out.end(),
            [](const Material& a, const Material& b) { return a.name < b.name; });
  return out;
}

namespace {
Material library_material(const std::string& name) {
  const std::vector<Material> lib = material_library();
  std::vector<std::string> names;
  for (const auto& m : lib) {
    if (m.name == name) return m;
    names.push_back(m.name);
  }
  throw InputError(
      fmt::format("'{}' is not in the materials library{}", name, suggestion(name, names)));
}
}  // namespace

Override parse_override(std::string_view text) {
  const auto eq = text.find('=');
  if (eq == std::string_view::npos) {
    throw InputError(fmt::format("--set '{}': expected section.key=value", text));
  }
  std::string key(text.substr(0, eq));
  std::string value(text.substr(eq + 1));
  auto trim = [](std::string& s) {
    const auto b = s.find_first_not_of(" \t");
    const auto e = s.find_last_not_of(" \t");
    s = b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  };
  trim(key);
  trim(value);
  const auto dot = key.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == key.size()) {
    throw InputError(fmt::format("--set '{}': the key must be section.key (e.g. path.step)", text));
  }
  if (value.empty()) throw InputError(fmt::format("--set '{}': the value is empty", text));
  return Override{key, value};
}

Job parse_job(std::string_view toml_text, std::string_view source_name,
              const std::vector<Override>& overrides) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}:{}: TOML syntax error: {}", source_name,
                                 e.source().begin.line, e.source().begin.column, e.description()));
  }
  std::set<std::string> overridden;
  for (const auto& o : overrides) {
    apply_override(root, o);
    overridden.insert(o.key);
  }
  return build_job(root, std::string(source_name), overridden);
}

Job load_job(const std::filesystem::path& file, const std::vector<Override>& overrides) {
  std::string text;
  try {
    text = read_file(file);
  } catch (const IoError& e) {
    throw InputError(e.what());
  }
  return parse_job(text, file.string(), overrides);
}

std::string_view to_string(PathType t) noexcept {
  switch (t) {
    case PathType::linear:
      return "linear";
    case PathType::trochoidal:
      return "trochoidal";
    case PathType::circular:
      return "circular";
    case PathType::elliptical:
      return "elliptical";
    case PathType::linear_elliptical:
      return "linear-elliptical";
  }
  return "?";
}
std::string_view to_string(ForceModel m) noexcept {
  switch (m) {
    case ForceModel::bergmann:
      return "bergmann";
    case ForceModel::kienzle:
      return "kienzle";
    case ForceModel::linear:
      return "linear";
  }
  return "?";
}
std::string_view to_string(Dialect d) noexcept {
  switch (d) {
    case Dialect::linuxcnc:
      return "linuxcnc";
    case Dialect::fanuc:
      return "fanuc";
    case Dialect::sinumerik:
      return "sinumerik";
    case Dialect::grbl:
      return "grbl";
  }
  return "?";
}
std::string_view to_string(EntryType e) noexcept {
  switch (e) {
    case EntryType::helix:
      return "helix";
    case EntryType::ramp:
      return "ramp";
    case EntryType::plunge:
      return "plunge";
    case EntryType::outside:
      return "outside";
  }
  return "?";
}
std::string_view to_string(Direction d) noexcept {
  return d == Direction::climb ? "climb" : "conventional";
}

Dialect parse_dialect(std::string_view name) {
  for (Dialect d : {Dialect::linuxcnc, Dialect::fanuc, Dialect::sinumerik, Dialect::grbl}) {
    if (to_string(d) == name) return d;
  }
  throw InputError(
      fmt::format("dialect '{}' is not one of linuxcnc | fanuc | sinumerik | grbl", name));
}

}  // namespace trochomill
