// Settings of the force module (force.hpp): the workpiece material's force model
// (`[material]`, given in the job or taken from the materials library) and `[forces]`
// (src/job/schema.cpp holds the keys, units and ranges).
#pragma once

#include <optional>
#include <string>

namespace trochomill {

/// Force model of `[material]` (docs/models.md section 12).
enum class ForceModel { bergmann, kienzle, linear };

/// `[material]`: the workpiece material's force coefficients. Forces act on the workpiece.
struct Material {
  std::string name;                 ///< library name, when taken from the library
  std::string source;               ///< citation of the coefficients
  std::string notes;                ///< conditions they hold for (tool, speed, coolant...)
  std::optional<ForceModel> model;  ///< absent: no force model in the job
  // Bergmann 2021 Eq. 3 and Kienzle: F = w h^(1 - m) k per direction.
  double k_c = 0;             ///< specific cutting force (N/mm^2), along the cutting direction
  double k_n = 0;             ///< specific normal force (N/mm^2), along the contour normal
  double m = 0;               ///< exponent of h (dimensionless, 0 <= m < 1)
  std::optional<double> m_n;  ///< Kienzle: exponent of the normal force (default m)
  double k_a = 0;             ///< Kienzle: specific force up the edge (N/mm^2)
  std::optional<double> m_a;  ///< Kienzle: its exponent (default m)
  // Linear edge-force model: F = w (K_c h + K_e) per direction.
  double k_tc = 0, k_rc = 0, k_ac = 0;  ///< cutting coefficients (N/mm^2)
  double k_te = 0, k_re = 0, k_ae = 0;  ///< edge coefficients (N/mm)
};

/// `[forces]`: settings of `trochomill forces` and `calibrate`.
struct ForceSettings {
  int fast_steps_per_rev = 96;      ///< fast chip source: time steps per revolution
  double ploughing_angle_deg = 80;  ///< zeta: sub-segments steeper than this to v_c plough (deg)
};

}  // namespace trochomill
