// The chip map's HDF5 file, behind the plugin libtrochomill_hdf5.so (hdf5_plugin.cpp): linked
// into the program, libhdf5 costs every start about 15 ms and 9 MB. The simulation makes the
// rows dense (hdf5.cpp); the plugin writes and reads the file.
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "trochomill/sim.hpp"

namespace trochomill::sim_detail {

// What a chip map file holds besides its per-step rows.
struct MapHeader {
  std::size_t teeth = 0, segments_per_tooth = 0;
  double resolution_mm = 0;
  int steps_per_rev = 0;
  bool complete = true;
  std::vector<double> segment_height_mm;
};

// Rows [first, first + count) of the per-step datasets, dense, row-major.
struct MapBlock {
  std::vector<double> t_s, tip_mm, removed_mm3;
  std::vector<float> h_mm, w_mm, v_mm3;
};

// Steps per block written (and the compressed datasets' chunk rows).
constexpr std::size_t kBlockSteps = 1024;

/// The plugin's functions (hdf5_table()).
struct Hdf5Table {
  /// A new chip map file at `path` for `teeth` teeth and `cols` segments: its datasets empty.
  void* (*open)(const std::filesystem::path& path, std::size_t teeth, std::size_t cols);
  /// Appends a block's rows.
  void (*append)(void* file, const MapBlock& block);
  /// The segment heights and the attributes; the file flushed.
  void (*finish)(void* file, const MapHeader& header);
  /// Closes the file (after finish, or unfinished).
  void (*close)(void* file) noexcept;
  /// Reads a file written by write_chip_map_h5.
  ChipMapData (*read)(const std::filesystem::path& path);
};
inline constexpr const char* kHdf5Symbol = "trochomill_hdf5_table";

}  // namespace trochomill::sim_detail
