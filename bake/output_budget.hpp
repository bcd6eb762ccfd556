#pragma once
/// A bound on what a run may write, checked before any work starts, so that a scene asking for a
/// million frames of a million faces ends in a clear error instead of a full disk hours later.

#include <cstdint>

#include "importers/scene_file.hpp"

namespace softbake {

/// Roughly what one frame of `scene` takes on disk, from what its outputs measured on the
/// built-in scene: OBJ about 80 bytes a vertex and 50 a triangle, VDB about 100 a triangle at the
/// default voxel size, PNG about a byte a pixel.
double estimatedFrameBytes(const SceneFile& scene, int pngWidth, int pngHeight);

/// Throws softbake::Error naming the scene when its frames times estimatedFrameBytes() is above
/// `maxBytes`, saying how to raise it (--max-output-gib).
void requireOutputWithin(const SceneFile& scene, int pngWidth, int pngHeight, double maxBytes);

}  // namespace softbake
