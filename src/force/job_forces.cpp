// Job-level forces: edge grid with the job's topography, chip source, forces (force.hpp).
#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/topography.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

EdgeGrid job_edge_grid(const Job& job, const SimTool& tool, EdgeTopography* info) {
  const TopographySettings& tp = job.topography;
  if (tp.states() == 0) return edge_grid(tool, tp.band_mm);
  const auto state = static_cast<std::size_t>(tp.state);
  if (state >= tp.states()) {
    throw InputError(
        fmt::format("[topography] state {} but only {} wear states", tp.state, tp.states()));
  }
  if (!tp.files.empty()) {
    return sample_topography(read_mesh(tp.files[state]), tool, tp.band_mm, info);
  }
  SyntheticInsert s;
  s.vb_mm = tp.synthetic_vb_mm[state];
  s.edge_radius_mm = job.tool.edge_radius_mm > 0 ? job.tool.edge_radius_mm : 0.02;
  s.rake_deg = tp.rake_deg;
  s.clearance_deg = tp.clearance_deg;
  s.face_mm = std::max(0.6, 2 * tp.band_mm + s.vb_mm + s.edge_radius_mm);
  return sample_topography(synthetic_insert(tool, s), tool, tp.band_mm, info);
}

JobForces job_forces(const Job& job, const ToolPath& path, double from_s, double to_s, bool fast,
                     const SimControl& control, const EngagementSeries* engagement) {
  using clock = std::chrono::steady_clock;
  JobForces out;
  out.fast = fast;
  const SimTool tool = sim_tool(job, job.simulation);
  const EdgeGrid grid = job_edge_grid(job, tool);
  const SegmentForces model(job.material, grid, deg_to_rad(job.forces.ploughing_angle_deg));
  const auto t0 = clock::now();
  auto t1 = t0;
  if (fast) {
    // Forces straight from the scan: no chip record (it can hold tens of millions of entries
    // for a whole slot).
    const FastChipSource src(job, path, from_s, to_s, job.forces.fast_steps_per_rev, engagement,
                             control.hooks);
    t1 = clock::now();
    out.series = src.forces(tool, grid, model, &out.chips.steps);
    out.chips.segments_per_tooth = tool.segments();
    tally_steps(out.chips);
  } else {
    out.chips = simulate_job(job, path, from_s, to_s, control).result;
    t1 = clock::now();
    out.series = compute_forces(out.chips, tool, grid, model);
  }
  out.summary = summarize(out.series);
  out.chips_wall_s = std::chrono::duration<double>(t1 - t0).count();
  out.forces_wall_s = std::chrono::duration<double>(clock::now() - t1).count();
  return out;
}

void fill_predicted_force(const Job& job, const ToolPath& path, ProcessMetrics& m) {
  // Over the steady cycle: a program without one has no figure to report (analysis.hpp).
  if (!job.material.model || !m.periodic) return;
  // analyze's series is the fast source's own engagement when it samples once per tooth pass.
  const EngagementSeries* eng =
      m.series.steps_per_tooth == 1 && !m.series.arcs.empty() ? &m.series : nullptr;
  const JobForces f =
      job_forces(job, path, m.cycle_start_s, m.cycle_start_s + m.cycle_time_s, true, {}, eng);
  set_performance_index(job, m, f.summary.f_resultant_max_n);
}

ProcessMetrics analyze_with_forces(const Job& job, const ToolPath& path, const RunHooks& hooks,
                                   const AnalysisParts& parts) {
  ProcessMetrics m = analyze_process(job, path, hooks, parts);
  if (parts.force) fill_predicted_force(job, path, m);
  return m;
}

}  // namespace trochomill
