// Text and mesh outputs of the tri-dexel simulation: per-step series, wall and floor
// profiles (CSV) and the machined surface (binary STL) (include/trochomill/report.hpp).
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report/analysis.hpp"
#include "trochomill/report/force.hpp"
#include "trochomill/report/sim.hpp"
#include "trochomill/version.hpp"

namespace trochomill {

std::string sim_series_header(std::size_t teeth) {
  std::string csv = "t_s,x_mm,y_mm,z_mm";
  for (std::size_t k = 0; k < teeth; ++k) csv += fmt::format(",removed_tooth{}_mm3", k);
  csv += ",h_max_mm,h_mean_mm,engaged_segments\n";
  return csv;
}

void append_sim_series_row(std::string& csv, const SimStep& st, std::size_t teeth) {
  auto out = std::back_inserter(csv);
  fmt::format_to(out, "{:.7f},{:.5f},{:.5f},{:.5f}", st.t_s, st.tip_mm[0], st.tip_mm[1],
                 st.tip_mm[2]);
  for (std::size_t k = 0; k < teeth; ++k) {
    fmt::format_to(out, ",{:.6g}", k < st.removed_mm3.size() ? st.removed_mm3[k] : 0.0);
  }
  fmt::format_to(out, ",{:.6f},{:.6f},{}\n", st.h_max_mm, st.h_mean_mm, st.engaged_segments);
}

std::string sim_series_csv(const SimResult& r, std::size_t teeth) {
  std::string csv = sim_series_header(teeth);
  for (const SimStep& st : r.steps) append_sim_series_row(csv, st, teeth);
  return csv;
}

std::string force_series_csv(const ForceSeries& s) {
  std::string csv = "t_s,f_x_n,f_y_n,f_z_n,f_resultant_n,torque_nm,power_w";
  for (int k = 0; k < s.teeth; ++k) {
    csv += fmt::format(",tooth{0}_f_x_n,tooth{0}_f_y_n,tooth{0}_f_z_n,tooth{0}_torque_nm", k);
  }
  csv += '\n';
  auto out = std::back_inserter(csv);
  const auto nz = static_cast<std::size_t>(s.teeth);
  for (std::size_t i = 0; i < s.size(); ++i) {
    fmt::format_to(out, "{:.8f},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}", s.t_s[i], s.fx_n[i],
                   s.fy_n[i], s.fz_n[i], s.resultant_n(i), s.torque_nm[i], s.power_w[i]);
    for (std::size_t k = 0; k < nz; ++k) {
      const std::size_t j = i * nz + k;
      fmt::format_to(out, ",{:.6g},{:.6g},{:.6g},{:.6g}", s.tooth_fx_n[j], s.tooth_fy_n[j],
                     s.tooth_fz_n[j], s.tooth_torque_nm[j]);
    }
    csv += '\n';
  }
  return csv;
}

std::string wall_profiles_csv(const std::vector<WallPoint>& w) {
  std::string csv = "y_mm,z_mm,left_x_mm,right_x_mm\n";
  auto out = std::back_inserter(csv);
  for (const WallPoint& p : w) {
    fmt::format_to(out, "{:.5f},{:.5f},{:.6f},{:.6f}\n", p.y_mm, p.z_mm, p.left_x_mm, p.right_x_mm);
  }
  return csv;
}

std::string floor_profiles_csv(const std::vector<FloorPoint>& f) {
  std::string csv = "y_mm,x_mm,z_mm\n";
  auto out = std::back_inserter(csv);
  for (const FloorPoint& p : f)
    fmt::format_to(out, "{:.5f},{:.5f},{:.6f}\n", p.y_mm, p.x_mm, p.z_mm);
  return csv;
}

namespace {

using P3 = std::array<double, 3>;

void put_f32(std::string& s, double v) {
  const auto f = static_cast<float>(v);
  char b[4];
  std::memcpy(b, &f, 4);
  s.append(b, 4);
}

void triangle(std::string& s, const P3& a, const P3& b, const P3& c, std::uint32_t& count) {
  const P3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  P3 n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0)) return;  // degenerate: left out
  for (double& x : n) x /= len;
  for (const P3* p : std::initializer_list<const P3*>{&n, &a, &b, &c}) {
    for (const double x : *p) put_f32(s, x);
  }
  s.append(2, '\0');
  ++count;
}

}  // namespace

std::string height_field_stl(const HeightField& f) {
  const std::size_t nc = f.x_mm_of_column.size(), nr = f.y_mm_of_row.size();
  std::string s(80, '\0');
  const char header[] = "trochomill machined surface (height field of the Z board), mm";
  std::memcpy(s.data(), header, sizeof(header) - 1);
  s.append(4, '\0');  // triangle count, set at the end
  std::uint32_t count = 0;
  if (nc < 2 || nr < 2) return s;
  auto top = [&](std::size_t a, std::size_t b) {
    return P3{f.x_mm_of_column[a], f.y_mm_of_row[b], f.z_mm[a * nr + b]};
  };
  auto bot = [&](std::size_t a, std::size_t b) {
    return P3{f.x_mm_of_column[a], f.y_mm_of_row[b], f.bottom_mm};
  };
  // Top: two triangles per cell, counter-clockwise seen from above (outward normals up).
  for (std::size_t a = 0; a + 1 < nc; ++a) {
    for (std::size_t b = 0; b + 1 < nr; ++b) {
      triangle(s, top(a, b), top(a + 1, b), top(a + 1, b + 1), count);
      triangle(s, top(a, b), top(a + 1, b + 1), top(a, b + 1), count);
    }
  }
  // The boundary loop (counter-clockwise seen from above), its side walls, and the bottom as a
  // fan from its centre: a closed solid.
  std::vector<std::pair<std::size_t, std::size_t>> loop;
  for (std::size_t a = 0; a + 1 < nc; ++a) loop.emplace_back(a, 0);
  for (std::size_t b = 0; b + 1 < nr; ++b) loop.emplace_back(nc - 1, b);
  for (std::size_t a = nc - 1; a > 0; --a) loop.emplace_back(a, nr - 1);
  for (std::size_t b = nr - 1; b > 0; --b) loop.emplace_back(0, b);
  const P3 centre{0.5 * (f.x_mm_of_column.front() + f.x_mm_of_column.back()),
                  0.5 * (f.y_mm_of_row.front() + f.y_mm_of_row.back()), f.bottom_mm};
  for (std::size_t q = 0; q < loop.size(); ++q) {
    const auto [a0, b0] = loop[q];
    const auto [a1, b1] = loop[(q + 1) % loop.size()];
    triangle(s, bot(a0, b0), bot(a1, b1), top(a1, b1), count);
    triangle(s, bot(a0, b0), top(a1, b1), top(a0, b0), count);
    triangle(s, centre, bot(a1, b1), bot(a0, b0), count);
  }
  std::memcpy(s.data() + 80, &count, 4);
  return s;
}

}  // namespace trochomill

namespace trochomill {
namespace {

// The share of the threads' time a phase kept busy: processor time / (wall time x threads),
// 0 for a phase that did not run.
double utilisation(double cpu_s, double wall_s, int threads) {
  return wall_s > 0 && threads > 0 ? cpu_s / (wall_s * threads) : 0.0;
}

}  // namespace

bool is_run_measurement(std::string_view key) {
  static constexpr std::string_view keys[] = {
      "wall_time_s",    "pre_roll_wall_s",    "window_wall_s",        "dexel_updates_per_s",
      "memory_peak_mb", "memory_estimate_mb", "chips_wall_s",         "forces_wall_s",
      "pre_roll_cpu_s", "window_cpu_s",       "pre_roll_utilisation", "window_utilisation",
      "threads"};
  return std::find(std::begin(keys), std::end(keys), key) != std::end(keys);
}

std::string simulation_json(const Job& job, const JobSimulation& js, double from_s, double to_s,
                            double wall_s, double memory_estimate_bytes) {
  const SimResult& r = js.result;
  const double h_max = r.h_max_mm;
  const nlohmann::json j = {
      {"removed_volume_mm3", r.removed_mm3},
      {"removed_volume_by_board_mm3", r.removed_by_board_mm3},
      {"h_max_mm", h_max},
      {"steps", r.step_count},
      {"dexel_updates", r.dexel_updates},
      {"wall_time_s", wall_s},
      {"pre_roll_wall_s", js.pre_roll_wall_s},
      {"window_wall_s", js.window_wall_s},
      {"threads", js.threads},
      {"pre_roll_cpu_s", js.pre_roll_cpu_s},
      {"window_cpu_s", js.window_cpu_s},
      {"pre_roll_utilisation", utilisation(js.pre_roll_cpu_s, js.pre_roll_wall_s, js.threads)},
      {"window_utilisation", utilisation(js.window_cpu_s, js.window_wall_s, js.threads)},
      {"dexel_updates_per_s",
       js.window_wall_s > 0 ? static_cast<double>(r.dexel_updates) / js.window_wall_s : 0.0},
      {"from_s", from_s},
      {"to_s", to_s},
      {"resolution_mm", job.simulation.resolution_mm},
      {"steps_per_rev", job.simulation.steps_per_rev},
      {"memory_mb", static_cast<double>(js.memory_bytes) / 1048576.0},
      {"memory_estimate_mb", memory_estimate_bytes / 1048576.0},
      {"memory_peak_mb", static_cast<double>(peak_memory_bytes()) / 1048576.0},
      {"complete", r.complete}};
  return j.dump(2) + "\n";
}

std::string simulation_text(const std::string& job_file, const Job& job, const JobSimulation& js,
                            double from_s, double to_s, double wall_s) {
  const SimResult& r = js.result;
  const double h_max = r.h_max_mm;
  return fmt::format(
      "{}: {} to {} s, {} steps at {} per rev, {:g} mm dexels: removed {} mm^3, h_max {} mm, "
      "{} dexel updates, {:.2f} s, {:.1f} MB{}\n",
      job_file, figure_text(from_s), figure_text(to_s), r.step_count, job.simulation.steps_per_rev,
      job.simulation.resolution_mm, figure_text(r.removed_mm3), figure_text(h_max), r.dexel_updates,
      wall_s, static_cast<double>(js.memory_bytes) / 1048576.0,
      r.complete ? "" : " (interrupted: incomplete)");
}

HeightMap simulated_floor(const Job& job, const JobSimulation& js) {
  const double d = job.simulation.resolution_mm;
  const double half = 0.5 * job.slot.width_mm - job.tool.corner_radius_mm - d;
  return floor_height_map(*js.work, -half, half, -0.5 * job.slot.depth_mm);
}

// The set being written: the staging folder inside the output folder, and the two files
// streamed into it as the steps come.
struct SimulationOutputs::State {
  State(std::filesystem::path dir_, const Job& job_)
      : dir(std::move(dir_)),
        job(job_),
        tool(sim_tool(job_, job_.simulation)),
        teeth(tool.tooth_angle_rad.size()),
        stage(dir / fmt::format(".trochomill-partial-{}", static_cast<long>(::getpid()))) {}
  std::filesystem::path dir;
  const Job& job;
  SimTool tool;
  std::size_t teeth;
  std::filesystem::path stage;
  std::unique_ptr<std::ofstream> series;
  std::unique_ptr<PendingFile> series_pending;
  std::string rows;  // series.csv rows not yet written
  std::unique_ptr<ChipMapWriter> chips;
  std::size_t steps = 0;
  double first_t_s = 0, last_t_s = 0;  // the steps' times (s)
  bool finished = false;
  bool made_dir = false;  // `dir` was made for this run: removed again if it fails

  // A failed write names the file where it would have been, not the staging folder.
  [[noreturn]] void rethrow_named(const IoError& e) const {
    throw IoError(replace_all(e.what(), stage.string(), dir.string()));
  }
  // Unfinished: none of this run's files stay, nor the folder when this run made it.
  void discard() noexcept {
    series.reset();
    chips.reset();
    std::error_code ec;
    std::filesystem::remove_all(stage, ec);
    if (made_dir) std::filesystem::remove(dir, ec);  // only if empty
  }

  void flush_rows() {
    series->write(rows.data(), static_cast<std::streamsize>(rows.size()));
    if (!*series) {
      throw IoError(fmt::format("cannot write '{}': {}", (stage / "series.csv").string(),
                                std::strerror(errno)));
    }
    rows.clear();
  }
};

SimulationOutputs::SimulationOutputs(const std::filesystem::path& dir, const Job& job)
    : s_(std::make_unique<State>(dir, job)) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // The folder is made as mkdir makes one: its parent must be there (a mistyped path is not
  // made silently).
  const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    throw IoError(
        fmt::format("cannot write the folder '{}': a file of that name is there", dir.string()));
  }
  if (!fs::is_directory(dir, ec)) {
    if (!fs::is_directory(parent, ec)) {
      throw InputError(fmt::format(
          "output folder '{}': its parent '{}' does not exist (only the last folder is made)",
          dir.string(), parent.string()));
    }
    if (!fs::create_directory(dir, ec) && ec) {
      throw IoError(fmt::format("cannot make the folder '{}': {}", dir.string(), ec.message()));
    }
    s_->made_dir = true;
  }
  fs::remove_all(s_->stage, ec);
  if (!fs::create_directory(s_->stage, ec) && ec) {
    s_->discard();
    throw IoError(fmt::format("cannot write in '{}': {}", dir.string(), ec.message()));
  }
  try {
    const fs::path series = s_->stage / "series.csv";
    s_->series_pending = std::make_unique<PendingFile>(series);
    s_->series = std::make_unique<std::ofstream>(series, std::ios::binary | std::ios::trunc);
    if (!*s_->series) {
      throw IoError(fmt::format("cannot write '{}': {}", series.string(), std::strerror(errno)));
    }
    s_->rows = sim_series_header(s_->teeth);
    s_->chips = std::make_unique<ChipMapWriter>(s_->stage / "chips.h5", s_->tool, job.simulation);
  } catch (const IoError& e) {
    s_->discard();
    s_->rethrow_named(e);
  } catch (...) {
    s_->discard();
    throw;
  }
}

SimulationOutputs::~SimulationOutputs() {
  if (!s_->finished) s_->discard();
}

void SimulationOutputs::take(const SimStep& step, std::span<const ChipEntry> chips) {
  if (s_->finished) throw Error("SimulationOutputs: a step after finish");
  if (s_->steps++ == 0) s_->first_t_s = step.t_s;
  s_->last_t_s = step.t_s;
  append_sim_series_row(s_->rows, step, s_->teeth);
  try {
    if (s_->rows.size() >= (std::size_t{1} << 20)) s_->flush_rows();
    s_->chips->take(step, chips);
  } catch (const IoError& e) {
    s_->rethrow_named(e);
  }
}

std::string SimulationOutputs::finish(const JobSimulation& js, std::optional<double> stl_step_mm,
                                      const RunHooks& hooks) {
  namespace fs = std::filesystem;
  if (s_->finished) throw Error("SimulationOutputs: finished twice");
  const Job& job = s_->job;
  const fs::path& dir = s_->dir;
  const fs::path& stage = s_->stage;
  // The floor as a height map, when the window left one across the slot.
  std::optional<HeightMap> floor;
  std::string floor_note;
  try {
    floor = simulated_floor(job, js);
  } catch (const InputError& e) {
    floor_note = fmt::format("floor.x3p not written: {}", e.what());
  }
  // The streamed files are closed first; then the floor's height map (the largest output:
  // released once written), then the others one at a time.
  const bool have_floor = floor.has_value();
  std::vector<std::pair<const char*, std::function<void(const fs::path&)>>> outputs{{
      {"series.csv",
       [&](const fs::path& p) {
         s_->flush_rows();
         s_->series->close();
         if (s_->series->fail()) {
           throw IoError(fmt::format("cannot write '{}': {}", p.string(), std::strerror(errno)));
         }
       }},
      {"chips.h5", [&](const fs::path&) { s_->chips->finish(js.result.complete); }},
  }};
  if (have_floor) {
    outputs.emplace_back("floor.x3p", [&](const fs::path& p) {
      X3pInfo info;
      info.creator = fmt::format("trochomill {}", kVersion);
      info.model = "tri-dexel simulation";
      info.comment = fmt::format(
          "{}; {:g} mm dexels, {} steps per revolution, t {:.4f} to {:.4f} s", floor->description,
          job.simulation.resolution_mm, job.simulation.steps_per_rev, s_->first_t_s, s_->last_t_s);
      write_x3p(p, *floor, info);
      floor.reset();
    });
  }
  outputs.emplace_back("walls.csv", [&](const fs::path& p) {
    write_file_atomic(p, wall_profiles_csv(wall_profiles(*js.work, 0.0)));
  });
  outputs.emplace_back("floor.csv", [&](const fs::path& p) {
    write_file_atomic(p, floor_profiles_csv(floor_profiles(*js.work)));
  });
  outputs.emplace_back("surface.stl", [&](const fs::path& p) {
    const double step = stl_step_mm ? *stl_step_mm : default_surface_step_mm(*js.work);
    write_file_atomic(p, height_field_stl(surface_height_field(*js.work, step)));
  });
  const char* stopped =
      "interrupted: the output folder was not written (no file of this run is in it)";
  hooks.begin("writing outputs");
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    hooks.check(stopped);
    if (hooks.progress) hooks.progress(k, outputs.size());
    try {
      outputs[k].second(stage / outputs[k].first);
    } catch (const IoError& e) {
      s_->rethrow_named(e);
    }
  }
  hooks.check(stopped);
  if (hooks.progress) hooks.progress(outputs.size(), outputs.size());
  // The set is complete: each file is renamed into place.
  std::error_code ec;
  for (const auto& [name, write] : outputs) {
    fs::rename(stage / name, dir / name, ec);
    if (ec) {
      throw IoError(fmt::format("cannot write '{}': {}", (dir / name).string(), ec.message()));
    }
  }
  s_->finished = true;
  s_->series_pending.reset();
  fs::remove(stage, ec);
  if (!have_floor) fs::remove(dir / "floor.x3p", ec);  // an earlier run's: not this set's
  return floor_note;
}

std::string write_simulation_outputs(const std::filesystem::path& dir, const Job& job,
                                     const JobSimulation& js, std::optional<double> stl_step_mm,
                                     const RunHooks& hooks) {
  SimulationOutputs out(dir, job);
  replay(js.result, out);
  return out.finish(js, stl_step_mm, hooks);
}

}  // namespace trochomill
