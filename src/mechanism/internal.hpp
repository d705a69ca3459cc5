// Internal pieces of the mechanism module (not installed).
#pragma once

#include <vector>

namespace trochomill::mech {

struct ChipPoint {
  double h_mm = 0;       ///< chip thickness at the contact (0: not cutting)
  double psi_rad = 0;    ///< engaged (contact) angle
  double kappa_rad = 0;  ///< kinematic angle change at the contact
};

/// The exact model at any theta of a steady-state cycle.
class ExactModel {
 public:
  ExactModel(double a_mm, double b_mm, double step_mm, double radius_mm, double fz_mm,
             double feed_mm_per_s, double edge_speed_mm_per_s);
  [[nodiscard]] ChipPoint at(double theta_rad) const;

 private:
  double a_, b_, s_, R_, fz_, feed_mm_per_s_, edge_speed_mm_per_s_;
  // The previous cycle's envelope and the path on fixed grids (see exact.cpp).
  double env_dt_ = 0, path_dt_ = 0;
  int env_m0_ = 0, path_m0_ = 0;
  std::vector<double> env_x_, env_y_, path_x_, path_y_;
};

}  // namespace trochomill::mech
