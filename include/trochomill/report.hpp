// Formatting of analysis results (JSON, CSV, tables) and the parameter study `compare`.
// The library formats; the CLI decides where the text goes.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/analysis.hpp"
#include "trochomill/feed.hpp"
#include "trochomill/force.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/job.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/progress.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/surface.hpp"
#include "trochomill/topography.hpp"

namespace trochomill {

/// The analysis as a JSON document (keys carry their units: _mm, _s, _deg, _mm3_per_min).
[[nodiscard]] std::string metrics_json(const Job& job, const ProcessMetrics& m);
/// `analyze`'s summary; `gcode`: the program analysed (empty: the planned path).
[[nodiscard]] std::string metrics_text(const std::string& job_file, const std::string& gcode,
                                       const Job& job, const ProcessMetrics& m);

/// `path`'s samples with every tooth's tip (mm, s).
[[nodiscard]] std::string path_samples_csv(const PathSamples& s, const ToothTracks& tr);
/// The same, handed to `sink` in pieces of about 1 MB (a file of any size, written as it is
/// made); `hooks`: the phase "writing CSV" with progress over the rows, cancelling throws
/// Interrupted.
void write_path_samples_csv(const PathSamples& s, const ToothTracks& tr,
                            const std::function<void(std::string_view)>& sink,
                            const RunHooks& hooks = {});
/// `check-gcode`'s report of a program: length, time (with the acceleration limit, when one
/// is given), bounding box, feeds and spindle speed.
[[nodiscard]] std::string gcode_check_json(const std::string& file, const GcodeProgram& prog,
                                           double time_with_acceleration_s);
[[nodiscard]] std::string gcode_check_text(const std::string& file, const GcodeProgram& prog,
                                           double time_with_acceleration_s,
                                           double max_acceleration_mm_per_s2);

/// `mechanism`'s curves and zone summary (`use_wear`: K_re with the flank wear).
[[nodiscard]] std::string mechanism_json(const Job& job, const MechanismSettings& st,
                                         const MechanismCurve& c, const ZoneSummary& z,
                                         bool use_wear);
[[nodiscard]] std::string mechanism_csv(const MechanismCurve& c);
[[nodiscard]] std::string mechanism_text(const std::string& job_file, const Job& job,
                                         const MechanismSettings& st, const MechanismCurve& c,
                                         const ZoneSummary& z, bool use_wear);
[[nodiscard]] std::string recommendation_json(const Job& job, const MechanismSettings& st,
                                              const Recommendation& r, bool for_feed);

/// The time series as CSV: t_s, x_mm, y_mm, z_mm, engaged angles (deg, "start:end" pairs
/// separated by ';'), engagement_deg, h_max_mm, teeth_in_cut, mrr_mm3_per_min.
[[nodiscard]] std::string series_csv(const EngagementSeries& e);

/// One `--vary key=v1,v2,...` of a parameter study.
[[nodiscard]] std::string study_table(const std::vector<Vary>& varies,
                                      const std::vector<StudyPoint>& points);
[[nodiscard]] std::string study_json(const std::vector<Vary>& varies,
                                     const std::vector<StudyPoint>& points);
[[nodiscard]] std::string study_csv(const std::vector<Vary>& varies,
                                    const std::vector<StudyPoint>& points);

/// The monitor's results as JSON: keys `k_f_mean`, `k_f_per_cycle` (array), `cycles` (count),
/// `cycle_source`, `period_s`, `reference_k_f`, `wear_trend`, `flags` (strings), per-cycle
/// details under `cycle_details`, the settings, and the model profile (`model`) with a job.
[[nodiscard]] std::string monitor_json(const MonitorReport& r, const std::string& signal,
                                       const Signal& s, const MonitorSettings& m);
/// Per window: t_s, rms_low, rms_high, k_f, cycle (-1 outside), phase, zone (-1 unknown).
[[nodiscard]] std::string monitor_csv(const MonitorReport& r);
/// A short human summary.
[[nodiscard]] std::string monitor_table(const MonitorReport& r, const std::string& signal,
                                        const Signal& s);
/// One live window as a JSON line (newline-terminated).
[[nodiscard]] std::string live_json_line(const LiveWindow& w);
/// Welch PSD as CSV (f_hz, psd_per_hz) and a spectrogram in long form (t_s, f_hz, db).
[[nodiscard]] std::string spectrum_csv(const Spectrum& sp);
[[nodiscard]] std::string spectrogram_csv(const Spectrogram& sg);
/// `spectrum`'s summary: the rate, the bins and the eight strongest peaks.
[[nodiscard]] std::string spectrum_text(const std::string& file, const Signal& sig,
                                        const Spectrum& sp, int nfft);

/// The simulation's per-step series: t_s, x_mm, y_mm, z_mm, removed_tooth<k>_mm3, h_max_mm,
/// h_mean_mm, engaged_segments.
[[nodiscard]] std::string sim_series_csv(const SimResult& r, std::size_t teeth);
/// sim_series_csv's header line, and one step's row appended to `csv` (the series streamed).
[[nodiscard]] std::string sim_series_header(std::size_t teeth);
void append_sim_series_row(std::string& csv, const SimStep& step, std::size_t teeth);
/// Whether a summary key (simulate's, forces', chips') is a measurement of the run itself
/// (wall and processor times, rates, utilisation, threads, peak memory, the memory estimate),
/// which differs from run to run with the same input.
[[nodiscard]] bool is_run_measurement(std::string_view key);
/// `simulate`'s summary: the window, removed volume, h_max, updates, wall times (s) and
/// memory (MB; `memory_estimate_bytes` as estimated before the run).
[[nodiscard]] std::string simulation_json(const Job& job, const JobSimulation& js, double from_s,
                                          double to_s, double wall_s, double memory_estimate_bytes);
[[nodiscard]] std::string simulation_text(const std::string& job_file, const Job& job,
                                          const JobSimulation& js, double from_s, double to_s,
                                          double wall_s);
/// The slot's floor a simulation left, as a height map at the dexel spacing: floor_height_map
/// across the slot less the tool's corner radius and a spacing at each wall, cut below half
/// the depth. Throws InputError when the window left no floor cut across the slot.
[[nodiscard]] HeightMap simulated_floor(const Job& job, const JobSimulation& js);
/// simulate's --out set, written as one set: series.csv and chips.h5 as the steps are made
/// (this is the SimSink for SimControl::sink: a whole program's records never sit in memory),
/// then by `finish` walls.csv, floor.csv, surface.stl (grid step `stl_step_mm`, or
/// default_surface_step_mm) and floor.x3p (the slot's floor as a height map at the dexel
/// spacing: simulated_floor) from the workpiece. Everything is made in a staging folder inside
/// `dir` (made if missing, as mkdir: its parent must exist, else InputError; removed again
/// when the run fails) and renamed into place by `finish`; when the window left no floor cut across
/// the slot, floor.x3p is not written (an earlier run's is removed: the set stays one run's)
/// and `finish` returns the reason (otherwise empty). A simulation stopped early (Ctrl-C) is
/// finished as well: chips.h5 then says complete = 0. `hooks`: the phase "writing outputs"
/// with progress per file; when cancelled between files `finish` throws Interrupted. Destroyed
/// unfinished (an error, a cancel), the staging folder is removed: `dir` then holds none of
/// this run's files (those of an earlier run stay as they were). Throws IoError (naming the
/// file under `dir`, with the system's reason) or Error.
class SimulationOutputs final : public SimSink {
 public:
  SimulationOutputs(const std::filesystem::path& dir, const Job& job);
  ~SimulationOutputs() override;
  void take(const SimStep& step, std::span<const ChipEntry> chips) override;
  [[nodiscard]] std::string finish(const JobSimulation& js, std::optional<double> stl_step_mm,
                                   const RunHooks& hooks = {});

 private:
  struct State;
  std::unique_ptr<State> s_;
};
/// The set of SimulationOutputs from a simulation whose records were kept (replayed into it).
[[nodiscard]] std::string write_simulation_outputs(const std::filesystem::path& dir, const Job& job,
                                                   const JobSimulation& js,
                                                   std::optional<double> stl_step_mm,
                                                   const RunHooks& hooks = {});
/// The force series: t_s, f_x_n, f_y_n, f_z_n, f_resultant_n, torque_nm, power_w, then per
/// tooth k: tooth<k>_f_x_n, tooth<k>_f_y_n, tooth<k>_f_z_n, tooth<k>_torque_nm. `calibrate`
/// reads it as it is.
[[nodiscard]] std::string force_series_csv(const ForceSeries& s);
/// `trochomill forces`' summary: JSON (f_resultant_max_n, f_x_max_n, f_y_max_n, f_z_max_n,
/// torque_max_nm, power_max_w, means, model, chip source, window, wall times) and text.
[[nodiscard]] std::string force_summary_json(const Job& job, const JobForces& f, double from_s,
                                             double to_s);
[[nodiscard]] std::string force_summary_text(const Job& job, const JobForces& f, double from_s,
                                             double to_s);
/// A calibration: JSON (the fitted parameters under their key names, rmse_n, r2, shift_s,
/// cutoff_hz, samples, iterations, ci95 per parameter) and text (with the [material] block).
[[nodiscard]] std::string calibration_json(const CalibrationResult& r);
[[nodiscard]] std::string calibration_text(const std::string& measured, const CalibrationResult& r);
/// The mean-force regression's [material] block (TOML) and JSON.
[[nodiscard]] std::string mean_force_toml(const MeanForceFit& f);
[[nodiscard]] std::string mean_force_json(const MeanForceFit& f);
/// The materials library as JSON and as a table with sources.
/// The job keys (job_keys()) as an aligned table, and as JSON.
[[nodiscard]] std::string job_keys_text();
[[nodiscard]] std::string job_keys_json();
[[nodiscard]] std::string materials_json(const std::vector<Material>& lib);
[[nodiscard]] std::string materials_text(const std::vector<Material>& lib, const std::string& dir);
/// The structured grid per cell: kappa, tau, s_mm, h_mm, r_mm, width_mm, proj_mm,
/// proj_end_mm, para_mm, facet_r, facet_c, facet_a (d_c in the tooth frame: radial, cutting
/// direction, axial), normal_r, normal_a (d_n).
[[nodiscard]] std::string edge_grid_csv(const EdgeGrid& g);
/// A sampled topography: JSON (points, facets_kept, facets_total, s_min_mm, s_max_mm,
/// segments, sub_segments, band_mm, and per segment the facet angle to the cutting direction
/// of its outermost and innermost sub-segments) and text.
[[nodiscard]] std::string topography_json(const EdgeGrid& g, const EdgeTopography& info);
[[nodiscard]] std::string topography_text(const std::string& source, const EdgeGrid& g,
                                          const EdgeTopography& info);
/// Wall profiles: y_mm, z_mm, left_x_mm, right_x_mm.
[[nodiscard]] std::string wall_profiles_csv(const std::vector<WallPoint>& w);
/// Floor profiles: y_mm, x_mm, z_mm.
[[nodiscard]] std::string floor_profiles_csv(const std::vector<FloorPoint>& f);
/// The height field as a closed solid in binary STL (mm): top surface, side walls, bottom.
[[nodiscard]] std::string height_field_stl(const HeightField& f);

/// One evaluated surface of `trochomill texture`.
struct TextureEntry {
  std::string surface;                ///< "left", "right", "floor", "profile" or "surface"
  std::string description;            ///< where the profile or map came from
  ProfileTexture texture;             ///< a profile's texture (when `areal` is empty)
  std::optional<ArealTexture> areal;  ///< an areal surface's texture instead
  /// The areal surface against a predicted one (`texture --against`), and where that came from.
  std::optional<SurfaceComparison> comparison;
  std::string against;
};
/// `texture`'s report: per profile the cut-off (and how it was chosen), Ra, Rq, Rsk, Rku, Rp,
/// Rv, Rz, Rt, RSm, Wa, Wt (mm), evaluation length (mm) and sections; per areal surface the
/// S- and L-filters' nesting indices, the F-operator, and Sa, Sq, Ssk, Sku, Sp, Sv, Sz (mm),
/// Sdr (%), Sal (mm), Str of the S-L surface and the same but Sal and Str of the S-F surface.
[[nodiscard]] std::string texture_json(const std::string& source,
                                       const std::vector<TextureEntry>& entries);
[[nodiscard]] std::string texture_text(const std::string& source,
                                       const std::vector<TextureEntry>& entries);

// ---- the HTML report (`trochomill report`) ---------------------------------------------------

/// Indices of the samples to keep when a series is drawn at `columns` pixel columns: the
/// samples are split into `columns` runs of equal length and each run keeps its first and last
/// sample and, for every series in `ys`, the sample of its minimum and maximum (NaN skipped).
/// So every extreme of every series survives, and at most columns * (2 + 2 ys.size()) samples
/// remain. All samples are kept when there are at most 2 columns. Sorted, without repeats.
[[nodiscard]] std::vector<std::size_t> decimation_indices(
    std::size_t samples, const std::vector<const std::vector<double>*>& ys, std::size_t columns);

/// A parameter study shown in the report.
struct ReportStudy {
  std::vector<Vary> varies;
  std::vector<StudyPoint> points;
};
/// The mechanism of the report: the job's chip model, and the other one when both apply.
struct ReportMechanism {
  MechanismCurve curve;
  ZoneSummary zones;
  bool use_wear = false;
  std::optional<MechanismCurve> other;  ///< the other chip model's curve (exact or published)
};
/// Forces of the report (fast chip source): the job's wear state, and the last state when the
/// job has several ([topography]).
struct ReportForces {
  JobForces forces;
  double from_s = 0, to_s = 0;  ///< the window (s of program)
  std::optional<JobForces> worn;
  std::string state_label, worn_label;  ///< e.g. "new (VB 0 mm)"
};
/// A calibration of the report: the fit, the measured record and the fitted model's forces.
struct ReportCalibration {
  std::string measured_file;
  CalibrationResult result;
  MeasuredForces measured;
  ForceSeries model;  ///< the fitted model over the window (measured time = t + shift_s)
};
/// A simulation of the report.
struct ReportSimulation {
  JobSimulation sim;
  double from_s = 0, to_s = 0, wall_s = 0, memory_estimate_bytes = 0;
};
/// The monitor of the report.
struct ReportMonitor {
  std::string signal_file;
  Signal signal;
  MonitorSettings settings;
  MonitorReport report;
  Spectrum spectrum;
  Spectrogram spectrogram;
};
/// A Pareto set of `optimize` shown in the report: per point the variables' values and the
/// goals' values.
struct ReportPareto {
  std::vector<std::string> keys;   ///< the variables
  std::vector<std::string> goals;  ///< the goals' metrics
  std::vector<bool> maximize;      ///< per goal
  std::vector<std::vector<std::string>> values;
  std::vector<std::vector<double>> goal_values;
};
/// Everything a report shows; each optional part is drawn when present, and `notes` say why a
/// default part is missing (e.g. no [material]: no forces).
struct ReportData {
  std::string job_file, gcode_file;
  std::string job_text;                ///< the job file as read
  std::vector<std::string> overrides;  ///< the --set overrides and flags, "key=value"
  std::string command;                 ///< the command line that made the report
  Job job;
  ToolPath path;
  ProcessMetrics metrics;
  std::optional<ReportMechanism> mechanism;
  std::optional<ReportForces> forces;
  std::optional<ReportCalibration> calibration;
  std::optional<ReportSimulation> simulation;
  std::optional<ReportMonitor> monitor;
  std::optional<ReportStudy> study;
  std::optional<ReportPareto> pareto;
  /// optimize-feed's result: feed, chip and force along the program before and after.
  std::optional<FeedOptimizeResult> feed;
  std::vector<std::string> notes;
};
/// What a report is asked to show besides the defaults, and what it records.
struct ReportRequest {
  std::string job_file, gcode_file;  ///< shown in the page
  std::string job_text;              ///< the job file as read
  std::vector<Override> overrides;   ///< recorded, and the base of the study's points
  std::string command;               ///< the command line that made it
  /// "mechanism" or "forces" (required: an error where the job cannot have them; by default
  /// shown where it can) and "simulate" (the tri-dexel window).
  std::vector<std::string> with;
  /// The window of forces, simulation and calibration (s of program); default: the steady
  /// cycle analyze finds (calibration: the measured record's span).
  std::optional<std::pair<double, double>> window_s;
  std::optional<Signal> signal;  ///< the monitor's recording
  std::string signal_file;
  std::optional<double> signal_start_s;    ///< where the program starts in it (s)
  std::optional<MeasuredForces> measured;  ///< a record to calibrate against
  std::string measured_file;
  std::vector<Vary> varies;               ///< a parameter study over these keys
  const JobDocument* document = nullptr;  ///< the job's document (the study builds from it)
  /// Called with the simulation's memory estimate (bytes) before it runs; throws to refuse.
  std::function<void(double)> check_simulation_memory;
};
/// Checks a request against its job before any work: the items of `with`, a signal without
/// its start (or the reverse), forces or a calibration without a [material] model, a study
/// without its document, the monitor's settings against the signal's rate. Throws
/// InputError naming the item and what is allowed.
void check_report_request(const Job& job, const ReportRequest& request);
/// Runs what the report needs on `path` (the job's plan or an NC program): analyze, the
/// mechanism where the family has one (both chip models where both apply), the fast forces
/// where the job has a [material] model (its wear state against the last or first of
/// [topography]), and what the request adds: the simulation window, the monitor (Welch
/// spectrum and spectrogram with it), the calibration (fast chips) with the fitted model's
/// forces, the study. What a default part leaves out goes into `notes`. Checks the request
/// first (check_report_request). `hooks`: the phases of each part; cancelling throws
/// Interrupted (a stopped simulation too).
[[nodiscard]] ReportData build_report(Job job, ToolPath path, ReportRequest request,
                                      const RunHooks& hooks = {});
/// The report as one self-contained HTML page: the data (decimated for display: at most
/// `report_columns` pixel columns per series by decimation_indices, the surface mesh within
/// `report_triangles`) as JSON and the bundled scripts and styles (uPlot, and three.js when
/// there is a 3D view) inline, nothing fetched. `hooks`: the phase "writing report".
inline constexpr std::size_t report_columns = 1000;
inline constexpr std::size_t report_triangles = 400000;
[[nodiscard]] std::string report_html(const ReportData& data, const RunHooks& hooks = {});
/// The data document the page draws (what report_html embeds), for tests and scripts.
[[nodiscard]] std::string report_data_json(const ReportData& data, const RunHooks& hooks = {});

}  // namespace trochomill
