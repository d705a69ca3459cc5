// The simulation's per-segment chip map made dense, and its HDF5 file (sim.hpp), written and
// read by the plugin libtrochomill_hdf5.so (chip_map_h5.hpp), loaded when a map is written.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "chip_map_h5.hpp"
#include "trochomill/common/plugin.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {
namespace {

using sim_detail::kBlockSteps;
using sim_detail::MapBlock;
using sim_detail::MapHeader;

const sim_detail::Hdf5Table& hdf5() {
  return plugin_table<sim_detail::Hdf5Table>("hdf5", sim_detail::kHdf5Symbol,
                                             "the chip map's file (HDF5)");
}

// A chip map file being written (the plugin's), closed when it goes out of scope.
class MapFile {
 public:
  MapFile(const std::filesystem::path& path, std::size_t teeth, std::size_t cols)
      : api_(hdf5()), file_(api_.open(path, teeth, cols)) {}
  MapFile(const MapFile&) = delete;
  MapFile& operator=(const MapFile&) = delete;
  ~MapFile() { api_.close(file_); }
  void append(const MapBlock& b) { api_.append(file_, b); }
  void finish(const MapHeader& h) { api_.finish(file_, h); }

 private:
  const sim_detail::Hdf5Table& api_;
  void* file_;
};

// A chip map header for `tool` and the settings (no steps counted).
MapHeader header_of(const SimTool& tool, const SimSettings& s) {
  MapHeader h;
  h.teeth = tool.tooth_angle_rad.size();
  h.segments_per_tooth = static_cast<std::size_t>(tool.segments());
  h.resolution_mm = s.resolution_mm;
  h.steps_per_rev = s.steps_per_rev;
  h.segment_height_mm = segment_heights_mm(tool, h.segments_per_tooth);
  return h;
}

// Appends a step's dense row to `b`: its time, tip and removed volumes, and the h, w and v of
// every segment (0 where not engaged).
void add_row(MapBlock& b, const MapHeader& h, const SimStep& st, std::span<const ChipEntry> chips) {
  const std::size_t cols = h.teeth * h.segments_per_tooth;
  b.t_s.push_back(st.t_s);
  b.tip_mm.insert(b.tip_mm.end(), st.tip_mm.begin(), st.tip_mm.end());
  for (std::size_t k = 0; k < h.teeth; ++k) {
    b.removed_mm3.push_back(k < st.removed_mm3.size() ? st.removed_mm3[k] : 0.0);
  }
  const std::size_t row = b.h_mm.size();
  b.h_mm.resize(row + cols, 0.0f);
  b.w_mm.resize(row + cols, 0.0f);
  b.v_mm3.resize(row + cols, 0.0f);
  for (const ChipEntry& c : chips) {
    if (c.segment >= cols) {
      throw Error(fmt::format("chip map: segment {} of {}", c.segment, cols));
    }
    b.h_mm[row + c.segment] = c.h_mm;
    b.w_mm[row + c.segment] = c.w_mm;
    b.v_mm3[row + c.segment] = c.v_mm3;
  }
}

void clear(MapBlock& b) {
  b.t_s.clear(), b.tip_mm.clear(), b.removed_mm3.clear();
  b.h_mm.clear(), b.w_mm.clear(), b.v_mm3.clear();
}

}  // namespace

void replay(const SimResult& r, SimSink& sink) {
  std::size_t q = 0;  // the next chip map entry
  for (std::size_t n = 0; n < r.steps.size(); ++n) {
    const std::size_t q0 = q;
    while (q < r.chip_map.size() && r.chip_map[q].step == n) ++q;
    if (q < r.chip_map.size() && r.chip_map[q].step < n) {
      throw Error("chip map: the entries are not in step order");
    }
    sink.take(r.steps[n], std::span<const ChipEntry>(r.chip_map).subspan(q0, q - q0));
  }
  if (q < r.chip_map.size()) {
    throw Error(fmt::format("chip map: an entry of step {} beyond the {} steps", r.chip_map[q].step,
                            r.steps.size()));
  }
}

struct ChipMapWriter::File {
  File(const std::filesystem::path& path_, const SimTool& tool, const SimSettings& s)
      : path(path_),
        header(header_of(tool, s)),
        map(path_, header.teeth, header.teeth * header.segments_per_tooth),
        pending(path_) {}
  std::filesystem::path path;
  MapHeader header;
  MapFile map;
  PendingFile pending;  // removed if the process is stopped while it is written
  MapBlock block;
};

namespace {
// A failed write names the file: "cannot write 'chips.h5': HDF5: cannot write h_mm: File too
// large".
template <class F>
void naming(const std::filesystem::path& path, F&& f) {
  try {
    f();
  } catch (const IoError& e) {
    throw IoError(fmt::format("cannot write '{}': {}", path.string(), e.what()));
  }
}
}  // namespace

ChipMapWriter::ChipMapWriter(const std::filesystem::path& path, const SimTool& tool,
                             const SimSettings& s) {
  naming(path, [&] { file_ = std::make_unique<File>(path, tool, s); });
}

ChipMapWriter::~ChipMapWriter() = default;

void ChipMapWriter::take(const SimStep& step, std::span<const ChipEntry> chips) {
  if (!file_) throw Error("ChipMapWriter: a step after finish");
  add_row(file_->block, file_->header, step, chips);
  if (file_->block.t_s.size() == kBlockSteps) {
    naming(file_->path, [&] { file_->map.append(file_->block); });
    clear(file_->block);
  }
}

void ChipMapWriter::finish(bool complete) {
  if (!file_) throw Error("ChipMapWriter: finished twice");
  naming(file_->path, [&] {
    file_->map.append(file_->block);
    file_->header.complete = complete;
    file_->map.finish(file_->header);
  });
  file_.reset();
}

void write_chip_map_h5(const std::filesystem::path& path, const ChipMapData& m) {
  const std::size_t steps = m.t_s.size();
  const std::size_t cols = m.teeth * m.segments_per_tooth;
  if (m.h_mm.size() != steps * cols || m.w_mm.size() != steps * cols ||
      m.v_mm3.size() != steps * cols || m.tip_mm.size() != 3 * steps ||
      m.removed_mm3.size() != steps * m.teeth) {
    throw Error("write_chip_map_h5: inconsistent chip map sizes");
  }
  const MapHeader header{m.teeth,         m.segments_per_tooth, m.resolution_mm,
                         m.steps_per_rev, m.complete,           m.segment_height_mm};
  write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    MapFile file(tmp, m.teeth, cols);
    MapBlock b;
    for (std::size_t first = 0; first < steps; first += kBlockSteps) {
      const std::size_t count = std::min(kBlockSteps, steps - first);
      auto rows = [&](const auto& all, std::size_t width, auto& out) {
        out.assign(all.begin() + static_cast<std::ptrdiff_t>(first * width),
                   all.begin() + static_cast<std::ptrdiff_t>((first + count) * width));
      };
      rows(m.t_s, 1, b.t_s);
      rows(m.tip_mm, 3, b.tip_mm);
      rows(m.removed_mm3, m.teeth, b.removed_mm3);
      rows(m.h_mm, cols, b.h_mm);
      rows(m.w_mm, cols, b.w_mm);
      rows(m.v_mm3, cols, b.v_mm3);
      file.append(b);
    }
    file.finish(header);
  });
}

void write_chip_map_h5(const std::filesystem::path& path, const SimResult& r, const SimTool& tool,
                       const SimSettings& s) {
  write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    ChipMapWriter writer(tmp, tool, s);
    replay(r, writer);
    writer.finish(r.complete);
  });
}

ChipMapData chip_map_data(const SimResult& r, const SimTool& tool, const SimSettings& s) {
  // The whole run as one block.
  struct Rows final : SimSink {
    explicit Rows(MapHeader h) : header(std::move(h)) {}
    void take(const SimStep& step, std::span<const ChipEntry> chips) override {
      add_row(block, header, step, chips);
    }
    MapHeader header;
    MapBlock block;
  } rows(header_of(tool, s));
  replay(r, rows);
  ChipMapData m;
  m.teeth = rows.header.teeth;
  m.segments_per_tooth = rows.header.segments_per_tooth;
  m.resolution_mm = rows.header.resolution_mm;
  m.steps_per_rev = rows.header.steps_per_rev;
  m.complete = r.complete;
  m.t_s = std::move(rows.block.t_s);
  m.tip_mm = std::move(rows.block.tip_mm);
  m.removed_mm3 = std::move(rows.block.removed_mm3);
  m.h_mm = std::move(rows.block.h_mm);
  m.w_mm = std::move(rows.block.w_mm);
  m.v_mm3 = std::move(rows.block.v_mm3);
  m.segment_height_mm = std::move(rows.header.segment_height_mm);
  return m;
}

std::vector<double> segment_heights_mm(const SimTool& tool, std::size_t segments) {
  std::vector<double> h;
  h.reserve(segments);
  for (std::size_t g = 0; g < segments; ++g) {
    h.push_back(tool.height_at_length((static_cast<double>(g) + 0.5) * tool.segment_mm));
  }
  return h;
}

ChipMapData read_chip_map_h5(const std::filesystem::path& path) { return hdf5().read(path); }

}  // namespace trochomill
