#pragma once
/// A simulated frame handed from the simulation thread to the writers.

#include <cstdint>
#include <vector>

#include "core/checkpoint.hpp"
#include "core/collision/contact.hpp"
#include "core/types.hpp"

namespace softbake {

struct Frame {
  int number = 1;                 ///< 1-based: frame 1 is the initial state
  double time = 0;                ///< seconds since the start
  std::vector<Vec3> positions;    ///< every particle of the scene, global order
  std::vector<Vec3> velocities;   ///< m/s, same order as positions (the VDB `vel` grids)
  std::vector<Contact> contacts;  ///< the contacts of the frame's last substep
  /// Sinks that write this frame, by their index in the FramePipeline: a resumed run writes only
  /// the files that are missing.
  std::uint64_t sinkMask = ~std::uint64_t(0);
  /// Set on the frames the simulation cache keeps a checkpoint of (its memory reused).
  bool hasCheckpoint = false;
  SimulationCheckpoint checkpoint;
};

/// A writer of frames, run on a thread of its own by FramePipeline. Implementations write each file
/// to a temporary name and rename it, so a killed run never leaves a torn frame.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  /// Called once per frame, in frame order, from the sink's own thread. Throws softbake::Error.
  virtual void write(const Frame& frame) = 0;
  /// Called once after the last frame, from the sink's own thread.
  virtual void finish() {}
  /// Short name for messages: "obj".
  virtual const char* name() const = 0;
  /// Bytes written to disk so far, for the progress display. Called from other threads while
  /// write() runs, so implementations keep it in an atomic.
  virtual std::uint64_t bytesWritten() const { return 0; }
};

}  // namespace softbake
