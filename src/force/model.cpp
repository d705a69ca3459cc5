// Force models per engaged segment and their sum over a chip record (force.hpp;
// docs/models.md section 12).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "internal.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

double ForceSeries::resultant_n(std::size_t i) const {
  return std::sqrt(fx_n[i] * fx_n[i] + fy_n[i] * fy_n[i] + fz_n[i] * fz_n[i]);
}

ForceSummary summarize(const ForceSeries& s) {
  ForceSummary r;
  const std::size_t n = s.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double fr = s.resultant_n(i);
    if (fr > r.f_resultant_max_n) r.f_resultant_max_n = fr, r.t_resultant_max_s = s.t_s[i];
    r.f_x_max_n = std::max(r.f_x_max_n, std::abs(s.fx_n[i]));
    r.f_y_max_n = std::max(r.f_y_max_n, std::abs(s.fy_n[i]));
    r.f_z_max_n = std::max(r.f_z_max_n, std::abs(s.fz_n[i]));
    r.f_x_mean_n += s.fx_n[i];
    r.f_y_mean_n += s.fy_n[i];
    r.f_z_mean_n += s.fz_n[i];
    r.torque_max_nm = std::max(r.torque_max_nm, s.torque_nm[i]);
    r.power_max_w = std::max(r.power_max_w, s.power_w[i]);
    r.power_mean_w += s.power_w[i];
  }
  if (n > 0) {
    const double inv = 1.0 / static_cast<double>(n);
    r.f_x_mean_n *= inv, r.f_y_mean_n *= inv, r.f_z_mean_n *= inv, r.power_mean_w *= inv;
  }
  return r;
}

SegmentForces::SegmentForces(const Material& material, const EdgeGrid& grid,
                             double ploughing_angle_rad)
    : m_(material), tau_(std::max(1, grid.sub_segments)) {
  if (!m_.model) {
    throw InputError(
        "no force model: give [material] model (bergmann | kienzle | linear) with its "
        "coefficients, or [material] name from `trochomill materials`");
  }
  if (*m_.model != ForceModel::linear && !(m_.k_c > 0 && m_.m >= 0 && m_.m < 1)) {
    throw InputError(
        fmt::format("[material] {}: need k_c > 0 N/mm^2 and 0 <= m < 1, got k_c {} m {}",
                    to_string(*m_.model), m_.k_c, m_.m));
  }
  if (grid.segments < 1 || grid.cells.size() != static_cast<std::size_t>(grid.segments * tau_)) {
    throw InputError("force model: the edge grid is empty or not segments x sub_segments");
  }
  const double cos_zeta = std::cos(ploughing_angle_rad);
  subs_.resize(grid.cells.size());
  for (int k = 0; k < grid.segments; ++k) {
    const EdgeCell& c0 = grid.at(k, 0);
    d_n_.push_back(c0.normal);
    along_.push_back({-c0.normal[2], 0.0, c0.normal[0]});
    std::array<double, 3> acc{};
    double plough = 0;
    for (int j = 0; j < tau_; ++j) {
      const EdgeCell& c = grid.at(k, j);
      for (int q = 0; q < 3; ++q) acc[q] += c.para_mm * c.facet[q];
      // Steeper than zeta to v_c: the facet's normal makes more than zeta with the cutting
      // direction (its component along v_c below cos zeta).
      if (c.facet[1] < cos_zeta) plough = std::max(plough, c.proj_end_mm);
      Sub& s = subs_[static_cast<std::size_t>(k * tau_ + j)];
      s.proj_mm = c.proj_mm;
      s.plough_mm = plough;
      const double nrm = std::sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2]);
      s.d_e = nrm > 0 ? std::array<double, 3>{acc[0] / nrm, acc[1] / nrm, acc[2] / nrm}
                      : std::array<double, 3>{0.0, 1.0, 0.0};
    }
  }
}

std::array<double, 3> SegmentForces::force(int kappa, double h, double w) const {
  const auto& dn = d_n_[static_cast<std::size_t>(kappa)];
  const auto& da = along_[static_cast<std::size_t>(kappa)];
  switch (*m_.model) {
    case ForceModel::linear: {
      const double fc = w * (m_.k_tc * h + m_.k_te), fn = w * (m_.k_rc * h + m_.k_re),
                   fa = w * (m_.k_ac * h + m_.k_ae);
      return {fn * dn[0] + fa * da[0], fc, fn * dn[2] + fa * da[2]};
    }
    case ForceModel::kienzle: {
      const double fc = w * m_.k_c * std::pow(h, 1 - m_.m);
      const double fn = w * m_.k_n * std::pow(h, 1 - m_.m_n.value_or(m_.m));
      const double fa = m_.k_a != 0 ? w * m_.k_a * std::pow(h, 1 - m_.m_a.value_or(m_.m)) : 0.0;
      return {fn * dn[0] + fa * da[0], fc, fn * dn[2] + fa * da[2]};
    }
    case ForceModel::bergmann: {
      // tau_h: the last sub-segment whose outer end lies inside the chip (the first always).
      const Sub* base = &subs_[static_cast<std::size_t>(kappa * tau_)];
      int j = 0;
      while (j + 1 < tau_ && base[j + 1].proj_mm < h) ++j;
      const Sub& s = base[j];
      const double p = w * std::pow(h, 1 - m_.m);
      std::array<double, 3> f{p * (m_.k_c * s.d_e[0] + m_.k_n * dn[0]),
                              p * (m_.k_c * s.d_e[1] + m_.k_n * dn[1]),
                              p * (m_.k_c * s.d_e[2] + m_.k_n * dn[2])};
      const double hs = std::min(h, s.plough_mm);
      if (hs > 0) f[1] += w * m_.k_c * std::pow(hs, 1 - m_.m);
      return f;
    }
  }
  return {0.0, 0.0, 0.0};
}

ForceSeries compute_forces(const SimResult& chips, const SimTool& tool, const EdgeGrid& grid,
                           const SegmentForces& model) {
  const int nz = static_cast<int>(tool.tooth_angle_rad.size());
  const int spt = chips.segments_per_tooth;
  if (spt != grid.segments) {
    throw InputError(
        fmt::format("forces: the chip record has {} segments per tooth, the edge "
                    "grid {}; both must come from the same tool",
                    spt, grid.segments));
  }
  ForceSeries s;
  s.teeth = nz;
  const std::size_t n = chips.steps.size();
  s.t_s.resize(n);
  for (std::size_t i = 0; i < n; ++i) s.t_s[i] = chips.steps[i].t_s;
  s.fx_n.assign(n, 0.0), s.fy_n.assign(n, 0.0), s.fz_n.assign(n, 0.0);
  s.torque_nm.assign(n, 0.0), s.power_w.assign(n, 0.0);
  const std::size_t nt = n * static_cast<std::size_t>(nz);
  s.tooth_fx_n.assign(nt, 0.0), s.tooth_fy_n.assign(nt, 0.0), s.tooth_fz_n.assign(nt, 0.0);
  s.tooth_torque_nm.assign(nt, 0.0);
  // The edge angle at a segment: tooth angle + omega t + the helix lag at its height. Per
  // segment the lag's cosine and sine once; per (step, tooth) the rest's once (entries come
  // grouped by step and tooth), combined by the angle-sum formulas.
  const double lag = std::tan(tool.helix_rad) / tool.radius_mm;  // rad per mm of height
  std::vector<double> cl(static_cast<std::size_t>(spt)), sl(static_cast<std::size_t>(spt));
  for (int k = 0; k < spt; ++k) {
    cl[static_cast<std::size_t>(k)] = std::cos(grid.at(k, 0).h_mm * lag);
    sl[static_cast<std::size_t>(k)] = std::sin(grid.at(k, 0).h_mm * lag);
  }
  const double dir = tool.omega_rad_per_s < 0 ? -1.0 : 1.0;
  std::size_t cached = static_cast<std::size_t>(-1);
  double cb = 1, sb = 0;
  for (const ChipEntry& e : chips.chip_map) {
    const int tooth = static_cast<int>(e.segment) / spt, k = static_cast<int>(e.segment) % spt;
    if (tooth >= nz || e.step >= n || !(e.h_mm > 0) || !(e.w_mm > 0)) continue;
    const EdgeCell& c = grid.at(k, 0);
    const std::size_t ti = e.step * static_cast<std::size_t>(nz) + static_cast<std::size_t>(tooth);
    if (ti != cached) {
      const double base = tool.tooth_angle_rad[static_cast<std::size_t>(tooth)] +
                          tool.omega_rad_per_s * chips.steps[e.step].t_s;
      cb = std::cos(base), sb = std::sin(base);
      cached = ti;
    }
    const double ct = cb * cl[static_cast<std::size_t>(k)] - sb * sl[static_cast<std::size_t>(k)];
    const double st = sb * cl[static_cast<std::size_t>(k)] + cb * sl[static_cast<std::size_t>(k)];
    add_segment_force(s, ti, model.force(k, e.h_mm, e.w_mm), ct, st, dir, c.r_mm);
  }
  sum_teeth(s, std::abs(tool.omega_rad_per_s));
  return s;
}

void sum_teeth(ForceSeries& s, double omega_abs) {
  const std::size_t n = s.t_s.size(), nz = static_cast<std::size_t>(s.teeth);
  s.fx_n.assign(n, 0.0), s.fy_n.assign(n, 0.0), s.fz_n.assign(n, 0.0);
  s.torque_nm.assign(n, 0.0), s.power_w.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < nz; ++k) {  // in tooth order: the same for any entry order
      const std::size_t ti = i * nz + k;
      s.fx_n[i] += s.tooth_fx_n[ti], s.fy_n[i] += s.tooth_fy_n[ti], s.fz_n[i] += s.tooth_fz_n[ti];
      s.torque_nm[i] += s.tooth_torque_nm[ti];
    }
    s.power_w[i] = s.torque_nm[i] * omega_abs;
  }
}

bool cutting_direction_only(const Material& m) {
  if (!m.model) return false;
  if (*m.model == ForceModel::linear) {
    return m.k_rc == 0 && m.k_ac == 0 && m.k_re == 0 && m.k_ae == 0;
  }
  return m.k_n == 0 && m.k_a == 0;
}

std::string cutting_direction_only_note(const Material& m) {
  return fmt::format(
      "{} gives the force along the cutting direction only ({} = 0): the forces are the "
      "cutting force alone, F_R,max a lower bound; the torque and the power are whole",
      m.name.empty() ? std::string("[material]") : m.name,
      m.model && *m.model == ForceModel::linear ? "k_rc, k_ac, k_re, k_ae" : "k_n, k_a");
}

}  // namespace trochomill
