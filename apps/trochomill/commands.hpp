// The command groups: each registers its commands on the app; the callback of a command runs
// it and stores its exit code (0, or 130 when interrupted) in `exit_code`.
#pragma once

#include <CLI/CLI.hpp>

namespace trochomill::cli {

void register_path_commands(CLI::App& app, int& exit_code);         // plan, path, check-gcode
void register_geometry_commands(CLI::App& app, int& exit_code);     // check-drawing
void register_analysis_commands(CLI::App& app, int& exit_code);     // analyze, compare
void register_mechanism_commands(CLI::App& app, int& exit_code);    // mechanism, recommend
void register_simulation_commands(CLI::App& app, int& exit_code);   // simulate, forces
void register_calibration_commands(CLI::App& app, int& exit_code);  // calibrate
void register_signal_commands(CLI::App& app, int& exit_code);   // monitor, synth-signal, spectrum
void register_tool_commands(CLI::App& app, int& exit_code);     // insert, topography, materials
void register_surface_commands(CLI::App& app, int& exit_code);  // texture
void register_study_commands(CLI::App& app, int& exit_code);    // sweep, optimize
void register_feed_commands(CLI::App& app, int& exit_code);     // optimize-feed
/// report; `argv` is recorded in the page.
void register_report_commands(CLI::App& app, int& exit_code, int argc, char** argv);

}  // namespace trochomill::cli
