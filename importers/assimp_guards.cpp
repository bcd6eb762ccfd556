#include "importers/assimp_guards.hpp"

#include <assimp/mesh.h>
#include <assimp/scene.h>

namespace softbake {

std::size_t dropEmptyFaces(const aiScene& scene) {
  std::size_t dropped = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    aiMesh& mesh = *scene.mMeshes[m];
    unsigned kept = 0;
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      if (mesh.mFaces[f].mNumIndices == 0) continue;
      // aiFace's assignment copies the indices; the faces left past mNumFaces are still freed
      // with the array.
      if (kept != f) mesh.mFaces[kept] = mesh.mFaces[f];
      ++kept;
    }
    dropped += mesh.mNumFaces - kept;
    mesh.mNumFaces = kept;
  }
  return dropped;
}

void matchPrimitiveTypesToFaces(const aiScene& scene) {
  constexpr unsigned kFaceTypes = aiPrimitiveType_POINT | aiPrimitiveType_LINE |
                                  aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    aiMesh& mesh = *scene.mMeshes[m];
    unsigned types = 0;
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const unsigned corners = mesh.mFaces[f].mNumIndices;
      types |= corners == 1   ? aiPrimitiveType_POINT
               : corners == 2 ? aiPrimitiveType_LINE
               : corners == 3 ? aiPrimitiveType_TRIANGLE
                              : aiPrimitiveType_POLYGON;
    }
    mesh.mPrimitiveTypes = (mesh.mPrimitiveTypes & ~kFaceTypes) | types;
  }
}

}  // namespace softbake
