// texture: roughness and waviness (ISO 16610-21 filter, ISO 21920-2 parameters) of a measured
// profile (CSV or X3P), a simulation's walls (simulate --out folder) or a job's predicted
// walls; the areal texture (ISO 16610-61 filter, ISO 25178-2 parameters) of a simulation's
// floor (floor.x3p) or a measured surface (X3P).
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/analysis.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report.hpp"
#include "trochomill/surface.hpp"

namespace trochomill::cli {

void register_surface_commands(CLI::App& app, int& exit_code) {
  struct Args {
    std::string source, surface = "all", columns, z_unit = "mm", json, form = "plane";
    std::string against;
    std::optional<double> lambda_c_mm, lambda_s_mm, z_mm, memory_gb, max_shift_mm;
    int degree = 2;
    bool robust = false;
    std::vector<std::string> sets;
    WindowArgs window;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "texture",
      "surface texture: roughness and waviness of profiles (a measured CSV or X3P, the walls of "
      "a simulate --out folder or of a job) and areal parameters of surfaces (a folder's "
      "floor.x3p, a measured X3P)");
  cmd->add_option("SOURCE", a->source,
                  "profile CSV (x, z), X3P file (surface or profile), folder written by simulate "
                  "--out, or job TOML")
      ->required();
  cmd->add_option("--surface", a->surface,
                  "left, right, walls (both), floor or all (a folder: walls and floor; a job: "
                  "its predicted walls, and with floor or an explicit all the floor of a "
                  "simulation window)")
      ->capture_default_str();
  cmd->add_option("--lambda-c", a->lambda_c_mm,
                  "cut-off wavelength (areal: the L-filter's nesting index), mm (default: "
                  "ISO 21920-3's for the Ra or Sa)")
      ->check(finite_above(0, 1e3));
  cmd->add_option("--lambda-s", a->lambda_s_mm,
                  "short-wave cut-off (lambda_s; areal: the S-filter's nesting index), mm "
                  "(default: none)")
      ->check(finite_above(0, 1e3));
  cmd->add_flag("--robust", a->robust,
                "profiles: the robust Gaussian regression filter (ISO 16610-31) for the mean "
                "line, which scratches and peaks do not drag");
  cmd->add_option("--form", a->form, "areal form removal: plane, polynomial or none")
      ->capture_default_str();
  cmd->add_option("--degree", a->degree, "polynomial degree with --form polynomial (1 to 6)")
      ->capture_default_str();
  cmd->add_option("--against", a->against,
                  "compare an areal SOURCE with a predicted surface: an X3P file or a simulate "
                  "--out folder (its floor.x3p); aligned by shift and plane, point by point");
  cmd->add_option("--max-shift", a->max_shift_mm,
                  "largest shift searched by --against, mm (default: a quarter of the measured "
                  "map's shorter side)")
      ->check(finite_in(0, 1e3));
  add_memory_limit(cmd, a->memory_gb);
  cmd->add_option("--z", a->z_mm, "the wall level of a simulation folder, mm (default: middle)")
      ->check(finite_in(-1e4, 1e4));
  cmd->add_option("--columns", a->columns,
                  "x,z column names of a CSV profile (default: the first two)");
  cmd->add_option("--z-unit", a->z_unit, "unit of a CSV profile's heights: mm or um")
      ->capture_default_str();
  cmd->add_option("--set", a->sets, "override a job key, section.key=value (job source)");
  add_window_args(cmd, a->window, "a job's floor: the simulation window's");
  cmd->add_option("--json", a->json, "write the report as JSON (- for stdout)");
  cmd->final_callback([a, cmd, &exit_code] {
    check_outputs({&a->json}, {&a->source});
    namespace fs = std::filesystem;
    const std::string& sf = a->surface;
    if (sf != "left" && sf != "right" && sf != "walls" && sf != "both" && sf != "floor" &&
        sf != "all") {
      throw InputError(fmt::format("--surface '{}': left, right, walls, floor or all", sf));
    }
    ArealFilterOptions areal;
    areal.s_mm = a->lambda_s_mm;
    areal.l_mm = a->lambda_c_mm;
    areal.degree = a->degree;
    if (a->form == "plane") {
      areal.form = FormRemoval::plane;
    } else if (a->form == "polynomial") {
      areal.form = FormRemoval::polynomial;
    } else if (a->form == "none") {
      areal.form = FormRemoval::none;
    } else {
      throw InputError(fmt::format("--form '{}': plane, polynomial or none", a->form));
    }
    // An areal texture holds about 12 copies of the map's doubles at its peak (the map, the
    // S-filtered, form-removed and L-filtered surfaces, the filter's scratch, and the
    // autocorrelation's spectra over the map padded by half in each direction): 100 bytes
    // a point with the process besides. Maps are refused past the limit before being read.
    constexpr double kArealBytesPerPoint = 100, kBaseBytes = 40e6;
    const double max_points = (memory_limit_bytes(a->memory_gb) - kBaseBytes) / kArealBytesPerPoint;
    std::error_code ec;
    // The predicted surface of --against, checked before any work.
    fs::path against = a->against;
    if (!against.empty()) {
      if (fs::is_directory(against, ec)) against /= "floor.x3p";
      if (lower_extension(against.string()) != ".x3p") {
        throw InputError(fmt::format(
            "--against '{}': an X3P file or a folder written by simulate --out", a->against));
      }
    }
    auto profile_entry = [](std::string surface, std::string description, ProfileTexture t) {
      TextureEntry e;
      e.surface = std::move(surface), e.description = std::move(description);
      e.texture = std::move(t);
      return e;
    };
    auto areal_entry = [&](const std::string& surface, const HeightMap& m) {
      TextureEntry e;
      e.surface = surface, e.description = m.description;
      e.areal = areal_texture(m, areal);
      if (!against.empty()) {
        e.comparison = compare_surfaces(m, read_x3p(against, nullptr, max_points), a->max_shift_mm);
        e.against = against.string();
      }
      return e;
    };
    ProfileFilterOptions pf;
    pf.lambda_s_mm = a->lambda_s_mm;
    pf.robust = a->robust;
    const bool want_left = sf == "left" || sf == "walls" || sf == "both" || sf == "all";
    const bool want_right = sf == "right" || sf == "walls" || sf == "both" || sf == "all";
    const bool want_floor = sf == "floor" || sf == "all";
    std::vector<bool> sides;
    if (want_left) sides.push_back(true);
    if (want_right) sides.push_back(false);
    std::vector<TextureEntry> entries;
    const std::string ext = lower_extension(a->source);
    // A job's floor comes from a simulation window (--surface floor, or all given explicitly).
    const bool job_floor =
        ext == ".toml" && (sf == "floor" || (sf == "all" && cmd->count("--surface") > 0));
    if (a->window.given() && !job_floor) {
      throw InputError(
          "--cycles, --from and --to choose the simulation window of a job's floor (--surface "
          "floor or all with a job as SOURCE)");
    }
    if (fs::is_directory(a->source, ec)) {
      const fs::path walls = fs::path(a->source) / "walls.csv";
      const fs::path floor = fs::path(a->source) / "floor.x3p";
      // Under `all` (the default) a wall that cannot be measured (a window holding only the
      // cut front) is left out with a note, as a missing floor is; asked for, it is an error.
      std::vector<std::string> skipped;
      if (!sides.empty()) {
        const std::string text = read_text_file(walls);
        for (const bool left : sides) {
          try {
            const MeasuredProfile p =
                read_wall_profile_csv(text, walls.string(), left, a->z_mm, true);
            entries.push_back(profile_entry(left ? "left" : "right", "simulated " + p.description,
                                            profile_texture(p.z_mm, p.dx_mm, a->lambda_c_mm, pf)));
          } catch (const InputError& e) {
            if (sf != "all") throw;
            skipped.emplace_back(cli_message(e));
          }
        }
      }
      if (want_floor && (sf == "floor" || fs::exists(floor, ec))) {
        if (!fs::exists(floor, ec)) {
          throw InputError(fmt::format(
              "{}: no floor.x3p (simulate writes it when its window leaves a floor cut across "
              "the slot)",
              a->source));
        }
        X3pInfo info;
        HeightMap m = read_x3p(floor, &info, max_points);
        if (!info.comment.empty()) m.description = info.comment;  // what simulate wrote
        entries.push_back(areal_entry("floor", m));
      }
      if (entries.empty() && !skipped.empty()) throw InputError(skipped.front());
      for (const std::string& s : skipped) fmt::print(stderr, "note: {} (left out)\n", s);
    } else if (ext == ".x3p") {
      const HeightMap m = read_x3p(a->source, nullptr, max_points);
      if (m.ny == 1) {
        entries.push_back(profile_entry("profile", m.description,
                                        profile_texture(m.z_mm, m.dx_mm, a->lambda_c_mm, pf)));
      } else {
        entries.push_back(areal_entry("surface", m));
      }
    } else if (ext == ".toml") {
      // A job: its predicted walls (the analysis's tooth-level profiles); its floor from a
      // simulation window.
      if (!sides.empty() && (a->robust || a->lambda_s_mm)) {
        throw InputError(
            "--robust and --lambda-s filter measured or simulated profiles and surfaces; a "
            "job's predicted walls are one period of an ideal profile");
      }
      JobArgs job;
      job.file = a->source;
      job.sets = a->sets;
      const Job j = job.load();
      const ToolPath path = plan_slot(j).path;
      const AnalysisParts walls{true, false, false};  // the walls alone
      const ProcessMetrics m =
          sides.empty() ? ProcessMetrics{} : analyze_process(j, path, {}, walls);
      for (const bool left : sides) {
        const WallProfile& w = left ? m.walls_tooth.left : m.walls_tooth.right;
        if (w.x_mm.size() < 3) {
          throw InputError(fmt::format("{}: the analysis found no tooth-level {} wall", a->source,
                                       left ? "left" : "right"));
        }
        entries.push_back(profile_entry(
            left ? "left" : "right",
            fmt::format("predicted {} wall, tooth level, one step of y repeated ({:g} mm)",
                        left ? "left" : "right", w.y_mm.back() - w.y_mm.front()),
            wall_texture(w, left, a->lambda_c_mm)));
      }
      if (job_floor) {
        const auto [from, to] = a->window.resolve(path);
        const MemoryEstimate est = estimate_simulation_memory(j, path, from, to);
        check_memory("texture", est.total(false), a->memory_gb,
                     fmt::format("shorten the window (--cycles, --from/--to) or coarsen "
                                 "[simulation] resolution (now {} mm)",
                                 j.simulation.resolution_mm));
        const GuardedRun run(true);
        SimControl control;
        control.hooks = run.hooks();
        control.reserve_chip_entries = static_cast<std::size_t>(est.chip_entries);
        const JobSimulation js = simulate_job(j, path, from, to, control);
        run.done();
        run.finish("interrupted: nothing written");
        HeightMap floor = simulated_floor(j, js);
        floor.description = fmt::format("{}; simulated, {:g} mm dexels, t {:.4f} to {:.4f} s",
                                        floor.description, j.simulation.resolution_mm, from, to);
        entries.push_back(areal_entry("floor", floor));
      }
    } else if (ext == ".csv" || ext == ".txt") {
      double unit = 1.0;
      if (a->z_unit == "um") {
        unit = 1e-3;
      } else if (a->z_unit != "mm") {
        throw InputError(fmt::format("--z-unit '{}': mm or um", a->z_unit));
      }
      std::string xc, zc;
      if (!a->columns.empty()) {
        const std::vector<std::string> c = split_trimmed(a->columns);
        if (c.size() != 2 || c[0].empty() || c[1].empty()) {
          throw InputError(fmt::format("--columns '{}': expected two names x,z", a->columns));
        }
        xc = c[0], zc = c[1];
      }
      const MeasuredProfile p =
          read_profile_csv(read_text_file(a->source), a->source, xc, zc, unit);
      entries.push_back(profile_entry("profile", p.description,
                                      profile_texture(p.z_mm, p.dx_mm, a->lambda_c_mm, pf)));
    } else {
      throw InputError(fmt::format(
          "texture: '{}' is not a folder written by simulate --out, a job (.toml), an X3P file "
          "(.x3p) or a CSV profile (.csv)",
          a->source));
    }
    if (!a->against.empty() && std::none_of(entries.begin(), entries.end(),
                                            [](const TextureEntry& e) { return e.areal; })) {
      throw InputError(
          "--against compares areal surfaces: give an X3P surface or a folder "
          "with a floor.x3p as SOURCE");
    }
    if (!a->json.empty()) emit(a->json, texture_json(a->source, entries));
    if (a->json != "-") fmt::print("{}", texture_text(a->source, entries));
    exit_code = 0;
  });
}

}  // namespace trochomill::cli
