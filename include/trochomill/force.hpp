// Cutting forces per engaged edge segment (Bergmann 2021 Eq. 2-3, Kienzle, the linear
// edge-force model), summed per tooth and over the tool in the workpiece (dynamometer)
// frame, with torque and spindle power; two chip sources (the dexel simulation and a fast
// analytic one); calibration of the coefficients against measured forces. docs/models.md
// section 12 gives every reading and its test.
//
// Units: mm, s, N, N m, W; angles in radians inside. Forces act on the workpiece: x across
// the slot, y along it, z up (the frame of path.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "trochomill/analysis.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/topography.hpp"

namespace trochomill {

/// Force, torque and power over time: one entry per chip step (SimResult::steps).
struct ForceSeries {
  int teeth = 0;
  std::vector<double> t_s;
  std::vector<double> fx_n, fy_n, fz_n;  ///< on the workpiece (N)
  std::vector<double> torque_nm;         ///< about the spindle axis, resisting the cut (N m)
  std::vector<double> power_w;           ///< spindle power torque * |omega| (W)
  /// Per tooth: [step * teeth + tooth].
  std::vector<double> tooth_fx_n, tooth_fy_n, tooth_fz_n, tooth_torque_nm;
  [[nodiscard]] std::size_t size() const noexcept { return t_s.size(); }
  [[nodiscard]] double resultant_n(std::size_t i) const;
};

struct ForceSummary {
  double f_resultant_max_n = 0, t_resultant_max_s = 0;
  double f_x_max_n = 0, f_y_max_n = 0, f_z_max_n = 0;  ///< largest magnitude of each component
  double f_x_mean_n = 0, f_y_mean_n = 0, f_z_mean_n = 0;
  double torque_max_nm = 0, power_max_w = 0, power_mean_w = 0;
};
[[nodiscard]] ForceSummary summarize(const ForceSeries& s);

/// The force model of a material on one edge grid: precomputed per segment the effective
/// directions d_e as the chip covers more sub-segments (Eq. 2) and the ploughing depth.
class SegmentForces {
 public:
  /// Throws InputError when the material has no model or its coefficients are unusable.
  SegmentForces(const Material& material, const EdgeGrid& grid, double ploughing_angle_rad);
  /// Force on the workpiece of segment kappa cutting a chip h (mm, normal to the edge) over
  /// the width w (mm), in the tooth frame (radial out, cutting direction, axial up) (N).
  [[nodiscard]] std::array<double, 3> force(int kappa, double h_mm, double w_mm) const;
  [[nodiscard]] const Material& material() const noexcept { return m_; }

 private:
  struct Sub {
    double proj_mm = 0;           // contact starts when h exceeds this
    double plough_mm = 0;         // h_s candidate: its inner Delta_proj if steep, else 0
    std::array<double, 3> d_e{};  // normalised sum of w_j d_c^j up to this sub-segment
  };
  Material m_;
  int tau_ = 1;
  std::vector<Sub> subs_;    // [kappa * tau + j]
  std::vector<Vec3> d_n_;    // contour normal per kappa
  std::vector<Vec3> along_;  // up the edge per kappa
};

/// Forces of a chip record (SimResult::steps and chip_map, from `simulate` or `fast_chips`):
/// each entry's segment force rotated into the workpiece frame at its edge angle (tooth
/// angle, spindle rotation and helix lag at the segment's height).
[[nodiscard]] ForceSeries compute_forces(const SimResult& chips, const SimTool& tool,
                                         const EdgeGrid& grid, const SegmentForces& model);

/// The fast chip source: the analytic engagement (engagement.hpp) gives the engaged arcs of
/// the tool circle; each tooth's edge is cut into axial discs (one per edge segment), each
/// at its own angle (helix lag); the chip normal to the edge is the offset, along the edge
/// normal, between this tooth's contour and each earlier tooth's when it passed that angle:
/// the tool-centre displacement projected on the radial direction plus the radial offsets
/// (runout, seating), times the normal's radial part, plus the tip-height difference (axial
/// runout, seating) times its downward part (docs/models.md section 12). Same record format
/// as the simulation (no removed volumes: SimStep::removed_mm3 stays empty). Throws
/// InputError for an empty window.
[[nodiscard]] SimResult fast_chips(const Job& job, const ToolPath& path, const SimTool& tool,
                                   double from_s, double to_s, int steps_per_rev);
/// The same, keeping the engagement and the centre path so chips can be recomputed for tools
/// that differ in runout or seating only (calibration).
class FastChipSource {
 public:
  /// `engagement`, if given, is the path's engagement at one sample per tooth pass (as
  /// analyze computes it), used instead of computing it again. `hooks`: the phases
  /// "engagement" (here) and "chips" (each scan) with their progress; cancelling throws
  /// Interrupted.
  FastChipSource(const Job& job, const ToolPath& path, double from_s, double to_s,
                 int steps_per_rev, const EngagementSeries* engagement = nullptr,
                 const RunHooks& hooks = {});
  /// The hooks of the scans from now on.
  void set_hooks(const RunHooks& hooks) { hooks_ = hooks; }
  /// Throws InputError when `tool` turns at another speed than the job's.
  [[nodiscard]] SimResult chips(const SimTool& tool) const;
  /// The forces of those chips directly, without storing the chip record (the same numbers
  /// as compute_forces(chips(tool), ...)); the steps (times, tips, chip statistics) if asked.
  [[nodiscard]] ForceSeries forces(const SimTool& tool, const EdgeGrid& grid,
                                   const SegmentForces& model,
                                   std::vector<SimStep>* steps = nullptr) const;

 private:
  template <class Visit>
  void scan(const SimTool& tool, std::vector<SimStep>& steps, const Visit& visit) const;
  int spr_ = 0;
  double dt_ = 0;
  std::size_t nsteps_ = 0, back_ = 0;
  std::vector<double> times_;
  PathSamples ps_;  ///< centre positions only (x, y, z) on times_
  EngagementSeries eng_;
  RunHooks hooks_;
};

/// Job level: the edge grid (with the job's topography), the chip source and the forces.
struct JobForces {
  ForceSeries series;
  ForceSummary summary;
  SimResult chips;  ///< the simulation's record; in fast mode the steps only (no chip map)
  bool fast = false;
  double chips_wall_s = 0;   ///< simulation, or the fast source's engagement and path
  double forces_wall_s = 0;  ///< forces (in fast mode with the chips they come from)
};
/// `from_s`..`to_s` of the path (programmed time, s). The simulation runs as `simulate_job`
/// (pre-roll included; cancelled, its chips stop incomplete). In fast mode the phases are the
/// fast source's, and cancelling throws Interrupted. Throws InputError when the job has no
/// [material] model.
[[nodiscard]] JobForces job_forces(const Job& job, const ToolPath& path, double from_s, double to_s,
                                   bool fast, const SimControl& control = {},
                                   const EngagementSeries* engagement = nullptr);
/// The edge grid of the job: edge_grid of its tool, filled from [topography] when given.
/// `info`, if given, receives the topography's statistics (untouched for a sharp edge).
[[nodiscard]] EdgeGrid job_edge_grid(const Job& job, const SimTool& tool,
                                     EdgeTopography* info = nullptr);

/// Whether the material gives the force along the cutting direction alone (Kienzle or
/// Bergmann with k_n and k_a zero; linear with only k_tc and k_te): the forces are then the
/// cutting force alone, F_R,max a lower bound, the torque and the power whole.
[[nodiscard]] bool cutting_direction_only(const Material& m);
/// What that means, one sentence for the outputs (CLI, JSON, report) of such a material.
[[nodiscard]] std::string cutting_direction_only_note(const Material& m);

/// When the job has a [material] force model: F_R,max (N) over the steady cycle of `m` with
/// the fast chip source (Wagih's F_R,max is the trochoidal operation's, not the entry's),
/// reusing m's engagement, and the performance index from it (set_performance_index).
/// Nothing without a model. For analyze and compare.
void fill_predicted_force(const Job& job, const ToolPath& path, ProcessMetrics& m);
/// analyze_process with the predicted force filled in (what `analyze` and `compare` report);
/// without parts.force, analyze_process alone.
[[nodiscard]] ProcessMetrics analyze_with_forces(const Job& job, const ToolPath& path,
                                                 const RunHooks& hooks = {},
                                                 const AnalysisParts& parts = {});

// ---------------------------------------------------------------- calibration

/// Measured forces (a dynamometer's record), on the workpiece, N over s.
struct MeasuredForces {
  std::vector<double> t_s, fx_n, fy_n, fz_n;
};
/// How to read a measured-force CSV: column names, and the factors to s and N.
struct ForceCsvFormat {
  std::string time = "t_s", fx = "f_x_n", fy = "f_y_n", fz = "f_z_n";
  double time_to_s = 1.0;   ///< e.g. 1e-3 for a column in ms
  double force_to_n = 1.0;  ///< e.g. 1e3 for kN
};
/// Reads a CSV with a header line (comma, semicolon or tab separated; '#' comments).
/// Throws InputError naming the file, line and column for anything malformed.
[[nodiscard]] MeasuredForces read_measured_forces(const std::filesystem::path& file,
                                                  const ForceCsvFormat& format = {});

struct CalibrationOptions {
  ForceModel model = ForceModel::bergmann;
  /// Parameters to fit: the model's coefficients (k_c, k_n, m, m_n, k_a, m_a | k_tc, k_rc,
  /// k_ac, k_te, k_re, k_ae) and runout_radial, runout_phase, runout_axial. Empty: the
  /// model's main coefficients.
  std::vector<std::string> fit;
  bool fast = false;            ///< fast chip source instead of the simulation
  double cutoff_hz = 0;         ///< low-pass of both signals; 0: 4 tooth-passing harmonics
  double max_shift_s = -1;      ///< alignment search +-; < 0: half a spindle revolution
  double from_s = 0, to_s = 0;  ///< the window of the path the measurement covers
  /// Phases: the model's chips (the simulation's or the fast source's phases), then "fit"
  /// with progress per solver iteration (of at most 100). Cancelling throws Interrupted.
  RunHooks hooks;
};
struct FittedParameter {
  std::string name;
  double value = 0, std_error = 0, ci95_lo = 0, ci95_hi = 0;
  bool at_bound = false;
};
struct CalibrationResult {
  Material material;  ///< the fitted coefficients (model set)
  Tool tool;          ///< the job's tool with the fitted runout
  std::vector<FittedParameter> parameters;
  double rmse_n = 0, r2 = 0;
  double shift_s = 0;  ///< measured time = model time + shift
  double cutoff_hz = 0;
  std::size_t samples = 0;  ///< residual samples per axis
  int iterations = 0;
  std::string report;  ///< the solver's one-line summary
  /// What may bias the fit (a record too coarse for the force jumps of each tooth pass).
  std::vector<std::string> warnings;
};
/// Fits the model to the measured forces with bounded nonlinear least squares (Ceres,
/// trust region): both signals low-pass filtered alike, the measured one aligned to the
/// model by cross-correlation of the resultant and sampled at the model's steps.
/// Throws InputError for bad options or too little overlap.
[[nodiscard]] CalibrationResult calibrate_forces(const Job& job, const ToolPath& path,
                                                 const MeasuredForces& measured,
                                                 const CalibrationOptions& options);
/// The memory calibrate_forces will hold (bytes), before running it: the chips of the window
/// (simulated, or the fast source at its 500 steps per tooth pass), the model's force series,
/// the solver's residuals and Jacobian (3 per model step), the measured record and its
/// filtered copies, and the process (its resident memory now, at least 20 MB: process_base_bytes).
[[nodiscard]] double estimate_calibration_memory(const Job& job, const ToolPath& path,
                                                 const CalibrationOptions& options,
                                                 std::size_t measured_samples);
/// The `[material]` block of a result, TOML.
[[nodiscard]] std::string material_toml(const CalibrationResult& r);

/// Classical mean-force calibration of the linear model from full-immersion straight slots
/// at several feeds per tooth: per axis the mean force is linear in f_z, and the closed-form
/// averages give the six coefficients (docs/models.md section 12).
struct MeanForcePoint {
  double feed_per_tooth_mm = 0, fx_n = 0, fy_n = 0, fz_n = 0;
};
struct MeanForceFit {
  Material material;               ///< model linear, K_tc..K_ae
  std::array<double, 3> r2{};      ///< of the line per axis
  std::array<double, 3> slope{};   ///< N/mm per axis
  std::array<double, 3> offset{};  ///< N per axis
};
[[nodiscard]] MeanForceFit fit_mean_forces(const Job& job,
                                           const std::vector<MeanForcePoint>& points);
/// Reads f_z_mm (feed per tooth), f_x_n, f_y_n, f_z_n mean forces per slot test from CSV.
[[nodiscard]] std::vector<MeanForcePoint> read_mean_forces(const std::filesystem::path& file);

}  // namespace trochomill
