// Settings of the topography module (topography.hpp): the digitised (or synthetic) wear
// states of the cutting edge, `[topography]` in the job (src/job/schema.cpp holds the keys).
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

namespace trochomill {

struct TopographySettings {
  std::vector<std::filesystem::path> files;  ///< STL/PLY/OBJ meshes, one per wear state
  std::vector<double> synthetic_vb_mm;       ///< or synthetic inserts, one per flank wear VB (mm)
  int state = 0;                             ///< the wear state used (index)
  double band_mm = 0.2;                      ///< band along the edge that is sampled (mm)
  double rake_deg = 0;                       ///< synthetic insert: rake angle (degrees)
  double clearance_deg = 7;                  ///< synthetic insert: clearance angle (degrees)
  [[nodiscard]] std::size_t states() const noexcept {
    return files.empty() ? synthetic_vb_mm.size() : files.size();
  }
};

}  // namespace trochomill
