// The plugin libtrochomill_hdf5.so (chip_map_h5.hpp): the chip map's HDF5 file through
// libhdf5's C API, readable with h5py or MATLAB.
#include <fmt/format.h>
#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "chip_map_h5.hpp"
#include "trochomill/error.hpp"

namespace trochomill::sim_detail {
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
// HDF5's error reporting is per thread (a thread-safe build): the printing is turned off
// before each use, on the thread that uses it (a pointer set: no thread_local here, whose
// dynamic TLS in a loaded plugin crashed LeakSanitizer's scan at exit under clang 14).
void init_hdf5() {
  static const bool once = [] {
    H5dont_atexit();
    return true;
  }();
  (void)once;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
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

ChipMapData read_file(const std::filesystem::path& path) {
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

void* open_file(const std::filesystem::path& path, std::size_t teeth, std::size_t cols) {
  return new MapFile(path, teeth, cols);
}
void append_block(void* file, const MapBlock& block) { static_cast<MapFile*>(file)->append(block); }
void finish_file(void* file, const MapHeader& header) {
  static_cast<MapFile*>(file)->finish(header);
}
void close_file(void* file) noexcept { delete static_cast<MapFile*>(file); }

const Hdf5Table kTable{&open_file, &append_block, &finish_file, &close_file, &read_file};

}  // namespace
}  // namespace trochomill::sim_detail

extern "C" __attribute__((visibility("default"))) const trochomill::sim_detail::Hdf5Table*
trochomill_hdf5_table() {
  return &trochomill::sim_detail::kTable;
}
