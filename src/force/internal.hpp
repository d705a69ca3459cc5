// Shared between the force sources (src/force/, not public).
#pragma once

#include "trochomill/force.hpp"

namespace trochomill {

/// Fills the totals of `s` (fx, fy, fz, torque, power) from its per-tooth arrays, summing the
/// teeth in order, with power = torque * |omega| (rad/s).
void sum_teeth(ForceSeries& s, double omega_abs);

}  // namespace trochomill
