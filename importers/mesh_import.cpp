#include "importers/mesh_import.hpp"

#include <assimp/MemoryIOWrapper.h>
#include <assimp/postprocess.h>
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <new>
#include <optional>
#include <unordered_set>
#include <utility>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/assimp_log.hpp"
#include "importers/assimp_snapshot.hpp"
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
  const SnapshotMesh* mesh;
  Eigen::Affine3d toWorld;
  std::string name;
};

// Loaders invent names like "<OFFRoot>" and "<3DSDummyRoot>" for nodes the file did not name.
bool isMadeUpName(std::string_view name) {
  return name.empty() || (name.front() == '<' && name.back() == '>');
}

std::string instanceName(const SnapshotNode& node, const SnapshotMesh& mesh,
                         const std::string& stem) {
  if (!isMadeUpName(node.name)) return node.name;
  if (!isMadeUpName(mesh.name)) return mesh.name;
  return stem;
}

// Depth-first in file order, without recursion: node depth comes from the file.
std::vector<MeshInstance> collectInstances(const AssimpSnapshot& scene, const std::string& file,
                                           const std::string& stem) {
  std::vector<MeshInstance> instances;
  if (scene.nodes.empty()) return instances;
  std::vector<std::pair<std::uint32_t, Eigen::Affine3d>> stack = {
      {0, Eigen::Affine3d(scene.nodes[0].transform)}};
  while (!stack.empty()) {
    const auto [index, toWorld] = stack.back();
    stack.pop_back();
    const SnapshotNode& node = scene.nodes[index];
    for (std::uint32_t m : node.meshes) {
      if (m >= scene.meshes.size())
        throw Error(
            cat(file, ": node '", node.name, "' names mesh ", m, " of ", scene.meshes.size()));
      instances.push_back({&scene.meshes[m], toWorld, instanceName(node, scene.meshes[m], stem)});
    }
    for (std::size_t i = node.children.size(); i-- > 0;) {
      const std::uint32_t child = node.children[i];
      if (child <= index || child >= scene.nodes.size())
        throw Error(cat(file, ": node '", node.name, "' has a child out of order"));
      stack.emplace_back(child, toWorld * Eigen::Affine3d(scene.nodes[child].transform));
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

TriangleMesh toTriangleMesh(const std::string& file, const MeshInstance& instance,
                            DroppedPrimitives& dropped) {
  const SnapshotMesh& source = *instance.mesh;
  dropped.points += source.points;
  dropped.lines += source.lines;
  TriangleMesh mesh;
  mesh.name = instance.name;
  if (source.triangles.empty()) return mesh;
  // assimp validated the loader's scene; post-processing is trusted no further than this.
  for (const Triangle& t : source.triangles)
    for (Index v : t)
      if (v >= source.positions.size())
        throw Error(cat(file, ": mesh '", source.name, "': a face uses vertex ", v, " of ",
                        source.positions.size()));
  mesh.triangles = source.triangles;
  mesh.positions = source.positions;
  mesh.normals = source.normals;
  mesh.uvs = source.uvs;
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
  // UVs go out again in every OBJ frame.
  for (std::size_t v = 0; v < mesh.uvs.size(); ++v) {
    const Vec2f& uv = mesh.uvs[v];
    if (!uv.allFinite()) {
      throw Error(cat(path.string(), ": mesh '", mesh.name, "': vertex ", v,
                      " has non-finite texture coordinates (", uv.x(), ", ", uv.y(), ")"));
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

// One mesh, or all merged into one, or each named apart.
void arrangeMeshes(const std::filesystem::path& path, const MeshImportOptions& options,
                   ImportedMeshes& result) {
  if (options.mergeMeshes) {
    std::vector<Index> offsets;
    Index offset = 0;
    for (const TriangleMesh& mesh : result.meshes) {
      offsets.push_back(offset);
      offset += Index(mesh.positions.size());
    }
    for (FileVertexPlace& place : result.fileVertices.places)
      if (place.mesh != FileVertexPlace::kNone) place = {0, offsets[place.mesh] + place.vertex};
    TriangleMesh merged = mergeAll(result.meshes, path, result.notes);
    result.meshes.clear();
    result.meshes.push_back(std::move(merged));
  } else {
    makeNamesUnique(result.meshes);
  }
}

std::string lowerExtension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

// Only the vertices a triangle uses can be pinned: the others become no particle.
std::vector<char> usedVertices(std::size_t vertices, const std::vector<Triangle>& triangles) {
  std::vector<char> used(vertices, 0);
  for (const Triangle& t : triangles)
    for (Index v : t)
      if (v < vertices) used[v] = 1;
  return used;
}

// The file's numbering of `scene`, whose instance i became result mesh keptAs[i] (kNone: none).
// `objText` is the file, for an OBJ.
FileVertices numberFileVertices(const std::filesystem::path& path, const AssimpSnapshot& scene,
                                const std::vector<MeshInstance>& instances,
                                const std::vector<Index>& keptAs, bool ply,
                                std::string_view objText) {
  FileVertices numbering;
  const std::string extension = lowerExtension(path);
  if (extension == ".obj") {
    // assimp made a vertex per face corner, so the `v` statements are matched by position. They
    // are shared by all of the file's objects, which have no transforms: one space for all.
    std::vector<ImportedVertices> meshes;
    for (std::size_t i = 0; i < instances.size(); ++i)
      if (keptAs[i] != FileVertexPlace::kNone)
        meshes.push_back({keptAs[i], instances[i].mesh->positions, instances[i].mesh->triangles});
    numbering.places = placeByPosition(objVertexPositions(objText), meshes);
    return numbering;
  }
  // These loaders keep the file's vertices as the file lists them, one aiMesh after another.
  const bool keepsOrder = ply || extension == ".off" || extension == ".stl" ||
                          extension == ".gltf" || extension == ".glb";
  if (!keepsOrder) {
    numbering.unknown =
        cat("softbake knows the vertex numbering of OBJ, PLY, OFF, STL and glTF "
            "files only, not of '",
            extension, "' files");
    return numbering;
  }
  bool unchanged = scene.loaderMeshVertices.size() == scene.meshes.size();
  for (std::size_t m = 0; unchanged && m < scene.meshes.size(); ++m)
    unchanged = scene.loaderMeshVertices[m] == scene.meshes[m].positions.size();
  if (!unchanged) {
    numbering.unknown =
        "assimp rebuilt the file's meshes (it mixes points or lines with faces), so their vertices "
        "are no longer in the file's order";
    return numbering;
  }
  // A mesh placed twice is numbered once in the file: its first placement is pinned.
  std::vector<Index> firstKept(scene.meshes.size(), FileVertexPlace::kNone);
  for (std::size_t i = instances.size(); i-- > 0;)
    if (keptAs[i] != FileVertexPlace::kNone)
      firstKept[std::size_t(instances[i].mesh - scene.meshes.data())] = keptAs[i];
  for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
    const SnapshotMesh& mesh = scene.meshes[m];
    const std::vector<char> used = usedVertices(mesh.positions.size(), mesh.triangles);
    for (Index v = 0; v < used.size(); ++v)
      numbering.places.push_back(used[v] && firstKept[m] != FileVertexPlace::kNone
                                     ? FileVertexPlace{firstKept[m], v}
                                     : FileVertexPlace{});
  }
  return numbering;
}

ImportedMeshes importWithAssimp(const std::filesystem::path& path, const MeshImportOptions& options,
                                const PlyPreparation* ply, const AssimpRead& read,
                                std::string_view objText) {
  const std::string file = path.string();
  // In a child process, within the time and memory limits: a crash inside assimp ends there, as
  // an error naming the file.
  const AssimpSnapshot scene = takeAssimpSnapshotInChild(read, kPostProcess, file, options.limits);
  if (!scene.error.empty()) {
    if (scene.error.find("No suitable reader found") != std::string::npos)
      throw Error(cat(file, ": unsupported format (assimp: ", scene.error, ")"));
    throw Error(cat(file, ": cannot import (assimp: ", scene.error, ")"));
  }
  std::vector<std::string> losses;
  if (ply) {
    losses = ply->losses;
    compareWithHeader(ply->header, scene.loaderVertices, scene.loaderFaces, losses);
  }
  if (std::optional<std::string> loss =
          unusedVertexLoss(scene.unusedVertices, scene.loaderVertices))
    losses.push_back(std::move(*loss));
  if (scene.emptyFaces > 0)
    losses.push_back(
        cat(scene.emptyFaces, scene.emptyFaces == 1 ? " face" : " faces", " with no corners"));

  // A message that says what was lost is told once, as a loss.
  std::vector<AssimpMessage> others;
  for (const AssimpMessage& message : scene.messages) {
    if (std::optional<std::string_view> lost = geometryLostIn(message.text))
      losses.push_back(cat(*lost, " (assimp: ", message.text, ")"));
    else
      others.push_back(message);
  }
  ImportedMeshes result;
  result.warnings = describeAssimpMessages(file, others, scene.unkeptMessages);
  settleLosses(file, losses, options.acceptLossy, result.warnings);

  const std::string stem = path.stem().string();
  const std::vector<MeshInstance> instances = collectInstances(scene, file, stem);
  std::uint64_t vertices = 0, faces = 0;
  for (const MeshInstance& instance : instances) {
    vertices += instance.mesh->positions.size();
    faces += instance.mesh->triangles.size() + instance.mesh->points + instance.mesh->lines;
  }
  requireWithinLimits(path, vertices, faces, options.limits);
  double bytes = double(vertices) * kBytesPerVertex + double(faces) * kBytesPerTriangle;
  // Merging copies everything once more.
  if (options.mergeMeshes) bytes *= 2;
  requireImportMemory(path, bytes, cat("importing ", instances.size(), " mesh instances"),
                      options.limits);

  DroppedPrimitives dropped;
  std::vector<Index> keptAs(instances.size(), FileVertexPlace::kNone);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    TriangleMesh mesh = toTriangleMesh(file, instances[i], dropped);
    if (mesh.triangles.empty()) continue;
    requireFinite(path, mesh);
    keptAs[i] = Index(result.meshes.size());
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
  if (options.numberFileVertices)
    result.fileVertices =
        numberFileVertices(path, scene, instances, keptAs, ply != nullptr, objText);
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
  if (options.numberFileVertices) {
    // softbake's own reader keeps the vertex element's order.
    for (Index v = 0; v < used.size(); ++v)
      result.fileVertices.places.push_back(used[v] ? FileVertexPlace{0, v} : FileVertexPlace{});
  }
  result.meshes.push_back(std::move(mesh));
  arrangeMeshes(path, options, result);
  return result;
}

// One file, in memory, and nothing else: a fuzzed OBJ's `mtllib /dev/zero` or a glTF's buffer
// URI must not reach the disk, and results must not depend on the current folder. (assimp's own
// ReadFileFromMemory() serves every name that starts like its made-up file name, so an OBJ's
// fallback material library, "<name>.mtl", is the OBJ itself, read as a material library.)
class OneFileSystem : public Assimp::IOSystem {
 public:
  OneFileSystem(std::string name, std::string_view bytes) : name_(std::move(name)), bytes_(bytes) {}

  bool Exists(const char* path) const override { return path && name_ == path; }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char* path, const char* mode) override {
    if (!Exists(path) || !mode || mode[0] != 'r') return nullptr;
    return new Assimp::MemoryIOStream(reinterpret_cast<const std::uint8_t*>(bytes_.data()),
                                      bytes_.size());
  }
  void Close(Assimp::IOStream* stream) override { delete stream; }

 private:
  std::string name_;
  std::string_view bytes_;
};

// An OBJ's text, read a second time (assimp read it in its child) for its vertex numbering.
std::string objTextToNumber(const std::filesystem::path& path, const MeshImportOptions& options) {
  if (!options.numberFileVertices || lowerExtension(path) != ".obj") return {};
  std::ifstream in(path, std::ios::binary);
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!in.good() && !in.eof())
    throw Error(cat(path.string(), ": cannot read the file to number its vertices"));
  return text;
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
    std::optional<PlyPreparation> ply;
    if (lowerExtension(path) == ".ply" || isPlyFile(path)) {
      ply = preparePly(path, options.limits);
      if (ply->mesh) return importPlyMesh(path, options, *ply);
    }
    return importWithAssimp(
        path, options, ply ? &*ply : nullptr,
        [&](Assimp::Importer& importer, unsigned flags) { return importer.ReadFile(file, flags); },
        objTextToNumber(path, options));
  } catch (const std::bad_alloc&) {
    throw Error(
        cat(file, ": mesh too large for this machine: ran out of memory while importing it"));
  }
}

ImportedMeshes importMeshBuffer(std::string_view bytes, const std::string& name,
                                const MeshImportOptions& options) {
  const std::filesystem::path path(name);
  // assimp's reader of memory refuses an empty buffer with "Invalid parameters".
  if (bytes.empty()) throw Error(cat(name, ": the file is empty"));
  requireImportMemory(path, double(bytes.size()), "reading the file", options.limits);
  try {
    const std::string extension = lowerExtension(path);
    std::optional<PlyPreparation> ply;
    if (extension == ".ply" || hasPlyMagic(bytes.substr(0, 3))) {
      ply = preparePlyBuffer(bytes, name, options.limits);
      if (ply->mesh) return importPlyMesh(path, options, *ply);
    }
    return importWithAssimp(
        path, options, ply ? &*ply : nullptr,
        [&](Assimp::Importer& importer, unsigned flags) {
          // The importer owns it.
          importer.SetIOHandler(new OneFileSystem(name, bytes));
          return importer.ReadFile(name, flags);
        },
        bytes);
  } catch (const std::bad_alloc&) {
    throw Error(
        cat(name, ": mesh too large for this machine: ran out of memory while importing it"));
  }
}

}  // namespace softbake
