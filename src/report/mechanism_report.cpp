// Formatting of the cutting mechanism's curves, zones and recommendation (report.hpp).
#include <fmt/format.h>

#include <iterator>
#include <nlohmann/json.hpp>

#include "trochomill/report/analysis.hpp"
#include "trochomill/report/mechanism.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

nlohmann::json zones_json(const ZoneSummary& z) {
  return {{"CZI", z.share[0]}, {"CZII", z.share[1]}, {"CZIII", z.share[2]}};
}
nlohmann::json cycle_zones_json(const ZoneSummary& z) {
  return {{"CZI", z.cycle_share[0]}, {"CZII", z.cycle_share[1]}, {"CZIII", z.cycle_share[2]}};
}

nlohmann::json times_json(const ZoneSummary& z) {
  nlohmann::json j = nlohmann::json::object();
  const char* names[3] = {"CZI", "CZII", "CZIII"};
  for (int q = 0; q < 3; ++q) j[names[q]] = {{"start_s", z.start_s[q]}, {"end_s", z.end_s[q]}};
  return j;
}

}  // namespace

std::string mechanism_json(const Job& job, const MechanismSettings& st, const MechanismCurve& c,
                           const ZoneSummary& z, bool use_wear) {
  nlohmann::json j = {{"model", to_string(st.model)},
                      {"edge_radius_mm", job.tool.edge_radius_mm},
                      {"flank_wear_mm", job.tool.flank_wear_mm},
                      {"cycle_time_s", c.cycle_time_s},
                      {"cutting_time_s", z.cutting_time_s},
                      {"cutting_start_s", z.cutting_start_s},
                      {"h_max_mm", z.h_max_mm},
                      {"h_m_mm", z.h_m_mm},
                      {"transition_s", z.transition_s},
                      {"zone_share", zones_json(z)},
                      {"zone_share_of_cycle", cycle_zones_json(z)},
                      {"plunger_first_half_share", z.plunger_first_half_share},
                      {"zone_times_s", times_json(z)},
                      {"thresholds_pct",
                       {{"czi_max", st.thresholds.czi_max_pct},
                        {"czii_max", st.thresholds.czii_max_pct},
                        {"transition", st.thresholds.transition_pct}}},
                      {"theta_deg", nlohmann::json::array()},
                      {"h_mm", c.h_mm},
                      {"k_re_pct", use_wear ? c.k_re_wear_pct : c.k_re_pct},
                      {"zone", c.zone}};
  for (const double th : c.theta_rad) j["theta_deg"].push_back(rad_to_deg(th));
  return j.dump(2) + "\n";
}

std::string mechanism_csv(const MechanismCurve& c) {
  std::string out =
      "theta_deg,t_s,h_mm,psi_deg,teeth_in_contact,gamma_k_deg,kappa_deg,k_re_pct,"
      "k_re_wear_pct,zone\n";
  for (std::size_t i = 0; i < c.theta_rad.size(); ++i) {
    fmt::format_to(std::back_inserter(out),
                   "{:.4f},{:.6f},{:.7f},{:.4f},{:.4f},{:.4f},{:.4f},{:.3f},{:.3f},{}\n",
                   rad_to_deg(c.theta_rad[i]), c.t_s[i], c.h_mm[i], rad_to_deg(c.psi_rad[i]),
                   c.teeth_in_contact[i], rad_to_deg(c.gamma_k_rad[i]), rad_to_deg(c.kappa_rad[i]),
                   c.k_re_pct[i], c.k_re_wear_pct[i], c.zone[i]);
  }
  return out;
}

std::string mechanism_text(const std::string& job_file, const Job& job, const MechanismSettings& st,
                           const MechanismCurve& c, const ZoneSummary& z, bool use_wear) {
  std::string out = fmt::format(
      "{}: {} model, r_e {:g} mm{}\n", job_file, to_string(st.model), job.tool.edge_radius_mm,
      use_wear ? fmt::format(", flank wear {:g} mm", job.tool.flank_wear_mm) : "");
  const auto n = [](double v) { return figure_text(v); };
  out += fmt::format("  cycle {} s, cutting {} s, h_max {} mm, h_m {}\n", n(c.cycle_time_s),
                     n(z.cutting_time_s), n(z.h_max_mm),
                     st.friction_angle_deg > 0 ? n(z.h_m_mm) + " mm"
                                               : std::string("n/a (no [material] friction_angle)"));
  const char* names[3] = {"CZI  ", "CZII ", "CZIII"};
  for (int q = 0; q < 3; ++q) {
    out += fmt::format("  {} {} % of the cutting part", names[q], n(100 * z.share[q]));
    if (z.start_s[q] >= 0) {
      out += fmt::format(", {} to {} s after cutting starts", n(z.start_s[q]), n(z.end_s[q]));
    }
    out += "\n";
  }
  out += fmt::format("  CZI is {} % of the cut's first half (the plunger criterion's share)\n",
                     n(100 * z.plunger_first_half_share));
  return out;
}

std::string recommendation_json(const Job& job, const MechanismSettings& st,
                                const Recommendation& r, bool for_feed) {
  const nlohmann::json j = {{"found", r.found},
                            {for_feed ? "min_feed_per_tooth_mm" : "min_step_mm",
                             r.found ? nlohmann::json(r.value) : nlohmann::json(nullptr)},
                            {"criterion", to_string(st.criterion)},
                            {"share", st.share},
                            {"share_of", to_string(st.share_of)},
                            {"plunger_share", st.plunger_share},
                            {"plunger_first_half_share", r.zones.plunger_first_half_share},
                            {"model", to_string(st.model)},
                            {"flank_wear_mm", job.tool.flank_wear_mm},
                            {"zone_share", zones_json(r.zones)},
                            {"zone_share_of_cycle", cycle_zones_json(r.zones)},
                            {"explanation", r.explanation}};
  return j.dump(2) + "\n";
}

}  // namespace trochomill
