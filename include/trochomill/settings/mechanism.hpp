// Settings of the mechanism module (mechanism.hpp): Pivkin 2025's zone thresholds, the chip
// model and the recommendation's share; `[mechanism]` and `[material] friction_angle` in the
// job (src/job/schema.cpp holds their keys, units and ranges).
#pragma once

namespace trochomill {

enum class ChipModel {
  exact,       ///< chip between the tool circle, the previous tooth's circle and the earlier
               ///< cycles' envelopes (semi-closed form; agrees with `analyze`'s kernel)
  pivkin2025,  ///< Pivkin 2025's published model (Eqs. 2-23), class Pivkin2025
};

/// What the recommendation's CZIII share is a share of (docs/models.md section 9).
enum class ShareOf {
  cutting,  ///< the cutting part of the cycle (the time a tooth is in the cut)
  cycle,    ///< the whole cycle, its cooling part included (Pivkin 2025: "more than half of
            ///< the cycle")
};

/// What `recommend` asks of a step (docs/models.md section 9).
enum class Criterion {
  cziii,    ///< at least `share` of the cutting part (or the cycle: share_of) in CZIII
  plunger,  ///< at most `plunger_share` of the first half of the cutting part in CZI (Pivkin
            ///< 2025's plunger criterion: the ploughing zone within 20 % of the first half)
};

/// Mechanism thresholds (percent of r_e) and the recommendation's default share.
struct MechanismThresholds {
  double czi_max_pct = 25;     ///< K_re below this: CZI (ploughing)
  double czii_max_pct = 60;    ///< K_re below this (and >= czi_max): CZII; above: CZIII
  double transition_pct = 40;  ///< marker where the acoustic ratio k_f crosses 1
};

/// `[mechanism]`; the flank wear VB_B is the tool's (`[tool] flank_wear`).
struct MechanismSettings {
  MechanismThresholds thresholds;
  double share = 0.5;  ///< required CZIII share (0..1) of the cutting part or the cycle
  ShareOf share_of = ShareOf::cutting;
  Criterion criterion = Criterion::cziii;
  double plunger_share = 0.2;  ///< largest CZI share (0..1) of the cut's first half (plunger)
  ChipModel model = ChipModel::exact;
  int points = 3600;  ///< theta samples per cycle
  /// `[material] friction_angle` theta_m (degrees) for h_m = r_e (1 - cos theta_m); 0 = not
  /// given.
  double friction_angle_deg = 0;
};

}  // namespace trochomill
