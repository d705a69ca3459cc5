// Pivkin 2025's published chip model, equation by equation (include/trochomill/mechanism.hpp,
// docs/models.md section 9 for our reading of the garbled equations).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {
using Xy = Pivkin2025::Xy;
double cross(Xy a, Xy b) { return a.x_mm * b.y_mm - a.y_mm * b.x_mm; }
double dot(Xy a, Xy b) { return a.x_mm * b.x_mm + a.y_mm * b.y_mm; }
double norm(Xy a) { return std::hypot(a.x_mm, a.y_mm); }
Xy minus(Xy a, Xy b) { return {a.x_mm - b.x_mm, a.y_mm - b.y_mm}; }
}  // namespace

Pivkin2025::Pivkin2025(double orbit_diameter_mm, double step_mm, double tool_diameter_mm,
                       double feed_per_tooth_mm, int teeth)
    : dt_(orbit_diameter_mm),
      ae_(step_mm),
      d_(tool_diameter_mm),
      fz_(feed_per_tooth_mm),
      z_(teeth) {
  if (!(dt_ > 0) || !(ae_ > 0) || !(d_ > 0) || !(fz_ > 0) || z_ < 1) {
    throw InputError(fmt::format(
        "the pivkin2025 model needs D_t, a_e, D, f_z > 0 and Z >= 1, got D_t = {} mm, a_e = {} "
        "mm, D = {} mm, f_z = {} mm, Z = {}",
        dt_, ae_, d_, fz_, z_));
  }
  if (!(ae_ < kPi * dt_)) {
    throw InputError(fmt::format(
        "the pivkin2025 model needs a looping orbit: step a_e = {} mm must be < pi D_t = {} mm",
        ae_, kPi * dt_));
  }
  // Eq. 6, our reading: N = L_c / (f_z Z) spindle radians per trochoid radian, with the
  // cycle length L_c taken as the paper's sqrt(pi^2 D_t^2 + a_e^2) (the unrolled helix).
  n_ = std::sqrt(kPi * kPi * dt_ * dt_ + ae_ * ae_) / (fz_ * z_);
  theta_tooth_ = kTwoPi / (n_ * z_);  // Eq. 11
}

Xy Pivkin2025::centre(double th) const {
  return {-0.5 * dt_ * std::cos(th) + ae_ * th / kTwoPi, 0.5 * dt_ * std::sin(th)};
}

Xy Pivkin2025::centre_velocity(double th) const {
  return {0.5 * dt_ * std::sin(th) + ae_ / kTwoPi, 0.5 * dt_ * std::cos(th)};
}

Xy Pivkin2025::tooth(double th, double beta) const {  // Eqs. 2-5
  const Xy c = centre(th);
  const double phi = beta + n_ * th;
  return {c.x_mm + 0.5 * d_ * std::cos(phi), c.y_mm - 0.5 * d_ * std::sin(phi)};
}

Xy Pivkin2025::tooth_velocity(double th, double beta) const {
  const Xy v = centre_velocity(th);
  const double phi = beta + n_ * th;
  return {v.x_mm - 0.5 * d_ * n_ * std::sin(phi), v.y_mm - 0.5 * d_ * n_ * std::cos(phi)};
}

double Pivkin2025::a_t(double th, double beta2) const {  // Eq. 8
  const double phi = beta2 + n_ * th;
  return (kPi * dt_ * std::cos(th) - kPi * d_ * n_ * std::cos(phi)) /
         (ae_ + kPi * dt_ * std::sin(th) - kPi * d_ * n_ * std::sin(phi));
}

double Pivkin2025::c_t(double th, double beta2) const {  // Eq. 9: y2 - A_t x2
  const Xy p = tooth(th, beta2);
  return p.y_mm - a_t(th, beta2) * p.x_mm;
}

double Pivkin2025::h_delta(double th, double beta1) const {  // Eq. 10
  return norm(minus(tooth(th + theta_tooth_, beta1), tooth(th, beta1 + kTwoPi / z_)));
}

double Pivkin2025::h_t(double th, double beta2) const {
  // Eq. 12. |A x1 - y1 + C| / sqrt(A^2 + 1) is the distance from tooth 1's point to the line
  // through tooth 2's point along its velocity; written with the cross product it stays
  // finite where the tangent is vertical (A infinite).
  const Xy p1 = tooth(th + theta_tooth_, beta2 - kTwoPi / z_);
  const Xy p2 = tooth(th, beta2);
  const Xy v2 = tooth_velocity(th, beta2);
  return std::abs(cross(v2, minus(p1, p2))) / norm(v2);
}

double Pivkin2025::h_sigma(double th, double beta2) const {  // Eq. 13
  const double beta1 = beta2 - kTwoPi / z_;
  return h_t(th, beta2) - (h_delta(th, beta2) - h_delta(th, beta1));
}

Xy Pivkin2025::envelope(double th) const {
  // Eqs. 14-15: C + (D/2)(-sin alpha, cos alpha), alpha the direction of motion. The paper's
  // atan flips to the inner side where the motion runs backwards (dC_x/dtheta < 0); atan2
  // keeps the outer side, the one the cycle leaves as the machined surface.
  const Xy c = centre(th), v = centre_velocity(th);
  const double alpha = std::atan2(v.y_mm, v.x_mm);
  return {c.x_mm - 0.5 * d_ * std::sin(alpha), c.y_mm + 0.5 * d_ * std::cos(alpha)};
}

double Pivkin2025::h_e(double th) const {
  // Eq. 16: the envelope's tangent at theta, dF/dtheta = C' + (D/2) dn/dtheta with n =
  // (-sin alpha, cos alpha) and dalpha/dtheta = (C' x C'') / |C'|^2; Eq. 17: the distance
  // from F(theta + 2 pi) to that line (cross-product form of |A_e x - y + C_e| /
  // sqrt(A_e^2 + 1)).
  const Xy v = centre_velocity(th);
  const Xy acc{0.5 * dt_ * std::cos(th), -0.5 * dt_ * std::sin(th)};
  const double alpha = std::atan2(v.y_mm, v.x_mm);
  const double dalpha = cross(v, acc) / dot(v, v);
  Xy de{v.x_mm - 0.5 * d_ * std::cos(alpha) * dalpha, v.y_mm - 0.5 * d_ * std::sin(alpha) * dalpha};
  if (norm(de) < 1e-12 * norm(v)) de = v;  // a cusp of the envelope: the tangent is C''s
  const Xy e0 = envelope(th), e1 = envelope(th + kTwoPi);
  return std::abs(cross(de, minus(e1, e0))) / norm(de);
}

double Pivkin2025::psi(double th) const {  // Eq. 18
  const double r = 0.5 * d_;
  return std::acos(std::clamp((r - h_e(th)) / r, -1.0, 1.0));
}

double Pivkin2025::kappa(double th, double beta2) const {
  // Eqs. 21-23, our reading: K_c is the tangent of the circle the tooth turns on (the
  // primary motion), K_t the tangent of its trajectory (Eq. 22, with the orbit's motion);
  // kappa = K_t - K_c, the resultant cutting speed angle, signed positive where the feed's
  // radial component drives the edge outwards into the material.
  const double phi = beta2 + n_ * th;
  const Xy u{std::cos(phi), -std::sin(phi)};   // radial, tool centre to tooth
  const Xy t{-std::sin(phi), -std::cos(phi)};  // rotation direction
  const Xy v = centre_velocity(th);
  return std::atan2(dot(v, u), 0.5 * d_ * n_ + dot(v, t));
}

Pivkin2025::Point Pivkin2025::at(double th) const {
  Point p;
  const Xy v = centre_velocity(th);
  const double lv = norm(v);
  const Xy vh{v.x_mm / lv, v.y_mm / lv};
  const Xy n{-vh.y_mm, vh.x_mm};  // outward normal (left of the clockwise orbit's motion)
  p.h_e_mm = h_e(th);
  p.psi_rad = psi(th);
  // Cutting while the contact faces the feed: the front half of the orbit, wall to wall.
  p.cutting = n.x_mm > 0 && p.h_e_mm > 0;
  // The engaged arc runs from the contact point (direction n, where the chip vanishes on
  // the machined surface) by psi towards the motion; its far edge is where the chip is
  // thickest (f_z sin psi for a straight wall). Tooth 2 is put there at theta, tooth 1 one
  // tooth period later.
  const Xy u{std::cos(p.psi_rad) * n.x_mm + std::sin(p.psi_rad) * vh.x_mm,
             std::cos(p.psi_rad) * n.y_mm + std::sin(p.psi_rad) * vh.y_mm};
  const double phi = std::atan2(-u.y_mm, u.x_mm);
  p.beta2_rad = phi - n_ * th;
  p.h_sigma_mm = h_sigma(th, p.beta2_rad);
  p.kappa_rad = kappa(th, p.beta2_rad);
  if (p.cutting) p.h_mm = std::max(0.0, std::min(p.h_sigma_mm, p.h_e_mm));
  if (p.h_mm <= 0) p.cutting = false;
  return p;
}

}  // namespace trochomill
