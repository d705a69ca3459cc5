// Shared between the force sources (src/force/, not public).
#pragma once

#include <array>
#include <cstddef>

#include "trochomill/force.hpp"

namespace trochomill {

/// Adds a segment's force f (tooth frame: radial, cutting, axial; N) at edge angle theta
/// (cosine ct, sine st) to tooth entry ti of `s`, with its torque at radius r_mm: radial
/// (cos, sin), cutting direction dir (-sin, cos) (dir = -1 for a clockwise spindle), axial z.
inline void add_segment_force(ForceSeries& s, std::size_t ti, const std::array<double, 3>& f,
                              double ct, double st, double dir, double r_mm) {
  s.tooth_fx_n[ti] += f[0] * ct - dir * f[1] * st;
  s.tooth_fy_n[ti] += f[0] * st + dir * f[1] * ct;
  s.tooth_fz_n[ti] += f[2];
  s.tooth_torque_nm[ti] += f[1] * r_mm * 1e-3;
}

/// Fills the totals of `s` (fx, fy, fz, torque, power) from its per-tooth arrays, summing the
/// teeth in order, with power = torque * |omega| (rad/s).
void sum_teeth(ForceSeries& s, double omega_abs);

}  // namespace trochomill
