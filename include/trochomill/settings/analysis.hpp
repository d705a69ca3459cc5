// Settings of the analysis module (analysis.hpp), owned here and aggregated by the job
// (`[analysis]` and `[measured]`; the keys, units and ranges are in src/job/schema.cpp).
#pragma once

#include <optional>

namespace trochomill {

/// `[analysis]`: resolution of `trochomill analyze`.
struct AnalysisSettings {
  int steps_per_tooth = 1;  ///< engagement samples per tooth pass (1..64)
  int imprint_points = 81;  ///< points across the slot width for the bottom imprint density
};

/// `[measured]`: results measured on the machine (or filled by a model); each optional.
struct Measured {
  std::optional<double> force_max_n;      ///< maximum resultant cutting force F_R,max (N)
  std::optional<double> roughness_ra_um;  ///< maximum roughness Ra of the slot (micrometres)
  std::optional<double> waviness_um;      ///< maximum wall waviness W_max (micrometres)
};

}  // namespace trochomill
