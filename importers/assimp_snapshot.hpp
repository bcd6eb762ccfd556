#pragma once
/// assimp's reading of a file, done in a child process and handed back as plain data.
///
/// assimp 5.2 crashes on some corrupt files (a segfault in its MTL reader, a debug assertion in its
/// Triangulate step: fuzz/README.md lists what fuzzing found), and a crash inside assimp takes the
/// whole process with it. So softbake runs assimp, and only assimp, in a forked child: the child
/// reads the file, post-processes it and sends back what softbake uses (the meshes, the node tree,
/// the log), and everything else (placing, checking, limits) runs in the calling process on that
/// copy. A child that dies becomes an error naming the file, whatever the bug was.
///
/// Forking copies only the calling thread, so imports must not race a thread that holds a lock
/// assimp needs; softbake imports before it starts any thread of its own.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mesh/triangle_mesh.hpp"
#include "importers/assimp_log.hpp"
#include "importers/import_limits.hpp"

namespace Assimp {
class Importer;
}
struct aiScene;

namespace softbake {

/// One aiMesh after post-processing, as softbake uses it.
struct SnapshotMesh {
  std::string name;
  std::vector<Vec3f> positions;
  std::vector<Vec3f> normals;  ///< empty when the mesh has none
  std::vector<Vec2f> uvs;      ///< the first UV channel; empty when the mesh has none
  std::vector<Triangle> triangles;
  std::uint64_t points = 0, lines = 0;  ///< faces of 1 and 2 corners, not kept
};

/// One aiNode. Node 0 is the root; children come after their parent.
struct SnapshotNode {
  std::string name;
  Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();  ///< relative to the parent
  std::vector<std::uint32_t> meshes;                        ///< into AssimpSnapshot::meshes
  std::vector<std::uint32_t> children;                      ///< into AssimpSnapshot::nodes
};

struct AssimpSnapshot {
  /// assimp's error when it could not read the file; empty when it could.
  std::string error;
  /// The loader's scene, before post-processing: what the file held.
  std::uint64_t loaderVertices = 0, loaderFaces = 0;
  /// Per mesh of the loader's scene, its vertices: where post-processing kept every mesh as it was,
  /// a vertex's index is still the loader's (mesh_import.cpp numbers a file's vertices by it).
  std::vector<std::uint64_t> loaderMeshVertices;
  std::uint64_t unusedVertices = 0;  ///< of loaderVertices, used by no face
  std::uint64_t emptyFaces = 0;      ///< faces with no corners, dropped (assimp_guards.hpp)
  std::vector<SnapshotMesh> meshes;
  std::vector<SnapshotNode> nodes;  ///< empty when the scene has no root
  std::vector<AssimpMessage> messages;
  std::size_t unkeptMessages = 0;
};

/// Reads the file into `importer` with the post-processing flags given.
using AssimpRead = std::function<const aiScene*(Assimp::Importer& importer, unsigned flags)>;

/// Reads, validates, guards (assimp_guards.hpp) and post-processes the file in this process.
/// `postProcess` is the post-processing done after validation.
AssimpSnapshot takeAssimpSnapshot(const AssimpRead& read, unsigned postProcess);

/// takeAssimpSnapshot() in a forked child (in this process in a ThreadSanitizer build, without
/// the limits: the .cpp says why), within `limits`:
/// - memory: the child may map at most importMemoryBytes(limits) beyond what it started with
///   (RLIMIT_AS), so an allocation past it fails inside assimp instead of taking the machine's
///   memory;
/// - time: the child that has not answered within limits.maxSeconds is killed (SIGKILL).
///
/// Throws softbake::Error starting with `file` when the child went past either limit (the message
/// names the limit and how to raise it), was killed by the system (most likely for lack of
/// memory), died otherwise (a crash inside assimp), or sent back less than a whole snapshot.
///
/// For the tests, two environment variables, read by the child only, act before it reads: it waits
/// as many seconds as SOFTBAKE_TEST_IMPORT_STALL_SECONDS says, and maps as many MiB as
/// SOFTBAKE_TEST_IMPORT_ALLOCATE_MIB says (in blocks of 64 MiB, untouched): an import past its
/// time or memory limit without a file that takes that long or that much.
AssimpSnapshot takeAssimpSnapshotInChild(const AssimpRead& read, unsigned postProcess,
                                         const std::string& file, const ImportLimits& limits = {});

/// The byte form the child sends through a pipe, written to and read from a file descriptor as it
/// goes, so neither side holds a second copy of a big mesh. writeAssimpSnapshot() returns false
/// when the descriptor takes no more; readAssimpSnapshot() throws std::runtime_error for bytes
/// that end early or do not fit together.
bool writeAssimpSnapshot(int fd, const AssimpSnapshot& snapshot);
AssimpSnapshot readAssimpSnapshot(int fd);

}  // namespace softbake
