// The HTML report (`trochomill report`): what it holds, how it is built and rendered. Part of the
// report module (trochomill/report.hpp includes every part).
#pragma once

#include <cstddef>
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
#include "trochomill/report/analysis.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {

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
/// forces (the parameter study is the caller's: report_data in app.hpp runs it, with the
/// studies above this module). What a default part leaves out goes into `notes`. Checks the request
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
