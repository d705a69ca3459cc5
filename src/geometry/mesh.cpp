// Triangle meshes: their files through assimp (in the plugin mesh_plugin.hpp describes), their box,
// and where a line crosses a triangle (geometry.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "mesh_plugin.hpp"
#include "trochomill/common/plugin.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/io.hpp"

namespace trochomill {

namespace {

const geometry_detail::AssimpTable& assimp() {
  return plugin_table<geometry_detail::AssimpTable>("assimp", geometry_detail::kAssimpSymbol,
                                                    "reading or writing a mesh file (assimp)");
}

}  // namespace

Mesh read_mesh(const std::filesystem::path& file) {
  if (!std::filesystem::is_regular_file(file)) {
    throw InputError(fmt::format("{}: no such mesh file", file.string()));
  }
  return assimp().read(file);
}

void write_mesh(const std::filesystem::path& file, const Mesh& mesh) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::string format;
  if (ext == ".stl") format = "stlb";
  if (ext == ".ply") format = "plyb";
  if (ext == ".obj") format = "objnomtl";
  if (format.empty()) {
    throw InputError(
        fmt::format("{}: unknown mesh extension '{}' (.stl, .ply or .obj)", file.string(), ext));
  }
  write_file_atomic(file, assimp().encode(file, mesh, format));
}

namespace {

// A point of the plane across a line.
struct UV {
  double u = 0, v = 0;
};

// The edge function of p against the edge a -> b (twice the signed area of a, b, p), computed
// from the edge's lexicographically first end: b -> a gives its exact negative.
double edge_fn(UV a, UV b, UV p) {
  const bool swap = b.u < a.u || (b.u == a.u && b.v < a.v);
  if (swap) std::swap(a, b);
  const double e = (b.u - a.u) * (p.v - a.v) - (b.v - a.v) * (p.u - a.u);
  return swap ? -e : e;
}

// The top-left rule for a counter-clockwise triangle: a point on the edge a -> b belongs to
// the triangle when the edge runs downward, or runs leftward level. The neighbour across the
// edge runs it the other way round, so exactly one of the two takes the point.
bool takes_edge(UV a, UV b) { return b.v < a.v || (b.v == a.v && b.u < a.u); }

}  // namespace

Box3 mesh_bounds(const Mesh& mesh) {
  if (mesh.triangles.empty()) throw InputError("the stock mesh has no triangles");
  Box3 b;
  for (const auto& t : mesh.triangles) {
    for (const std::uint32_t i : t) {
      if (i >= mesh.vertices.size()) throw InputError("the stock mesh indexes a missing vertex");
      const auto& p = mesh.vertices[i];
      for (std::size_t k = 0; k < 3; ++k) {
        if (!std::isfinite(p[k]) || std::abs(p[k]) > 1e6) {
          throw InputError(fmt::format(
              "the stock mesh has a vertex coordinate {} (mm; finite, within 1 km)", p[k]));
        }
      }
      b.extend(p);
    }
  }
  return b;
}

void check_closed_mesh(const Mesh& mesh) {
  (void)mesh_bounds(mesh);
  // The vertices joined by position (a reader joins only vertices identical in every
  // attribute: an STL's differ in their faces' normals).
  std::vector<std::uint32_t> id(mesh.vertices.size());
  {
    std::vector<std::uint32_t> order(mesh.vertices.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    const auto less = [&](std::uint32_t a, std::uint32_t b) {
      const Vec3& p = mesh.vertices[a];
      const Vec3& q = mesh.vertices[b];
      return std::tie(p[0], p[1], p[2], a) < std::tie(q[0], q[1], q[2], b);
    };
    std::sort(order.begin(), order.end(), less);
    for (std::size_t k = 0; k < order.size(); ++k) {
      id[order[k]] = k > 0 && mesh.vertices[order[k]] == mesh.vertices[order[k - 1]]
                         ? id[order[k - 1]]
                         : order[k];
    }
  }
  // Each directed edge (i, j) of a triangle: a closed surface turned one way has each once, and
  // its reverse once (the neighbour across it).
  std::unordered_map<std::uint64_t, int> edges;
  edges.reserve(3 * mesh.triangles.size());
  auto key = [](std::uint32_t i, std::uint32_t j) {
    return (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint64_t>(j);
  };
  double volume = 0;  // six times the signed volume (divergence theorem)
  for (const auto& tri : mesh.triangles) {
    const std::array<std::uint32_t, 3> t{id[tri[0]], id[tri[1]], id[tri[2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;  // a point or a line: no face
    for (int q = 0; q < 3; ++q)
      ++edges[key(t[static_cast<std::size_t>(q)], t[static_cast<std::size_t>((q + 1) % 3)])];
    const Vec3& a = mesh.vertices[t[0]];
    const Vec3& b = mesh.vertices[t[1]];
    const Vec3& c = mesh.vertices[t[2]];
    volume += a.x() * (b.y() * c.z() - b.z() * c.y()) - a.y() * (b.x() * c.z() - b.z() * c.x()) +
              a.z() * (b.x() * c.y() - b.y() * c.x());
  }
  auto at = [&](std::uint32_t i) {
    const Vec3& p = mesh.vertices[i];
    return fmt::format("({:.6g}, {:.6g}, {:.6g})", p.x(), p.y(), p.z());
  };
  // The first bad edge in the triangles' order (deterministic, whatever the map's).
  for (const auto& tri : mesh.triangles) {
    const std::array<std::uint32_t, 3> t{id[tri[0]], id[tri[1]], id[tri[2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    for (int q = 0; q < 3; ++q) {
      const std::uint32_t i = t[static_cast<std::size_t>(q)],
                          j = t[static_cast<std::size_t>((q + 1) % 3)];
      const int here = edges[key(i, j)];
      const auto back = edges.find(key(j, i));
      const int there = back == edges.end() ? 0 : back->second;
      if (here == 1 && there == 1) continue;
      throw InputError(fmt::format(
          "the stock mesh is not a closed solid: its edge from {} to {} mm {} (each edge must "
          "join exactly two triangles, turned the same way: repair the mesh in the CAD tool "
          "or a mesh editor)",
          at(i), at(j),
          here == 2 && there == 0 ? "is run the same way by two triangles (one of them turned "
                                    "inside out)"
          : there == 0 ? "belongs to one triangle only (a hole or a crack in the surface)"
                       : "is shared by more than two triangles"));
    }
  }
  if (!(volume > 0)) {
    throw InputError(fmt::format(
        "the stock mesh's triangles face inwards (its signed volume is {:.6g} mm^3): turn them "
        "counter-clockwise seen from outside",
        volume / 6));
  }
}

std::optional<double> line_crossing(const Vec3& a, const Vec3& b, const Vec3& c, int axis, double u,
                                    double v) {
  const auto k = static_cast<std::size_t>(axis), ku = static_cast<std::size_t>((axis + 1) % 3),
             kv = static_cast<std::size_t>((axis + 2) % 3);
  UV p[3] = {{a[ku], a[kv]}, {b[ku], b[kv]}, {c[ku], c[kv]}};
  double w[3] = {a[k], b[k], c[k]};
  double area = edge_fn(p[0], p[1], p[2]);
  if (area == 0) return std::nullopt;
  if (area < 0) {
    std::swap(p[1], p[2]);
    std::swap(w[1], w[2]);
    area = -area;
  }
  const UV q{u, v};
  double e[3];
  for (int m = 0; m < 3; ++m) {
    const UV x = p[(m + 1) % 3], y = p[(m + 2) % 3];  // the edge facing vertex m
    e[m] = edge_fn(x, y, q);
    if (!(e[m] > 0 || (e[m] == 0 && takes_edge(x, y)))) return std::nullopt;
  }
  if (w[0] == w[1] && w[1] == w[2]) return w[0];
  return (e[0] * w[0] + e[1] * w[1] + e[2] * w[2]) / area;
}

}  // namespace trochomill
