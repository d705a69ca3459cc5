// Studies over many job variants: `trochomill sweep` evaluates a grid or a space-filling
// sample of keys with analyze, mechanism, forces or simulate and writes one row per point,
// appended as points finish (in point order), so a stopped run resumes where it stopped.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "trochomill/analysis.hpp"
#include "trochomill/job.hpp"
#include "trochomill/progress.hpp"

namespace trochomill {

/// Parses "section.key=v1,v2,..." (a value may be a TOML array in brackets): the values of
/// compare's and sweep's grids and optimize's choices. Throws InputError.
[[nodiscard]] Vary parse_vary(const std::string& text);

/// `compare`: analyze (with the predicted force) on every point of the grid, the Cartesian
/// product of `varies` in plan_sweep's order (the first key slowest), through the sweep's own
/// plan, evaluation and parallel loop, every point's metrics kept (at most 100,000 points).
/// Each point's job is built from the parsed document `doc` with the `base` overrides then its
/// values (the file is read once); results are in grid order whatever `threads` (0: all
/// cores). A point whose job is invalid or whose evaluation fails records the message, not
/// thrown; an unknown or repeated key is an InputError before any point runs. `hooks`: the
/// phase "grid" with progress per point; cancelling stops it with Interrupted.
[[nodiscard]] std::vector<StudyPoint> run_compare(const JobDocument& doc,
                                                  const std::vector<Override>& base,
                                                  const std::vector<Vary>& varies, int threads,
                                                  const RunHooks& hooks = {});

/// A key sampled over an interval (`--range key=lo:hi`); integer keys are rounded.
struct SweepRange {
  std::string key;
  double lo = 0, hi = 0;
};
/// Parses "section.key=lo:hi" (lo < hi, finite). Throws InputError, its message starting with
/// `what` (the option the text came from, an option_name; empty: the sweep's ranges).
[[nodiscard]] SweepRange parse_range(const std::string& text, std::string_view what = {});

enum class Sampler {
  sobol,  ///< Sobol's low-discrepancy sequence (Joe and Kuo's directions; first point skipped)
  lhs,    ///< Latin hypercube: one sample per stratum and dimension, seeded permutations
};
[[nodiscard]] Sampler parse_sampler(const std::string& name);

/// The points of a sweep: every combination of the grid's values (the first key slowest),
/// each combined with every sample of the ranges (`samples` points in [lo, hi] per key).
struct SweepPlan {
  std::vector<std::string> keys;                 ///< the grid's keys, then the ranges'
  std::vector<std::vector<std::string>> points;  ///< per point, a TOML value per key
};
/// Throws InputError for an unknown key, a key given twice, ranges without samples (or
/// samples without ranges), or more than 1,000,000 points.
[[nodiscard]] SweepPlan plan_sweep(const std::vector<Vary>& grid,
                                   const std::vector<SweepRange>& ranges, std::size_t samples,
                                   Sampler sampler, std::uint64_t seed);
/// The unit-cube samples (samples x dimensions, each in [0, 1)) the plan maps onto its ranges.
[[nodiscard]] std::vector<std::vector<double>> unit_samples(std::size_t samples,
                                                            std::size_t dimensions, Sampler sampler,
                                                            std::uint64_t seed);

/// What each point runs.
enum class SweepEval { analyze, mechanism, forces, simulate };
[[nodiscard]] SweepEval parse_sweep_eval(const std::string& name);
[[nodiscard]] std::string_view to_string(SweepEval e) noexcept;

/// The metrics of one point: the numbers of the evaluation's JSON document (as the sweep's
/// columns; null figures left out). Throws what the evaluation throws.
/// `memory_limit_bytes` (> 0): a simulation whose memory estimate passes it is refused
/// (InputError) before it starts. `parts`: for analyze, the analysis's parts to compute
/// (report.hpp: analysis_parts_for; the metrics of the others are left out).
[[nodiscard]] std::map<std::string, double> point_metrics(
    const Job& job, SweepEval eval, const std::optional<std::pair<int, int>>& cycles,
    const RunHooks& hooks = {}, double memory_limit_bytes = 0, const AnalysisParts& parts = {});
/// The metric names an evaluation gives (the sweep's metric columns).
[[nodiscard]] std::vector<std::string> metric_names(const Job& base, SweepEval eval);

/// How a sweep runs.
struct SweepOptions {
  SweepEval eval = SweepEval::analyze;
  /// forces and simulate: the window, trochoid cycles [first, last) (default: the steady
  /// cycle analyze finds).
  std::optional<std::pair<int, int>> cycles;
  int threads = 0;  ///< points evaluated at once (0: all cores)
  /// The memory the points in flight may take together (bytes; 0: no limit): each
  /// simulation is refused before it starts when its estimate passes its share.
  double memory_limit_bytes = 0;
};

/// The columns of a sweep's CSV: index, the plan's keys, ok, error, then the metrics of the
/// evaluation (the numeric leaves of its JSON document, nested keys joined by '.', e.g.
/// zone_share.CZIII; wall times left out).
[[nodiscard]] std::vector<std::string> sweep_columns(const SweepPlan& plan, const Job& base,
                                                     SweepEval eval);

/// The MPI world of a run started by mpirun (Open MPI's OMPI_COMM_WORLD_SIZE or a PMI_SIZE in
/// the environment) in a build with MPI: MPI is initialised (threads: funneled) for the
/// object's life. A plain run, or a build without MPI, is one rank and never touches MPI.
class Distributed {
 public:
  Distributed();
  ~Distributed();
  Distributed(const Distributed&) = delete;
  Distributed& operator=(const Distributed&) = delete;
  [[nodiscard]] int rank() const noexcept { return rank_; }
  [[nodiscard]] int size() const noexcept { return size_; }
  /// True when the build has MPI.
  [[nodiscard]] static bool built_with_mpi() noexcept;

 private:
  int rank_ = 0, size_ = 1;
  bool initialised_ = false;
};

/// Runs the sweep into `csv`: rows are appended as points finish, in point order, each with
/// one write (a killed run leaves whole rows; a torn last line is dropped on resume). With
/// `resume`, an existing file whose header is this sweep's keeps its rows and only the points
/// not in it run; without, an existing file is refused. A point that fails records its
/// message in `error` (the sweep goes on). Each point's job is built from `doc` with `base`
/// then its values. Returns the number of points evaluated now. `hooks`: the phase "points"
/// with progress per point; Ctrl-C stops it after the points running (Interrupted; the rows
/// written stay). Results do not depend on the thread count. With a `world` of several
/// ranks, rank 0 reads and writes the file and hands out points one at a time to whichever
/// rank asks (itself included, on a second thread), so ranks of unequal speed stay busy;
/// every rank evaluates one point at a time; the file is the single-process run's, row for
/// row. The other ranks return 0.
std::size_t run_sweep(const JobDocument& doc, const std::vector<Override>& base,
                      const SweepPlan& plan, const SweepOptions& options,
                      const std::filesystem::path& csv, bool resume, const RunHooks& hooks = {},
                      const Distributed* world = nullptr);

/// A sweep's CSV read back: the columns and the rows (cells as text). Throws InputError for
/// a file that is not a sweep's.
struct SweepTable {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
};
[[nodiscard]] SweepTable read_sweep_csv(const std::filesystem::path& csv);
/// The table as JSON: {"columns": [...], "points": [{column: value}...]} (numbers as numbers).
[[nodiscard]] std::string sweep_json(const SweepTable& t);

// ---- optimisation (`trochomill optimize`) ---------------------------------------------------

/// A variable: a number key over [lo, hi] (`key=lo:hi`; integer keys rounded) or a choice
/// among TOML values (`key=a,b,c`, e.g. the path family).
struct OptVariable {
  std::string key;
  double lo = 0, hi = 0;
  bool integer = false;
  std::vector<std::string> choices;  ///< non-empty: a choice variable
};
/// Parses "section.key=lo:hi" or "section.key=v1,v2,..."; checks the key (a number or integer
/// key for a range). Throws InputError.
[[nodiscard]] OptVariable parse_opt_variable(const std::string& text);
/// A goal: a metric to maximise or minimise.
struct Objective {
  std::string metric;
  bool maximize = true;
};
/// A constraint "metric<=value" or "metric>=value".
struct Constraint {
  std::string metric;
  bool upper = true;  ///< metric <= value (else >=)
  double value = 0;
};
[[nodiscard]] Constraint parse_constraint(const std::string& text);

struct OptimizeOptions {
  SweepEval eval = SweepEval::analyze;
  std::optional<std::pair<int, int>> cycles;  ///< forces and simulate: the window
  int max_evaluations = 300;                  ///< per choice combination
  std::uint64_t seed = 1;
  int population = 24;  ///< NSGA-II's population (two or more objectives; a multiple of 4)
  /// The memory an evaluation may take (bytes; 0: no limit): a simulation whose estimate
  /// passes it is refused before it starts (the point fails, saying so).
  double memory_limit_bytes = 0;
};
/// One evaluated point.
struct OptPoint {
  std::vector<std::string> values;        ///< per variable, the TOML value
  std::map<std::string, double> metrics;  ///< empty when the point failed
  std::string error;
  bool feasible = false;  ///< evaluated, every constraint held (within 1e-9 of its bound)
};
struct OptimizeResult {
  std::vector<std::string> keys;  ///< the variables' keys
  std::optional<OptPoint> best;   ///< one objective: the best feasible point
  std::vector<OptPoint> pareto;   ///< two or more: the feasible non-dominated points
  std::size_t evaluations = 0;    ///< distinct points evaluated
  std::size_t failed = 0;         ///< of them, the points whose evaluation failed
  std::string first_error;        ///< the first failed point's error (in evaluation order)
  std::string method;
};
/// One objective: for each combination of the choice variables, NLopt's ISRES (global,
/// with the constraints) then COBYLA (local polish) over the numeric variables, seeded; the
/// best feasible point of all evaluated. Two or more: pagmo's NSGA-II, infeasible points
/// penalised, and the Pareto set of all feasible points evaluated. Points that fail count as
/// infeasible. Throws InputError for an unknown metric or no variables; cancelling (hooks)
/// throws Interrupted.
[[nodiscard]] OptimizeResult optimize(const JobDocument& doc, const std::vector<Override>& base,
                                      const std::vector<OptVariable>& variables,
                                      const std::vector<Objective>& objectives,
                                      const std::vector<Constraint>& constraints,
                                      const OptimizeOptions& options, const RunHooks& hooks = {});

}  // namespace trochomill
