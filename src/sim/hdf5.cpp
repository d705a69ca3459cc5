// The simulation's per-segment chip map in HDF5 (libhdf5's C API), readable with h5py or
// MATLAB (sim.hpp).
#include <fmt/format.h>
#include <hdf5.h>

#include <filesystem>
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

void write_dataset(hid_t file, const char* name, hid_t mem_type, hid_t file_type,
                   const std::vector<hsize_t>& dims, const void* data, const char* unit,
                   bool compress = false) {
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose,
               "a dataspace");
  Handle props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "dataset properties");
  // No modification times in the object headers: the same simulation writes the same bytes.
  check(H5Pset_obj_track_times(props, false), name);
  bool empty = false;
  for (const hsize_t d : dims) empty = empty || d == 0;
  if (compress && !empty) {
    std::vector<hsize_t> chunk = dims;
    chunk[0] = std::min<hsize_t>(dims[0], 1024);
    check(H5Pset_chunk(props, static_cast<int>(chunk.size()), chunk.data()), name);
    check(H5Pset_deflate(props, 4), name);
  }
  Handle set(H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, props, H5P_DEFAULT), H5Dclose,
             name);
  if (!empty) check(H5Dwrite(set, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
  Handle str(H5Tcopy(H5T_C_S1), H5Tclose, "a string type");
  const std::string u = unit;
  check(H5Tset_size(str, u.size() + 1), name);
  Handle aspace(H5Screate(H5S_SCALAR), H5Sclose, "an attribute space");
  Handle attr(H5Acreate2(set, "unit", str, aspace, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, "unit");
  check(H5Awrite(attr, str, u.c_str()), name);
}

void write_attr(hid_t obj, const char* name, double v) {
  Handle space(H5Screate(H5S_SCALAR), H5Sclose, "an attribute space");
  Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
              name);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &v), name);
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
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported by exceptions
  // Written beside the target and renamed into place: never a half-written file.
  write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    Handle file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose,
                tmp.c_str());
    const hsize_t n = steps;
    write_dataset(file, "t_s", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n}, m.t_s.data(), "s");
    write_dataset(file, "tip_mm", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n, 3}, m.tip_mm.data(), "mm");
    write_dataset(file, "removed_mm3", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {n, m.teeth},
                  m.removed_mm3.data(), "mm^3");
    write_dataset(file, "h_mm", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {n, cols}, m.h_mm.data(), "mm",
                  true);
    write_dataset(file, "w_mm", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {n, cols}, m.w_mm.data(), "mm",
                  true);
    write_dataset(file, "v_mm3", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, {n, cols}, m.v_mm3.data(),
                  "mm^3", true);
    write_dataset(file, "segment_height_mm", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE,
                  {m.segment_height_mm.size()}, m.segment_height_mm.data(), "mm");
    write_attr(file, "teeth", static_cast<double>(m.teeth));
    write_attr(file, "segments_per_tooth", static_cast<double>(m.segments_per_tooth));
    write_attr(file, "resolution_mm", m.resolution_mm);
    write_attr(file, "steps_per_rev", static_cast<double>(m.steps_per_rev));
    write_attr(file, "complete", m.complete ? 1.0 : 0.0);
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), "the file");
  });
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
