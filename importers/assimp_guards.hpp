#pragma once
/// What softbake does to a scene between assimp's loader and its post-processing, against bugs in
/// assimp 5.2 that fuzzing found (fuzz/README.md lists each with its input). A debug assertion or
/// a crash inside assimp takes the whole process down, so these run before the step that would
/// trip over them, and turn the file into a clear error or a good import instead.

#include <cstddef>

struct aiScene;

namespace softbake {

/// Removes faces with no corners and returns how many there were. A PLY face list of length 0
/// comes through validation, and the Triangulate step asserts on it, aborting the process.
std::size_t dropEmptyFaces(const aiScene& scene);

/// Sets each mesh's primitive-type flags from its faces. Loaders set them from what the file
/// declares (PLY) or leave stale ones, and the Triangulate step asserts, aborting the process,
/// when a mesh flagged as holding polygons holds none.
void matchPrimitiveTypesToFaces(const aiScene& scene);

}  // namespace softbake
