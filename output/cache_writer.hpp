#pragma once
/// OUT/cache/: the simulation cache, the record of a run that `--resume` continues from and
/// `softbake export` writes outputs from.
///
///   cache/<scene>_0001.sbframe        every frame: positions, velocities, contacts (cache_format)
///   cache/<scene>_0017.sbcheckpoint   every N frames: the exact state to continue from
///   cache/index.json                  written when the run completes: what the cache holds
///
/// Every file is fsync'ed before it is renamed into place, so a file found in the cache after a
/// kill or a power cut is whole; its checksum says so again when it is read.

#include <atomic>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "output/cache_format.hpp"
#include "output/frame.hpp"
#include "output/frame_naming.hpp"
#include "output/manifest.hpp"

namespace softbake {

/// Where a run's cache files are, and which ones are there.
class CacheLayout {
 public:
  CacheLayout(std::filesystem::path outputDirectory, std::string scene, int framePadding);

  std::filesystem::path framePath(int frameNumber) const;
  std::filesystem::path checkpointPath(int frameNumber) const;
  std::filesystem::path indexPath() const;
  std::filesystem::path directory() const;
  const FrameNaming& frameNaming() const { return frames_; }
  const FrameNaming& checkpointNaming() const { return checkpoints_; }

  /// The checkpoint with the highest frame number at or below `frame` that reads back whole, or
  /// nothing. Damaged ones are passed over, each with a line in `skipped`.
  std::optional<DecodedCheckpoint> latestCheckpoint(int frame,
                                                    std::vector<std::string>* skipped) const;
  /// Reads frame `frameNumber` into `frame`. Throws softbake::Error naming the file when it is
  /// missing or damaged.
  void readFrame(int frameNumber, Frame& frame) const;
  /// Where the particles go over frames 1…`frames`: the union of every frame's bounds, for a
  /// camera that frames the whole shot. Throws softbake::Error naming a frame file that is missing
  /// or damaged.
  Eigen::AlignedBox3f shotBounds(int frames) const;

 private:
  std::filesystem::path outputDirectory_;
  FrameNaming frames_, checkpoints_;
};

/// The frames at which a run of `frames` frames keeps a checkpoint, every `every` frames after the
/// first (frame 1 needs none: the scene itself is that state).
bool isCheckpointFrame(int frame, int every);

/// Checkpoints every how many frames, so that they take at most a tenth of the cache: from the
/// sizes of a checkpoint and a frame record of the initial state.
int defaultCheckpointInterval(std::size_t checkpointBytes, std::size_t frameBytes);

class CacheWriter : public FrameSink {
 public:
  /// Creates OUT/cache. `frames`, `checkpointEvery` and `particles` go into the index.
  CacheWriter(const std::filesystem::path& outputDirectory, std::string scene, int framePadding,
              int frames, int checkpointEvery, std::size_t particles);

  /// Writes the frame's record, and its checkpoint when it carries one. Throws softbake::Error
  /// naming the file.
  void write(const Frame& frame) override;
  /// Writes the index.
  void finish() override;
  const char* name() const override { return "cache"; }
  std::uint64_t bytesWritten() const override { return bytes_.load(std::memory_order_relaxed); }

  const CacheLayout& layout() const { return layout_; }
  OutputSequence sequence() const;
  /// The index's JSON text, which depends on the run's shape alone: a resumed run writes the same.
  std::string indexJson() const;

 private:
  CacheLayout layout_;
  std::string scene_;
  int frames_, checkpointEvery_;
  std::size_t particles_;
  std::string buffer_;  ///< one frame's bytes, reused
  std::atomic<std::uint64_t> bytes_{0};
};

}  // namespace softbake
