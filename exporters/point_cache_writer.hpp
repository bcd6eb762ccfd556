#pragma once
/// Point caches, which Blender's Mesh Cache modifier and 3ds Max's Point Cache modifier play back
/// natively: per body, every frame's positions in one file, beside a rest mesh whose vertices are
/// in the same order.
///
///   OUT/cache_mesh/<scene>_<body>.obj  the body at frame 1: `v` in particle order (the order of
///                                      the OBJ sequence's `v` lines), the file's UVs, its faces
///   OUT/pc2/<scene>_<body>.pc2         PC2, little-endian: char[12] "POINTCACHE2\0", int32 version
///                                      1, int32 points, float32 start frame, float32 sample rate
///                                      (frames per sample, 1), int32 samples; then per sample the
///                                      points' x, y, z as float32
///   OUT/mdd/<scene>_<body>.mdd         MDD, big-endian: int32 frames, int32 points, float32 time
///   of
///                                      each frame (s), then per frame the points' x, y, z, float32
///
/// The files are streamed: the header, with the run's frame count, then each frame appended to a
/// temporary file as it arrives; finish() renames the file into place once every frame is in, so a
/// cache is never held whole in memory and a stopped run leaves no part-written cache under its
/// name. Frames must arrive in
/// order, from the first: a resumed or exported run feeds them from the simulation cache.

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/scene/scene_topology.hpp"
#include "output/frame.hpp"

namespace softbake {

enum class PointCacheFormat { Pc2, Mdd };

/// One body's files, relative to the output directory.
struct PointCacheFiles {
  std::string body;
  std::string restMesh;  ///< "cache_mesh/default_ballA.obj"
  std::string cache;     ///< "pc2/default_ballA.pc2"
};

/// The file stem of each body, `<scene>_<body>` with every character other than letters, digits,
/// '.', '-' and '_' replaced by '_', made unique.
std::vector<std::string> pointCacheStems(const SceneTopology& topology, const std::string& scene);

/// Writes every body's rest mesh, OUT/cache_mesh/<stem>.obj, at `topology`'s initial state, in
/// `upAxis` ('y' as simulated, or 'z': x, −z, y). Throws softbake::Error naming the file.
void writeRestMeshes(const SceneTopology& topology, const std::filesystem::path& outputDirectory,
                     const std::string& scene, char upAxis);

class PointCacheWriter : public FrameSink {
 public:
  /// Creates OUT/pc2 or OUT/mdd. The caches will hold `frames` frames at `fps`, in `upAxis`.
  PointCacheWriter(std::shared_ptr<const SceneTopology> topology,
                   const std::filesystem::path& outputDirectory, std::string scene,
                   PointCacheFormat format, int frames, double fps, char upAxis);
  ~PointCacheWriter() override;

  /// Appends the frame to every body's cache. Throws softbake::Error naming the file for a frame
  /// out of order, a position that is not finite, or a failed write.
  void write(const Frame& frame) override;
  /// With every frame written, completes the headers and renames the files into place; with
  /// fewer (a stopped run), removes the temporary files.
  void finish() override;
  const char* name() const override { return format_ == PointCacheFormat::Pc2 ? "pc2" : "mdd"; }
  std::uint64_t bytesWritten() const override { return bytes_.load(std::memory_order_relaxed); }

  /// Per body, its rest mesh and its cache, relative to the output directory.
  std::vector<PointCacheFiles> files() const;

 private:
  struct Stream {
    std::filesystem::path path, temporary;
    std::FILE* file = nullptr;
  };
  void closeAndRemoveTemporaries();

  std::shared_ptr<const SceneTopology> topology_;
  std::filesystem::path outputDirectory_;
  PointCacheFormat format_;
  int frames_;
  double fps_;
  char upAxis_;
  std::vector<std::string> stems_;
  std::vector<Stream> streams_;  ///< per body, opened by the first frame
  int nextFrame_ = 1;
  std::vector<float> buffer_;  ///< one body's frame, in file order
  std::atomic<std::uint64_t> bytes_{0};
};

}  // namespace softbake
