// The simulation's per-segment chip map made dense, and in HDF5 (libhdf5's C API),
// readable with h5py or MATLAB (sim.hpp).
#include <fmt/format.h>
#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {
namespace {

// Why HDF5's last call failed, from its error stack: the system's message where the file
// driver gave one ("File too large", "No space left on device"), else the innermost entry.
std::string hdf5_reason() {
  std::string reason;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned, const H5E_error2_t* e, void* out) -> herr_t {
        auto& r = *static_cast<std::string*>(out);
        if (e->desc == nullptr) return 0;
        const std::string d = e->desc;
        const std::string key = "error message = '";
        const auto k = d.find(key);
        if (k != std::string::npos) {
          const auto end = d.find('\'', k + key.size());
          r = d.substr(k + key.size(),
                       end == std::string::npos ? std::string::npos : end - k - key.size());
          return 1;  // the system's reason: the walk stops
        }
        if (r.empty()) r = d;
        return 0;
      },
      &reason);
  return reason;
}

// HDF5 is set up once, before its first call: errors thrown, not printed, and no clean-up
// of its own at exit. A file whose write failed (a full disk, the file size limit) cannot be
// closed (HDF5 keeps it open to flush it), and HDF5's exit handler then crashed flushing it
// again after the temporary file was gone; the files that were written are closed by their
// handles before that.
// HDF5's error reporting is per thread (a thread-safe build): each thread that writes turns
// the printing off for itself.
void init_hdf5() {
  static const bool once = [] {
    H5dont_atexit();
    return true;
  }();
  (void)once;
  thread_local const bool quiet = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)quiet;
}

// Closes an HDF5 handle when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t), const char* what) : id_(id), close_(close) {
    if (id_ < 0) {
      const std::string why = hdf5_reason();
      throw IoError(why.empty() ? fmt::format("HDF5: cannot create {}", what)
                                : fmt::format("HDF5: cannot create {}: {}", what, why));
    }
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  operator hid_t() const noexcept { return id_; }  // NOLINT: a handle is used as its id

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

void check(herr_t status, const char* what) {
  if (status < 0) {
    const std::string why = hdf5_reason();
    throw IoError(why.empty() ? fmt::format("HDF5: cannot write {}", what)
                              : fmt::format("HDF5: cannot write {}: {}", what, why));
  }
}

void write_attr(hid_t obj, const char* name, double v) {
  Handle space(H5Screate(H5S_SCALAR), H5Sclose, "an attribute space");
  Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
              name);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &v), name);
}

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

// A dataset whose rows (along the first dimension; `width` the others) are appended block by
// block: extendible, chunked `kBlockSteps` rows at a time, deflated when `compress`.
class RowDataset {
 public:
  RowDataset(hid_t file, const char* name, hid_t mem_type, hid_t file_type,
             std::vector<hsize_t> width, const char* unit, bool compress)
      : name_(name),
        mem_type_(mem_type),
        width_(std::move(width)),
        set_(create(file, name, file_type, width_, compress), H5Dclose, name) {
    Handle str(H5Tcopy(H5T_C_S1), H5Tclose, "a string type");
    const std::string u = unit;
    check(H5Tset_size(str, u.size() + 1), name);
    Handle aspace(H5Screate(H5S_SCALAR), H5Sclose, "an attribute space");
    Handle attr(H5Acreate2(set_, "unit", str, aspace, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "unit");
    check(H5Awrite(attr, str, u.c_str()), name);
  }
  RowDataset(const RowDataset&) = delete;
  RowDataset& operator=(const RowDataset&) = delete;
  ~RowDataset() = default;
  // Appends `count` rows from `data` (row-major).
  void append(hsize_t count, const void* data) {
    if (count == 0) return;
    init_hdf5();  // this thread's errors thrown, not printed
    std::vector<hsize_t> start(width_.size() + 1, 0), size{count}, dims{rows_ + count};
    start[0] = rows_;
    size.insert(size.end(), width_.begin(), width_.end());
    dims.insert(dims.end(), width_.begin(), width_.end());
    check(H5Dset_extent(set_, dims.data()), name_);
    Handle file_space(H5Dget_space(set_), H5Sclose, name_);
    check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start.data(), nullptr, size.data(),
                              nullptr),
          name_);
    Handle mem_space(H5Screate_simple(static_cast<int>(size.size()), size.data(), nullptr),
                     H5Sclose, "a dataspace");
    check(H5Dwrite(set_, mem_type_, mem_space, file_space, H5P_DEFAULT, data), name_);
    rows_ += count;
  }

 private:
  // The dataset (its id, or -1): no rows yet, up to any number.
  static hid_t create(hid_t file, const char* name, hid_t file_type,
                      const std::vector<hsize_t>& width, bool compress) {
    std::vector<hsize_t> dims{0}, max{H5S_UNLIMITED}, chunk{kBlockSteps};
    for (const hsize_t w : width) {
      dims.push_back(w), max.push_back(w), chunk.push_back(std::max<hsize_t>(w, 1));
    }
    Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), max.data()), H5Sclose,
                 "a dataspace");
    Handle props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "dataset properties");
    // No modification times in the object headers: the same simulation writes the same bytes.
    check(H5Pset_obj_track_times(props, false), name);
    check(H5Pset_chunk(props, static_cast<int>(chunk.size()), chunk.data()), name);
    if (compress) check(H5Pset_deflate(props, 4), name);
    return H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, props, H5P_DEFAULT);
  }

  const char* name_;
  hid_t mem_type_;
  std::vector<hsize_t> width_;
  hsize_t rows_ = 0;
  Handle set_;
};

// Opens a new HDF5 file at `path` (its id, or -1); HDF5's errors are thrown, not printed.
hid_t create_file(const std::filesystem::path& path) {
  init_hdf5();
  return H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
}

// A chip map file being written: its per-step datasets, appended a block at a time, then the
// segment heights and the attributes.
class MapFile {
 public:
  MapFile(const std::filesystem::path& path, std::size_t teeth, std::size_t cols)
      : teeth_(teeth),
        cols_(cols),
        file_(create_file(path), H5Fclose, path.c_str()),
        t_(file_, "t_s", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {}, "s", false),
        tip_(file_, "tip_mm", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {3}, "mm", false),
        removed_(file_, "removed_mm3", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {teeth}, "mm^3", false),
        h_(file_, "h_mm", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {cols}, "mm", true),
        w_(file_, "w_mm", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {cols}, "mm", true),
        v_(file_, "v_mm3", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {cols}, "mm^3", true) {}
  // Appends the block's rows.
  void append(const MapBlock& b) {
    const std::size_t count = b.t_s.size();
    if (b.tip_mm.size() != 3 * count || b.removed_mm3.size() != count * teeth_ ||
        b.h_mm.size() != count * cols_ || b.w_mm.size() != count * cols_ ||
        b.v_mm3.size() != count * cols_) {
      throw Error("write_chip_map_h5: inconsistent chip map block sizes");
    }
    t_.append(count, b.t_s.data());
    tip_.append(count, b.tip_mm.data());
    removed_.append(count, b.removed_mm3.data());
    h_.append(count, b.h_mm.data());
    w_.append(count, b.w_mm.data());
    v_.append(count, b.v_mm3.data());
  }
  // The segment heights and the attributes, and the file flushed.
  void finish(const MapHeader& m) {
    init_hdf5();
    RowDataset heights(file_, "segment_height_mm", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {}, "mm",
                       false);
    heights.append(m.segment_height_mm.size(), m.segment_height_mm.data());
    write_attr(file_, "teeth", static_cast<double>(m.teeth));
    write_attr(file_, "segments_per_tooth", static_cast<double>(m.segments_per_tooth));
    write_attr(file_, "resolution_mm", m.resolution_mm);
    write_attr(file_, "steps_per_rev", static_cast<double>(m.steps_per_rev));
    write_attr(file_, "complete", m.complete ? 1.0 : 0.0);
    check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "the file");
  }

 private:
  std::size_t teeth_, cols_;
  Handle file_;  // closed after the datasets (members are destroyed in reverse order)
  RowDataset t_, tip_, removed_, h_, w_, v_;
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

ChipMapData read_chip_map_h5(const std::filesystem::path& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  init_hdf5();
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, path.c_str());
  ChipMapData m;
  auto dims_of = [&](const char* name) {
    Handle set(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose, name);
    Handle space(H5Dget_space(set), H5Sclose, name);
    const int rank = H5Sget_simple_extent_ndims(space);
    std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(rank, 0)));
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    return dims;
  };
  auto read = [&](const char* name, hid_t type, void* out) {
    Handle set(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose, name);
    check(H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out), name);
  };
  auto attr = [&](const char* name) {
    Handle a(H5Aopen(file, name, H5P_DEFAULT), H5Aclose, name);
    double v = 0;
    check(H5Aread(a, H5T_NATIVE_DOUBLE, &v), name);
    return v;
  };
  const auto hd = dims_of("h_mm");
  if (hd.size() != 2) throw Error(fmt::format("{}: h_mm is not two-dimensional", path.string()));
  m.teeth = static_cast<std::size_t>(attr("teeth"));
  m.segments_per_tooth = static_cast<std::size_t>(attr("segments_per_tooth"));
  m.resolution_mm = attr("resolution_mm");
  m.steps_per_rev = static_cast<int>(attr("steps_per_rev"));
  m.complete = attr("complete") != 0;
  const std::size_t steps = hd[0];
  m.t_s.resize(steps);
  m.tip_mm.resize(3 * steps);
  m.removed_mm3.resize(steps * m.teeth);
  m.h_mm.resize(steps * hd[1]);
  m.w_mm.resize(steps * hd[1]);
  m.v_mm3.resize(steps * hd[1]);
  m.segment_height_mm.resize(dims_of("segment_height_mm")[0]);
  if (steps > 0) {
    read("t_s", H5T_NATIVE_DOUBLE, m.t_s.data());
    read("tip_mm", H5T_NATIVE_DOUBLE, m.tip_mm.data());
    read("removed_mm3", H5T_NATIVE_DOUBLE, m.removed_mm3.data());
    read("h_mm", H5T_NATIVE_FLOAT, m.h_mm.data());
    read("w_mm", H5T_NATIVE_FLOAT, m.w_mm.data());
    read("v_mm3", H5T_NATIVE_FLOAT, m.v_mm3.data());
  }
  if (!m.segment_height_mm.empty()) {
    read("segment_height_mm", H5T_NATIVE_DOUBLE, m.segment_height_mm.data());
  }
  return m;
}

}  // namespace trochomill
