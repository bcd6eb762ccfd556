#pragma once
/// OpenVDB sequences for Houdini, Blender and volume renderers: OUT/vdb/<scene>_0001.vdb, one file
/// per frame, holding for every body
///
///   surface   FloatGrid, class level set: narrow-band signed distance of the deformed mesh
///   density   FloatGrid, class fog volume (VdbOptions::fog): the level set through sdfToFogVolume
///   vel       Vec3SGrid, vector_type "contravariant relative" (what Houdini reads as velocity):
///             the surface velocity on the level set's active voxels, for motion blur
///
/// prefixed "<body>_" when the scene has several bodies, plus `contacts`, a PointDataGrid with
/// position, `N` (normal, Vec3f) and `body` (int: index of the contact's surface A) when the frame
/// has contacts. Every grid and the file carry the metadata frame (int), time (s), fps, scene,
/// softbake_version and units.
///
/// Open bodies (Body::closed false) have no inside, so a signed distance would be meaningless:
/// they are written as an unsigned distance field named `surface_udf` (`<body>_surface_udf`),
/// grid class unknown, with their `vel` but without `density`. A distinct name rather than a
/// skipped body keeps cloth visible for collisions and effects, and no importer mistakes the
/// all-positive field for a level set with nothing inside.
///
/// The grid transform is a plain scale by the voxel size, so world space is exactly the OBJ
/// frame's space (after the optional y-up to z-up rotation, applied to positions, velocities and
/// normals alike).

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/scene/scene_topology.hpp"
#include "output/frame.hpp"
#include "output/frame_naming.hpp"
#include "output/manifest.hpp"

namespace softbake {

class MeshLevelSet;

struct VdbOptions {
  /// World units per voxel. 0: automatic, half the mean edge length of the bodies at rest. Finer
  /// voxels add nothing the triangles do not have, while at half an edge every triangle covers a
  /// few voxels, so small and large bodies both keep their shape; the size follows the mesh, not
  /// the scene's extent.
  double voxelSize = 0;
  double bandWidth = 3;  ///< half width of the narrow band, in voxels, on each side; at least 1
  bool fog = false;      ///< also write `density`, a fog volume of each closed body
  bool velocity = true;  ///< write `vel`; needs Frame::velocities
  bool contacts = true;  ///< write `contacts` for frames that have some
  enum class Compression { Blosc, Zip, None };
  /// Blosc is faster, zip is read by every OpenVDB build. Blosc fails validate() when this
  /// OpenVDB was built without it (bloscAvailable()).
  Compression compression = Compression::Zip;
  /// 'y' (as the simulation, OBJ and Houdini) or 'z' (Blender's VDB import, which does not rotate
  /// as its OBJ import does): (x, y, z) -> (x, -z, y).
  char upAxis = 'y';
  double fps = 24;                ///< recorded in the metadata
  std::string units = "m";        ///< recorded in the metadata
  std::uint64_t memoryLimit = 0;  ///< bytes the grids of one frame may take; 0: half the RAM
};

/// Whether this OpenVDB build can write Blosc-compressed files.
bool bloscAvailable();

/// The automatic voxel size: half the mean triangle edge length of every body, at rest.
double autoVoxelSize(const SceneTopology& topology);

/// Throws softbake::Error, before any work, for a voxel size <= 0 (when given) or not finite, a
/// band narrower than 1 voxel, an up axis other than 'y'/'z', Blosc without Blosc, or when the
/// estimated narrow-band voxels of the bodies at rest (surface area / voxel² × (2·band + 1))
/// would take more than the memory limit; the message gives the numbers and the voxel size that
/// would fit.
void validate(const VdbOptions& options, const SceneTopology& topology);

class VdbSequenceWriter : public FrameSink {
 public:
  /// Validates `options`, copies what it needs from `topology` (which may be destroyed
  /// afterwards) and creates OUT/vdb. Throws softbake::Error.
  VdbSequenceWriter(const SceneTopology& topology, const std::filesystem::path& outputDirectory,
                    std::string scene, VdbOptions options, int framePadding = 4);

  /// Builds every grid of the frame and writes the file through a temporary name. Throws
  /// softbake::Error for a frame without velocities when they are asked for, a position,
  /// velocity, contact or time that is not finite (naming the file and the value), or a failed
  /// write; no file is left behind for that frame.
  void write(const Frame& frame) override;
  const char* name() const override { return "vdb"; }
  std::uint64_t bytesWritten() const override { return bytes_.load(std::memory_order_relaxed); }

  std::filesystem::path framePath(int frameNumber) const;
  OutputSequence sequence() const;
  double voxelSize() const { return voxelSize_; }
  /// Grid name of `kind` ("surface", "vel", ...) for body `body`.
  std::string gridName(std::size_t body, const std::string& kind) const;

 private:
  struct BodyData {
    std::string name;  ///< sanitized: letters, digits and '_'
    Index firstParticle = 0, particleCount = 0;
    std::shared_ptr<const MeshLevelSet> levelSet;  ///< its triangles (body-local) and closedness
  };

  std::filesystem::path outputDirectory_;
  FrameNaming naming_;
  VdbOptions options_;
  double voxelSize_ = 0;
  std::vector<BodyData> bodies_;
  std::size_t particleCount_ = 0;
  std::atomic<std::uint64_t> bytes_{0};
};

}  // namespace softbake
