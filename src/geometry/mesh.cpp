// Triangle meshes: their files through assimp, their box, and where a line crosses a triangle
// (geometry.hpp).
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/io.hpp"

namespace trochomill {

Mesh read_mesh(const std::filesystem::path& file) {
  if (!std::filesystem::is_regular_file(file)) {
    throw InputError(fmt::format("{}: no such mesh file", file.string()));
  }
  Assimp::Importer imp;
  const aiScene* scene =
      imp.ReadFile(file.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                      aiProcess_FindDegenerates | aiProcess_SortByPType);
  if (scene == nullptr) {
    throw InputError(fmt::format("{}: not a readable STL/PLY/OBJ mesh ({})", file.string(),
                                 imp.GetErrorString()));
  }
  Mesh m;
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* am = scene->mMeshes[i];
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      m.vertices.push_back(
          {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)});
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      m.triangles.push_back(
          {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (m.triangles.empty()) {
    throw InputError(fmt::format("{}: the mesh has no triangles", file.string()));
  }
  return m;
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
  aiScene scene;
  scene.mRootNode = new aiNode();
  scene.mMaterials = new aiMaterial* [1] { new aiMaterial() };
  scene.mNumMaterials = 1;
  scene.mMeshes = new aiMesh* [1] { new aiMesh() };
  scene.mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  aiMesh* am = scene.mMeshes[0];
  am->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  am->mNumVertices = static_cast<unsigned>(mesh.vertices.size());
  am->mVertices = new aiVector3D[mesh.vertices.size()];
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    am->mVertices[i] = aiVector3D(static_cast<ai_real>(v[0]), static_cast<ai_real>(v[1]),
                                  static_cast<ai_real>(v[2]));
  }
  am->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  am->mFaces = new aiFace[mesh.triangles.size()];
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    aiFace& f = am->mFaces[i];
    f.mNumIndices = 3;
    f.mIndices = new unsigned[3]{mesh.triangles[i][0], mesh.triangles[i][1], mesh.triangles[i][2]};
  }
  Assimp::Exporter ex;
  const aiExportDataBlob* blob = ex.ExportToBlob(&scene, format);
  if (blob == nullptr) {
    throw IoError(
        fmt::format("{}: cannot write the mesh ({})", file.string(), ex.GetErrorString()));
  }
  write_file_atomic(file, std::string_view(static_cast<const char*>(blob->data), blob->size));
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
