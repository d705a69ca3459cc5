// Forces, calibrations and the mean-force fit; an edge's grid and sampled topography. Part of the
// report module (trochomill/report.hpp includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/force.hpp"
#include "trochomill/topography.hpp"

namespace trochomill {

/// The force series: t_s, f_x_n, f_y_n, f_z_n, f_resultant_n, torque_nm, power_w, then per
/// tooth k: tooth<k>_f_x_n, tooth<k>_f_y_n, tooth<k>_f_z_n, tooth<k>_torque_nm. `calibrate`
/// reads it as it is.
[[nodiscard]] std::string force_series_csv(const ForceSeries& s);
/// `trochomill forces`' summary: JSON (f_resultant_max_n, f_x_max_n, f_y_max_n, f_z_max_n,
/// torque_max_nm, power_max_w, means, model, chip source, window, wall times) and text.
[[nodiscard]] std::string force_summary_json(const Job& job, const JobForces& f, double from_s,
                                             double to_s);
[[nodiscard]] std::string force_summary_text(const Job& job, const JobForces& f, double from_s,
                                             double to_s);
/// A calibration: JSON (the fitted parameters under their key names, rmse_n, r2, shift_s,
/// cutoff_hz, samples, iterations, ci95 per parameter) and text (with the [material] block).
[[nodiscard]] std::string calibration_json(const CalibrationResult& r);
[[nodiscard]] std::string calibration_text(const std::string& measured, const CalibrationResult& r);
/// The mean-force regression's [material] block (TOML) and JSON.
[[nodiscard]] std::string mean_force_toml(const MeanForceFit& f);
[[nodiscard]] std::string mean_force_json(const MeanForceFit& f);
/// The structured grid per cell: kappa, tau, s_mm, h_mm, r_mm, width_mm, proj_mm,
/// proj_end_mm, para_mm, facet_r, facet_c, facet_a (d_c in the tooth frame: radial, cutting
/// direction, axial), normal_r, normal_a (d_n).
[[nodiscard]] std::string edge_grid_csv(const EdgeGrid& g);
/// A sampled topography: JSON (points, facets_kept, facets_total, s_min_mm, s_max_mm,
/// segments, sub_segments, band_mm, and per segment the facet angle to the cutting direction
/// of its outermost and innermost sub-segments) and text.
[[nodiscard]] std::string topography_json(const EdgeGrid& g, const EdgeTopography& info);
[[nodiscard]] std::string topography_text(const std::string& source, const EdgeGrid& g,
                                          const EdgeTopography& info);

}  // namespace trochomill
