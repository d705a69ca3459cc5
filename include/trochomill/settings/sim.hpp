// Settings of the tri-dexel simulation (sim.hpp) and of the cutter's edge grid (cutter.hpp):
// `[simulation]` in the job (src/job/schema.cpp holds the keys, units and ranges).
#pragma once

namespace trochomill {

struct SimSettings {
  double resolution_mm = 0.01;      ///< dexel spacing (mm)
  int steps_per_rev = 600;          ///< time steps per spindle revolution
  double chip_sampling_mm = 0.001;  ///< sampling of removed intervals into points (mm)
  double segment_mm = 0.05;         ///< edge segment length along the edge, kappa (mm)
  int sub_segments = 5;             ///< sub-segments inward (tau), for wear topography
  int threads = 0;                  ///< worker threads (0: all cores)
  /// Search each wedge's whole sector, not only the annulus where material can be, and every
  /// ray, not only where the boards' summaries show material (slow; to check both arguments
  /// of docs/models.md section 11). Not a job key.
  bool exhaustive = false;
};

}  // namespace trochomill
