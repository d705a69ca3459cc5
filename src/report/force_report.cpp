// Formatting of forces, calibration results and the materials library (report.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "trochomill/report/analysis.hpp"
#include "trochomill/report/force.hpp"

namespace trochomill {

std::string force_summary_json(const Job& job, const JobForces& f, double from_s, double to_s) {
  const ForceSummary& sm = f.summary;
  const nlohmann::json j = {{"f_resultant_max_n", sm.f_resultant_max_n},
                            {"t_resultant_max_s", sm.t_resultant_max_s},
                            {"f_x_max_n", sm.f_x_max_n},
                            {"f_y_max_n", sm.f_y_max_n},
                            {"f_z_max_n", sm.f_z_max_n},
                            {"f_x_mean_n", sm.f_x_mean_n},
                            {"f_y_mean_n", sm.f_y_mean_n},
                            {"f_z_mean_n", sm.f_z_mean_n},
                            {"torque_max_nm", sm.torque_max_nm},
                            {"power_max_w", sm.power_max_w},
                            {"power_mean_w", sm.power_mean_w},
                            {"model", to_string(*job.material.model)},
                            {"material", job.material.name},
                            {"chip_source", f.fast ? "fast" : "simulation"},
                            {"steps", f.series.size()},
                            {"from_s", from_s},
                            {"to_s", to_s},
                            {"chips_wall_s", f.chips_wall_s},
                            {"forces_wall_s", f.forces_wall_s},
                            {"complete", f.chips.complete},
                            {"cutting_direction_only", cutting_direction_only(job.material)},
                            {"note", cutting_direction_only(job.material)
                                         ? nlohmann::json(cutting_direction_only_note(job.material))
                                         : nlohmann::json(nullptr)}};
  return j.dump(2) + "\n";
}

std::string force_summary_text(const Job& job, const JobForces& f, double from_s, double to_s) {
  const ForceSummary& sm = f.summary;
  const auto n = [](double v) { return figure_text(v); };
  return fmt::format(
      "{}: {} model{}, {} chips, {} to {} s, {} steps\n"
      "  F_R,max {} N at {} s; |F_x| {}, |F_y| {}, |F_z| {} N max\n"
      "  torque max {} N m, power max {} W (mean {} W); {:.2f} s + {:.2f} s{}\n{}",
      job.source, to_string(*job.material.model),
      job.material.name.empty() ? "" : " (" + job.material.name + ")",
      f.fast ? "fast" : "simulated", n(from_s), n(to_s), f.series.size(), n(sm.f_resultant_max_n),
      n(sm.t_resultant_max_s), n(sm.f_x_max_n), n(sm.f_y_max_n), n(sm.f_z_max_n),
      n(sm.torque_max_nm), n(sm.power_max_w), n(sm.power_mean_w), f.chips_wall_s, f.forces_wall_s,
      f.chips.complete ? "" : " (interrupted: incomplete)",
      cutting_direction_only(job.material)
          ? "  note: " + cutting_direction_only_note(job.material) + "\n"
          : "");
}

std::string calibration_json(const CalibrationResult& r) {
  nlohmann::json j = {{"model", to_string(*r.material.model)},
                      {"rmse_n", r.rmse_n},
                      {"r2", r.r2},
                      {"shift_s", r.shift_s},
                      {"cutoff_hz", r.cutoff_hz},
                      {"samples", r.samples},
                      {"iterations", r.iterations},
                      {"warnings", r.warnings}};
  nlohmann::json ci = nlohmann::json::object();
  for (const auto& p : r.parameters) {
    j[p.name] = p.value;
    ci[p.name] = {
        {"lo", p.ci95_lo}, {"hi", p.ci95_hi}, {"std_error", p.std_error}, {"at_bound", p.at_bound}};
  }
  j["ci95"] = ci;
  return j.dump(2) + "\n";
}

std::string calibration_text(const std::string& measured, const CalibrationResult& r) {
  return fmt::format(
      "{}: {} samples per axis, shift {:.6f} s, low-pass {:.0f} Hz, {} iterations\n"
      "  RMSE {:.3f} N, R^2 {:.4f}\n{}",
      measured, r.samples, r.shift_s, r.cutoff_hz, r.iterations, r.rmse_n, r.r2, material_toml(r));
}

std::string mean_force_toml(const MeanForceFit& f) {
  const Material& m = f.material;
  return fmt::format(
      "[material]\nmodel = \"linear\"\nk_tc = {:.6g}  # N/mm^2\nk_rc = {:.6g}  # N/mm^2\n"
      "k_ac = {:.6g}  # N/mm^2\nk_te = {:.6g}  # N/mm\nk_re = {:.6g}  # N/mm\n"
      "k_ae = {:.6g}  # N/mm\nsource = \"{}\"\n",
      m.k_tc, m.k_rc, m.k_ac, m.k_te, m.k_re, m.k_ae, m.source);
}

std::string mean_force_json(const MeanForceFit& f) {
  const Material& m = f.material;
  const nlohmann::json j = {{"model", "linear"},   {"k_tc", m.k_tc},  {"k_rc", m.k_rc},
                            {"k_ac", m.k_ac},      {"k_te", m.k_te},  {"k_re", m.k_re},
                            {"k_ae", m.k_ae},      {"r2_axes", f.r2}, {"slope_n_per_mm", f.slope},
                            {"offset_n", f.offset}};
  return j.dump(2) + "\n";
}

std::string materials_json(const std::vector<Material>& lib) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& m : lib) {
    nlohmann::json o = {
        {"name", m.name}, {"model", to_string(*m.model)}, {"source", m.source}, {"notes", m.notes}};
    if (*m.model == ForceModel::linear) {
      o["k_tc"] = m.k_tc, o["k_rc"] = m.k_rc, o["k_ac"] = m.k_ac;
      o["k_te"] = m.k_te, o["k_re"] = m.k_re, o["k_ae"] = m.k_ae;
    } else {
      o["k_c"] = m.k_c, o["k_n"] = m.k_n, o["m"] = m.m;
      if (*m.model == ForceModel::kienzle) {
        o["m_n"] = m.m_n.value_or(m.m), o["k_a"] = m.k_a, o["m_a"] = m.m_a.value_or(m.m);
      }
    }
    j.push_back(o);
  }
  return j.dump(2) + "\n";
}

std::string materials_text(const std::vector<Material>& lib, const std::string& dir) {
  std::string out = fmt::format("{} materials in {}\n", lib.size(), dir);
  for (const auto& m : lib) {
    if (*m.model == ForceModel::linear) {
      out += fmt::format(
          "  {:<28} linear   K_tc {:g} K_rc {:g} K_ac {:g} N/mm^2, K_te {:g} K_re {:g} K_ae {:g} "
          "N/mm\n",
          m.name, m.k_tc, m.k_rc, m.k_ac, m.k_te, m.k_re, m.k_ae);
    } else {
      out += fmt::format("  {:<28} {:<8} k_c {:g} k_n {:g} N/mm^2, m {:g}\n", m.name,
                         to_string(*m.model), m.k_c, m.k_n, m.m);
    }
    out += fmt::format("  {:<28} source: {}\n", "", m.source);
  }
  return out;
}

std::string edge_grid_csv(const EdgeGrid& g) {
  std::string csv =
      "kappa,tau,s_mm,h_mm,r_mm,width_mm,proj_mm,proj_end_mm,para_mm,facet_r,facet_c,facet_a,"
      "normal_r,normal_a\n";
  auto out = std::back_inserter(csv);
  for (const EdgeCell& c : g.cells) {
    fmt::format_to(out,
                   "{},{},{:.6f},{:.6f},{:.6f},{:.6f},{:.7f},{:.7f},{:.7f},{:.6f},{:.6f},{:.6f},"
                   "{:.6f},{:.6f}\n",
                   c.kappa, c.tau, c.s_mm, c.h_mm, c.r_mm, c.width_mm, c.proj_mm, c.proj_end_mm,
                   c.para_mm, c.facet[0], c.facet[1], c.facet[2], c.normal[0], c.normal[2]);
  }
  return csv;
}

namespace {
double angle_to_cutting_deg(const EdgeCell& c) {
  return std::acos(std::clamp(c.facet[1], -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}
}  // namespace

std::string topography_json(const EdgeGrid& g, const EdgeTopography& info) {
  nlohmann::json segs = nlohmann::json::array();
  for (int k = 0; k < g.segments; ++k) {
    const EdgeCell& o = g.at(k, 0);
    const EdgeCell& i = g.at(k, g.sub_segments - 1);
    segs.push_back({{"kappa", k},
                    {"s_mm", o.s_mm},
                    {"outer_facet_angle_deg", angle_to_cutting_deg(o)},
                    {"inner_facet_angle_deg", angle_to_cutting_deg(i)},
                    {"profile_length_mm", o.para_mm * g.sub_segments}});
  }
  const nlohmann::json j = {{"points", info.points},
                            {"facets_kept", info.facets_kept},
                            {"facets_total", info.facets_total},
                            {"s_min_mm", info.s_min_mm},
                            {"s_max_mm", info.s_max_mm},
                            {"segments", g.segments},
                            {"sub_segments", g.sub_segments},
                            {"band_mm", g.band_mm},
                            {"per_segment", segs}};
  return j.dump(2) + "\n";
}

std::string topography_text(const std::string& source, const EdgeGrid& g,
                            const EdgeTopography& info) {
  std::string out = fmt::format(
      "{}: {} of {} facets face the cutting direction, {} points along the edge from {:.3f} to "
      "{:.3f} mm; grid {} segments x {} sub-segments in a {:g} mm band\n",
      source, info.facets_kept, info.facets_total, info.points, info.s_min_mm, info.s_max_mm,
      g.segments, g.sub_segments, g.band_mm);
  out += "  kappa   s_mm   profile_mm  facet angle to v_c, outer -> inner (degrees)\n";
  const int step = std::max(1, g.segments / 12);
  for (int k = 0; k < g.segments; k += step) {
    out += fmt::format("  {:5d} {:7.3f} {:10.4f} ", k, g.at(k, 0).s_mm,
                       g.at(k, 0).para_mm * g.sub_segments);
    for (int t = 0; t < g.sub_segments; ++t)
      out += fmt::format(" {:5.1f}", angle_to_cutting_deg(g.at(k, t)));
    out += "\n";
  }
  return out;
}

}  // namespace trochomill
