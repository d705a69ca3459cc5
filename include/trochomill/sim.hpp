// Tri-dexel material-removal simulation (Bergmann 2021 Section 3; docs/models.md
// section 11): the workpiece as three perpendicular boards of dexels (rays holding sorted
// material intervals), the tool's cutting edges sweeping thin wedges between time steps,
// the removed intervals assigned to the edge segments that removed them, giving each
// segment's uncut chip thickness and removed volume. Lengths in mm, times in s, angles in
// radians inside (degrees at the job interface).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "trochomill/cutter.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/path.hpp"
#include "trochomill/progress.hpp"
#include "trochomill/settings/sim.hpp"
#include "trochomill/surface.hpp"

namespace trochomill {

struct Job;

/// A simulation's per-segment chip map, dense (the HDF5 file's layout): step n, tooth k,
/// segment g at h_mm[n * teeth * segments_per_tooth + k * segments_per_tooth + g]; 0 where
/// the segment is not engaged.
struct ChipMapData {
  std::size_t teeth = 0, segments_per_tooth = 0;
  double resolution_mm = 0;
  int steps_per_rev = 0;
  bool complete = true;
  std::vector<double> t_s;                ///< step times (s)
  std::vector<double> tip_mm;             ///< tool tip per step, x y z (mm)
  std::vector<double> removed_mm3;        ///< per step and tooth (mm^3)
  std::vector<float> h_mm;                ///< uncut chip thickness (mm)
  std::vector<float> w_mm;                ///< engaged width along the edge (mm), same layout
  std::vector<float> v_mm3;               ///< removed volume (mm^3), same layout
  std::vector<double> segment_height_mm;  ///< segment centres above the tip (mm)
};

/// Writes the chip map as HDF5 (datasets t_s, tip_mm, removed_mm3, h_mm, w_mm and v_mm3
/// (deflate),
/// segment_height_mm, each with a "unit" attribute; root attributes teeth,
/// segments_per_tooth, resolution_mm, steps_per_rev, complete), atomically. Throws Error.
void write_chip_map_h5(const std::filesystem::path& path, const ChipMapData& m);
/// Reads a file written by write_chip_map_h5. Throws Error.
[[nodiscard]] ChipMapData read_chip_map_h5(const std::filesystem::path& path);

/// The workpiece: three perpendicular boards of dexels over the stock. Opaque here: users hold
/// it (JobSimulation::work) and pass it to the profile and surface functions below; its storage
/// (BasicDexel, DexelBoard, TriDexel's boards, stock_from_mesh) is in trochomill/sim/dexel.hpp,
/// for the simulation's own tests and benchmarks.
struct TriDexel;

/// One time step's results.
struct SimStep {
  double t_s = 0;
  Vec3 tip_mm = Vec3::Zero();
  std::vector<double> removed_mm3;  ///< per tooth (Z board)
  double h_max_mm = 0, h_mean_mm = 0;
  int engaged_segments = 0;
};

/// One engaged segment at one step (the chip map, sparse).
struct ChipEntry {
  std::uint32_t step = 0;     ///< index into SimResult::steps
  std::uint32_t segment = 0;  ///< tooth * segments_per_tooth + segment along the edge
  float h_mm = 0;             ///< uncut chip thickness, normal to the edge
  float w_mm = 0;             ///< engaged width: the chip's extent along the edge (<= w_s)
  float v_mm3 = 0;            ///< volume the segment removed in the step (Z board)
};

/// What a simulate() call knows at its end about where material can still lie (the path
/// length swept in its last revolution of steps, the steps since the depth last changed), for
/// a call that continues it (SimControl::after).
struct SimCarry {
  double t_s = 0;                ///< the time the call's last step ended at (s)
  int steps_per_rev = 0;         ///< the steps per revolution it ran at
  std::size_t steps = 0;         ///< steps since the first call of the chain
  std::size_t level_steps = 0;   ///< steps since the depth last changed
  bool envelope_before = false;  ///< the chain's first call started after the envelope
  double cum_now_mm = 0;         ///< path length since the chain's start (mm)
  /// Path length (mm) and the centre's x and y (mm) at the last steps_per_rev + 4 +
  /// kSimRingSlack steps (rings indexed by the chain's step modulo their size).
  std::vector<double> cum_mm, x_mm, y_mm;
};

/// Steps the rings of SimCarry keep beyond a revolution and four.
inline constexpr std::size_t kSimRingSlack = 16;

struct SimResult {
  std::vector<SimStep> steps;       ///< empty when not kept (SimControl::keep_records)
  std::vector<ChipEntry> chip_map;  ///< likewise
  std::size_t step_count = 0;       ///< the steps taken, kept or not
  double h_max_mm = 0;              ///< the largest SimStep::h_max_mm of those steps
  int segments_per_tooth = 0;
  double removed_mm3 = 0;  ///< Z board
  std::array<double, 3> removed_by_board_mm3{};
  std::uint64_t dexel_updates = 0;  ///< ray-interval subtractions that removed material
  bool complete = true;             ///< false when cancelled: the steps computed so far
  /// Steps whose wedges searched only the annulus where material can lie (the others the
  /// whole sector: a call's first revolution, unless it continues one or follows the envelope).
  std::size_t annulus_steps = 0;
  SimCarry carry;  ///< for a call continuing this one on the same workpiece
};

/// Takes a simulation's records as they are made (SimControl::sink): each step in order,
/// with its chip map entries (their `step` the step's index in the call), one call at a time,
/// possibly from a worker thread of the simulation. Whatever `take` throws stops the
/// simulation and passes on.
class SimSink {
 public:
  SimSink() = default;
  SimSink(const SimSink&) = delete;
  SimSink& operator=(const SimSink&) = delete;
  virtual ~SimSink() = default;
  virtual void take(const SimStep& step, std::span<const ChipEntry> chips) = 0;
};

/// Sets `step_count` and `h_max_mm` from the kept steps (for records made outside simulate).
void tally_steps(SimResult& r);

/// Progress and cancellation of a running simulation.
struct SimControl {
  /// Phases ("pre-roll: envelope", "pre-roll: last revolution", "window") and progress in
  /// each (pieces of path or steps). When `hooks.cancel` turns true (e.g. from a SIGINT
  /// handler) the simulation stops after the steps under way (a few hundred at most) and
  /// returns what it has, with `complete = false` (no exception).
  RunHooks hooks;
  /// The tool's envelope was swept (sweep_envelope) up to the call's start: the wedges may
  /// search only the annulus from the first step (docs/models.md section 11).
  bool envelope_before = false;
  /// The call continues the one that left this carry (its SimResult::carry), on the same
  /// path, tool and workpiece from the time that one ended: the wedges search only the annulus
  /// from the first step, as one call over both would. The results are those of the call
  /// without it, bit for bit (the wedges' shapes are each call's own; only the search knows
  /// more). Throws Error when the carry ended at another time or steps per revolution.
  const SimCarry* after = nullptr;
  /// Chip map entries to reserve up front (MemoryEstimate::chip_entries); 0: grow as needed.
  std::size_t reserve_chip_entries = 0;
  /// Each step's record and chip entries go to the sink as they are made (for outputs
  /// streamed to files).
  SimSink* sink = nullptr;
  /// Keep every step's record and the chip map in SimResult::steps and chip_map. Without
  /// them (a sink takes them, or only the totals are wanted) the memory does not grow with
  /// the steps: a whole program fits (MemoryEstimate::streamed).
  bool keep_records = true;
};

/// Simulates the path from t0 to t1 (s) on the workpiece (modified in place).
[[nodiscard]] SimResult simulate(const ToolPath& path, const SimTool& tool, const SimSettings& s,
                                 TriDexel& work, double t0_s, double t1_s,
                                 const SimControl& control = {});

/// One point of the slot's wall profiles (mm): at (y, z), the walls' x on either side of the
/// slot's centre line, read off the X board.
struct WallPoint {
  double y_mm = 0, z_mm = 0, left_x_mm = 0, right_x_mm = 0;
};
/// Wall profiles at about `levels` heights (every ray along y there), where the X board was
/// cut and holds no material on the centre line x = centre_x_mm.
[[nodiscard]] std::vector<WallPoint> wall_profiles(const TriDexel& work, double centre_x_mm,
                                                   int levels = 10);

/// One point of the floor profiles (mm): the top of the material on the Z board's ray (x, y).
struct FloorPoint {
  double x_mm = 0, y_mm = 0, z_mm = 0;
};
/// Floor profiles across the slot (every ray along x) at about `rows` positions along y,
/// those where the Z board was cut.
[[nodiscard]] std::vector<FloorPoint> floor_profiles(const TriDexel& work, int rows = 100);

/// The machined surface as a height field over the Z board (every ray `step_mm` apart, at
/// least the spacing): the top of the material at each (x, y), the stock's top where untouched.
struct HeightField {
  std::vector<double> x_mm_of_column, y_mm_of_row;
  std::vector<double> z_mm;  ///< column-major: z_mm[column * rows + row]
  double bottom_mm = 0;      ///< the stock's bottom
};
[[nodiscard]] HeightField surface_height_field(const TriDexel& work, double step_mm);
/// The slot's floor as a height map (ISO 25178 input): every ray of the Z board (its spacing)
/// with x in [x_from_mm, x_to_mm], along the longest run of rows in which every one of those
/// rays was cut below `below_mm` (the floor, clear of the stock's top). Throws InputError
/// naming the range when no row is cut across it, or fewer than 2 x 2 rays remain.
[[nodiscard]] HeightMap floor_height_map(const TriDexel& work, double x_from_mm, double x_to_mm,
                                         double below_mm);
/// The grid step (mm) of the machined surface's mesh: the Z board's spacing, coarser in whole
/// multiples when the mesh would pass 4 million triangles.
[[nodiscard]] double default_surface_step_mm(const TriDexel& work);

/// Removes the tool's envelope swept along the path from t0 to t1 (s): the solid of revolution
/// of its profile (radius plus the largest radial runout, tip at the lowest axial runout)
/// along chords within a quarter spacing of the path and 1 um, without teeth or time steps. Fast:
/// the workpiece as that part of the cut leaves it, less the feed marks (about f_z^2 / 8R) the
/// teeth would leave. Returns the volume removed from the Z board (mm^3).
/// Works in strips of whole tiles on every core; the result is the same for any thread count.
/// `hooks`: progress over the strips (all boards); `hooks.cancel` stops it between strips.
double sweep_envelope(const ToolPath& path, const SimTool& tool, TriDexel& work, double t0_s,
                      double t1_s, const RunHooks& hooks = {});

/// The result's chip map made dense (the HDF5 layout, see ChipMapData).
[[nodiscard]] ChipMapData chip_map_data(const SimResult& r, const SimTool& tool,
                                        const SimSettings& s);
/// Writes the result's chip map as write_chip_map_h5(path, chip_map_data(r, tool, s)) does (the
/// same datasets and values), made dense 1024 steps at a time: the memory of one such block
/// instead of the whole dense map. Throws Error.
void write_chip_map_h5(const std::filesystem::path& path, const SimResult& r, const SimTool& tool,
                       const SimSettings& s);
/// The heights above the tip of the middles of the first `segments` edge segments (mm).
[[nodiscard]] std::vector<double> segment_heights_mm(const SimTool& tool, std::size_t segments);

/// Hands a result's kept steps to `sink` in order, each with its chip map entries, as
/// simulate would have (SimControl::sink). Throws Error when the entries are not in step
/// order or name a step beyond the steps.
void replay(const SimResult& r, SimSink& sink);

/// Writes a chip map file (write_chip_map_h5's datasets and attributes) as the steps come: a
/// SimSink that makes 1024 steps dense at a time and appends them to extendible datasets, so
/// that a whole program's map is written in the memory of one block. `finish` writes the
/// segment heights and the attributes and closes the file; a writer destroyed unfinished leaves
/// it without them (write to a staging path). Throws Error when HDF5 fails.
class ChipMapWriter final : public SimSink {
 public:
  ChipMapWriter(const std::filesystem::path& path, const SimTool& tool, const SimSettings& s);
  ~ChipMapWriter() override;
  void take(const SimStep& step, std::span<const ChipEntry> chips) override;
  /// `complete`: the simulation ran to its end (the file's attribute "complete").
  void finish(bool complete);

 private:
  struct File;
  std::unique_ptr<File> file_;
};

/// The job's stock: `[stock]` min / max, or the slot region (y from 0 to the slot length: the
/// slot runs through the workpiece) with a 1 mm margin beside the walls (x) and 0.5 mm below
/// the floor, up to the top face z = 0.
[[nodiscard]] Box3 job_stock(const Job& job);

/// A job's simulation over [from_s, to_s]. Before `from_s` the tool's envelope is swept
/// (sweep_envelope) up to one revolution before the window, and that revolution is simulated
/// with the teeth without being recorded, so the window starts from the workpiece as the
/// earlier cut left it, feed marks included.
struct JobSimulation {
  SimResult result;            ///< the window only
  double pre_roll_s = 0;       ///< programmed time before the window (s)
  double pre_roll_wall_s = 0;  ///< wall time of the pre-roll (s)
  double window_wall_s = 0;    ///< wall time of the window (s)
  /// Processor time of the process in each phase (s, all threads), and the threads it ran
  /// on: a phase's utilisation is its processor time / (wall time x threads).
  double pre_roll_cpu_s = 0, window_cpu_s = 0;
  int threads = 1;
  std::size_t memory_bytes = 0;
  std::unique_ptr<TriDexel> work;  ///< the workpiece after the window

  // Out of line, where the workpiece's type is complete.
  JobSimulation();
  ~JobSimulation();
  JobSimulation(JobSimulation&&) noexcept;
  JobSimulation& operator=(JobSimulation&&) noexcept;
};
/// Runs on `[simulation] threads` worker threads (0: all cores); the results are the same
/// for any thread count.
/// `stock_mesh`: the stock as a closed mesh in the path's frame (stock_from_mesh) instead of
/// the job's box; null: the job's [stock] mesh (Job::stock_mesh) where it has one.
[[nodiscard]] JobSimulation simulate_job(const Job& job, const ToolPath& path, double from_s,
                                         double to_s, const SimControl& control = {},
                                         const Mesh* stock_mesh = nullptr);

/// What a job's simulation will hold in memory (bytes), estimated before running it: the
/// boards' tiles over the region the tool visits up to the window's end, the per-step
/// records and the sparse chip map, and the dense chip map (whole, as the Python module
/// returns it, or the HDF5 writer's blocks).
struct MemoryEstimate {
  double boards_bytes = 0;      ///< the dexel tiles of the region the tool visits
  double records_bytes = 0;     ///< per-step records, sample arrays and the sparse chip map
  double dense_map_bytes = 0;   ///< the whole chip map made dense (chip_map_data)
  double map_writer_bytes = 0;  ///< writing chips.h5 (write_chip_map_h5, ChipMapWriter)
  /// Without kept records (SimControl::keep_records false): one block of path samples.
  double stream_bytes = 0;
  /// The largest of the outputs made from the workpiece at the end (SimulationOutputs: the
  /// floor's height map, the surface's mesh).
  double outputs_bytes = 0;
  double base_bytes = 0;    ///< the process besides: libraries, job, path
  double chip_entries = 0;  ///< expected engaged (segment, step) pairs
  /// The whole, with or without the whole dense map (bytes).
  [[nodiscard]] double total(bool with_map) const {
    return boards_bytes + records_bytes + base_bytes + (with_map ? dense_map_bytes : 0.0);
  }
  /// What SimulationOutputs holds at its largest: its ChipMapWriter during the run, then the
  /// largest output made at the end (bytes).
  [[nodiscard]] double writing_bytes() const { return std::max(map_writer_bytes, outputs_bytes); }
  /// The whole when the records are not kept, with or without the outputs (bytes).
  [[nodiscard]] double streamed(bool with_outputs) const {
    return boards_bytes + stream_bytes + base_bytes + (with_outputs ? writing_bytes() : 0.0);
  }
};
/// With `stock_mesh` the boards hold every ray of the mesh's box (stock_from_mesh).
[[nodiscard]] MemoryEstimate estimate_simulation_memory(const Job& job, const ToolPath& path,
                                                        double from_s, double to_s,
                                                        const Mesh* stock_mesh = nullptr);

}  // namespace trochomill
