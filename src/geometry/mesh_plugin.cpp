// The plugin libtrochomill_assimp.so (mesh_plugin.hpp): mesh files through assimp.
#include "mesh_plugin.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <string>

#include "trochomill/error.hpp"

namespace trochomill::geometry_detail {
namespace {

Mesh read(const std::filesystem::path& file) {
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

std::string encode(const std::filesystem::path& file, const Mesh& mesh, const std::string& format) {
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
  return std::string(static_cast<const char*>(blob->data), blob->size);
}

const AssimpTable kTable{&read, &encode};

}  // namespace
}  // namespace trochomill::geometry_detail

extern "C" __attribute__((visibility("default"))) const trochomill::geometry_detail::AssimpTable*
trochomill_assimp_table() {
  return &trochomill::geometry_detail::kTable;
}
