// Unit conversions at the interface. Interface units: mm, s, mm/min, rpm, m/min, degrees.
// Internally: mm, s, radians. Every conversion in trochomill goes through these functions.
#pragma once

#include <numbers>

namespace trochomill {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// Degrees -> radians.
[[nodiscard]] constexpr double deg_to_rad(double deg) noexcept { return deg * kPi / 180.0; }
/// Radians -> degrees.
[[nodiscard]] constexpr double rad_to_deg(double rad) noexcept { return rad * 180.0 / kPi; }
/// Feed in mm/min -> mm/s.
[[nodiscard]] constexpr double mm_per_min_to_mm_per_s(double f) noexcept { return f / 60.0; }
/// Spindle speed in rpm -> angular speed in rad/s.
[[nodiscard]] constexpr double rpm_to_rad_per_s(double rpm) noexcept { return rpm * kTwoPi / 60.0; }
/// Cutting speed v_c (m/min) and tool diameter (mm) -> spindle speed (rpm): n = 1000 v_c / (pi D).
[[nodiscard]] constexpr double spindle_rpm_from_cutting_speed(double cutting_speed_m_per_min,
                                                              double diameter_mm) noexcept {
  return 1000.0 * cutting_speed_m_per_min / (kPi * diameter_mm);
}
/// Spindle speed (rpm) and tool diameter (mm) -> cutting speed v_c (m/min).
[[nodiscard]] constexpr double cutting_speed_from_spindle_rpm(double spindle_rpm,
                                                              double diameter_mm) noexcept {
  return spindle_rpm * kPi * diameter_mm / 1000.0;
}

}  // namespace trochomill
