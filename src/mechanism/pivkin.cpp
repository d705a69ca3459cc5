// Pivkin 2025's published chip model, equation by equation (include/trochomill/mechanism.hpp,
// docs/models.md section 9 for our reading of the garbled equations).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "common/sincos.hpp"
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
  cos_tooth_ = std::cos(theta_tooth_);
  sin_tooth_ = std::sin(theta_tooth_);
}

Xy Pivkin2025::centre(double th) const {
  return {-0.5 * dt_ * std::cos(th) + ae_ * th / kTwoPi, 0.5 * dt_ * std::sin(th)};
}

Xy Pivkin2025::centre_velocity(double th) const {
  return {0.5 * dt_ * std::sin(th) + ae_ / kTwoPi, 0.5 * dt_ * std::cos(th)};
}

// Tooth k's angular position phi = beta_k + N theta enters every equation only through
// (cos phi, sin phi): the helpers take those (`Phase`), so the model (at) can place a tooth
// by its direction without computing a large angle N theta and back.
Xy Pivkin2025::tooth_at(double th, Phase ph) const {  // Eqs. 2-5
  const Xy c = centre(th);
  return {c.x_mm + 0.5 * d_ * ph.c, c.y_mm - 0.5 * d_ * ph.s};
}

Xy Pivkin2025::tooth_velocity_at(double th, Phase ph) const {
  const Xy v = centre_velocity(th);
  return {v.x_mm - 0.5 * d_ * n_ * ph.s, v.y_mm - 0.5 * d_ * n_ * ph.c};
}

double Pivkin2025::h_t_at(double th, Phase ph) const {
  // Eq. 12. |A x1 - y1 + C| / sqrt(A^2 + 1) is the distance from tooth 1's point to the line
  // through tooth 2's point along its velocity; written with the cross product it stays
  // finite where the tangent is vertical (A infinite). Tooth 1 at theta + Theta has tooth
  // 2's phase at theta: beta1 + N (theta + Theta) = beta2 - 2 pi / Z + N theta + 2 pi / Z.
  const Xy p1 = tooth_at(th + theta_tooth_, ph), p2 = tooth_at(th, ph);
  const Xy v2 = tooth_velocity_at(th, ph);
  return std::abs(cross(v2, minus(p1, p2))) / norm(v2);
}

double Pivkin2025::kappa_at(double th, Phase ph) const {
  // Eqs. 21-23, our reading: K_c is the tangent of the circle the tooth turns on (the
  // primary motion), K_t the tangent of its trajectory (Eq. 22, with the orbit's motion);
  // kappa = K_t - K_c, the resultant cutting speed angle, signed positive where the feed's
  // radial component drives the edge outwards into the material.
  const Xy u{ph.c, -ph.s};   // radial, tool centre to tooth
  const Xy t{-ph.s, -ph.c};  // rotation direction
  const Xy v = centre_velocity(th);
  return std::atan2(dot(v, u), 0.5 * d_ * n_ + dot(v, t));
}

Pivkin2025::Phase Pivkin2025::phase(double th, double beta) const {
  const double phi = beta + n_ * th;
  return {std::cos(phi), std::sin(phi)};
}

Xy Pivkin2025::tooth(double th, double beta) const { return tooth_at(th, phase(th, beta)); }

Xy Pivkin2025::tooth_velocity(double th, double beta) const {
  return tooth_velocity_at(th, phase(th, beta));
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

double Pivkin2025::h_t(double th, double beta2) const { return h_t_at(th, phase(th, beta2)); }

double Pivkin2025::h_sigma(double th, double beta2) const {  // Eq. 13
  const double beta1 = beta2 - kTwoPi / z_;
  return h_t(th, beta2) - (h_delta(th, beta2) - h_delta(th, beta1));
}

double Pivkin2025::kappa(double th, double beta2) const { return kappa_at(th, phase(th, beta2)); }

Xy Pivkin2025::envelope(double th) const {
  // Eqs. 14-15: C + (D/2)(-sin alpha, cos alpha), alpha the direction of motion. The paper's
  // atan flips to the inner side where the motion runs backwards (dC_x/dtheta < 0); we keep
  // the outer side (alpha = atan2), the one the cycle leaves as the machined surface.
  const Xy c = centre(th), v = centre_velocity(th);
  const double lv = norm(v);  // (cos alpha, sin alpha) = v / |v|
  return {c.x_mm - 0.5 * d_ * v.y_mm / lv, c.y_mm + 0.5 * d_ * v.x_mm / lv};
}

double Pivkin2025::h_e(double th) const {
  // Eq. 16: the envelope's tangent at theta, dF/dtheta = C' + (D/2) dn/dtheta with n =
  // (-sin alpha, cos alpha) and dalpha/dtheta = (C' x C'') / |C'|^2; Eq. 17: the distance
  // from F(theta + 2 pi) to that line (cross-product form of |A_e x - y + C_e| /
  // sqrt(A_e^2 + 1)). F(theta + 2 pi) = F(theta) + (a_e, 0): the orbit repeats a_e ahead.
  const double sn = std::sin(th), cs = std::cos(th);
  const Xy v{0.5 * dt_ * sn + ae_ / kTwoPi, 0.5 * dt_ * cs};
  const Xy acc{0.5 * dt_ * cs, -0.5 * dt_ * sn};
  const double vv = dot(v, v), lv = std::sqrt(vv);
  const double dalpha = cross(v, acc) / vv;
  Xy de{v.x_mm - 0.5 * d_ * (v.x_mm / lv) * dalpha, v.y_mm - 0.5 * d_ * (v.y_mm / lv) * dalpha};
  if (norm(de) < 1e-12 * lv) de = v;  // a cusp of the envelope: the tangent is C''s
  return std::abs(cross(de, Xy{ae_, 0})) / norm(de);
}

double Pivkin2025::psi_of(double h_e_mm) const {  // Eq. 18
  const double r = 0.5 * d_;
  return std::acos(std::clamp((r - h_e_mm) / r, -1.0, 1.0));
}

double Pivkin2025::psi(double th) const { return psi_of(h_e(th)); }

Pivkin2025::Point Pivkin2025::at(double th) const {
  // The equations of the helpers above, written once more with what they share computed once:
  // one sine and cosine of theta (from the table, within 2.2e-16 of libm's) and of theta +
  // Theta (the same turned by Theta), cos psi from Eq. 18's argument and sin psi from it,
  // square roots for the norms. The helpers are the reference (test
  // Pivkin2025.EquationsAgainstHandValues); this agrees with them to rounding, some ten times
  // faster, for the thousands of points a cycle takes.
  Point p;
  const detail::SinCos q = detail::sincos_table()(th);
  const double sn = q.s, cs = q.c, hr = 0.5 * dt_;
  const Xy v{hr * sn + ae_ / kTwoPi, hr * cs};  // centre_velocity(th)
  const double vv = dot(v, v), lv = std::sqrt(vv);
  const Xy vh{v.x_mm / lv, v.y_mm / lv};
  const Xy n{-vh.y_mm, vh.x_mm};  // outward normal (left of the clockwise orbit's motion)
  {                               // h_e(th), Eqs. 16-17
    const Xy acc{hr * cs, -hr * sn};
    const double dalpha = cross(v, acc) / vv;
    Xy de{v.x_mm - 0.5 * d_ * vh.x_mm * dalpha, v.y_mm - 0.5 * d_ * vh.y_mm * dalpha};
    double lde = std::sqrt(dot(de, de));
    if (lde < 1e-12 * lv) {  // a cusp of the envelope: the tangent is C''s
      de = v;
      lde = lv;
    }
    p.h_e_mm = std::abs(cross(de, Xy{ae_, 0})) / lde;
  }
  const double r = 0.5 * d_;
  const double cp = std::clamp((r - p.h_e_mm) / r, -1.0, 1.0);  // cos psi, Eq. 18
  p.psi_rad = std::acos(cp);
  const double sp = std::sqrt(std::max(0.0, 1 - cp * cp));
  // Cutting while the contact faces the feed: the front half of the orbit, wall to wall.
  p.cutting = n.x_mm > 0 && p.h_e_mm > 0;
  // Tooth 2 on the engaged arc's far edge (see the comments of the reference below).
  const Xy u{cp * n.x_mm + sp * vh.x_mm, cp * n.y_mm + sp * vh.y_mm};
  const Phase ph{u.x_mm, -u.y_mm};
  p.beta2_rad = std::atan2(ph.s, ph.c) - n_ * th;
  {  // h_t_at(th, ph), Eq. 12: tooth 1 at theta + Theta minus tooth 2 at theta is the
     // centres' difference (same phase); tooth 2's velocity is the centre's plus the edge's.
    const double sn1 = sn * cos_tooth_ + cs * sin_tooth_, cs1 = cs * cos_tooth_ - sn * sin_tooth_;
    const Xy dc{-hr * (cs1 - cs) + ae_ * theta_tooth_ / kTwoPi, hr * (sn1 - sn)};
    const Xy v2{v.x_mm - 0.5 * d_ * n_ * ph.s, v.y_mm - 0.5 * d_ * n_ * ph.c};
    p.h_sigma_mm = std::abs(cross(v2, dc)) / std::sqrt(dot(v2, v2));
  }
  {  // kappa_at(th, ph), Eqs. 21-23
    const Xy ur{ph.c, -ph.s}, t{-ph.s, -ph.c};
    p.kappa_rad = std::atan2(dot(v, ur), 0.5 * d_ * n_ + dot(v, t));
  }
  if (p.cutting) p.h_mm = std::max(0.0, std::min(p.h_sigma_mm, p.h_e_mm));
  if (p.h_mm <= 0) p.cutting = false;
  return p;
}

/// The reference of at(): each equation through its helper (kept for the tests).
Pivkin2025::Point Pivkin2025::at_reference(double th) const {
  Point p;
  const Xy v = centre_velocity(th);
  const double lv = norm(v);
  const Xy vh{v.x_mm / lv, v.y_mm / lv};
  const Xy n{-vh.y_mm, vh.x_mm};  // outward normal (left of the clockwise orbit's motion)
  p.h_e_mm = h_e(th);
  p.psi_rad = psi_of(p.h_e_mm);
  // Cutting while the contact faces the feed: the front half of the orbit, wall to wall.
  p.cutting = n.x_mm > 0 && p.h_e_mm > 0;
  // The engaged arc runs from the contact point (direction n, where the chip vanishes on
  // the machined surface) by psi towards the motion; its far edge is where the chip is
  // thickest (f_z sin psi for a straight wall). Tooth 2 is put there at theta (its phase
  // from the direction u: (cos phi, -sin phi) = u), tooth 1 one tooth period later.
  const double cp = std::cos(p.psi_rad), sp = std::sin(p.psi_rad);
  const Xy u{cp * n.x_mm + sp * vh.x_mm, cp * n.y_mm + sp * vh.y_mm};
  const Phase ph{u.x_mm, -u.y_mm};
  p.beta2_rad = std::atan2(ph.s, ph.c) - n_ * th;
  // Eq. 13 is h_t minus h_delta(beta2) - h_delta(beta1), which vanishes identically for
  // equal pitch (h_delta is the centre's move over Theta, whatever beta; test
  // Pivkin2025.EquationsAgainstHandValues): h_Sigma = h_t here.
  p.h_sigma_mm = h_t_at(th, ph);
  p.kappa_rad = kappa_at(th, ph);
  if (p.cutting) p.h_mm = std::max(0.0, std::min(p.h_sigma_mm, p.h_e_mm));
  if (p.h_mm <= 0) p.cutting = false;
  return p;
}

}  // namespace trochomill
