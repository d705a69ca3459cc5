// The simulation's outputs: the per-step series, the summary, the floor as a height map, the
// output folder (`simulate --out`), wall and floor profiles and the surface as STL. Part of the
// report module (trochomill/report.hpp includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/progress.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/texture.hpp"

namespace trochomill {

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
/// Wall profiles: y_mm, z_mm, left_x_mm, right_x_mm.
[[nodiscard]] std::string wall_profiles_csv(const std::vector<WallPoint>& w);
/// Floor profiles: y_mm, x_mm, z_mm.
[[nodiscard]] std::string floor_profiles_csv(const std::vector<FloorPoint>& f);
/// The height field as a closed solid in binary STL (mm): top surface, side walls, bottom.
[[nodiscard]] std::string height_field_stl(const HeightField& f);

}  // namespace trochomill
