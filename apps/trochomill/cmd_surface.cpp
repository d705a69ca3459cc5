// texture: roughness and waviness (ISO 16610-21 filter, ISO 21920-2 parameters) of a measured
// profile (CSV), a simulation's walls (simulate --out folder) or a job's predicted walls.
#include <fmt/format.h>

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
    std::string source, surface = "both", columns, z_unit = "mm", json;
    std::optional<double> lambda_c_mm, z_mm;
    std::vector<std::string> sets;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "texture",
      "roughness and waviness of a profile: a measured CSV, a simulate --out folder (its walls) "
      "or a job (its predicted walls)");
  cmd->add_option("SOURCE", a->source,
                  "profile CSV (x, z), folder written by simulate --out, or job TOML")
      ->required();
  cmd->add_option("--surface", a->surface, "left, right or both (walls of a folder or a job)")
      ->capture_default_str();
  cmd->add_option("--lambda-c", a->lambda_c_mm,
                  "cut-off wavelength, mm (default: ISO 21920-3's for the profile's Ra)")
      ->check(finite_above(0, 1e3));
  cmd->add_option("--z", a->z_mm, "the wall level of a simulation folder, mm (default: middle)")
      ->check(finite_in(-1e4, 1e4));
  cmd->add_option("--columns", a->columns,
                  "x,z column names of a CSV profile (default: the first two)");
  cmd->add_option("--z-unit", a->z_unit, "unit of a CSV profile's heights: mm or um")
      ->capture_default_str();
  cmd->add_option("--set", a->sets, "override a job key, section.key=value (job source)");
  cmd->add_option("--json", a->json, "write the report as JSON (- for stdout)");
  cmd->final_callback([a, &exit_code] {
    check_outputs({&a->json}, {&a->source});
    namespace fs = std::filesystem;
    if (a->surface != "left" && a->surface != "right" && a->surface != "both") {
      throw InputError(fmt::format("--surface '{}': left, right or both", a->surface));
    }
    std::vector<bool> sides;
    if (a->surface != "right") sides.push_back(true);
    if (a->surface != "left") sides.push_back(false);
    std::vector<TextureEntry> entries;
    std::error_code ec;
    const std::string ext = lower_extension(a->source);
    if (fs::is_directory(a->source, ec)) {
      const fs::path walls = fs::path(a->source) / "walls.csv";
      const std::string text = read_text_file(walls);
      for (const bool left : sides) {
        const MeasuredProfile p = read_wall_profile_csv(text, walls.string(), left, a->z_mm);
        entries.push_back({left ? "left" : "right", "simulated " + p.description,
                           profile_texture(p.z_mm, p.dx_mm, a->lambda_c_mm)});
      }
    } else if (ext == ".toml") {
      JobArgs job;
      job.file = a->source;
      job.sets = a->sets;
      const Job j = job.load();
      const ProcessMetrics m = analyze_process(j, plan_path(j).path);
      for (const bool left : sides) {
        const WallProfile& w = left ? m.walls_tooth.left : m.walls_tooth.right;
        if (w.x_mm.size() < 3) {
          throw InputError(fmt::format("{}: the analysis found no tooth-level {} wall", a->source,
                                       left ? "left" : "right"));
        }
        entries.push_back(
            {left ? "left" : "right",
             fmt::format("predicted {} wall, tooth level, one step of y repeated ({:g} mm)",
                         left ? "left" : "right", w.y_mm.back() - w.y_mm.front()),
             wall_texture(w, left, a->lambda_c_mm)});
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
      entries.push_back(
          {"profile", p.description, profile_texture(p.z_mm, p.dx_mm, a->lambda_c_mm)});
    } else {
      throw InputError(fmt::format(
          "texture: '{}' is not a folder written by simulate --out, a job (.toml) or a CSV "
          "profile (.csv)",
          a->source));
    }
    if (!a->json.empty()) emit(a->json, texture_json(a->source, entries));
    if (a->json != "-") fmt::print("{}", texture_text(a->source, entries));
    exit_code = 0;
  });
}

}  // namespace trochomill::cli
