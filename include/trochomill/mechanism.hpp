// Cutting mechanism over a trochoid cycle (Pivkin 2025 Sections 2-3; docs/models.md section 9): the
// uncut chip thickness h_e(theta) at the contact, the ratio K_re = h_e / r_e that classifies the
// mechanism (CZI ploughing, CZII mixed shear, CZIII cutting), contact angle, teeth in
// contact, kinematic rake angle and kinematic angle change, the wear-corrected K_re, and
// the smallest trochoid step (or feed per tooth) that puts a chosen share of the cutting
// part of the cycle in CZIII.
//
// Frame: ours (the slot along +Y); the cycle is the family's curve
// c(theta) = (-a cos theta, b sin theta + s theta / 2 pi), theta in [0, 2 pi) from the left
// wall (Pivkin's frame feeds along +X; the geometry is the same rotated). Steady state of
// an endless slot: the previous cycle is c(theta) - (0, s).
#pragma once

#include <string>
#include <vector>

#include "trochomill/job.hpp"
#include "trochomill/settings/mechanism.hpp"

namespace trochomill {

/// Pivkin 2025's published chip model, equation by equation (docs/models.md section 9 gives
/// our reading of each garbled equation). In the paper's frame: feed along +X, the tool
/// centre C(theta) = (-(D_t/2) cos theta + a_e theta / 2 pi, (D_t/2) sin theta) on an orbit
/// of diameter D_t (ours: 2a = W - D) advancing a_e (ours: the step s) per cycle, theta in
/// radians (theta_P = theta_ours + pi/2); tooth k at C + (D/2)(cos phi, -sin phi), phi =
/// beta_k + N theta (a clockwise spindle). Lengths in mm, angles in radians.
class Pivkin2025 {
 public:
  struct Xy {
    double x_mm = 0, y_mm = 0;
  };
  /// The model's result at one theta: the chip at the tooth on the engaged arc's far edge.
  struct Point {
    bool cutting = false;   ///< the contact faces the feed (theta_P in (pi/2, 3 pi/2))
    double h_mm = 0;        ///< chip thickness min(h_Sigma, h_e) (Fig. 4: h_e restricts h)
    double h_sigma_mm = 0;  ///< Eq. 13 at that tooth
    double h_e_mm = 0;      ///< Eq. 17, the layer between cycles
    double psi_rad = 0;     ///< Eq. 18
    double kappa_rad = 0;   ///< Eqs. 21-23 at that tooth
    double beta2_rad = 0;   ///< tooth 2's initial angle that puts it there at theta
  };
  /// Throws InputError unless every argument is positive (and a_e < pi D_t, so the orbit
  /// loops).
  Pivkin2025(double orbit_diameter_mm, double step_mm, double tool_diameter_mm,
             double feed_per_tooth_mm, int teeth);

  [[nodiscard]] double n_spindle() const { return n_; }                  ///< Eq. 6: N (rad per rad)
  [[nodiscard]] double tooth_angle_rad() const { return theta_tooth_; }  ///< Eq. 11: Theta
  [[nodiscard]] Xy centre(double theta) const;
  [[nodiscard]] Xy centre_velocity(double theta) const;              ///< dC/dtheta (mm/rad)
  [[nodiscard]] Xy tooth(double theta, double beta) const;           ///< Eqs. 2-5
  [[nodiscard]] Xy tooth_velocity(double theta, double beta) const;  ///< d/dtheta (mm/rad)
  [[nodiscard]] double a_t(double theta, double beta2) const;        ///< Eq. 8: tangent slope
  [[nodiscard]] double c_t(double theta, double beta2) const;        ///< Eq. 9: intercept (mm)
  /// Eq. 10: |F_Z1(theta + Theta) - F_Z2(theta)|, beta2 = beta1 + 2 pi / Z (mm).
  [[nodiscard]] double h_delta(double theta, double beta1) const;
  /// Eq. 12: distance from tooth 1 at theta + Theta to the tangent of tooth 2's path at
  /// theta (beta1 = beta2 - 2 pi / Z), written as |A x - y + C| / sqrt(A^2 + 1) (mm).
  [[nodiscard]] double h_t(double theta, double beta2) const;
  /// Eq. 13: h_t - (h_delta(beta2) - h_delta(beta1)) (mm); see docs/models.md on the
  /// printed trailing factor.
  [[nodiscard]] double h_sigma(double theta, double beta2) const;
  [[nodiscard]] Xy envelope(double theta) const;  ///< Eqs. 14-15, the outer side
  /// Eqs. 16-17: distance from the next cycle's envelope point (theta + 2 pi) to this one's
  /// tangent: the radial depth of the layer between cycles (mm).
  [[nodiscard]] double h_e(double theta) const;
  [[nodiscard]] double psi(double theta) const;  ///< Eq. 18: acos((D/2 - h_e) / (D/2))
  /// Eqs. 21-23: the angle from the tooth's rotation tangent to its trajectory's tangent,
  /// positive where the feed drives the edge into the material.
  [[nodiscard]] double kappa(double theta, double beta2) const;
  [[nodiscard]] Point at(double theta) const;
  /// at() through the helpers above, one equation at a time (at() shares their sines and
  /// norms; the two agree to rounding).
  [[nodiscard]] Point at_reference(double theta) const;

 private:
  struct Phase {
    double c, s;  ///< cos and sin of a tooth's angle phi = beta + N theta
  };
  [[nodiscard]] Phase phase(double theta, double beta) const;
  [[nodiscard]] Xy tooth_at(double theta, Phase ph) const;
  [[nodiscard]] Xy tooth_velocity_at(double theta, Phase ph) const;
  [[nodiscard]] double h_t_at(double theta, Phase ph) const;
  [[nodiscard]] double kappa_at(double theta, Phase ph) const;
  [[nodiscard]] double psi_of(double h_e_mm) const;
  double dt_, ae_, d_, fz_;
  int z_;
  double n_, theta_tooth_, cos_tooth_ = 1, sin_tooth_ = 0;
};

/// The settings (MechanismSettings, settings/mechanism.hpp) are the job's `[mechanism]`
/// (job.mechanism); a caller may pass changed copies (a share, a model). The flank wear VB_B
/// is the job's `[tool] flank_wear`.
/// The curves over one cycle, structure of arrays (one entry per theta sample).
struct MechanismCurve {
  ChipModel model = ChipModel::exact;
  double edge_radius_mm = 0;
  double cycle_time_s = 0;
  std::vector<double> theta_rad;         ///< trochoid angle
  std::vector<double> t_s;               ///< time from the cycle's start (theta = 0)
  std::vector<double> h_mm;              ///< uncut chip thickness h_e (0 when not cutting)
  std::vector<double> psi_rad;           ///< contact (engagement) angle
  std::vector<double> teeth_in_contact;  ///< Z_c = psi Z / 2 pi
  std::vector<double> gamma_k_rad;       ///< kinematic rake angle (negative below r_e)
  std::vector<double> kappa_rad;         ///< kinematic angle change
  std::vector<double> k_re_pct;          ///< 100 h / r_e
  std::vector<double> k_re_wear_pct;     ///< 100 (h + VB tan kappa) / r_e where kappa > 0
  std::vector<int> zone;                 ///< 0 not cutting, 1 CZI, 2 CZII, 3 CZIII
};

/// Zone shares of the cutting part of the cycle (by time; they sum to 1) and of the whole
/// cycle (they sum to the cutting part's share of the cycle), and where each zone starts and
/// ends (s from the cycle's start of cutting; -1 when the zone is absent).
struct ZoneSummary {
  double share[3] = {0, 0, 0};        ///< CZI, CZII, CZIII, of the cutting part
  double cycle_share[3] = {0, 0, 0};  ///< the same of the whole cycle
  double start_s[3] = {-1, -1, -1};
  double end_s[3] = {-1, -1, -1};
  double cutting_time_s = 0;
  double cutting_start_s = 0;  ///< from theta = 0
  double cutting_span_s = 0;   ///< from the cut's start to its end, pauses included
  double transition_s = -1;    ///< first time K_re crosses the transition marker
  double h_max_mm = 0;
  double h_m_mm = 0;  ///< minimum undeformed chip thickness r_e (1 - cos theta_m)
  /// CZI's share of the first half of the cutting part (the span from the cut's start to its
  /// end, pauses included, halved): Pivkin 2025's plunger criterion, the up-cut half.
  double plunger_first_half_share = 0;
};

/// The chip curves for a trochoidal or elliptical job (InputError for other families or
/// bad settings). `use_wear` classifies zones with the wear-corrected K_re.
[[nodiscard]] MechanismCurve mechanism_curve(const Job& job, const MechanismSettings& settings,
                                             bool use_wear = false);
/// The same curves at given trochoid angles (rad, any order; t_s is the time from theta = 0
/// along the cycle, by Simpson's rule on the path speed).
[[nodiscard]] MechanismCurve mechanism_curve_at(const Job& job, const MechanismSettings& settings,
                                                const std::vector<double>& theta_rad,
                                                bool use_wear = false);
[[nodiscard]] ZoneSummary summarize_zones(const MechanismCurve& c,
                                          const MechanismSettings& settings, bool use_wear);

/// Recommendation: the smallest step (mm) for which at least `share` of the cutting part (or
/// of the cycle: `share_of`) is in CZIII, or with criterion = plunger at most `plunger_share`
/// of the cut's first half is in CZI (or, with `for_feed`, the smallest feed per tooth at the
/// job's step).
struct Recommendation {
  bool found = false;
  double value = 0;   ///< min_step_mm or min_feed_per_tooth_mm
  ZoneSummary zones;  ///< at that value
  std::string explanation;
};
[[nodiscard]] Recommendation recommend(const Job& job, const MechanismSettings& settings,
                                       bool use_wear, bool for_feed);

}  // namespace trochomill
