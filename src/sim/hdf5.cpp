// The simulation's per-segment chip map made dense, and in HDF5 (libhdf5's C API),
// readable with h5py or MATLAB (sim.hpp).
#include <fmt/format.h>
#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {
namespace {

// Closes an HDF5 handle when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t), const char* what) : id_(id), close_(close) {
    if (id_ < 0) throw Error(fmt::format("HDF5: cannot create {}", what));
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
  if (status < 0) throw Error(fmt::format("HDF5: cannot write {}", what));
}

void write_attr(hid_t obj, const char* name, double v) {
  Handle space(H5Screate(H5S_SCALAR), H5Sclose, "an attribute space");
  Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
              name);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &v), name);
}

// What a chip map file holds besides its per-step rows.
struct MapHeader {
  std::size_t steps = 0, teeth = 0, segments_per_tooth = 0;
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

// A dataset of `dims` whose rows are written block by block (rows along the first dimension).
class RowDataset {
 public:
  RowDataset(hid_t file, const char* name, hid_t mem_type, hid_t file_type,
             std::vector<hsize_t> dims, const char* unit, bool compress)
      : name_(name),
        mem_type_(mem_type),
        dims_(std::move(dims)),
        set_(create(file, name, file_type, dims_, compress), H5Dclose, name) {
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
  // Writes rows [first, first + count) from `data` (count rows of the other dimensions).
  void write_rows(hsize_t first, hsize_t count, const void* data) {
    if (count == 0) return;
    std::vector<hsize_t> start(dims_.size(), 0), size = dims_;
    start[0] = first;
    size[0] = count;
    Handle file_space(H5Dget_space(set_), H5Sclose, name_);
    check(H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start.data(), nullptr, size.data(),
                              nullptr),
          name_);
    Handle mem_space(H5Screate_simple(static_cast<int>(size.size()), size.data(), nullptr),
                     H5Sclose, "a dataspace");
    check(H5Dwrite(set_, mem_type_, mem_space, file_space, H5P_DEFAULT, data), name_);
  }

 private:
  // The dataset (its id, or -1), chunked and deflated when `compress` and not empty.
  static hid_t create(hid_t file, const char* name, hid_t file_type,
                      const std::vector<hsize_t>& dims, bool compress) {
    Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose,
                 "a dataspace");
    Handle props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "dataset properties");
    // No modification times in the object headers: the same simulation writes the same bytes.
    check(H5Pset_obj_track_times(props, false), name);
    bool empty = false;
    for (const hsize_t d : dims) empty = empty || d == 0;
    if (compress && !empty) {
      std::vector<hsize_t> chunk = dims;
      chunk[0] = std::min<hsize_t>(dims[0], kBlockSteps);
      check(H5Pset_chunk(props, static_cast<int>(chunk.size()), chunk.data()), name);
      check(H5Pset_deflate(props, 4), name);
    }
    return H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, props, H5P_DEFAULT);
  }

  const char* name_;
  hid_t mem_type_;
  std::vector<hsize_t> dims_;
  Handle set_;
};

// Writes a chip map file atomically, its per-step rows `kBlockSteps` at a time from
// fill(first, count, block), which sizes and fills the block's arrays.
void write_map(const std::filesystem::path& path, const MapHeader& m,
               const std::function<void(std::size_t, std::size_t, MapBlock&)>& fill) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported by exceptions
  const std::size_t cols = m.teeth * m.segments_per_tooth;
  // Written beside the target and renamed into place: never a half-written file.
  write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    Handle file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose,
                tmp.c_str());
    const hsize_t n = m.steps;
    {
      RowDataset t(file, "t_s", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n}, "s", false);
      RowDataset tip(file, "tip_mm", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n, 3}, "mm", false);
      RowDataset removed(file, "removed_mm3", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n, m.teeth},
                         "mm^3", false);
      RowDataset h(file, "h_mm", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {n, cols}, "mm", true);
      RowDataset w(file, "w_mm", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {n, cols}, "mm", true);
      RowDataset v(file, "v_mm3", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {n, cols}, "mm^3", true);
      MapBlock b;
      for (std::size_t first = 0; first < m.steps; first += kBlockSteps) {
        const std::size_t count = std::min(kBlockSteps, m.steps - first);
        fill(first, count, b);
        if (b.t_s.size() != count || b.tip_mm.size() != 3 * count ||
            b.removed_mm3.size() != count * m.teeth || b.h_mm.size() != count * cols ||
            b.w_mm.size() != count * cols || b.v_mm3.size() != count * cols) {
          throw Error("write_chip_map_h5: inconsistent chip map block sizes");
        }
        t.write_rows(first, count, b.t_s.data());
        tip.write_rows(first, count, b.tip_mm.data());
        removed.write_rows(first, count, b.removed_mm3.data());
        h.write_rows(first, count, b.h_mm.data());
        w.write_rows(first, count, b.w_mm.data());
        v.write_rows(first, count, b.v_mm3.data());
      }
      RowDataset heights(file, "segment_height_mm", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE,
                         {m.segment_height_mm.size()}, "mm", false);
      heights.write_rows(0, m.segment_height_mm.size(), m.segment_height_mm.data());
    }
    write_attr(file, "teeth", static_cast<double>(m.teeth));
    write_attr(file, "segments_per_tooth", static_cast<double>(m.segments_per_tooth));
    write_attr(file, "resolution_mm", m.resolution_mm);
    write_attr(file, "steps_per_rev", static_cast<double>(m.steps_per_rev));
    write_attr(file, "complete", m.complete ? 1.0 : 0.0);
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), "the file");
  });
}

// A simulation's chip map header.
MapHeader header_of(const SimResult& r, const SimTool& tool, const SimSettings& s) {
  MapHeader h;
  h.steps = r.steps.size();
  h.teeth = tool.tooth_angle_rad.size();
  h.segments_per_tooth = static_cast<std::size_t>(r.segments_per_tooth);
  h.resolution_mm = s.resolution_mm;
  h.steps_per_rev = s.steps_per_rev;
  h.complete = r.complete;
  h.segment_height_mm = segment_heights_mm(tool, h.segments_per_tooth);
  return h;
}

// Steps [first, first + count) of a simulation made dense into `b`; `q` is the next chip map
// entry (they are in step order), advanced past the block's.
void dense_rows(const SimResult& r, const MapHeader& h, std::size_t first, std::size_t count,
                std::size_t& q, MapBlock& b) {
  const std::size_t cols = h.teeth * h.segments_per_tooth;
  b.t_s.clear();
  b.tip_mm.clear();
  b.removed_mm3.clear();
  for (std::size_t n = first; n < first + count; ++n) {
    const SimStep& st = r.steps[n];
    b.t_s.push_back(st.t_s);
    b.tip_mm.insert(b.tip_mm.end(), st.tip_mm.begin(), st.tip_mm.end());
    for (std::size_t k = 0; k < h.teeth; ++k) {
      b.removed_mm3.push_back(k < st.removed_mm3.size() ? st.removed_mm3[k] : 0.0);
    }
  }
  b.h_mm.assign(count * cols, 0.0f);
  b.w_mm.assign(count * cols, 0.0f);
  b.v_mm3.assign(count * cols, 0.0f);
  for (; q < r.chip_map.size() && r.chip_map[q].step < first + count; ++q) {
    const ChipEntry& c = r.chip_map[q];
    if (c.step < first || c.segment >= cols) {
      throw Error("chip map: the entries are not in step order");
    }
    const std::size_t at = (c.step - first) * cols + c.segment;
    b.h_mm[at] = c.h_mm;
    b.w_mm[at] = c.w_mm;
    b.v_mm3[at] = c.v_mm3;
  }
}

}  // namespace

void write_chip_map_h5(const std::filesystem::path& path, const ChipMapData& m) {
  const std::size_t steps = m.t_s.size();
  const std::size_t cols = m.teeth * m.segments_per_tooth;
  if (m.h_mm.size() != steps * cols || m.w_mm.size() != steps * cols ||
      m.v_mm3.size() != steps * cols || m.tip_mm.size() != 3 * steps ||
      m.removed_mm3.size() != steps * m.teeth) {
    throw Error("write_chip_map_h5: inconsistent chip map sizes");
  }
  const MapHeader header{steps,           m.teeth,    m.segments_per_tooth, m.resolution_mm,
                         m.steps_per_rev, m.complete, m.segment_height_mm};
  write_map(path, header, [&](std::size_t first, std::size_t count, MapBlock& b) {
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
  });
}

void write_chip_map_h5(const std::filesystem::path& path, const SimResult& r, const SimTool& tool,
                       const SimSettings& s) {
  const MapHeader header = header_of(r, tool, s);
  std::size_t q = 0;  // the next chip map entry
  write_map(path, header, [&](std::size_t first, std::size_t count, MapBlock& b) {
    dense_rows(r, header, first, count, q, b);
  });
}

ChipMapData chip_map_data(const SimResult& r, const SimTool& tool, const SimSettings& s) {
  MapHeader header = header_of(r, tool, s);
  MapBlock b;
  std::size_t q = 0;
  dense_rows(r, header, 0, header.steps, q, b);
  ChipMapData m;
  m.teeth = header.teeth;
  m.segments_per_tooth = header.segments_per_tooth;
  m.resolution_mm = header.resolution_mm;
  m.steps_per_rev = header.steps_per_rev;
  m.complete = header.complete;
  m.t_s = std::move(b.t_s);
  m.tip_mm = std::move(b.tip_mm);
  m.removed_mm3 = std::move(b.removed_mm3);
  m.h_mm = std::move(b.h_mm);
  m.w_mm = std::move(b.w_mm);
  m.v_mm3 = std::move(b.v_mm3);
  m.segment_height_mm = std::move(header.segment_height_mm);
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
