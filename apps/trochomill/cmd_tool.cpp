// insert, topography and materials: synthetic insert meshes, the sampled edge grid of a
// digitised (or synthetic) wear state, and the materials library.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report/force.hpp"
#include "trochomill/report/job.hpp"
#include "trochomill/topography.hpp"

namespace trochomill::cli {

void register_tool_commands(CLI::App& app, int& exit_code) {
  // insert
  {
    struct Args {
      JobArgs job;
      std::string out;
      SyntheticInsert spec;
      std::optional<double> edge_radius_mm;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "insert",
        "write a synthetic insert mesh (new, or worn with a flank wear land) for the "
        "job's tool, in the tooth frame");
    add_job_args(cmd, a->job);
    cmd->add_option("-o,--output", a->out,
                    "mesh file: .stl, .ply or .obj (- for binary STL on stdout)")
        ->required();
    cmd->add_option("--vb", a->spec.vb_mm, "flank wear land width VB, mm")
        ->capture_default_str()
        ->check(finite_in(0, 2));
    cmd->add_option("--edge-radius", a->edge_radius_mm,
                    "hone radius, mm (default [tool] edge_radius or 0.02)")
        ->check(finite_above(0, 1));
    cmd->add_option("--rake", a->spec.rake_deg, "rake angle, degrees")
        ->capture_default_str()
        ->check(finite_in(-30, 30));
    cmd->add_option("--clearance", a->spec.clearance_deg, "clearance angle, degrees")
        ->capture_default_str()
        ->check(finite_in(1, 30));
    cmd->add_option("--sections", a->spec.sections, "profile sections along the edge")
        ->capture_default_str()
        ->check(CLI::Range(2, 20000));
    cmd->add_option("--points", a->spec.profile_points, "points per profile")
        ->capture_default_str()
        ->check(CLI::Range(8, 20000));
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->out}, {&a->job.file});
      const std::string ext = lower_extension(a->out);
      if (a->out != "-" && ext != ".stl" && ext != ".ply" && ext != ".obj") {
        throw InputError(fmt::format(
            "-o {}: insert writes .stl, .ply or .obj (or - for STL on stdout)", a->out));
      }
      const Job job = a->job.load();
      const SimTool tool = sim_tool(job, job.simulation);
      SyntheticInsert spec = a->spec;
      spec.edge_radius_mm =
          a->edge_radius_mm.value_or(job.tool.edge_radius_mm > 0 ? job.tool.edge_radius_mm : 0.02);
      spec.face_mm =
          std::max(spec.face_mm, 2 * job.topography.band_mm + spec.vb_mm + spec.edge_radius_mm);
      const Mesh mesh = synthetic_insert(tool, spec);
      if (a->out == "-") {  // the mesh writer needs a file: a temporary STL, then stdout
        emit_file("-", ".stl", [&](const std::filesystem::path& p) { write_mesh(p, mesh); });
      } else {
        write_mesh(a->out, mesh);  // atomic itself, its format by the extension
      }
      fmt::print(
          a->out == "-" ? stderr : stdout,
          "{}: {} vertices, {} triangles (VB {:g} mm, hone {:g} mm, rake {:g}, clearance {:g} "
          "degrees)\n",
          a->out, mesh.vertices.size(), mesh.triangles.size(), spec.vb_mm, spec.edge_radius_mm,
          spec.rake_deg, spec.clearance_deg);
      exit_code = 0;
    });
  }
  // topography
  {
    struct Args {
      JobArgs job;
      std::string mesh, csv, json;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "topography",
        "sample a digitised (or synthetic) edge into the structured grid and report it");
    add_job_args(cmd, a->job);
    cmd->add_option("--mesh", a->mesh, "this mesh instead of the job's [topography] state");
    cmd->add_option("--csv", a->csv, "write the grid as CSV (- for stdout)");
    cmd->add_option("--json", a->json, "write the summary as JSON (- for stdout)");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->csv, &a->json}, {&a->job.file, &a->mesh});
      const Job job = a->job.load();
      const SimTool tool = sim_tool(job, job.simulation);
      EdgeTopography info;
      EdgeGrid grid;
      std::string source;
      if (!a->mesh.empty()) {
        grid = sample_topography(read_mesh(a->mesh), tool, job.topography.band_mm, &info);
        source = a->mesh;
      } else if (job.topography.states() > 0) {
        grid = job_edge_grid(job, tool, &info);
        source = fmt::format("[topography] state {}", job.topography.state);
      } else {
        throw InputError(
            fmt::format("{}: no [topography] (files or synthetic_vb) and no --mesh", a->job.file));
      }
      if (!a->csv.empty()) emit(a->csv, edge_grid_csv(grid));
      if (!a->json.empty()) emit(a->json, topography_json(grid, info));
      if (summary_to_stdout({&a->json, &a->csv})) {
        fmt::print("{}", topography_text(source, grid, info));
      }
      exit_code = 0;
    });
  }
  // keys
  {
    struct Args {
      bool markdown = false, json = false;
    };
    auto a = std::make_shared<Args>();
    auto* cmd =
        app.add_subcommand("keys", "list every job key: type, unit, allowed values, default");
    auto* md = cmd->add_flag("--markdown", a->markdown, "as the user guide's Markdown tables");
    cmd->add_flag("--json", a->json, "as JSON")->excludes(md);
    cmd->final_callback([a, &exit_code] {
      fmt::print("{}", a->markdown ? job_keys_markdown()
                       : a->json   ? job_keys_json()
                                   : job_keys_text());
      exit_code = 0;
    });
  }
  // materials
  {
    auto json = std::make_shared<bool>(false);
    auto* cmd = app.add_subcommand("materials", "list the materials library (data/materials)");
    cmd->add_flag("--json", *json, "as JSON");
    cmd->final_callback([json, &exit_code] {
      const std::vector<Material> lib = material_library();
      fmt::print("{}", *json ? materials_json(lib) : materials_text(lib, materials_dir().string()));
      exit_code = 0;
    });
  }
}

}  // namespace trochomill::cli
