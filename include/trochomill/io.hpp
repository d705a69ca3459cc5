// File output helpers shared by the CLI and every writer: outputs are written to a temporary
// file beside the target and renamed, so a failed or interrupted run never leaves a
// half-finished file.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace trochomill {

/// Writes `content` to `path` atomically (temp file in the same directory, then rename).
/// Throws IoError naming the path on failure; the target is then left untouched.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// Reads a whole file. Throws IoError naming the path when it cannot be read.
[[nodiscard]] std::string read_file(const std::filesystem::path& path);

/// A simulation's per-segment chip map, dense (the HDF5 file's layout): step n, tooth k,
/// segment g at h_mm[n * teeth * segments_per_tooth + k * segments_per_tooth + g]; 0 where
/// the segment is not engaged.
struct ChipMapData {
  std::size_t teeth = 0, segments_per_tooth = 0;
  double resolution_mm = 0;
  int steps_per_rev = 0;
  bool complete = true;
  std::vector<double> t_s;                ///< step times (s)
  std::vector<double> tip_mm;             ///< tool tip per step, x y z (mm)
  std::vector<double> removed_mm3;        ///< per step and tooth (mm^3)
  std::vector<float> h_mm;                ///< uncut chip thickness (mm)
  std::vector<float> w_mm;                ///< engaged width along the edge (mm), same layout
  std::vector<float> v_mm3;               ///< removed volume (mm^3), same layout
  std::vector<double> segment_height_mm;  ///< segment centres above the tip (mm)
};

/// Writes the chip map as HDF5 (datasets t_s, tip_mm, removed_mm3, h_mm, w_mm and v_mm3
/// (deflate),
/// segment_height_mm, each with a "unit" attribute; root attributes teeth,
/// segments_per_tooth, resolution_mm, steps_per_rev, complete), atomically. Throws Error.
void write_chip_map_h5(const std::filesystem::path& path, const ChipMapData& m);
/// Reads a file written by write_chip_map_h5. Throws Error.
[[nodiscard]] ChipMapData read_chip_map_h5(const std::filesystem::path& path);

}  // namespace trochomill
