// The job schema: one entry per key (section, key, type, unit, allowed range or choices, the
// struct member it fills, what it means), with the default read from the struct. The table
// drives parsing and validation (build_job), the unknown-key suggestions, `--set` (an
// override is validated as the key it sets) and the key reference of docs/user-guide.md
// (job_keys_markdown; a test fails when the two differ). The rules that tie several keys
// together (one of feed_rate or feed_per_tooth, the slot wider than the tool, a material
// model's coefficients) follow the table in build_job.
#include "job/schema.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <set>
#include <type_traits>

#include "job/names.hpp"
#include "trochomill/error.hpp"
#include "trochomill/units.hpp"

namespace trochomill::job_detail {
namespace {

constexpr double kMaxLengthMm = 1e5;  // 100 m: any slot, tool or travel

template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};

// The member a key fills: a function from the job to a reference to it.
template <class T>
using Field = T& (*)(Job&);

std::string show_number(double v) { return fmt_num(v); }

template <class E, std::size_t N>
std::vector<std::pair<std::string, E>> options_of(const Names<E> (&table)[N]) {
  std::vector<std::pair<std::string, E>> out;
  for (const auto& [name, v] : table) out.emplace_back(std::string(name), v);
  return out;
}

template <class E, std::size_t N>
std::string choices_text(const Names<E> (&table)[N]) {
  std::string out;
  for (const auto& [name, v] : table) out += (out.empty() ? "" : " | ") + std::string(name);
  return out;
}

// A job with [pocket] plans a pocket: the slot's required keys and the path family are not.
// Nor are they in a job of a [stock] without [slot]: the stock a program read from G-code
// cuts, which plans nothing (plan_path says so).
bool pocket_waives(const JobReader& r, std::string_view section) {
  return (section == "slot" || section == "path") &&
         (r.has_section("pocket") || (r.has_section("stock") && !r.has_section("slot")));
}

// A number key: absent keeps the member's value (the struct's default, or a library
// material's coefficient); an optional member stays empty.
template <class T>
Key number(const char* section, const char* key, const char* unit, Range range, Field<T> field,
           const char* doc, bool required = false) {
  Key k{section, key, "number", unit, range.describe(), required, doc, {}, {}};
  k.read = [=](JobReader& r, Job& job) {
    T& dst = field(job);
    if constexpr (is_optional<T>::value) {
      if (auto v = r.number(section, key, unit, range)) dst = *v;
    } else {
      dst = r.number(section, key, unit, range, dst, required && !pocket_waives(r, section))
                .value_or(dst);
    }
  };
  k.show = [=](Job& defaults) -> std::string {
    if (required) return "required";
    if constexpr (is_optional<T>::value) {
      const T& v = field(defaults);
      return v ? show_number(*v) : "none";
    } else {
      return show_number(field(defaults));
    }
  };
  return k;
}

Key integer(const char* section, const char* key, int lo, int hi, Field<int> field, const char* doc,
            bool required = false) {
  Key k{section, key, "integer", "", fmt::format("in [{}, {}]", lo, hi), required, doc, {}, {}};
  k.read = [=](JobReader& r, Job& job) {
    int& dst = field(job);
    dst = r.integer(section, key, lo, hi, dst, required).value_or(dst);
  };
  k.show = [=](Job& d) { return required ? std::string("required") : fmt::format("{}", field(d)); };
  return k;
}

template <class E, std::size_t N>
Key choice(const char* section, const char* key, const Names<E> (&table)[N], Field<E> field,
           const char* doc, bool required = false) {
  Key k{section, key, "choice", "", choices_text(table), required, doc, {}, {}};
  k.read = [=, options = options_of(table)](JobReader& r, Job& job) {
    E& dst = field(job);
    dst = r.choice<E>(section, key, options, dst, required && !pocket_waives(r, section))
              .value_or(dst);
  };
  k.show = [=, &table](Job& d) {
    return required ? std::string("required") : std::string(name_of(table, field(d)));
  };
  return k;
}

// A key whose reading is its own (arrays, keys that depend on others): `read` does it all.
Key custom(const char* section, const char* key, const char* type, const char* unit,
           std::string allowed, std::string default_text, const char* doc,
           std::function<void(JobReader&, Job&)> read) {
  return Key{section,
             key,
             type,
             unit,
             std::move(allowed),
             false,
             doc,
             std::move(read),
             [d = std::move(default_text)](Job&) { return d; }};
}

// A [machine] key [x, y, z] in machine coordinates (mm).
Key machine_position(const char* key, const char* doc, std::optional<Vec3>& (*field)(Job&)) {
  return custom("machine", key, "array of numbers", "mm", "[x, y, z], within +-1e6", "none", doc,
                [key, field](JobReader& r, Job& job) {
                  if (auto v = r.number_array("machine", key, Range{-1e6, 1e6})) {
                    if (v->size() != 3) {
                      r.problem("machine", key, "give [x, y, z] in mm");
                    } else {
                      field(job) = Vec3((*v)[0], (*v)[1], (*v)[2]);
                    }
                  }
                });
}

// A [slot] key only a slot along a drawing's contour has: true with [slot] along, else the
// problem `what` on the key.
bool along_only(JobReader& r, const char* key, const char* what) {
  if (r.has("slot", "along")) return true;
  r.problem("slot", key, what);
  return false;
}

// A key naming a layer (or SVG id) of [geometry] file: read into `dst` when given and not
// empty; when absent, reported missing with `missing` (what it names) if that is given.
void read_layer(JobReader& r, const char* section, const char* key, std::string& dst,
                const char* missing = nullptr) {
  if (auto v = r.string(section, key)) {
    if (v->empty()) {
      r.problem(section, key, "give the drawing's layer (or SVG id)");
    } else {
      dst = *v;
    }
  } else if (missing != nullptr) {
    r.problems().push_back(
        fmt::format("{}: missing required key [{}] {} ({})", r.source(), section, key, missing));
  }
}

#define FIELD(member)     \
  +[](Job & j) -> auto& { \
    return j.member;      \
  }

// [material] keys (also read for a library entry, whose keys the job's then override).
std::vector<Key> material_keys() {
  const Range exponent{0.0, 1.0, true, false};
  return {
      custom("material", "name", "string", "", "a name of `trochomill materials`", "none",
             "a library entry (`trochomill materials`), e.g. inconel718-bergmann2021; keys given "
             "beside it override the library's",
             [](JobReader& r, Job& job) {
               if (auto name = r.string("material", "name")) {
                 try {
                   job.material = library_material(*name);
                 } catch (const InputError& e) {
                   r.problem("material", "name", e.what());
                 }
               }
             }),
      custom("material", "source", "string", "", "text", "none",
             "where the coefficients come from (`calibrate` fills it)",
             [](JobReader& r, Job& job) {
               if (auto v = r.string("material", "source")) job.material.source = *v;
             }),
      custom("material", "notes", "string", "", "text", "none",
             "conditions the coefficients hold for (tool, speed, coolant...)",
             [](JobReader& r, Job& job) {
               if (auto v = r.string("material", "notes")) job.material.notes = *v;
             }),
      custom("material", "model", "choice", "", choices_text(kForceModels), "none",
             "force model: bergmann (Bergmann 2021 Eq. 3, topography-aware), kienzle or linear "
             "(docs/models.md section 12); absent: no force model",
             [](JobReader& r, Job& job) {
               if (auto v = r.choice<ForceModel>("material", "model", options_of(kForceModels),
                                                 std::nullopt)) {
                 job.material.model = *v;
               }
             }),
      number("material", "k_c", "N/mm^2", positive(), FIELD(material.k_c),
             "specific cutting force along the cutting direction (bergmann, kienzle)"),
      number("material", "k_n", "N/mm^2", Range{}, FIELD(material.k_n),
             "specific normal force along the contour normal (bergmann, kienzle)"),
      number("material", "m", "", exponent, FIELD(material.m),
             "exponent of h: F = w h^(1 - m) k (bergmann, kienzle)"),
      number("material", "m_n", "", exponent, FIELD(material.m_n),
             "kienzle: exponent of the normal force (default m)"),
      number("material", "k_a", "N/mm^2", Range{}, FIELD(material.k_a),
             "kienzle: specific force up the edge"),
      number("material", "m_a", "", exponent, FIELD(material.m_a),
             "kienzle: exponent of the force up the edge (default m)"),
      number("material", "k_tc", "N/mm^2", positive(), FIELD(material.k_tc),
             "linear: tangential cutting coefficient"),
      number("material", "k_rc", "N/mm^2", Range{}, FIELD(material.k_rc),
             "linear: radial cutting coefficient"),
      number("material", "k_ac", "N/mm^2", Range{}, FIELD(material.k_ac),
             "linear: axial cutting coefficient"),
      number("material", "k_te", "N/mm", Range{}, FIELD(material.k_te),
             "linear: tangential edge coefficient"),
      number("material", "k_re", "N/mm", Range{}, FIELD(material.k_re),
             "linear: radial edge coefficient"),
      number("material", "k_ae", "N/mm", Range{}, FIELD(material.k_ae),
             "linear: axial edge coefficient"),
  };
}

// Per-insert seating arrays of an insert mill.
void read_insert_array(JobReader& r, Job& job, const char* key, std::vector<double>& dest) {
  const Tool& tool = job.tool;
  if (auto v = r.number_array("tool", key, Range{-1.0, 1.0})) {
    if (tool.type != ToolType::insert_mill) {
      r.problem("tool", key, "applies to type = \"insert_mill\"");
    } else if (tool.teeth > 0 && static_cast<int>(v->size()) != tool.teeth) {
      r.problem("tool", key,
                fmt::format("must list one value (mm) per insert ({} for teeth = {}), got {}",
                            tool.teeth, tool.teeth, v->size()));
    } else {
      dest = *v;
    }
  }
}

std::vector<Key> build_schema() {
  std::vector<Key> keys = {
      // [tool]
      number("tool", "diameter", "mm", positive(), FIELD(tool.diameter_mm), "cutter diameter D",
             true),
      integer("tool", "teeth", 1, 64, FIELD(tool.teeth), "number of teeth Z", true),
      number("tool", "helix_angle", "degrees", Range{0, 90, true, false},
             FIELD(tool.helix_angle_deg), "helix angle"),
      number("tool", "corner_radius", "mm", non_negative(), FIELD(tool.corner_radius_mm),
             "corner radius (0: square end mill; at most D/2)"),
      number("tool", "dish_angle", "degrees", Range{0, 10, true, false}, FIELD(tool.dish_angle_deg),
             "the end edges' dish (concavity) angle: each end edge rises by it from the corner "
             "towards the axis (0: a flat end face; the floor's predicted texture)"),
      number("tool", "edge_radius", "mm", non_negative(), FIELD(tool.edge_radius_mm),
             "cutting-edge rounding radius r_e (below D/10)"),
      number("tool", "flute_length", "mm", non_negative(), FIELD(tool.flute_length_mm),
             "flute length, the edge's axial reach (0: not given; the simulation then reaches 1 mm "
             "above the slot)"),
      number("tool", "runout_radial", "mm", non_negative(), FIELD(tool.runout_radial_mm),
             "radial runout: the axis offset e"),
      number("tool", "runout_axial", "mm", non_negative(), FIELD(tool.runout_axial_mm),
             "axial runout"),
      number("tool", "runout_phase", "degrees", Range{-360, 360}, FIELD(tool.runout_phase_deg),
             "angle of the runout offset from tooth 0; the tooth at this angle cuts the largest "
             "radius and sits lowest"),
      integer("tool", "tool_number", 0, 9999, FIELD(tool.tool_number), "T word"),
      custom("tool", "tooth_angles", "array of numbers", "degrees",
             "strictly increasing in [0, 360), one per tooth", "equal pitches",
             "tooth angular positions (variable pitch)",
             [](JobReader& r, Job& job) {
               Tool& tool = job.tool;
               auto angles = r.number_array("tool", "tooth_angles", Range{0, 360, true, false});
               if (!angles) return;
               if (tool.teeth > 0 && static_cast<int>(angles->size()) != tool.teeth) {
                 r.problem("tool", "tooth_angles",
                           fmt::format("must list one angle per tooth ({} values for teeth = "
                                       "{}), got {}",
                                       tool.teeth, tool.teeth, angles->size()));
               } else if (!std::is_sorted(angles->begin(), angles->end()) ||
                          std::adjacent_find(angles->begin(), angles->end()) != angles->end()) {
                 r.problem("tool", "tooth_angles",
                           "must be strictly increasing degrees in [0, 360)");
               } else {
                 tool.tooth_angles_deg = *angles;
               }
             }),
      choice("tool", "type", kToolTypes, FIELD(tool.type),
             "solid end mill, or indexable insert mill (the teeth are the inserts)"),
      number("tool", "lead_angle", "degrees", Range{0, 90, false, true}, FIELD(tool.lead_angle_deg),
             "insert mill: the main edge's angle to the face; 90 is a shoulder mill, less runs "
             "the edge inward (face mill)"),
      custom("tool", "insert_radial", "array of numbers", "mm", "in [-1, 1], one per insert",
             "none", "insert mill: each insert's radial seating, added to the runout",
             [](JobReader& r, Job& job) {
               read_insert_array(r, job, "insert_radial", job.tool.insert_radial_mm);
             }),
      custom("tool", "insert_axial", "array of numbers", "mm", "in [-1, 1], one per insert", "none",
             "insert mill: each insert's axial seating (positive: lower)",
             [](JobReader& r, Job& job) {
               read_insert_array(r, job, "insert_axial", job.tool.insert_axial_mm);
             }),
      number("tool", "flank_wear", "mm", non_negative(), FIELD(tool.flank_wear_mm),
             "flank wear land VB_B (0: new tool); the mechanism commands then use the "
             "wear-corrected K_re"),
      // [geometry]
      custom("geometry", "file", "string", "", "a .dxf or .svg file", "none",
             "the drawing the part's contours come from (relative to the job file)",
             [](JobReader& r, Job& job) {
               if (auto v = r.string("geometry", "file")) {
                 if (v->empty()) {
                   r.problem("geometry", "file", "give the drawing's file name");
                 } else {
                   job.geometry.file = *v;
                 }
               }
             }),
      number("geometry", "join_tolerance", "mm", Range{1e-6, 100},
             FIELD(geometry.join_tolerance_mm),
             "ends of the drawing's lines, arcs and curves closer than this are one point"),
      custom("geometry", "units", "string", "", "mm, cm, m, in or ft", "none",
             "the unit of a DXF drawing that gives none (no $INSUNITS, or 0); without it such "
             "a drawing is read as mm, with a warning",
             [](JobReader& r, Job& job) {
               if (auto v = r.string("geometry", "units")) {
                 if (drawing_unit_mm(*v)) {
                   job.geometry.units_name = *v;
                 } else {
                   r.problem(
                       "geometry", "units",
                       fmt::format("'{}' is no unit trochomill reads: mm, cm, m, in or ft", *v));
                 }
               }
             }),
      // [slot]
      number("slot", "width", "mm", positive(), FIELD(slot.width_mm),
             "slot width W along X, >= D (> D for the trochoidal families)", true),
      custom("slot", "along", "string", "", "a layer (or SVG id) of [geometry] file", "none",
             "the slot's centreline: the one open or closed contour on this layer of the "
             "drawing (the slot is every point within W/2 of it); none: a straight slot along +Y",
             [](JobReader& r, Job& job) { read_layer(r, "slot", "along", job.slot.along); }),
      custom("slot", "max_step_down", "number", "mm", "in [0.001, 1e5]", "the whole depth",
             "a slot along a contour is cut in levels of equal depth, each at most this deep, "
             "each entered by [path] entry",
             [](JobReader& r, Job& job) {
               if (auto v = r.number("slot", "max_step_down", "mm", Range{1e-3, kMaxLengthMm})) {
                 if (along_only(r, "max_step_down",
                                "levels are planned for a slot along a drawing's contour "
                                "([slot] along); a straight slot is cut at its whole depth")) {
                   job.slot.max_step_down_mm = *v;
                 }
               }
             }),
      custom("slot", "finish_allowance", "number", "mm", ">= 0, below (W - D) / 2", "0",
             "a slot along a contour: the stock its cycles leave on the walls (their orbit "
             "narrowed by it), for the finishing pass",
             [](JobReader& r, Job& job) {
               if (auto v = r.number("slot", "finish_allowance", "mm", non_negative())) {
                 if (along_only(r, "finish_allowance",
                                "is for a slot along a drawing's contour ([slot] along)")) {
                   job.slot.finish_allowance_mm = *v;
                 }
               }
             }),
      custom("slot", "finish_pass", "boolean", "", "true or false", "false",
             "a slot along a contour: after its levels, one pass along its walls at full depth "
             "(climb or conventional as [path] direction)",
             [](JobReader& r, Job& job) {
               if (auto v = r.boolean("slot", "finish_pass")) {
                 if (along_only(r, "finish_pass",
                                "is for a slot along a drawing's contour ([slot] along)")) {
                   job.slot.finish_pass = *v;
                 }
               }
             }),
      // [pocket]
      custom("pocket", "boundary", "string", "", "a layer (or SVG id) of [geometry] file",
             "required (a pocket)",
             "the pocket's walls: the closed contours on this layer of the drawing (several "
             "apart: several pockets; nested: the pocket is inside an odd number of them, an "
             "outline's holes are islands); a job gives [slot] or [pocket]",
             [](JobReader& r, Job& job) {
               if (!r.has_section("pocket")) return;
               read_layer(r, "pocket", "boundary", job.pocket.boundary,
                          "the drawing's layer of the pocket's walls");
             }),
      custom(
          "pocket", "islands", "string", "", "a layer (or SVG id) of [geometry] file", "none",
          "the islands left standing: the closed contours on this layer, each inside a "
          "boundary, none touching another",
          [](JobReader& r, Job& job) { read_layer(r, "pocket", "islands", job.pocket.islands); }),
      custom("pocket", "depth", "number", "mm", "> 0", "required (a pocket)",
             "the pocket's floor below the top face z = 0",
             [](JobReader& r, Job& job) {
               if (!r.has_section("pocket")) return;
               job.pocket.depth_mm =
                   r.number("pocket", "depth", "mm", Range{0, kMaxLengthMm, false}, 0.0, true)
                       .value_or(0.0);
             }),
      number("pocket", "max_step_down", "mm", Range{1e-3, kMaxLengthMm},
             FIELD(pocket.max_step_down_mm),
             "the pocket is cleared in levels of equal depth, each at most this deep (0: one "
             "level)"),
      number("pocket", "stock_to_leave", "mm", Range{0, 100}, FIELD(pocket.stock_to_leave_mm),
             "what the clearing leaves on walls and islands for the finishing pass"),
      number("pocket", "max_engagement", "degrees", Range{0, 180, false},
             FIELD(pocket.max_engagement_deg),
             "the clearing's largest engagement (arc of the tool in the material) once in the "
             "pocket, entries excepted; give this or max_chip"),
      number("pocket", "max_chip", "mm", positive(), FIELD(pocket.max_chip_mm),
             "the target as a side cut's largest chip, below f_z: the engagement target is "
             "then asin(max_chip / f_z) (where the tool turns into the stock the chip may reach "
             "f_z: `plan` prints the largest); give this or max_engagement"),
      custom("pocket", "finish_pass", "boolean", "", "true or false", "true",
             "after the levels, one pass along walls and islands at full depth (climb or "
             "conventional as [path] direction)",
             [](JobReader& r, Job& job) {
               if (auto v = r.boolean("pocket", "finish_pass")) job.pocket.finish_pass = *v;
             }),
      number("pocket", "fit_tolerance", "mm", Range{1e-4, 0.005}, FIELD(pocket.fit_tolerance_mm),
             "the clearing path is written as arcs and lines within this of the planned points "
             "(the walls are kept this much further away); at most 0.005 mm: a looser fit moves "
             "the path off the points checked and the target no longer holds (0.1 mm: 63 "
             "degrees for 53)"),
      number("pocket", "channel_width", "mm", Range{0, 1e4}, FIELD(pocket.channel_width_mm),
             "parts of the pocket narrower than this are channels, cleared by trochoidal loops "
             "along their medial axis (each loop as wide as the channel there, each step the "
             "largest that holds the target); 0: twice the tool's diameter. Parts narrower "
             "than D + 2 stock_to_leave + R / 2, where the clearing passes do not go, always "
             "are"),
      custom("pocket", "rest_of", "string", "", "an NC program file", "none",
             "rest machining: the program an earlier tool cleared the pocket with (relative "
             "to the job file); its remaining material is the stock, and only what it left "
             "gets a path",
             [](JobReader& r, Job& job) {
               if (auto f = r.string("pocket", "rest_of")) {
                 if (f->empty()) {
                   r.problem("pocket", "rest_of", "names a program file; got an empty string");
                   return;
                 }
                 const std::filesystem::path fp(*f);
                 job.pocket.rest_of = *f;
                 job.pocket.rest_of_path =
                     fp.is_absolute() ? fp : std::filesystem::path(r.source()).parent_path() / fp;
               }
             }),
      // At most 1 m: the earlier tool's sweep is a grid of discs of this job's radius over the
      // region within the difference of the radii of its moves (1 m: 7 s on a test pocket).
      number("pocket", "rest_tool_diameter", "mm", Range{1e-3, 1000},
             FIELD(pocket.rest_tool_diameter_mm),
             "the diameter of rest_of's tool, a flat end mill at least as wide as this job's "
             "(0: the program header's tool.diameter, as trochomill writes it)"),
      custom("pocket", "entry_holes", "array of [x, y]", "mm", "points the tool centre may reach",
             "none",
             "pre-drilled holes, each at least the tool's diameter and through the depth: a "
             "part of the pocket holding one is entered by feeding straight down it (the first "
             "listed in the part) instead of a helix",
             [](JobReader& r, Job& job) {
               const toml::node* n = r.find("pocket", "entry_holes");
               if (n == nullptr) return;
               const toml::array* arr = n->as_array();
               if (arr == nullptr) {
                 r.problem("pocket", "entry_holes",
                           "expected an array of [x, y] points in mm, e.g. [[20, 15], [60, 30]]");
                 return;
               }
               for (std::size_t i = 0; i < arr->size(); ++i) {
                 const toml::array* xy = arr->get(i)->as_array();
                 const bool ok = xy != nullptr && xy->size() == 2 && xy->get(0)->is_number() &&
                                 xy->get(1)->is_number();
                 const double x = ok ? xy->get(0)->value<double>().value_or(0) : 0;
                 const double y = ok ? xy->get(1)->value<double>().value_or(0) : 0;
                 if (!ok || !(std::abs(x) <= kMaxLengthMm && std::abs(y) <= kMaxLengthMm)) {
                   r.problem("pocket", "entry_holes",
                             fmt::format("hole {} (counting from 1) must be a point [x, y] "
                                         "of finite numbers within +-{:g} mm, e.g. [[20, 15], "
                                         "[60, 30]]",
                                         i + 1, kMaxLengthMm));
                   return;
                 }
                 job.pocket.entry_holes_mm.emplace_back(x, y);
               }
             }),
      custom("slot", "length", "number", "mm", "> 0", "required (none with along)",
             "slot length along +Y (a slot along a drawing's contour has the contour's length)",
             [](JobReader& r, Job& job) {
               const bool along = r.has("slot", "along");
               if (along && r.has("slot", "length")) {
                 r.problem("slot", "length",
                           "a slot along a drawing's contour has the contour's length; remove "
                           "[slot] length (or along)");
                 return;
               }
               job.slot.length_mm = r.number("slot", "length", "mm", positive(), 0.0,
                                             !along && !pocket_waives(r, "slot"))
                                        .value_or(0.0);
             }),
      number("slot", "depth", "mm", positive(), FIELD(slot.depth_mm),
             "slot depth a_p below the top face z = 0", true),
      number("slot", "origin_x", "mm", Range{-kMaxLengthMm, kMaxLengthMm}, FIELD(slot.origin_x_mm),
             "workpiece X (in the work offset) of the slot frame's origin: the middle of the "
             "slot's start"),
      number("slot", "origin_y", "mm", Range{-kMaxLengthMm, kMaxLengthMm}, FIELD(slot.origin_y_mm),
             "workpiece Y of the slot frame's origin"),
      number("slot", "angle", "degrees", Range{-360, 360}, FIELD(slot.angle_deg),
             "direction the slot runs in the workpiece: its +Y turned this far from +Y, "
             "counter-clockwise seen from above (90: along -X)"),
      // [path]
      choice("path", "type", kPathTypes, FIELD(path.type),
             "path family (docs/models.md section 2); with [pocket], the family that clears its "
             "channels (not linear; none: circular loops about the medial axis' points)",
             true),
      custom(
          "path", "step", "number", "mm", "> 0, below the tool diameter",
          "required (linear: when W > D)",
          "trochoidal step s (advance per cycle), below D; for linear the stepover between passes",
          [](JobReader& r, Job& job) {
            const bool needs_step =
                !pocket_waives(r, "path") &&
                (job.path.type != PathType::linear || job.slot.width_mm > job.tool.diameter_mm);
            job.path.step_mm =
                r.number("path", "step", "mm", positive(), 0.0, needs_step).value_or(0.0);
          }),
      number("path", "aspect_ratio", "(b/a)", positive(), FIELD(path.aspect_ratio),
             "r_e = b / a for elliptical and linear-elliptical (trochoidal is r_e = 1); slots and "
             "a pocket's channels"),
      number("path", "linear_distance", "mm", non_negative(), FIELD(path.linear_distance_mm),
             "d, the straight wall moves of linear-elliptical; slots and a pocket's channels"),
      choice(
          "path", "direction", kDirections, FIELD(path.direction),
          "milling direction: climb orbits counter-clockwise with a cw spindle (G3), conventional "
          "mirrors it"),
      choice("path", "entry", kEntries, FIELD(path.entry),
             "outside: open slot start, feed in from y < 0 at depth; helix, ramp, plunge: closed "
             "start"),
      number("path", "entry_radius", "mm", non_negative(), FIELD(path.entry_radius_mm),
             "helix radius (0: half the largest that fits)"),
      number("path", "entry_pitch", "mm per turn", positive(), FIELD(path.entry_pitch_mm),
             "helix descent per turn"),
      number("path", "entry_angle", "degrees", Range{0, 90, false, false},
             FIELD(path.entry_angle_deg), "ramp angle"),
      number("path", "entry_feed", "mm/min", non_negative(), FIELD(path.entry_feed_mm_per_min),
             "feed of the entry moves (0: half the feed)"),
      number(
          "path", "clearance", "mm", non_negative(), FIELD(path.clearance_mm),
          "height above the top face where feeding starts; distance kept from the stock outside"),
      // [cutting]: the pairs are checked and completed after the table.
      number("cutting", "feed_rate", "mm/min", positive(), FIELD(cutting.feed_rate_mm_per_min),
             "f_r, tool-centre feed (or feed_per_tooth)"),
      number("cutting", "spindle_speed", "rpm", positive(), FIELD(cutting.spindle_speed_rpm),
             "n (or cutting_speed)"),
      number("cutting", "feed_per_tooth", "mm", positive(), FIELD(cutting.feed_per_tooth_mm),
             "f_z = f_r / (n Z) (or feed_rate)"),
      number("cutting", "cutting_speed", "m/min", positive(),
             FIELD(cutting.cutting_speed_m_per_min), "v_c = pi D n / 1000 (or spindle_speed)"),
      choice("cutting", "spindle_direction", kSpindleDirections, FIELD(cutting.spindle_direction),
             "spindle rotation seen from above: cw = M3, ccw = M4"),
      choice("cutting", "coolant", kCoolants, FIELD(cutting.coolant),
             "coolant: flood = M8, mist = M7"),
      // [machine]
      choice("machine", "dialect", kDialects, FIELD(machine.dialect), "control of the program"),
      number("machine", "safe_z", "mm above the top face", positive(), FIELD(machine.safe_z_mm),
             "retract height above the top face"),
      number("machine", "rapid_rate", "mm/min", positive(), FIELD(machine.rapid_rate_mm_per_min),
             "rapid traverse rate (G0), for time estimates and G-code read back"),
      number("machine", "max_acceleration", "mm/s^2", non_negative(),
             FIELD(machine.max_acceleration_mm_per_s2),
             "path acceleration limit for time estimates (0: unlimited)"),
      number("machine", "max_feed", "mm/min", non_negative(), FIELD(machine.max_feed_mm_per_min),
             "fastest feed a feed schedule may program (0: three times the job's feed)"),
      number("machine", "min_feed", "mm/min", non_negative(), FIELD(machine.min_feed_mm_per_min),
             "slowest feed a feed schedule may program (0: a tenth of the job's feed)"),
      number("machine", "air_feed", "mm/min", non_negative(), FIELD(machine.air_feed_mm_per_min),
             "feed a schedule programs where the tool cuts nothing (0: the max feed)"),
      number("machine", "junction_deviation", "mm", non_negative(),
             FIELD(machine.junction_deviation_mm), "corner blending tolerance for time estimates"),
      number("machine", "arc_tolerance", "mm", Range{1e-6, 1.0}, FIELD(machine.arc_tolerance_mm),
             "largest deviation of fitted arcs or chords from the path"),
      choice("machine", "arc_output", kArcOutputs, FIELD(machine.arc_output),
             "elliptical arcs as biarcs (G2/G3) or as G1 chords"),
      integer("machine", "program_number", 1, 9999, FIELD(machine.program_number),
              "Fanuc O number"),
      choice("machine", "work_offset", kWorkOffsets, FIELD(machine.work_offset),
             "work coordinate system the program selects (sinumerik: G54 .. G57)"),
      integer("machine", "length_offset", 0, 9999, FIELD(machine.length_offset),
              "tool length offset register H of G43 (linuxcnc, fanuc; 0: the tool number)"),
      custom("machine", "tool_table", "string", "", "a LinuxCNC tool table file", "none",
             "tool lengths for G43 when reading programs (T1 P1 Z<length> D<diameter>, mm; "
             "relative to the job file)",
             [](JobReader& r, Job& job) {
               if (auto f = r.string("machine", "tool_table")) {
                 const std::filesystem::path fp(*f);
                 job.machine.tool_table =
                     fp.is_absolute() ? fp : std::filesystem::path(r.source()).parent_path() / fp;
               }
             }),
      machine_position(
          "g28_position",
          "G28's position in machine coordinates, for reading programs (default: X0 "
          "Y0 of the work system at safe_z)",
          [](Job & j) -> auto& { return j.machine.g28_position_mm; }),
      machine_position(
          "g30_position",
          "G30's position in machine coordinates, for reading programs (default: as "
          "G28's)",
          [](Job & j) -> auto& { return j.machine.g30_position_mm; }),
      machine_position(
          "origin_g54",
          "G54's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[0]; }),
      machine_position(
          "origin_g55",
          "G55's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[1]; }),
      machine_position(
          "origin_g56",
          "G56's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[2]; }),
      machine_position(
          "origin_g57",
          "G57's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[3]; }),
      machine_position(
          "origin_g58",
          "G58's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[4]; }),
      machine_position(
          "origin_g59",
          "G59's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[5]; }),
      machine_position(
          "origin_g59_1",
          "G59.1's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[6]; }),
      machine_position(
          "origin_g59_2",
          "G59.2's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[7]; }),
      machine_position(
          "origin_g59_3",
          "G59.3's origin in machine coordinates, for reading programs that use it "
          "(default: the work_offset system's)",
          [](Job & j) -> auto& { return j.machine.origins_mm[8]; }),
      // [measured]
      number("measured", "force_max", "N", positive(), FIELD(measured.force_max_n),
             "measured maximum resultant force F_R,max"),
      number("measured", "roughness_ra", "um", positive(), FIELD(measured.roughness_ra_um),
             "measured maximum roughness Ra"),
      number("measured", "waviness", "um", positive(), FIELD(measured.waviness_um),
             "measured maximum wall waviness W_max"),
      // [mechanism]
      number("mechanism", "czi_max", "% of r_e", positive(),
             FIELD(mechanism.thresholds.czi_max_pct), "K_re below this: CZI (ploughing)"),
      number("mechanism", "czii_max", "% of r_e", positive(),
             FIELD(mechanism.thresholds.czii_max_pct),
             "K_re below this: CZII (mixed shear); above: CZIII (cutting); > czi_max"),
      number("mechanism", "transition", "% of r_e", positive(),
             FIELD(mechanism.thresholds.transition_pct),
             "marker where the acoustic ratio k_f crosses 1"),
      number("mechanism", "share", "fraction", Range{0.0, 1.0, false, true}, FIELD(mechanism.share),
             "required CZIII share for `recommend`, of what share_of says"),
      choice("mechanism", "share_of", kSharesOf, FIELD(mechanism.share_of),
             "what share is a share of: cutting (the time in the cut) or cycle (the whole "
             "cycle, cooling included: Pivkin 2025's reading)"),
      choice("mechanism", "criterion", kCriteria, FIELD(mechanism.criterion),
             "what `recommend` asks of a step: cziii (at least share of CZIII) or plunger (at "
             "most plunger_share of the cut's first half in CZI: Pivkin 2025's criterion)"),
      number("mechanism", "plunger_share", "fraction", Range{0.0, 1.0, true, false},
             FIELD(mechanism.plunger_share),
             "criterion = plunger: the largest share of the first half of the cutting part in "
             "CZI (ploughing, the plunger mechanism)"),
      choice("mechanism", "model", kChipModels, FIELD(mechanism.model),
             "chip model: exact, or pivkin2025, the published model (circular trochoid only; "
             "docs/models.md section 9)"),
      integer("mechanism", "points", 36, 1000000, FIELD(mechanism.points),
              "theta samples per cycle"),
      number("material", "friction_angle", "degrees", Range{0.0, 90.0, false, false},
             FIELD(mechanism.friction_angle_deg),
             "friction angle theta_m for the mechanism model: h_m = r_e (1 - cos theta_m) (0: not "
             "given)"),
      // [monitor]
      number("monitor", "low_min", "Hz", positive(), FIELD(monitor.low_min_hz),
             "low band, lower -3 dB edge"),
      number("monitor", "low_max", "Hz", positive(), FIELD(monitor.low_max_hz),
             "low band, upper -3 dB edge"),
      number("monitor", "high_min", "Hz", positive(), FIELD(monitor.high_min_hz),
             "high band, lower edge"),
      number("monitor", "high_max", "Hz", positive(), FIELD(monitor.high_max_hz),
             "high band, upper edge"),
      integer("monitor", "order", 1, 12, FIELD(monitor.order),
              "Butterworth order of each band (the band-pass has twice the poles)"),
      number("monitor", "window", "s", Range{1e-5, 10.0}, FIELD(monitor.window_s),
             "RMS window (and hop)"),
      integer("monitor", "baseline_cycles", 1, 1000, FIELD(monitor.baseline_cycles),
              "wear: cycles whose k_f level is the reference"),
      number("monitor", "wear_ratio", "ratio", Range{1.0, 100.0, false, true},
             FIELD(monitor.wear_ratio),
             "wear flagged where the k_f level exceeds the reference by this"),
      number("monitor", "ploughing_ratio", "ratio", Range{1.0, 100.0, false, true},
             FIELD(monitor.ploughing_ratio),
             "ploughing flagged where k_f in CZI exceeds CZIII's by this"),
      integer("monitor", "phase_bins", 4, 10000, FIELD(monitor.phase_bins),
              "k_f profile bins over a cycle"),
      choice("monitor", "criteria", kKfCriteria, FIELD(monitor.criteria),
             "with a job, the k_f ranges each cycle is judged against per zone and half of the "
             "cut: pivkin2025 (Pivkin 2025 Figs. 21 and 24, new and worn tool) or none"),
      // [simulation]
      number("simulation", "resolution", "mm", Range{1e-4, 10.0}, FIELD(simulation.resolution_mm),
             "dexel spacing of the three boards (Bergmann 2021: 0.005)"),
      integer("simulation", "steps_per_rev", 8, 100000, FIELD(simulation.steps_per_rev),
              "time steps per spindle revolution"),
      number("simulation", "chip_sampling", "mm", Range{1e-5, 1.0},
             FIELD(simulation.chip_sampling_mm),
             "resolution of a chip: thinner ones are not recorded as engagement"),
      number("simulation", "segment", "mm", Range{1e-3, 10.0}, FIELD(simulation.segment_mm),
             "edge segment length along the edge (kappa)"),
      integer("simulation", "sub_segments", 1, 100, FIELD(simulation.sub_segments),
              "sub-segments inward (tau), for wear topography"),
      integer("simulation", "threads", 0, 1024, FIELD(simulation.threads),
              "worker threads (0: all cores); results are the same for any count"),
      // [stock]
      custom("stock", "min", "array of numbers", "mm", "[x, y, z], below max", "the slot region",
             "lower corner of the stock box (give min and max) in the work offset's "
             "coordinates, the frame of the job's G-code: the simulation's workpiece and, "
             "given, the engagement's stock (x, y range, below the top); by default the slot "
             "from y = 0 to its length (1 mm beside each wall and 0.5 mm below the floor for "
             "the simulation), up to z = 0",
             [](JobReader& r, Job& job) {
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
                   job.stock_min_mm = Vec3((*lo)[0], (*lo)[1], (*lo)[2]);
                   job.stock_max_mm = Vec3((*hi)[0], (*hi)[1], (*hi)[2]);
                 }
               }
             }),
      custom("stock", "max", "array of numbers", "mm", "[x, y, z], above min", "the slot region",
             "upper corner of the stock box (read with min); `plan` refuses a top above z = 0, "
             "where its rapids come down",
             [](JobReader&, Job&) {}),
      custom("stock", "mesh", "string", "", "an STL, PLY or OBJ file", "none",
             "a pocket's stock as a closed triangle mesh (mm, in the drawing's frame, relative "
             "to the job file; instead of min and max): a casting, a cored or stepped blank. "
             "The planner clears only where it stands (comes down beside it where it can), "
             "and the proof, analyze and simulate take it as the stock",
             [](JobReader& r, Job& job) {
               if (auto f = r.string("stock", "mesh")) {
                 if (f->empty()) {
                   r.problem("stock", "mesh", "names a mesh file; got an empty string");
                   return;
                 }
                 if (!r.has_section("pocket")) {
                   r.problem("stock", "mesh",
                             "is read by pocket jobs ([pocket]); a slot's stock mesh is given to "
                             "optimize-feed --stock");
                   return;
                 }
                 if (r.has("stock", "min") || r.has("stock", "max")) {
                   r.problem("stock", "mesh",
                             "give the stock as a box (min and max) or as a mesh, not both");
                   return;
                 }
                 const std::filesystem::path fp(*f);
                 job.stock_mesh_file = *f;
                 job.stock_mesh_path =
                     fp.is_absolute() ? fp : std::filesystem::path(r.source()).parent_path() / fp;
               }
             }),
      // [analysis]
      integer("analysis", "steps_per_tooth", 1, 64, FIELD(analysis.steps_per_tooth),
              "engagement samples per tooth pass (the chip spans that many)"),
      integer("analysis", "imprint_points", 3, 10001, FIELD(analysis.imprint_points),
              "points across the slot width for the floor imprint density"),
  };
  for (Key& k : material_keys()) keys.push_back(std::move(k));
  const std::vector<Key> rest = {
      // [forces]
      integer("forces", "fast_steps_per_rev", 8, 100000, FIELD(forces.fast_steps_per_rev),
              "time steps per revolution of the fast chip source (the fast forces, analyze's "
              "predicted force); calibration uses at least 500 per tooth pass"),
      number("forces", "ploughing_angle", "degrees", Range{0.0, 90.0, false, false},
             FIELD(forces.ploughing_angle_deg),
             "zeta: sub-segments steeper than this to the cutting direction form the ploughing "
             "surrogate h_s"),
      // [topography]: file names relative to the job file's directory.
      custom("topography", "files", "array of strings", "", "STL, PLY or OBJ files", "none",
             "meshes of the insert or tooth, one per wear state (mm, tooth frame: x radial, y "
             "cutting direction, z axial; paths relative to the job file)",
             [](JobReader& r, Job& job) {
               if (auto files = r.string_array("topography", "files")) {
                 const std::filesystem::path base = std::filesystem::path(r.source()).parent_path();
                 for (const auto& f : *files) {
                   const std::filesystem::path fp(f);
                   job.topography.files.push_back(fp.is_absolute() ? fp : base / fp);
                 }
               }
             }),
      custom("topography", "synthetic_vb", "array of numbers", "mm", "in [0, 2]", "none",
             "or synthetic inserts, one per flank wear land width VB (0: new; hone radius [tool] "
             "edge_radius, default 0.02 mm); not with files",
             [](JobReader& r, Job& job) {
               if (auto vb = r.number_array("topography", "synthetic_vb", Range{0.0, 2.0})) {
                 job.topography.synthetic_vb_mm = *vb;
               }
               if (!job.topography.files.empty() && !job.topography.synthetic_vb_mm.empty()) {
                 r.problem("topography", "synthetic_vb", "give files or synthetic_vb, not both");
               }
             }),
      number("topography", "band", "mm", Range{1e-3, 5.0}, FIELD(topography.band_mm),
             "band along the edge that is sampled into the sub-segments"),
      number("topography", "rake", "degrees", Range{-30.0, 30.0}, FIELD(topography.rake_deg),
             "synthetic insert: rake angle"),
      number("topography", "clearance", "degrees", Range{1.0, 30.0},
             FIELD(topography.clearance_deg), "synthetic insert: clearance angle"),
      custom(
          "topography", "state", "integer", "", "in [0, states - 1]",
          fmt::format("{}", TopographySettings{}.state),
          "the wear state used (index into files or synthetic_vb)",
          [](JobReader& r, Job& job) {
            const int states = static_cast<int>(job.topography.states());
            int& state = job.topography.state;
            state =
                r.integer("topography", "state", 0, std::max(0, states - 1), state).value_or(state);
          }),
  };
  for (const Key& k : rest) keys.push_back(k);
  return keys;
}

#undef FIELD

}  // namespace

const std::vector<Key>& schema() {
  static const std::vector<Key> keys = build_schema();
  return keys;
}

const std::map<std::string, std::vector<std::string>>& schema_sections() {
  static const std::map<std::string, std::vector<std::string>> sections = [] {
    std::map<std::string, std::vector<std::string>> m;
    for (const Key& k : schema()) m[k.section].push_back(k.key);
    return m;
  }();
  return sections;
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

void read_material_section(JobReader& r, Material& m) {
  Job holder;
  holder.material = std::move(m);
  for (const Key& k : schema()) {
    if (std::string_view(k.section) == "material" && std::string_view(k.key) != "name" &&
        std::string_view(k.key) != "friction_angle") {
      k.read(r, holder);
    }
  }
  m = std::move(holder.material);
}

namespace {

// The rules of the sections that stand alone (a band's edges, the zone thresholds).
void check_settings_rules(JobReader& r, const Job& job) {
  const MechanismSettings& mj = job.mechanism;
  if (mj.thresholds.czii_max_pct <= mj.thresholds.czi_max_pct) {
    r.problem("mechanism", "czii_max",
              fmt::format("must be greater than czi_max ({}), got {}",
                          fmt_num(mj.thresholds.czi_max_pct), fmt_num(mj.thresholds.czii_max_pct)));
  }
  const MonitorSettings& mo = job.monitor;
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
}

// `[slot] along`: the drawing read (relative to the job file), its one contour on the layer
// The job's drawing ([geometry] file, relative to the job file) with only `layers`; none
// (and the problem recorded on [geometry] file) when it cannot be read.
std::optional<Drawing> read_job_drawing(JobReader& r, Job& job, std::vector<std::string> layers) {
  const std::filesystem::path file(job.geometry.file);
  job.geometry.path =
      file.is_absolute() ? file : std::filesystem::path(r.source()).parent_path() / file;
  DrawingOptions options;
  options.join_tolerance_mm = job.geometry.join_tolerance_mm;
  options.arc_tolerance_mm = job.machine.arc_tolerance_mm;
  options.layers = std::move(layers);
  options.unitless_unit = job.geometry.units_name;
  try {
    Drawing d = read_drawing(job.geometry.path, options);
    job.geometry.units = d.units;
    return d;
  } catch (const InputError& e) {
    r.problem("geometry", "file", e.what());
    return std::nullopt;
  }
}

// the centreline, checked for what a slot along it needs: no corner, no bend tighter than
// W/2, no crossing of itself. The slot's length becomes the contour's and, without a [stock]
// box, the stock is the box around the slot (1 mm beside it, 0.5 mm below its floor).
void check_centreline(JobReader& r, Job& job) {
  Slot& slot = job.slot;
  if (slot.along.empty()) return;
  if (job.geometry.file.empty()) {
    r.problem("slot", "along", "names a layer of a drawing: give [geometry] file");
    return;
  }
  for (const char* key : {"origin_x", "origin_y", "angle"}) {
    if (r.has("slot", key)) {
      r.problem("slot", key,
                "places a straight slot; a slot along a drawing's contour is where the drawing "
                "puts it (move the contour in the drawing)");
    }
  }
  if (!r.problems().empty()) return;
  const auto read = read_job_drawing(r, job, {slot.along});
  if (!read) return;
  Drawing drawing = std::move(*read);
  if (drawing.contours.size() != 1) {
    r.problem("slot", "along",
              fmt::format("layer '{}' of {} holds {} contours; a slot's centreline is one (put "
                          "the others on other layers)",
                          slot.along, job.geometry.file, drawing.contours.size()));
    return;
  }
  DrawnContour centre = std::move(drawing.contours.front());
  const Contour& c = centre.contour;
  const double half_width = 0.5 * slot.width_mm;
  const auto where = [](const Vec2& p) { return fmt::format("({:.4f}, {:.4f})", p.x(), p.y()); };
  // The tightest bend (one message, however many arcs are too tight).
  const ContourPiece* tightest = nullptr;
  int too_tight = 0;
  for (const ContourPiece& p : c.pieces) {
    if (p.is_arc() && p.radius_mm() < half_width) {
      ++too_tight;
      if (tightest == nullptr || p.radius_mm() < tightest->radius_mm()) tightest = &p;
    }
  }
  if (tightest != nullptr) {
    r.problem("slot", "along",
              fmt::format("layer '{}' bends on a radius of {} mm at {} (the tightest of {} "
                          "arcs), tighter than the slot's half width ({} mm): the inner wall "
                          "would fold; widen the bend to at least W/2",
                          slot.along, fmt_num(tightest->radius_mm()),
                          where(tightest->point_at(0.5)), too_tight, fmt_num(half_width)));
  }
  for (std::size_t i = 0; i < c.pieces.size(); ++i) {
    const ContourPiece& p = c.pieces[i];
    // Tangent turns between pieces: the loops follow the centreline's normal, which a corner
    // breaks. Drawings' chained entities meet within 0.06 degrees (1e-3 rad) when tangent.
    if (i + 1 < c.pieces.size() || c.closed) {
      const ContourPiece& q = c.pieces[(i + 1) % c.pieces.size()];
      const Vec2 t0 = p.tangent_at(1), t1 = q.tangent_at(0);
      const double turn = std::atan2(t0.x() * t1.y() - t0.y() * t1.x(), t0.dot(t1));
      if (std::abs(turn) > 1e-3) {
        r.problem("slot", "along",
                  fmt::format("layer '{}' has a corner at {} (the direction turns by {:.3g} "
                              "degrees): a slot's centreline must be smooth; round the corner "
                              "with an arc of radius at least W/2 = {} mm",
                              slot.along, where(p.end), turn * 180 / M_PI, fmt_num(half_width)));
      }
    }
  }
  if (const auto cross = contour_self_crossing(c)) {
    r.problem("slot", "along",
              fmt::format("layer '{}' crosses itself at {}: a slot's centreline must not",
                          slot.along, where(*cross)));
  }
  const double orbit = 0.5 * (slot.width_mm - job.tool.diameter_mm);
  if (slot.finish_allowance_mm > 0 && !(slot.finish_allowance_mm < orbit)) {
    r.problem("slot", "finish_allowance",
              fmt::format("must be below the orbit's half width (W - D) / 2 = {} mm, got {}",
                          fmt_num(orbit), fmt_num(slot.finish_allowance_mm)));
  }
  if (!r.problems().empty()) return;
  slot.length_mm = c.length_mm();
  if (!job.stock_min_mm) {
    Box3 box;
    for (const Vec2& p : c.points(1e-3)) box.extend(Vec3(p.x(), p.y(), 0));
    const double m = half_width + 1.0;
    job.stock_min_mm = Vec3(box.lo.x() - m, box.lo.y() - m, -slot.depth_mm - 0.5);
    job.stock_max_mm = Vec3(box.hi.x() + m, box.hi.y() + m, 0);
  }
  slot.centreline = std::make_shared<const DrawnContour>(std::move(centre));
}

// [pocket]: one of the engagement targets, the drawing's closed contours on the boundary and
// island layers, the islands inside the boundaries and apart, the boundaries apart. Without a
// [stock] box the stock is the box around the boundaries down to 0.5 mm below the floor.
void check_pocket(JobReader& r, Job& job) {
  if (!r.has_section("pocket")) return;
  Pocket& pk = job.pocket;
  if (r.has_section("slot")) {
    r.problems().push_back(fmt::format(
        "{}: [slot] and [pocket]: a job plans a slot or a pocket; remove one", r.source()));
  }
  const bool by_angle = r.has("pocket", "max_engagement"), by_chip = r.has("pocket", "max_chip");
  if (by_angle && by_chip) {
    r.problem("pocket", "max_chip", "give max_engagement (degrees) or max_chip (mm), not both");
  } else if (!by_angle && !by_chip) {
    r.problems().push_back(fmt::format(
        "{}: missing [pocket] max_engagement (degrees) or max_chip (mm): give one", r.source()));
  }
  if (r.has("path", "step")) {
    r.problem("path", "step",
              "is for slots; a pocket's steps are planned from its engagement target "
              "([pocket] max_engagement or max_chip)");
  }
  // [path] type chooses the channels' family (docs/models.md, "Channels").
  if (r.has("path", "type")) {
    if (job.path.type == PathType::linear) {
      r.problem("path", "type",
                "a pocket's channels are cleared by the trochoidal families (trochoidal, "
                "circular, elliptical or linear-elliptical); linear slots at 180 degrees");
    } else {
      pk.channel_family = job.path.type;
    }
  } else {
    for (const char* key : {"aspect_ratio", "linear_distance"}) {
      if (r.has("path", key)) {
        r.problem("path", key,
                  "shapes the family of a pocket's channels: give [path] type (elliptical or "
                  "linear-elliptical)");
      }
    }
  }
  if (r.has("path", "entry") && job.path.entry != EntryType::helix) {
    r.problem("path", "entry",
              fmt::format("a pocket is entered by a helix (entry = \"helix\"), got \"{}\"",
                          to_string(job.path.entry)));
  }
  job.path.entry = EntryType::helix;
  if (job.geometry.file.empty()) {
    r.problem("pocket", "boundary", "names a layer of a drawing: give [geometry] file");
  }
  if (!r.problems().empty() || pk.boundary.empty()) return;
  const double fz = job.cutting.feed_per_tooth_mm;
  if (by_chip) {
    if (!(pk.max_chip_mm < fz)) {
      r.problem("pocket", "max_chip",
                fmt::format("must be below the feed per tooth f_z = {} mm (a side cut's chip is "
                            "f_z sin of its engagement, f_z from 90 degrees on): give "
                            "max_engagement for targets of 90 degrees and more; got {} mm",
                            fmt_num(fz), fmt_num(pk.max_chip_mm)));
      return;
    }
    pk.max_engagement_deg = rad_to_deg(std::asin(pk.max_chip_mm / fz));
  } else {
    pk.max_chip_mm = fz * std::sin(deg_to_rad(std::min(90.0, pk.max_engagement_deg)));
  }
  if (pk.rest_tool_diameter_mm > 0 && pk.rest_of.empty()) {
    r.problem("pocket", "rest_tool_diameter", "is rest_of's tool: give [pocket] rest_of too");
  }
  std::vector<std::string> layers{pk.boundary};
  if (!pk.islands.empty()) {
    if (pk.islands == pk.boundary) {
      r.problem("pocket", "islands", "must be another layer than boundary");
      return;
    }
    layers.push_back(pk.islands);
  }
  const auto drawing = read_job_drawing(r, job, layers);
  if (!drawing) return;
  auto boundaries = std::make_shared<std::vector<DrawnContour>>();
  auto islands = std::make_shared<std::vector<DrawnContour>>();
  for (const DrawnContour& c : drawing->contours) {
    const bool is_boundary = c.layer == pk.boundary;
    if (!c.contour.closed) {
      const Vec2 a = c.contour.pieces.front().start, b = c.contour.pieces.back().end;
      r.problem("pocket", is_boundary ? "boundary" : "islands",
                fmt::format("layer '{}' has an open contour ({}, from ({:.4f}, {:.4f}) to "
                            "({:.4f}, {:.4f})): a pocket's walls and islands are closed",
                            c.layer, c.entities.front(), a.x(), a.y(), b.x(), b.y()));
      continue;
    }
    (is_boundary ? boundaries : islands)->push_back(c);
  }
  if (!r.problems().empty()) return;
  // Overlaps, to 1e-6 of the smaller area (Clipper's chords at 1 um of the contours).
  constexpr double kTol = 1e-3;
  auto overlap = [&](const Contour& a, const Contour& b) {
    const double area = std::abs(region_area_mm2(region_intersection({a}, {b}, kTol)));
    return area > 1e-6 * std::min(std::abs(a.signed_area_mm2()), std::abs(b.signed_area_mm2()));
  };
  auto name = [](const DrawnContour& c) { return c.entities.front(); };
  // Contours of the boundary layer may nest (a part's outline and its holes drawn on one
  // layer, as shops draw them): the pocket is what lies inside an odd number of them. They
  // may not cross.
  for (std::size_t i = 0; i < boundaries->size(); ++i) {
    for (std::size_t j = i + 1; j < boundaries->size(); ++j) {
      const Contour &a = (*boundaries)[i].contour, &b = (*boundaries)[j].contour;
      if (!overlap(a, b)) continue;
      const bool a_smaller = std::abs(a.signed_area_mm2()) < std::abs(b.signed_area_mm2());
      const Contour& in = a_smaller ? a : b;
      const double out =
          std::abs(region_area_mm2(region_difference({in}, {a_smaller ? b : a}, kTol)));
      if (out <= 1e-6 * std::abs(in.signed_area_mm2())) continue;  // nested
      r.problem("pocket", "boundary",
                fmt::format("the contours of {} and {} on layer '{}' cross ({:.4g} mm^2 of the "
                            "smaller lies outside the other): the walls are closed contours "
                            "that nest or stand apart",
                            name((*boundaries)[i]), name((*boundaries)[j]), pk.boundary, out));
    }
  }
  std::vector<Contour> walls;
  for (const DrawnContour& b : *boundaries) walls.push_back(b.contour);
  for (std::size_t i = 0; i < islands->size(); ++i) {
    const Contour& c = (*islands)[i].contour;
    const double outside = std::abs(region_area_mm2(region_difference({c}, walls, kTol)));
    if (outside > 1e-6 * std::abs(c.signed_area_mm2())) {
      r.problem("pocket", "islands",
                fmt::format("the island {} on layer '{}' is not inside a boundary ({:.4g} mm^2 "
                            "of it lies outside layer '{}' or in a contour nested in it)",
                            name((*islands)[i]), pk.islands, outside, pk.boundary));
    }
    for (std::size_t j = i + 1; j < islands->size(); ++j) {
      if (overlap(c, (*islands)[j].contour)) {
        r.problem("pocket", "islands",
                  fmt::format("the islands {} and {} on layer '{}' overlap or nest: draw them as "
                              "one island",
                              name((*islands)[i]), name((*islands)[j]), pk.islands));
      }
    }
  }
  if (!r.problems().empty()) return;
  if (!job.stock_mesh_path.empty()) {
    // The mesh read once here (a job is copied often: shared), its box the stock's extent.
    try {
      auto mesh = std::make_shared<const Mesh>(read_mesh(job.stock_mesh_path));
      try {
        check_closed_mesh(*mesh);
      } catch (const InputError& e) {
        throw InputError(fmt::format("{}: {}", job.stock_mesh_path.string(), e.what()));
      }
      const Box3 box = mesh_bounds(*mesh);
      job.stock_min_mm = box.lo;
      job.stock_max_mm = box.hi;
      job.stock_mesh = std::move(mesh);
    } catch (const InputError& e) {
      r.problem("stock", "mesh", e.what());
      return;
    }
  }
  if (!job.stock_min_mm) {
    Box3 box;
    for (const Contour& w : walls) {
      for (const Vec2& p : w.points(1e-3)) box.extend(Vec3(p.x(), p.y(), 0));
    }
    job.stock_min_mm = Vec3(box.lo.x(), box.lo.y(), -pk.depth_mm - 0.5);
    job.stock_max_mm = Vec3(box.hi.x(), box.hi.y(), 0);
  }
  pk.boundary_contours = std::move(boundaries);
  pk.island_contours = std::move(islands);
}

// What a program and the models can represent (beyond each key's own range): coordinates
// are written with 4 decimals (0.0001 mm), F with 4, S in whole rpm; counts of cycles must
// fit the planner. A value outside is refused with the reason, never written rounded to 0.
constexpr double kMinStepMm = 1e-3;   // 10 coordinate counts per cycle
constexpr double kMinSpindleRpm = 1;  // S is written in whole rpm
constexpr double kMaxSpindleRpm = 1e6;
constexpr double kMinFeedMmPerMin = 1e-3;  // F has 4 decimals: 10 counts
constexpr double kMaxFeedMmPerMin = 1e6;

void check_representable(JobReader& r, const Job& job) {
  const auto at_most = [&](const char* section, const char* key, double v, double hi,
                           const char* unit) {
    if (v > hi) {
      r.problem(section, key,
                fmt::format("must be at most {:g} {} (what trochomill represents), got {}", hi,
                            unit, fmt_num(v)));
    }
  };
  at_most("tool", "diameter", job.tool.diameter_mm, kMaxLengthMm, "mm");
  at_most("slot", "width", job.slot.width_mm, kMaxLengthMm, "mm");
  at_most("slot", "length", job.slot.length_mm, kMaxLengthMm, "mm");
  at_most("slot", "depth", job.slot.depth_mm, kMaxLengthMm, "mm");
  at_most("machine", "safe_z", job.machine.safe_z_mm, kMaxLengthMm, "mm");
  at_most("machine", "rapid_rate", job.machine.rapid_rate_mm_per_min, kMaxFeedMmPerMin, "mm/min");
  at_most("machine", "max_feed", job.machine.max_feed_mm_per_min, kMaxFeedMmPerMin, "mm/min");
  at_most("machine", "min_feed", job.machine.min_feed_mm_per_min, kMaxFeedMmPerMin, "mm/min");
  at_most("machine", "air_feed", job.machine.air_feed_mm_per_min, kMaxFeedMmPerMin, "mm/min");
  if (job.machine.min_feed_mm_per_min > 0 && job.machine.max_feed_mm_per_min > 0 &&
      job.machine.min_feed_mm_per_min > job.machine.max_feed_mm_per_min) {
    r.problem("machine", "min_feed",
              fmt::format("must not exceed max_feed ({} mm/min), got {} mm/min",
                          fmt_num(job.machine.max_feed_mm_per_min),
                          fmt_num(job.machine.min_feed_mm_per_min)));
  }
  at_most("path", "entry_feed", job.path.entry_feed_mm_per_min, kMaxFeedMmPerMin, "mm/min");
  if (job.path.step_mm > 0 && job.path.step_mm < kMinStepMm) {
    r.problem("path", "step",
              fmt::format("must be at least {:g} mm (the program's coordinates have 4 decimals), "
                          "got {}",
                          kMinStepMm, fmt_num(job.path.step_mm)));
  }
  // The cutting conditions as the program writes them, given or derived.
  const Cutting& c = job.cutting;
  const char* speed_key = r.has("cutting", "cutting_speed") ? "cutting_speed" : "spindle_speed";
  if (c.spindle_speed_rpm > 0 &&
      (c.spindle_speed_rpm < kMinSpindleRpm - 0.5 || c.spindle_speed_rpm > kMaxSpindleRpm)) {
    r.problem("cutting", speed_key,
              fmt::format("gives a spindle speed of {} rpm: it must be in [{:g}, {:g}] rpm (S is "
                          "written in whole rpm)",
                          fmt_num(c.spindle_speed_rpm), kMinSpindleRpm, kMaxSpindleRpm));
  }
  const char* feed_key = r.has("cutting", "feed_per_tooth") ? "feed_per_tooth" : "feed_rate";
  if (c.feed_rate_mm_per_min > 0 &&
      (c.feed_rate_mm_per_min < kMinFeedMmPerMin || c.feed_rate_mm_per_min > kMaxFeedMmPerMin)) {
    r.problem("cutting", feed_key,
              fmt::format("gives a feed of {} mm/min: it must be in [{:g}, {:g}] mm/min (F is "
                          "written with 4 decimals)",
                          fmt_num(c.feed_rate_mm_per_min), kMinFeedMmPerMin, kMaxFeedMmPerMin));
  }
}

// The rules that tie keys together, after every key was read.
// [stock] is given in the work offset's coordinates (the frame of the job's G-code and of
// programs read with it); the models work in the slot's frame. A straight slot placed by
// slot.origin_x, origin_y and angle: the box moved into that frame (turned by a multiple of
// 90 degrees it stays a box).
void place_stock(JobReader& r, Job& job) {
  if (!r.has("stock", "min") || !job.stock_min_mm || !job.stock_max_mm) return;
  const Slot& slot = job.slot;
  if (slot.origin_x_mm == 0 && slot.origin_y_mm == 0 && slot.angle_deg == 0) return;
  const double quarters = slot.angle_deg / 90.0;
  if (std::abs(quarters - std::round(quarters)) > 1e-9) {
    r.problem("stock", "min",
              fmt::format("is in the work offset's coordinates, where slot.angle = {} degrees "
                          "turns the slot: a box turned by other than a multiple of 90 degrees "
                          "is no box in the slot's frame (give the stock as a mesh: --stock "
                          "FILE.stl, or turn the slot by a multiple of 90 degrees)",
                          fmt_num(slot.angle_deg)));
    return;
  }
  // Work -> slot: p - origin turned back by the angle (a quarter turn at a time, exactly).
  const long turns = ((std::lround(quarters) % 4) + 4) % 4;
  auto to_slot = [&](double x, double y) {
    double u = x - slot.origin_x_mm, v = y - slot.origin_y_mm;
    for (long k = 0; k < turns; ++k) {
      const double t = u;  // a quarter turn clockwise (back)
      u = v;
      v = -t;
    }
    return std::pair{u, v};
  };
  const Vec3 lo = *job.stock_min_mm, hi = *job.stock_max_mm;
  const auto [ax, ay] = to_slot(lo.x(), lo.y());
  const auto [bx, by] = to_slot(hi.x(), hi.y());
  job.stock_min_mm = Vec3(std::min(ax, bx), std::min(ay, by), lo.z());
  job.stock_max_mm = Vec3(std::max(ax, bx), std::max(ay, by), hi.z());
}

void check_rules(JobReader& r, Job& job) {
  Tool& tool = job.tool;
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
  if (tool.type != ToolType::insert_mill && r.has("tool", "lead_angle") &&
      tool.lead_angle_deg != Tool{}.lead_angle_deg) {
    r.problem("tool", "lead_angle",
              "applies to type = \"insert_mill\" (an end mill's flank is at 90 degrees)");
  }
  if (tool.tooth_angles_deg.empty() && tool.teeth > 0) {
    for (int k = 0; k < tool.teeth; ++k) tool.tooth_angles_deg.push_back(360.0 * k / tool.teeth);
  }

  // [machine]: what the control can do with the program's set-up blocks.
  const Machine& mc = job.machine;
  if (mc.dialect == Dialect::sinumerik && mc.work_offset > WorkOffset::g57) {
    r.problem("machine", "work_offset",
              fmt::format("dialect = \"sinumerik\" has the settable offsets G54 .. G57, got {}",
                          to_string(mc.work_offset)));
  }
  if ((mc.dialect == Dialect::linuxcnc || mc.dialect == Dialect::fanuc ||
       mc.dialect == Dialect::haas || mc.dialect == Dialect::mach3) &&
      (mc.length_offset > 0 ? mc.length_offset : tool.tool_number) == 0) {
    r.problem(r.has("machine", "length_offset") ? "machine" : "tool",
              r.has("machine", "length_offset") ? "length_offset" : "tool_number",
              "G43 H0 applies no tool length offset: give [tool] tool_number >= 1 or "
              "[machine] length_offset >= 1");
  }

  // Geometry feasibility (only when the inputs themselves were valid).
  const PathSpec& path = job.path;
  const bool trochoidal_family = path.type != PathType::linear;
  const double D = tool.diameter_mm, W = job.slot.width_mm;
  const bool needs_step = trochoidal_family || W > D;
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
  if (path.type == PathType::trochoidal && r.has("path", "type") && r.has("path", "aspect_ratio") &&
      path.aspect_ratio != 1.0) {
    r.problem("path", "aspect_ratio",
              "type = \"trochoidal\" is the elliptical family with aspect_ratio = 1; "
              "use type = \"elliptical\" for other aspect ratios");
  }

  // [cutting]: exactly one way to give each of feed and speed; the table read the valid ones.
  Cutting& cut = job.cutting;
  const bool has_fr = r.has("cutting", "feed_rate"), has_fz = r.has("cutting", "feed_per_tooth");
  const bool has_n = r.has("cutting", "spindle_speed"), has_vc = r.has("cutting", "cutting_speed");
  const bool fr = has_fr && cut.feed_rate_mm_per_min > 0;
  const bool fz = has_fz && cut.feed_per_tooth_mm > 0;
  const bool n = has_n && cut.spindle_speed_rpm > 0;
  const bool vc = has_vc && cut.cutting_speed_m_per_min > 0;
  if (has_fr && has_fz) {
    r.problem("cutting", "feed_per_tooth",
              "give either [cutting] feed_rate (mm/min) or feed_per_tooth (mm), not both");
  } else if (!has_fr && !has_fz) {
    r.problems().push_back(fmt::format(
        "{}: missing [cutting] feed_rate (mm/min) or feed_per_tooth (mm): give exactly one",
        r.source()));
  }
  if (has_n && has_vc) {
    r.problem("cutting", "cutting_speed",
              "give either [cutting] spindle_speed (rpm) or cutting_speed (m/min), not both");
  } else if (!has_n && !has_vc) {
    r.problems().push_back(fmt::format(
        "{}: missing [cutting] spindle_speed (rpm) or cutting_speed (m/min): give exactly one",
        r.source()));
  }
  if ((n || vc) && D > 0) {
    if (!n) cut.spindle_speed_rpm = spindle_rpm_from_cutting_speed(cut.cutting_speed_m_per_min, D);
    cut.cutting_speed_m_per_min = cutting_speed_from_spindle_rpm(cut.spindle_speed_rpm, D);
    if ((fr || fz) && tool.teeth > 0) {
      if (!fr)
        cut.feed_rate_mm_per_min = cut.feed_per_tooth_mm * tool.teeth * cut.spindle_speed_rpm;
      cut.feed_per_tooth_mm = cut.feed_rate_mm_per_min / (tool.teeth * cut.spindle_speed_rpm);
    }
  }

  check_settings_rules(r, job);
  check_material(r, job.material);
  check_centreline(r, job);
  check_pocket(r, job);
  place_stock(r, job);
  check_representable(r, job);
}

}  // namespace

Job build_job(const toml::table& root, const std::string& source,
              const std::map<std::string, std::string>& overridden) {
  JobReader r(root, source, overridden, schema_sections());
  Job job;
  job.source = source;
  for (const Key& k : schema()) k.read(r, job);
  check_rules(r, job);
  r.check_unknown();
  if (!r.problems().empty()) throw InputError(r.problems());
  return job;
}

void apply_to_job(const toml::table& root, const std::map<std::string, std::string>& overridden,
                  Job& job) {
  static const std::set<std::string> standalone = {"machine",    "measured", "mechanism", "monitor",
                                                   "simulation", "forces",   "analysis"};
  JobReader r(root, job.source.empty() ? std::string("(no job file)") : job.source, overridden,
              schema_sections());
  for (auto&& [section, table] : root) {
    if (!standalone.count(std::string(section.str()))) {
      r.problems().push_back(fmt::format("[{}] keys need a job file", section.str()));
    }
  }
  for (const Key& k : schema()) {
    if (standalone.count(k.section) && r.has(k.section, k.key)) k.read(r, job);
  }
  check_settings_rules(r, job);
  r.check_unknown();
  if (!r.problems().empty()) throw InputError(r.problems());
}

}  // namespace trochomill::job_detail

namespace trochomill {

const std::vector<JobKey>& job_keys() {
  static const std::vector<JobKey> keys = [] {
    std::vector<JobKey> out;
    Job defaults;
    for (const auto& k : job_detail::schema()) {
      out.push_back(JobKey{k.section, k.key, k.type, k.unit, k.allowed, k.show(defaults), k.doc});
    }
    return out;
  }();
  return keys;
}

const JobKey* find_job_key(std::string_view full_key) {
  for (const JobKey& k : job_keys()) {
    if (full_key.size() == k.section.size() + 1 + k.key.size() && full_key.starts_with(k.section) &&
        full_key[k.section.size()] == '.' && full_key.ends_with(k.key)) {
      return &k;
    }
  }
  return nullptr;
}

std::string job_keys_markdown() {
  // One table per section, the sections in the order they first appear in the schema.
  std::vector<std::string> sections;
  for (const JobKey& k : job_keys()) {
    if (std::find(sections.begin(), sections.end(), k.section) == sections.end()) {
      sections.push_back(k.section);
    }
  }
  std::string out;
  for (const std::string& section : sections) {
    out += fmt::format(
        "\n#### [{}]\n\n| key | type | unit | allowed | default | meaning |\n"
        "|---|---|---|---|---|---|\n",
        section);
    for (const JobKey& k : job_keys()) {
      if (k.section != section) continue;
      std::string allowed = k.allowed;
      for (std::size_t p = 0; (p = allowed.find('|', p)) != std::string::npos; p += 2) {
        allowed.replace(p, 1, "\\|");
      }
      out += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", k.key, k.type, k.unit, allowed,
                         k.default_text, k.doc);
    }
  }
  return out;
}

std::string_view to_string(PathType t) noexcept {
  return job_detail::name_of(job_detail::kPathTypes, t);
}
std::string_view to_string(ForceModel m) noexcept {
  return job_detail::name_of(job_detail::kForceModels, m);
}
std::string_view to_string(Dialect d) noexcept {
  return job_detail::name_of(job_detail::kDialects, d);
}
std::string_view to_string(EntryType e) noexcept {
  return job_detail::name_of(job_detail::kEntries, e);
}
std::string_view to_string(Direction d) noexcept {
  return job_detail::name_of(job_detail::kDirections, d);
}
std::string_view to_string(ChipModel m) noexcept {
  return job_detail::name_of(job_detail::kChipModels, m);
}
std::string_view to_string(ShareOf s) noexcept {
  return job_detail::name_of(job_detail::kSharesOf, s);
}
std::string_view to_string(Criterion c) noexcept {
  return job_detail::name_of(job_detail::kCriteria, c);
}
std::string_view to_string(KfCriteria c) noexcept {
  return job_detail::name_of(job_detail::kKfCriteria, c);
}
std::string_view to_string(WorkOffset w) noexcept {
  return job_detail::name_of(job_detail::kWorkOffsets, w);
}

namespace {
template <class E, std::size_t N>
E parse_name(const job_detail::Names<E> (&table)[N], std::string_view what, std::string_view name) {
  for (const auto& [n, v] : table) {
    if (n == name) return v;
  }
  throw InputError(
      fmt::format("{} '{}' is not one of {}", what, name, job_detail::choices_text(table)));
}
}  // namespace

Dialect parse_dialect(std::string_view name) {
  return parse_name(job_detail::kDialects, "dialect", name);
}
ChipModel parse_chip_model(std::string_view name) {
  return parse_name(job_detail::kChipModels, "chip model", name);
}
ForceModel parse_force_model(std::string_view name) {
  return parse_name(job_detail::kForceModels, "force model", name);
}

}  // namespace trochomill
