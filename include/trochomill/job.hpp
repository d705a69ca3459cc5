// The job file: one TOML document describing tool, slot, path, cutting conditions, machine,
// material and each module's settings. Every subcommand reads it; `--set section.key=value`
// overrides any key. All lengths are mm, angles degrees, feeds mm/min, spindle speeds rpm,
// cutting speed m/min, accelerations mm/s^2 at this interface. The job's own sections are
// defined here; each module owns its settings struct (trochomill/settings/<module>.hpp) and
// the job aggregates them. Every key is one entry of the schema (src/job/schema.cpp), which
// drives parsing, validation, `--set`, the G-code header and the key reference in
// docs/user-guide.md (job_keys_markdown()).
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/geometry.hpp"
#include "trochomill/geometry/drawing.hpp"
#include "trochomill/settings/analysis.hpp"
#include "trochomill/settings/force.hpp"
#include "trochomill/settings/mechanism.hpp"
#include "trochomill/settings/signal.hpp"
#include "trochomill/settings/sim.hpp"
#include "trochomill/settings/topography.hpp"

namespace trochomill {

enum class ToolType { end_mill, insert_mill };

struct Tool {
  ToolType type = ToolType::end_mill;  ///< solid end mill or indexable insert mill
  double diameter_mm = 0;              ///< cutter diameter D (mm)
  int teeth = 0;                       ///< number of teeth Z
  double helix_angle_deg = 0;          ///< helix angle (degrees)
  double corner_radius_mm = 0;         ///< corner radius (mm), 0 for a square end mill
  double dish_angle_deg = 0;  ///< end edges' dish angle: rise from the corner to the axis (degrees)
  double edge_radius_mm = 0;  ///< cutting-edge rounding radius r_e (mm)
  double flute_length_mm = 0;   ///< flute length (mm); 0 = not given
  double runout_radial_mm = 0;  ///< radial runout: axis offset e (mm)
  double runout_axial_mm = 0;   ///< axial runout (mm)
  double runout_phase_deg = 0;  ///< angle of the runout offset relative to tooth 0 (degrees)
  std::vector<double> tooth_angles_deg;  ///< tooth angular positions (degrees); Z equal pitches
                                         ///< when empty in the file (filled by load)
  int tool_number = 1;                   ///< T word for the tool change
  double flank_wear_mm = 0;              ///< flank wear land VB_B (mm); 0 = new tool
  double lead_angle_deg = 90;            ///< insert mill: main edge's angle to the face (degrees)
  std::vector<double> insert_radial_mm;  ///< insert mill: each insert's radial seating (mm)
  std::vector<double> insert_axial_mm;   ///< insert mill: each insert's axial seating (mm)
  [[nodiscard]] double radius_mm() const noexcept { return 0.5 * diameter_mm; }
};

/// The slot in its own frame (the frame every model works in): along +Y from y = 0, width
/// along X centred on x = 0, top face z = 0. The placement puts that frame in the workpiece
/// (the work offset's frame) for the G-code: rotated by angle_deg about Z, counter-clockwise
/// seen from +Z, then moved so the slot frame's origin lands on (origin_x_mm, origin_y_mm).
struct Slot {
  double width_mm = 0;     ///< slot width W along X (mm)
  double length_mm = 0;    ///< slot length along +Y (mm)
  double depth_mm = 0;     ///< slot depth a_p below the top face z = 0 (mm)
  double origin_x_mm = 0;  ///< workpiece X of the slot frame's origin (mm)
  double origin_y_mm = 0;  ///< workpiece Y of the slot frame's origin (mm)
  double angle_deg = 0;    ///< direction of the slot's +Y in the workpiece, from +Y (degrees)
  /// `[slot] along`: the drawing's layer (or SVG id) whose one contour is the slot's
  /// centreline; empty: the straight slot of length_mm along +Y.
  std::string along;
  /// That contour (mm, the drawing's frame = the workpiece's; set by the job reader from
  /// `[geometry] file`); length_mm is then its length. Shared: a job is copied often.
  std::shared_ptr<const DrawnContour> centreline;
  /// `[slot] max_step_down` (mm): the depth of each level; 0: the whole depth in one level.
  /// Levels are planned for slots along a contour.
  double max_step_down_mm = 0;
  /// `[slot] finish_allowance` (mm): the walls' stock the cycles leave (their orbit narrowed
  /// by it); `finish_pass`: one pass along the walls at full depth after the levels.
  double finish_allowance_mm = 0;
  bool finish_pass = false;
  [[nodiscard]] bool curved() const noexcept { return centreline != nullptr; }
};

enum class PathType { linear, trochoidal, circular, elliptical, linear_elliptical };

/// `[pocket]`: a pocket cleared down to its floor, its walls the closed contours of a drawing's
/// layer and the islands left standing those of another (lengths mm, the drawing's frame = the
/// workpiece's; top face z = 0).
struct RestStock;  // path.hpp: an earlier program's remaining stock

struct Pocket {
  std::string boundary;          ///< the layer (or SVG id) of the walls' closed contours
  std::string islands;           ///< the layer of the islands' closed contours; empty: none
  double depth_mm = 0;           ///< floor below the top face (mm)
  double max_step_down_mm = 0;   ///< depth of each level (mm); 0: the whole depth at once
  double stock_to_leave_mm = 0;  ///< left on walls and islands by the clearing (mm)
  /// The clearing's engagement target (degrees): the largest arc of the tool in the material
  /// once in the pocket (entries excepted). From [pocket] max_engagement, or from max_chip:
  /// asin(h / f_z) (a side cut's largest chip is f_z sin of its engagement).
  double max_engagement_deg = 0;
  double max_chip_mm = 0;           ///< the largest chip that engagement makes, f_z sin (mm)
  bool finish_pass = true;          ///< one pass along walls and islands at full depth
  double fit_tolerance_mm = 0.002;  ///< the clearing path written as arcs within this (mm)
  /// Parts of the pocket narrower than this (mm) are cleared by trochoidal loops along their
  /// medial axis (channels); 0: twice the tool's diameter.
  double channel_width_mm = 0;
  /// The channels' family: [path] type in a pocket's job (trochoidal, circular, elliptical or
  /// linear-elliptical, shaped by [path] aspect_ratio and linear_distance), its cycles carried
  /// along the channels' axis; none: circles about the axis' points joined along the axis.
  std::optional<PathType> channel_family;
  /// The contours (set by the job reader from [geometry] file). Shared: a job is copied often.
  std::shared_ptr<const std::vector<DrawnContour>> boundary_contours, island_contours;
  /// [pocket] rest_of: an earlier program (as written in the job; `rest_of_path` resolved
  /// against the job file's folder) whose remaining material is the stock: the clearing cuts
  /// only what it left. Empty: the stock is the [stock] box.
  std::string rest_of;
  std::filesystem::path rest_of_path;
  /// Its tool's diameter (mm): [pocket] rest_tool_diameter, else (0) the program header's
  /// tool.diameter (a trochomill program's).
  double rest_tool_diameter_mm = 0;
  /// The earlier program as read (attach_rest_stock, pocket.hpp), which the planner, the
  /// engagement kernel and the simulation take as removed; null until attached.
  std::shared_ptr<const RestStock> rest;
  /// [pocket] entry_holes: pre-drilled holes (x, y in mm, at least the tool's diameter wide,
  /// through the depth). A part of the pocket holding one is entered by feeding straight down
  /// it (the first listed in the part), not by a helix.
  std::vector<Vec2> entry_holes_mm;
  [[nodiscard]] bool defined() const noexcept { return boundary_contours != nullptr; }
};

/// `[geometry]`: the drawing the part's contours come from.
struct GeometrySource {
  std::string file;                 ///< as written in the job (relative to the job file)
  std::filesystem::path path;       ///< resolved against the job file's folder
  double join_tolerance_mm = 0.01;  ///< ends closer than this are one point (mm)
  /// [geometry] units: a unitless DXF's unit (drawing_unit_mm's names); empty: read as mm.
  std::string units_name;
  /// The drawing's unit as read (Drawing::units): "mm", "in", ..., "unitless (read as mm)".
  std::string units;
};

enum class Direction { climb, conventional };
enum class EntryType { helix, ramp, plunge, outside };
enum class SpindleDirection { cw, ccw };
enum class Coolant { off, flood, mist };
/// The control a program is written for or read as. haas and mach3 are the languages of
/// Fanuc and of LinuxCNC with their controls' differences (docs/gcode.md); written as fanuc's
/// and linuxcnc's programs.
enum class Dialect { linuxcnc, fanuc, sinumerik, grbl, haas, mach3 };
/// The work offset the program selects (G54 .. G59).
enum class WorkOffset { g54, g55, g56, g57, g58, g59 };
enum class ArcOutput { arcs, chords };

struct PathSpec {
  PathType type = PathType::trochoidal;
  double step_mm = 0;             ///< trochoidal step s (advance per cycle); stepover for linear
  double aspect_ratio = 1;        ///< r_e = b / a (elliptical families)
  double linear_distance_mm = 0;  ///< d, the straight wall move of linear-elliptical (mm)
  Direction direction = Direction::climb;
  EntryType entry = EntryType::outside;
  double entry_radius_mm = 0;        ///< helix radius (mm); 0 = automatic
  double entry_pitch_mm = 1;         ///< helix descent per turn (mm)
  double entry_angle_deg = 3;        ///< ramp angle (degrees)
  double entry_feed_mm_per_min = 0;  ///< feed for the entry moves (mm/min); 0 = half the feed
  double clearance_mm = 1;           ///< distance kept from stock before feeding in (mm)
};

struct Cutting {
  double feed_rate_mm_per_min = 0;     ///< f_r, tool-centre feed (mm/min)
  double spindle_speed_rpm = 0;        ///< n (rpm)
  double feed_per_tooth_mm = 0;        ///< f_z = f_r / (n Z) (mm)
  double cutting_speed_m_per_min = 0;  ///< v_c = pi D n / 1000 (m/min)
  SpindleDirection spindle_direction = SpindleDirection::cw;
  Coolant coolant = Coolant::off;
};

struct Machine {
  Dialect dialect = Dialect::linuxcnc;
  double safe_z_mm = 5;                   ///< retract height above the top face (mm)
  double rapid_rate_mm_per_min = 10000;   ///< rapid traverse rate (mm/min)
  double max_acceleration_mm_per_s2 = 0;  ///< path acceleration limit (mm/s^2); 0 = unlimited
  /// Feed scheduling limits (mm/min): the fastest and slowest feed a schedule may program and
  /// the feed where the tool cuts nothing; 0 = three times, a tenth of the job's feed, and
  /// the max feed (analysis.hpp: default_feed_targets).
  double max_feed_mm_per_min = 0, min_feed_mm_per_min = 0, air_feed_mm_per_min = 0;
  double junction_deviation_mm = 0.01;       ///< corner blending tolerance for time estimates (mm)
  double arc_tolerance_mm = 0.001;           ///< max deviation when fitting arcs/chords (mm)
  ArcOutput arc_output = ArcOutput::arcs;    ///< elliptical arcs as biarcs or as G1 chords
  int program_number = 1000;                 ///< O number (fanuc)
  WorkOffset work_offset = WorkOffset::g54;  ///< work coordinate system of the program
  /// Tool length offset register H (linuxcnc, fanuc: G43 H); 0 = the tool number.
  int length_offset = 0;
  /// For reading programs: the origins of G54, G55, ... G59.3 (index 0 .. 8) in machine
  /// coordinates (mm), the G28 and G30 positions (mm, machine coordinates) and a LinuxCNC tool
  /// table (G43's lengths). Unset: the reader assumes and says so (docs/gcode.md).
  std::array<std::optional<Vec3>, 9> origins_mm;
  std::optional<Vec3> g28_position_mm, g30_position_mm;
  std::filesystem::path tool_table;
};

struct Job {
  std::string source;  ///< file name the job came from (for messages)
  Tool tool;
  GeometrySource geometry;
  Slot slot;
  Pocket pocket;  ///< defined(): the job plans a pocket, not a slot
  PathSpec path;
  Cutting cutting;
  Machine machine;
  Measured measured;
  AnalysisSettings analysis;
  MechanismSettings mechanism;
  MonitorSettings monitor;
  SimSettings simulation;
  Material material;
  ForceSettings forces;
  TopographySettings topography;
  /// `[stock]` min / max corners (mm); absent: the slot region with a 1 mm margin (sim.hpp).
  std::optional<Vec3> stock_min_mm, stock_max_mm;
  /// `[stock] mesh`: a pocket's stock as a closed mesh (as written in the job; `stock_mesh_path`
  /// resolved against the job file's folder), read by the job reader into `stock_mesh`, whose
  /// box then is stock_min_mm .. stock_max_mm. The planner, the engagement kernel and the
  /// simulation take it as the stock. Empty (null): the box.
  std::string stock_mesh_file;
  std::filesystem::path stock_mesh_path;
  std::shared_ptr<const Mesh> stock_mesh;
  // The original document, flattened `section.key = value` (TOML syntax), after overrides:
  // written into the G-code header so a program records the job that produced it.
  std::vector<std::pair<std::string, std::string>> flat_keys;
};

/// A `--set section.key=value` override (value in TOML syntax; bare words are strings).
struct Override {
  std::string key;    ///< "section.key"
  std::string value;  ///< "0.8", "true", "elliptical", "[0, 90, 180, 270]"
  /// How messages name it, as the caller does (the CLI's "--set path.step", or "--share
  /// (mechanism.share)" for a flag that stands for the key); empty: the key.
  std::string origin;
};

/// The job as a TOML document: its keys after the overrides (`flat_keys`), section by
/// section in the document's order; load_job of it gives the same job.
[[nodiscard]] std::string to_toml(const Job& job);

/// Parses "section.key=value". Throws InputError when there is no '=' or no section.
[[nodiscard]] Override parse_override(std::string_view text);

/// A parsed job document: read and parsed once, then turned into jobs with different overrides
/// (a parameter study builds one job per grid point from one document).
class JobDocument {
 public:
  /// Parses TOML text; `source_name` is used in messages. Throws InputError (syntax errors
  /// with file:line:column).
  static JobDocument parse(std::string_view toml_text, std::string_view source_name);
  /// Reads and parses a job file. Throws InputError.
  static JobDocument load(const std::filesystem::path& file);
  JobDocument(JobDocument&&) noexcept;
  JobDocument& operator=(JobDocument&&) noexcept;
  ~JobDocument();
  /// The validated job with the overrides applied in order (the document is not changed).
  /// Throws InputError listing every problem (file:line:column or key, what is allowed).
  [[nodiscard]] Job build(const std::vector<Override>& overrides = {}) const;
  [[nodiscard]] const std::string& source() const noexcept;

 private:
  struct Impl;
  explicit JobDocument(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Loads and validates a job file, applying overrides in order.
/// Throws InputError listing every problem (file:line:column or key, what is allowed).
[[nodiscard]] Job load_job(const std::filesystem::path& file,
                           const std::vector<Override>& overrides = {});

/// Same as load_job, from TOML text; `source_name` is used in messages.
[[nodiscard]] Job parse_job(std::string_view toml_text, std::string_view source_name,
                            const std::vector<Override>& overrides = {});

/// Validates and applies overrides to a job that exists already (the default settings of a
/// command run without a job file, e.g. `monitor`): each key as the schema reads it, then the
/// rules of its section. Only the sections whose rules stand alone may be set this way
/// (machine, measured, mechanism, monitor, simulation, forces, analysis); others throw
/// InputError asking for a job file.
void apply_overrides(Job& job, const std::vector<Override>& overrides);

/// One key of the job schema, as the user sees it.
struct JobKey {
  std::string section, key;  ///< `[section] key`
  std::string type;          ///< number, integer, string, choice, array of numbers, ...
  std::string unit;          ///< mm, degrees, mm/min, rpm, Hz, ... (empty: dimensionless)
  std::string allowed;       ///< range or choices, e.g. "> 0", "in [1, 64]", "climb | conventional"
  std::string default_text;  ///< the default (from the settings struct), "required" or "none"
  std::string doc;           ///< what it means
};
/// Every key of the job file, in the order of the reference (section by section).
[[nodiscard]] const std::vector<JobKey>& job_keys();
/// The key `section.key` (e.g. "path.step"), or nullptr when the schema has none.
[[nodiscard]] const JobKey* find_job_key(std::string_view full_key);
/// The key reference as Markdown tables (the one in docs/user-guide.md is this text).
[[nodiscard]] std::string job_keys_markdown();

/// The materials library: data/materials/*.toml, looked up in $TROCHOMILL_DATA/materials, then
/// the source tree's data/materials, then the installed share/trochomill/materials.
[[nodiscard]] std::filesystem::path materials_dir();
/// Every material of the library, sorted by name; read once per directory and process.
/// Throws InputError for a malformed file.
[[nodiscard]] std::vector<Material> material_library();

[[nodiscard]] std::string_view to_string(PathType t) noexcept;
[[nodiscard]] std::string_view to_string(ForceModel m) noexcept;
[[nodiscard]] std::string_view to_string(Dialect d) noexcept;
[[nodiscard]] std::string_view to_string(EntryType e) noexcept;
[[nodiscard]] std::string_view to_string(Direction d) noexcept;
[[nodiscard]] std::string_view to_string(ChipModel m) noexcept;
[[nodiscard]] std::string_view to_string(ShareOf s) noexcept;
[[nodiscard]] std::string_view to_string(Criterion c) noexcept;
[[nodiscard]] std::string_view to_string(KfCriteria c) noexcept;
[[nodiscard]] std::string_view to_string(WorkOffset w) noexcept;  ///< "G54" .. "G59"
/// Parses a chip model name (exact | pivkin2025); InputError otherwise.
[[nodiscard]] ChipModel parse_chip_model(std::string_view name);
/// Parses a force model name (bergmann | kienzle | linear); InputError otherwise.
[[nodiscard]] ForceModel parse_force_model(std::string_view name);
/// Parses a dialect name (linuxcnc | fanuc | sinumerik | grbl | haas | mach3); InputError
/// otherwise.
[[nodiscard]] Dialect parse_dialect(std::string_view name);

}  // namespace trochomill
