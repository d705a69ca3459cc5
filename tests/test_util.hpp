// Shared helpers for the trochomill tests: example jobs, inline jobs, directory listings and
// geometric distance checks used by several test files.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/topography.hpp"

namespace trochomill::test {

// A block as a closed mesh of 12 triangles (outward, counter-clockwise seen from outside):
// x from x0 to x1, y from y0 to y1, bottom at z_bottom, its top's corners at the heights
// top_z (at (x0, y0), (x1, y0), (x0, y1), (x1, y1)): a box, or a block with a sloping top.
// The faces' diagonals run through ray centres when the sides are whole multiples of a
// dexel spacing.
inline Mesh block_mesh(double x0, double x1, double y0, double y1, double z_bottom,
                       const std::array<double, 4>& top_z) {
  Mesh m;
  for (int k = 0; k < 8; ++k) {
    const double x = (k & 1) ? x1 : x0, y = (k & 2) ? y1 : y0;
    m.vertices.push_back({x, y, (k & 4) ? top_z[static_cast<std::size_t>(k & 3)] : z_bottom});
  }
  const std::uint32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : f) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}
inline Mesh box_mesh(const Vec3& lo, const Vec3& hi) {
  return block_mesh(lo[0], hi[0], lo[1], hi[1], lo[2], {hi[2], hi[2], hi[2], hi[2]});
}

// A block |x|, |y| <= h from z = bottom to 0 with a cored cavity about the z axis: a frustum
// of n sides (n a multiple of 8: the rays at multiples of 45 degrees meet the block's
// corners), radius r_top at z = 0 and r_floor at its floor z = floor_z (above bottom), its
// vertices at angles 2 pi k / n. Closed, counter-clockwise seen from outside.
inline Mesh cored_block_mesh(double h, double bottom, double r_top, double r_floor, double floor_z,
                             int n) {
  Mesh m;
  auto add = [&](double x, double y, double z) {
    m.vertices.push_back({x, y, z});
    return static_cast<std::uint32_t>(m.vertices.size() - 1);
  };
  std::vector<std::uint32_t> ot, ob, it, jf;  // outer top, outer bottom, cavity top, floor
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n, c = std::cos(a), s = std::sin(a);
    const double to_side = h / std::max(std::abs(c), std::abs(s));
    ot.push_back(add(to_side * c, to_side * s, 0));
    ob.push_back(add(to_side * c, to_side * s, bottom));
    it.push_back(add(r_top * c, r_top * s, 0));
    jf.push_back(add(r_floor * c, r_floor * s, floor_z));
  }
  const std::uint32_t cb = add(0, 0, bottom), cf = add(0, 0, floor_z);
  for (int k = 0; k < n; ++k) {
    const auto a = static_cast<std::size_t>(k), b = static_cast<std::size_t>((k + 1) % n);
    m.triangles.push_back({it[a], ot[a], ot[b]});  // top ring, up
    m.triangles.push_back({it[a], ot[b], it[b]});
    m.triangles.push_back({ob[a], ob[b], ot[b]});  // outer walls, outwards
    m.triangles.push_back({ob[a], ot[b], ot[a]});
    m.triangles.push_back({cb, ob[b], ob[a]});     // bottom, down
    m.triangles.push_back({jf[a], it[a], it[b]});  // cavity wall, towards the axis
    m.triangles.push_back({jf[a], it[b], jf[b]});
    m.triangles.push_back({cf, jf[a], jf[b]});  // cavity floor, up
  }
  return m;
}

// The message of the InputError f throws ("no error" when it throws none).
inline std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

inline std::filesystem::path source_dir() { return TROCHOMILL_SOURCE_DIR; }
inline std::filesystem::path example(const std::string& rel) {
  return source_dir() / "examples" / rel;
}
inline std::vector<std::filesystem::path> files_in(const std::filesystem::path& dir,
                                                   const std::string& ext) {
  std::vector<std::filesystem::path> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ext) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}
/// A folder of this test process's own in the temporary directory ("trochomill-NAME-PID"),
/// made on first use and removed, with what is in it, when the process ends (each test is a
/// process of its own under ctest, so none is left behind in /tmp).
inline std::filesystem::path scratch_dir(const std::string& name) {
  struct Folders {
    std::vector<std::filesystem::path> made;
    ~Folders() {
      for (const auto& d : made) {
        std::error_code ec;
        std::filesystem::remove_all(d, ec);
      }
    }
  };
  static Folders folders;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("trochomill-" + name + "-" + std::to_string(::getpid()));
  if (std::find(folders.made.begin(), folders.made.end(), dir) == folders.made.end()) {
    std::filesystem::create_directories(dir);
    folders.made.push_back(dir);
  }
  return dir;
}
// The whole file's bytes.
inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
inline std::string first_line(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

// The Wagih 2023 Table 1 job with a chosen family; extra TOML lines go into [path].
inline Job wagih_job(const std::string& type, const std::vector<Override>& ov = {}) {
  const std::string text = R"(
[tool]
diameter = 10.0
teeth = 4
[slot]
width = 20.0
length = 20.0
depth = 6.0
[path]
type = ")" + type + R"("
step = 1.0
[cutting]
feed_rate = 600.0
spindle_speed = 2000.0
[machine]
rapid_rate = 10000.0
)";
  return parse_job(text, "wagih.toml", ov);
}

// A straight slot 40 mm long, 6 deep, D 10 mm, 600 mm/min at 2000 rpm ("linear" family).
inline Job straight_job(double width, int teeth = 4, const std::vector<Override>& ov = {}) {
  return parse_job(R"(
[tool]
diameter = 10.0
teeth = )" + std::to_string(teeth) +
                       R"(
[slot]
width = )" + std::to_string(width) +
                       R"(
length = 40.0
depth = 6.0
[path]
type = "linear"
step = 1.0
[cutting]
feed_rate = 600.0
spindle_speed = 2000.0
)",
                   "straight.toml", ov);
}

// A job of a tool and a [stock] box alone (no [slot], no [path]: for programs read with
// analyze --gcode or optimize-feed): diameter (mm), teeth, flute length 20 mm, the [cutting]
// lines as given, the box from lo to hi (mm).
inline Job stock_job(double diameter_mm, int teeth, const std::string& cutting, const Vec3& lo,
                     const Vec3& hi, const std::string& name) {
  const auto point = [](const Vec3& p) {
    return "[" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
           std::to_string(p.z()) + "]";
  };
  return parse_job("[tool]\ndiameter = " + std::to_string(diameter_mm) +
                       "\nteeth = " + std::to_string(teeth) + "\nflute_length = 20.0\n[cutting]\n" +
                       cutting + "[stock]\nmin = " + point(lo) + "\nmax = " + point(hi) + "\n",
                   name);
}

// Distance from q to the polyline through samples (x, y, z), searching a window of indices
// from just behind `hint` forward (paths are compared in order; a path may retrace itself
// exactly, so ties go to the earliest index from the hint on) and updating it.
inline double distance_to_polyline(const PathSamples& s, const Vec3& q, std::size_t& hint,
                                   std::size_t window) {
  const std::size_t n = s.size();
  const std::size_t lo = hint > 5 ? hint - 5 : 0;
  const std::size_t hi = std::min(n - 1, hint + window);
  double best = 1e300;
  std::size_t best_i = hint;
  // Plain doubles, not Eigen expressions: this loop runs 10^8 times in some tests, and the
  // sanitizer build (-O1, Eigen's asserts on) made the expression form 50x slower.
  const double qx = q.x(), qy = q.y(), qz = q.z();
  const double* xs = s.x_mm.data();
  const double* ys = s.y_mm.data();
  const double* zs = s.z_mm.data();
  auto consider = [&](std::size_t i) {
    const double ax = xs[i], ay = ys[i], az = zs[i];
    const double dx = xs[i + 1] - ax, dy = ys[i + 1] - ay, dz = zs[i + 1] - az;
    const double L2 = dx * dx + dy * dy + dz * dz;
    const double t =
        L2 > 0 ? std::clamp(((qx - ax) * dx + (qy - ay) * dy + (qz - az) * dz) / L2, 0.0, 1.0)
               : 0.0;
    const double ex = qx - ax - t * dx, ey = qy - ay - t * dy, ez = qz - az - t * dz;
    const double dist = std::sqrt(ex * ex + ey * ey + ez * ez);
    if (dist < best) {
      best = dist;
      best_i = i;
    }
  };
  // Forward from the hint first, so an exact tie with an earlier pass over the same place
  // keeps the path's progress.
  for (std::size_t i = std::min(hint, hi); i < hi; ++i) consider(i);
  for (std::size_t i = std::min(hint, hi); i-- > lo;) consider(i);
  hint = best_i;
  return best;
}

// Each segment's largest radial chip over the engagement's samples in it (mm): the chip the
// analysis counts (engagement.hpp: radial_chip_mm), per segment of the path.
inline std::vector<double> chips_per_segment(const Job& job, const ToolPath& path) {
  const EngagementSeries e = compute_engagement(path, job);
  std::vector<double> h(path.segments().size(), 0.0);
  const double R = 0.5 * job.tool.diameter_mm;
  for (std::size_t i = 1; i < e.samples.size(); ++i) {
    h[e.samples.segment[i]] = std::max(h[e.samples.segment[i]], radial_chip_mm(e, i, R));
  }
  return h;
}

}  // namespace trochomill::test
