#include "importers/mesh_import.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <new>
#include <optional>
#include <unordered_set>
#include <utility>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/assimp_log.hpp"
#include "importers/import_losses.hpp"
#include "importers/mesh_transform.hpp"
#include "importers/ply_guard.hpp"
#include "importers/ply_import.hpp"

namespace softbake {

namespace {

// Welding (core/mesh/weld.hpp) replaces JoinIdenticalVertices, and walking the node tree ourselves
// replaces PreTransformVertices, which would bake mirrored instances without fixing their winding.
// Validation runs before these, on the loader's own scene.
constexpr unsigned kPostProcess = aiProcess_Triangulate | aiProcess_SortByPType;

// A render vertex as importMeshFile stores it: position, normal, UV.
constexpr double kBytesPerVertex = 2 * sizeof(Vec3f) + sizeof(Vec2f);
constexpr double kBytesPerTriangle = sizeof(Triangle);

struct MeshInstance {
  const aiMesh* mesh;
  Eigen::Affine3d toWorld;
  std::string name;
};

Eigen::Affine3d toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d matrix;
  matrix << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2,
      m.d3, m.d4;
  return Eigen::Affine3d(matrix);
}

// Loaders invent names like "<OFFRoot>" and "<3DSDummyRoot>" for nodes the file did not name.
bool isMadeUpName(std::string_view name) {
  return name.empty() || (name.front() == '<' && name.back() == '>');
}

std::string instanceName(const aiNode& node, const aiMesh& mesh, const std::string& stem) {
  if (!isMadeUpName(node.mName.C_Str())) return node.mName.C_Str();
  if (!isMadeUpName(mesh.mName.C_Str())) return mesh.mName.C_Str();
  return stem;
}

// Depth-first in file order, without recursion: node depth comes from the file.
std::vector<MeshInstance> collectInstances(const aiScene& scene, const std::string& stem) {
  std::vector<MeshInstance> instances;
  if (!scene.mRootNode) return instances;
  std::vector<std::pair<const aiNode*, Eigen::Affine3d>> stack = {
      {scene.mRootNode, toEigen(scene.mRootNode->mTransformation)}};
  while (!stack.empty()) {
    const auto [node, toWorld] = stack.back();
    stack.pop_back();
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const aiMesh* mesh = scene.mMeshes[node->mMeshes[i]];
      instances.push_back({mesh, toWorld, instanceName(*node, *mesh, stem)});
    }
    for (unsigned i = node->mNumChildren; i-- > 0;) {
      const aiNode* child = node->mChildren[i];
      stack.emplace_back(child, toWorld * toEigen(child->mTransformation));
    }
  }
  return instances;
}

void makeNamesUnique(std::vector<TriangleMesh>& meshes) {
  std::unordered_set<std::string> used;
  for (const TriangleMesh& mesh : meshes) used.insert(mesh.name);
  std::unordered_set<std::string> seen;
  for (TriangleMesh& mesh : meshes) {
    if (seen.insert(mesh.name).second) continue;
    for (int suffix = 2;; ++suffix) {
      std::string candidate = cat(mesh.name, '_', suffix);
      if (!used.contains(candidate)) {
        used.insert(candidate);
        seen.insert(candidate);
        mesh.name = std::move(candidate);
        break;
      }
    }
  }
}

struct DroppedPrimitives {
  std::size_t points = 0, lines = 0;
};

TriangleMesh toTriangleMesh(const MeshInstance& instance, DroppedPrimitives& dropped) {
  const aiMesh& source = *instance.mesh;
  TriangleMesh mesh;
  mesh.name = instance.name;
  mesh.triangles.reserve(source.mNumFaces);
  for (unsigned f = 0; f < source.mNumFaces; ++f) {
    const aiFace& face = source.mFaces[f];
    if (face.mNumIndices == 3) {
      mesh.triangles.push_back({face.mIndices[0], face.mIndices[1], face.mIndices[2]});
    } else if (face.mNumIndices == 1) {
      ++dropped.points;
    } else {
      ++dropped.lines;
    }
  }
  if (mesh.triangles.empty()) return mesh;

  mesh.positions.resize(source.mNumVertices);
  for (unsigned v = 0; v < source.mNumVertices; ++v) {
    const aiVector3D& p = source.mVertices[v];
    mesh.positions[v] = Vec3f(p.x, p.y, p.z);
  }
  if (source.HasNormals()) {
    mesh.normals.resize(source.mNumVertices);
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      const aiVector3D& n = source.mNormals[v];
      mesh.normals[v] = Vec3f(n.x, n.y, n.z);
    }
  }
  if (source.HasTextureCoords(0)) {
    mesh.uvs.resize(source.mNumVertices);
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      const aiVector3D& uv = source.mTextureCoords[0][v];
      mesh.uvs[v] = Vec2f(uv.x, uv.y);
    }
  }
  transformMesh(mesh, instance.toWorld);
  return mesh;
}

void requireFinite(const std::filesystem::path& path, const TriangleMesh& mesh) {
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const Vec3f& p = mesh.positions[v];
    if (!p.allFinite()) {
      throw Error(cat(path.string(), ": mesh '", mesh.name, "': vertex ", v,
                      " has non-finite coordinates (", p.x(), ", ", p.y(), ", ", p.z(), ")"));
    }
  }
}

TriangleMesh mergeAll(std::vector<TriangleMesh>& meshes, const std::filesystem::path& path,
                      std::vector<std::string>& notes) {
  TriangleMesh merged;
  merged.name = path.stem().string();
  bool allNormals = true, allUvs = true, anyNormals = false, anyUvs = false;
  std::size_t vertices = 0, triangles = 0;
  for (const TriangleMesh& mesh : meshes) {
    allNormals &= !mesh.normals.empty();
    anyNormals |= !mesh.normals.empty();
    allUvs &= !mesh.uvs.empty();
    anyUvs |= !mesh.uvs.empty();
    vertices += mesh.positions.size();
    triangles += mesh.triangles.size();
  }
  if (vertices > std::numeric_limits<Index>::max())
    throw Error(
        cat(path.string(), ": mesh too large: ", vertices, " vertices do not fit 32-bit indices"));
  if (anyUvs && !allUvs)
    notes.push_back(cat(path.string(), ": not every mesh has UVs, so the merged mesh has none"));
  if (anyNormals && !allNormals)
    notes.push_back(
        cat(path.string(), ": not every mesh has normals, so the merged mesh has none"));

  merged.positions.reserve(vertices);
  merged.triangles.reserve(triangles);
  if (allNormals) merged.normals.reserve(vertices);
  if (allUvs) merged.uvs.reserve(vertices);
  for (TriangleMesh& mesh : meshes) {
    const Index offset = Index(merged.positions.size());
    merged.positions.insert(merged.positions.end(), mesh.positions.begin(), mesh.positions.end());
    if (allNormals)
      merged.normals.insert(merged.normals.end(), mesh.normals.begin(), mesh.normals.end());
    if (allUvs) merged.uvs.insert(merged.uvs.end(), mesh.uvs.begin(), mesh.uvs.end());
    for (const Triangle& t : mesh.triangles)
      merged.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    mesh = TriangleMesh();  // give the memory back as we go
  }
  return merged;
}

// Vertices of the file's meshes that no face uses, as the loader returned them: post-processing
// could split them off or drop them.
std::size_t unusedVertices(const aiScene& scene) {
  std::size_t unused = 0;
  std::vector<char> used;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    used.assign(mesh.mNumVertices, 0);
    for (unsigned f = 0; f < mesh.mNumFaces; ++f)
      for (unsigned i = 0; i < mesh.mFaces[f].mNumIndices; ++i)
        if (mesh.mFaces[f].mIndices[i] < mesh.mNumVertices) used[mesh.mFaces[f].mIndices[i]] = 1;
    unused += std::size_t(std::count(used.begin(), used.end(), 0));
  }
  return unused;
}

std::size_t vertexCount(const aiScene& scene) {
  std::size_t vertices = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) vertices += scene.mMeshes[m]->mNumVertices;
  return vertices;
}

std::size_t faceCount(const aiScene& scene) {
  std::size_t faces = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) faces += scene.mMeshes[m]->mNumFaces;
  return faces;
}

// One mesh, or all merged into one, or each named apart.
void arrangeMeshes(const std::filesystem::path& path, const MeshImportOptions& options,
                   ImportedMeshes& result) {
  if (options.mergeMeshes) {
    TriangleMesh merged = mergeAll(result.meshes, path, result.notes);
    result.meshes.clear();
    result.meshes.push_back(std::move(merged));
  } else {
    makeNamesUnique(result.meshes);
  }
}

ImportedMeshes importWithAssimp(const std::filesystem::path& path, const MeshImportOptions& options,
                                const PlyPreparation* ply) {
  const std::string file = path.string();
  const AssimpLogCapture log;
  Assimp::Importer importer;
  // Validation only, so the scene can be inspected as the loader made it before post-processing.
  const aiScene* scene = importer.ReadFile(file, aiProcess_ValidateDataStructure);
  if (!scene) {
    const std::string why = importer.GetErrorString();
    if (why.find("No suitable reader found") != std::string::npos)
      throw Error(cat(file, ": unsupported format (assimp: ", why, ")"));
    throw Error(cat(file, ": cannot import (assimp: ", why, ")"));
  }
  std::vector<std::string> losses;
  if (ply) {
    losses = ply->losses;
    compareWithHeader(ply->header, vertexCount(*scene), faceCount(*scene), losses);
  }
  if (std::optional<std::string> loss =
          unusedVertexLoss(unusedVertices(*scene), vertexCount(*scene)))
    losses.push_back(std::move(*loss));
  scene = importer.ApplyPostProcessing(kPostProcess);
  if (!scene) throw Error(cat(file, ": cannot import (assimp: ", importer.GetErrorString(), ")"));

  // A message that says what was lost is told once, as a loss.
  std::vector<AssimpMessage> others;
  for (const AssimpMessage& message : log.messages()) {
    if (std::optional<std::string_view> lost = geometryLostIn(message.text))
      losses.push_back(cat(*lost, " (assimp: ", message.text, ")"));
    else
      others.push_back(message);
  }
  ImportedMeshes result;
  result.warnings = describeAssimpMessages(file, others, log.unkept());
  settleLosses(file, losses, options.acceptLossy, result.warnings);

  const std::string stem = path.stem().string();
  const std::vector<MeshInstance> instances = collectInstances(*scene, stem);
  std::uint64_t vertices = 0, faces = 0;
  for (const MeshInstance& instance : instances) {
    vertices += instance.mesh->mNumVertices;
    faces += instance.mesh->mNumFaces;
  }
  requireWithinLimits(path, vertices, faces, options.limits);
  double bytes = double(vertices) * kBytesPerVertex + double(faces) * kBytesPerTriangle;
  // Merging copies everything once more.
  if (options.mergeMeshes) bytes *= 2;
  requireImportMemory(path, bytes, cat("importing ", instances.size(), " mesh instances"),
                      options.limits);

  DroppedPrimitives dropped;
  for (const MeshInstance& instance : instances) {
    TriangleMesh mesh = toTriangleMesh(instance, dropped);
    if (mesh.triangles.empty()) continue;
    requireFinite(path, mesh);
    result.meshes.push_back(std::move(mesh));
  }
  if (dropped.points + dropped.lines > 0) {
    result.notes.push_back(cat(file, ": ignored ", dropped.points, " points and ", dropped.lines,
                               " lines (only triangles are simulated)"));
  }
  if (result.meshes.empty()) {
    if (dropped.points + dropped.lines > 0)
      throw Error(cat(file, ": no triangles (the file holds only points and lines)"));
    throw Error(cat(file, ": no triangles (the file holds no meshes)"));
  }
  arrangeMeshes(path, options, result);
  return result;
}

// A PLY file softbake read itself: what assimp's path checks, on softbake's mesh.
ImportedMeshes importPlyMesh(const std::filesystem::path& path, const MeshImportOptions& options,
                             PlyPreparation& ply) {
  const std::string file = path.string();
  TriangleMesh& mesh = *ply.mesh;
  std::vector<char> used(mesh.positions.size(), 0);
  for (const Triangle& t : mesh.triangles)
    for (Index v : t) used[v] = 1;
  std::vector<std::string> losses = std::move(ply.losses);
  if (std::optional<std::string> loss = unusedVertexLoss(
          std::size_t(std::count(used.begin(), used.end(), 0)), mesh.positions.size()))
    losses.push_back(std::move(*loss));
  ImportedMeshes result;
  result.notes = std::move(ply.notes);
  settleLosses(file, losses, options.acceptLossy, result.warnings);
  if (mesh.triangles.empty()) throw Error(cat(file, ": no triangles"));
  requireWithinLimits(path, mesh.positions.size(), mesh.triangles.size(), options.limits);
  mesh.name = path.stem().string();
  requireFinite(path, mesh);
  result.meshes.push_back(std::move(mesh));
  arrangeMeshes(path, options, result);
  return result;
}

}  // namespace

ImportedMeshes importMeshFile(const std::filesystem::path& path, const MeshImportOptions& options) {
  const std::string file = path.string();
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status)) throw Error(cat(file, ": file not found"));
  if (std::filesystem::is_directory(status))
    throw Error(cat(file, ": is a directory, not a mesh file"));
  if (!std::filesystem::is_regular_file(status)) throw Error(cat(file, ": not a regular file"));
  const std::uintmax_t fileSize = std::filesystem::file_size(path, error);
  if (error) throw Error(cat(file, ": cannot read the file (", error.message(), ")"));
  // assimp reads the whole file into memory before parsing it.
  requireImportMemory(path, double(fileSize), "reading the file", options.limits);

  try {
    std::string extension = path.extension().string();
    for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
    std::optional<PlyPreparation> ply;
    if (extension == ".ply" || isPlyFile(path)) {
      ply = preparePly(path, options.limits);
      if (ply->mesh) return importPlyMesh(path, options, *ply);
    }
    return importWithAssimp(path, options, ply ? &*ply : nullptr);
  } catch (const std::bad_alloc&) {
    throw Error(
        cat(file, ": mesh too large for this machine: ran out of memory while importing it"));
  }
}

}  // namespace softbake
