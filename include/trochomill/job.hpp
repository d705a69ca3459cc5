// The job file: one TOML document describing tool, slot, path, cutting conditions and
// machine. Every subcommand reads it; `--set section.key=value` overrides any key.
// All lengths are mm, angles degrees, feeds mm/min, spindle speeds rpm, cutting speed m/min,
// accelerations mm/s^2 at this interface (docs/user-guide.md lists every key).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace trochomill {

enum class ToolType { end_mill, insert_mill };

struct Tool {
  ToolType type = ToolType::end_mill;  ///< solid end mill or indexable insert mill
  double diameter_mm = 0;              ///< cutter diameter D (mm)
  int teeth = 0;                       ///< number of teeth Z
  double helix_angle_deg = 0;          ///< helix angle (degrees)
  double corner_radius_mm = 0;         ///< corner radius (mm), 0 for a square end mill
  double edge_radius_mm = 0;           ///< cutting-edge rounding radius r_e (mm)
  double flute_length_mm = 0;          ///< flute length (mm); 0 = not given
  double runout_radial_mm = 0;         ///< radial runout: axis offset e (mm)
  double runout_axial_mm = 0;          ///< axial runout (mm)
  double runout_phase_deg = 0;         ///< angle of the runout offset relative to tooth 0 (degrees)
  std::vector<double> tooth_angles_deg;  ///< tooth angular positions (degrees); Z equal pitches
                                         ///< when empty in the file (filled by load)
  int tool_number = 1;                   ///< T word for the tool change
  double flank_wear_mm = 0;              ///< flank wear land VB_B (mm); 0 = new tool
  double lead_angle_deg = 90;            ///< insert mill: main edge's angle to the face (degrees)
  std::vector<double> insert_radial_mm;  ///< insert mill: each insert's radial seating (mm)
  std::vector<double> insert_axial_mm;   ///< insert mill: each insert's axial seating (mm)
  [[nodiscard]] double radius_mm() const noexcept { return 0.5 * diameter_mm; }
};

struct Slot {
  double width_mm = 0;   ///< slot width W along X (mm)
  double length_mm = 0;  ///< slot length along +Y (mm)
  double depth_mm = 0;   ///< slot depth a_p below the top face z = 0 (mm)
};

enum class PathType { linear, trochoidal, circular, elliptical, linear_elliptical };
enum class Direction { climb, conventional };
enum class EntryType { helix, ramp, plunge, outside };
enum class SpindleDirection { cw, ccw };
enum class Coolant { off, flood, mist };
enum class Dialect { linuxcnc, fanuc, sinumerik, grbl };
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
  double safe_z_mm = 5;                    ///< retract height above the top face (mm)
  double rapid_rate_mm_per_min = 10000;    ///< rapid traverse rate (mm/min)
  double max_acceleration_mm_per_s2 = 0;   ///< path acceleration limit (mm/s^2); 0 = unlimited
  double junction_deviation_mm = 0.01;     ///< corner blending tolerance for time estimates (mm)
  double arc_tolerance_mm = 0.001;         ///< max deviation when fitting arcs/chords (mm)
  ArcOutput arc_output = ArcOutput::arcs;  ///< elliptical arcs as biarcs or as G1 chords
  int program_number = 1000;               ///< O number (fanuc)
};

/// `[measured]`: results measured on the machine (or filled by a model); each optional.
struct Measured {
  std::optional<double> force_max_n;      ///< maximum resultant cutting force F_R,max (N)
  std::optional<double> roughness_ra_um;  ///< maximum roughness Ra of the slot (micrometres)
  std::optional<double> waviness_um;      ///< maximum wall waviness W_max (micrometres)
};

/// `[analysis]`: resolution of `trochomill analyze`.
struct AnalysisSettings {
  int steps_per_tooth = 1;  ///< engagement samples per tooth pass (1..64)
  int imprint_points = 81;  ///< points across the slot width for the bottom imprint density
};

/// `[mechanism]` (Pivkin 2025's zones) and `[material] friction_angle`.
struct MechanismJob {
  double czi_max_pct = 25;      ///< K_re below this: CZI (percent of r_e)
  double czii_max_pct = 60;     ///< K_re below this: CZII; above: CZIII
  double transition_pct = 40;   ///< marker where the acoustic ratio k_f crosses 1
  double share = 0.5;           ///< required CZIII share of the cutting part for `recommend`
  std::string model = "exact";  ///< chip model
  int points = 3600;            ///< theta samples per cycle
  std::optional<double> friction_angle_deg;  ///< [material] friction_angle theta_m (degrees)
};

/// Vibroacoustic monitor settings (`[monitor]`; the CLI's flags override; signal.hpp).
struct MonitorSettings {
  double low_min_hz = 2000, low_max_hz = 5000;     ///< low band
  double high_min_hz = 8000, high_max_hz = 13000;  ///< high band
  int order = 4;                                   ///< Butterworth order of each band
  double window_s = 0.005;                         ///< RMS window (and hop)
  int baseline_cycles = 3;  ///< wear: cycles whose k_f level is the reference
  double wear_ratio = 1.3;  ///< wear flagged where the k_f level exceeds the reference by this
  double ploughing_ratio = 1.15;  ///< ploughing flagged where k_f in CZI exceeds CZIII's by this
  int phase_bins = 50;            ///< k_f profile bins over a cycle
};

/// Tri-dexel simulation settings (`[simulation]`; sim.hpp).
struct SimSettings {
  double resolution_mm = 0.01;      ///< dexel spacing
  int steps_per_rev = 600;          ///< time steps per spindle revolution
  double chip_sampling_mm = 0.001;  ///< sampling of removed intervals into points
  double segment_mm = 0.05;         ///< edge segment length along the edge (kappa)
  int sub_segments = 5;             ///< sub-segments inward (tau), for wear topography
  int threads = 0;                  ///< worker threads (0: all cores)
  /// Search each wedge's whole sector, not only the annulus where material can be, and every
  /// ray, not only where the boards' summaries show material (slow; to check both arguments
  /// of docs/models.md section 11). Not a job key.
  bool exhaustive = false;
};

/// Force model of `[material]` (force.hpp, docs/models.md section 12).
enum class ForceModel { bergmann, kienzle, linear };

/// `[material]`: the workpiece material's force coefficients, given in the job or taken from
/// the materials library (`name`, data/materials/*.toml). Forces act on the workpiece.
struct Material {
  std::string name;                 ///< library name, when taken from the library
  std::string source;               ///< citation of the coefficients
  std::string notes;                ///< conditions they hold for (tool, speed, coolant...)
  std::optional<ForceModel> model;  ///< absent: no force model in the job
  // Bergmann 2021 Eq. 3 and Kienzle: F = w h^(1 - m) k per direction.
  double k_c = 0;             ///< specific cutting force (N/mm^2), along the cutting direction
  double k_n = 0;             ///< specific normal force (N/mm^2), along the contour normal
  double m = 0;               ///< exponent of h (dimensionless, 0 <= m < 1)
  std::optional<double> m_n;  ///< Kienzle: exponent of the normal force (default m)
  double k_a = 0;             ///< Kienzle: specific force up the edge (N/mm^2)
  std::optional<double> m_a;  ///< Kienzle: its exponent (default m)
  // Linear edge-force model: F = w (K_c h + K_e) per direction.
  double k_tc = 0, k_rc = 0, k_ac = 0;  ///< cutting coefficients (N/mm^2)
  double k_te = 0, k_re = 0, k_ae = 0;  ///< edge coefficients (N/mm)
};

/// `[forces]`: settings of `trochomill forces` and `calibrate`.
struct ForceSettings {
  int fast_steps_per_rev = 96;      ///< fast chip source: time steps per revolution
  double ploughing_angle_deg = 80;  ///< zeta: sub-segments steeper than this to v_c plough
};

/// `[topography]`: digitised (or synthetic) wear states of the cutting edge (topography.hpp).
struct TopographySettings {
  std::vector<std::filesystem::path> files;  ///< STL/PLY/OBJ meshes, one per wear state
  std::vector<double> synthetic_vb_mm;       ///< or synthetic inserts, one per flank wear VB
  int state = 0;                             ///< the wear state used (index)
  double band_mm = 0.2;                      ///< band along the edge that is sampled (mm)
  double rake_deg = 0;                       ///< synthetic insert: rake angle (degrees)
  double clearance_deg = 7;                  ///< synthetic insert: clearance angle (degrees)
  [[nodiscard]] std::size_t states() const noexcept {
    return files.empty() ? synthetic_vb_mm.size() : files.size();
  }
};

struct Job {
  std::string source;  ///< file name the job came from (for messages)
  Tool tool;
  Slot slot;
  PathSpec path;
  Cutting cutting;
  Machine machine;
  Measured measured;
  AnalysisSettings analysis;
  MechanismJob mechanism;
  MonitorSettings monitor;
  SimSettings simulation;
  Material material;
  ForceSettings forces;
  TopographySettings topography;
  /// `[stock]` min / max corners (mm); absent: the slot region with a 1 mm margin (sim.hpp).
  std::optional<std::array<double, 3>> stock_min_mm, stock_max_mm;
  // The original document, flattened `section.key = value` (TOML syntax), after overrides:
  // written into the G-code header so a program records the job that produced it.
  std::vector<std::pair<std::string, std::string>> flat_keys;
};

/// A `--set section.key=value` override (value in TOML syntax; bare words are strings).
struct Override {
  std::string key;    ///< "section.key"
  std::string value;  ///< "0.8", "true", "elliptical", "[0, 90, 180, 270]"
};

/// Parses "section.key=value". Throws InputError when there is no '=' or no section.
[[nodiscard]] Override parse_override(std::string_view text);

/// Loads and validates a job file, applying overrides in order.
/// Throws InputError listing every problem (file:line:column or key, what is allowed).
[[nodiscard]] Job load_job(const std::filesystem::path& file,
                           const std::vector<Override>& overrides = {});

/// Same as load_job, from TOML text; `source_name` is used in messages.
[[nodiscard]] Job parse_job(std::string_view toml_text, std::string_view source_name,
                            const std::vector<Override>& overrides = {});

/// The materials library: data/materials/*.toml, looked up in $TROCHOMILL_DATA/materials, then
/// the source tree's data/materials, then the installed share/trochomill/materials.
[[nodiscard]] std::filesystem::path materials_dir();
/// Every material of the library, sorted by name. Throws InputError for a malformed file.
[[nodiscard]] std::vector<Material> material_library();

[[nodiscard]] std::string_view to_string(PathType t) noexcept;
[[nodiscard]] std::string_view to_string(ForceModel m) noexcept;
[[nodiscard]] std::string_view to_string(Dialect d) noexcept;
[[nodiscard]] std::string_view to_string(EntryType e) noexcept;
[[nodiscard]] std::string_view to_string(Direction d) noexcept;
/// Parses a dialect name (linuxcnc | fanuc | sinumerik | grbl); InputError otherwise.
[[nodiscard]] Dialect parse_dialect(std::string_view name);

}  // namespace trochomill
