#pragma once
/// Overlaps simulation with writing: the simulation thread fills pooled frame buffers while every
/// sink writes earlier frames on a thread of its own.
///
///   simulation: acquire() -> fill -> submit() --+--> sink 0 thread: write(1), write(2), ...
///                  ^                            +--> sink 1 thread: write(1), ...
///                  +-- a buffer returns to the pool when the last sink is done with it
///
/// The pool is the only memory: `depth` frames sized once, so a run of any length allocates
/// nothing per frame, and a slow disk holds the simulation back (acquire() blocks) instead of
/// queueing frames until memory runs out.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "output/frame.hpp"

namespace softbake {

class FramePipeline {
 public:
  /// Starts one thread per sink. `depth` (at least 1) frame buffers of `particleCount` positions
  /// each: 2 already overlaps one frame of simulation with one of writing, 3 absorbs jitter.
  FramePipeline(std::vector<std::unique_ptr<FrameSink>> sinks, std::size_t particleCount,
                std::size_t depth = 3);
  /// Stops the threads after the frame each is writing, without finishing the sinks: frames not
  /// yet written are dropped. Call finish() for a complete run.
  ~FramePipeline();
  FramePipeline(const FramePipeline&) = delete;
  FramePipeline& operator=(const FramePipeline&) = delete;

  /// A free frame buffer to fill; its positions already have `particleCount` entries (keep that
  /// size). Blocks while every buffer is queued or being written. Throws softbake::Error when a
  /// sink has failed or after finish().
  Frame& acquire();
  /// Queues a frame from acquire() for every sink, in submission order. Throws softbake::Error
  /// when a sink has failed, after finish(), or for a frame that is not from acquire().
  void submit(Frame& frame);
  /// Waits for every sink to write every submitted frame, then calls their finish(). Throws
  /// softbake::Error, naming the sink, when one failed at any point of the run.
  void finish();

  std::size_t depth() const { return frames_.size(); }
  std::size_t sinkCount() const { return workers_.size(); }
  const FrameSink& sink(std::size_t index) const { return *workers_[index]->sink; }
  /// Frames sink `index` has written (or skipped, by the frame's sinkMask) so far. Safe to call
  /// from any thread.
  std::uint64_t framesWritten(std::size_t index) const;
  /// Bytes all sinks have written so far. Safe to call from any thread.
  std::uint64_t bytesWritten() const;
  /// Calls of acquire() that found every buffer out and had to wait for a sink. Safe to call from
  /// any thread: how a test knows the producer is held back without waiting for it a while.
  std::uint64_t acquireWaits() const { return acquireWaits_; }

 private:
  enum class SlotState { Free, Filling, Queued };
  struct Worker {
    std::unique_ptr<FrameSink> sink;
    std::size_t index = 0;  ///< its bit in Frame::sinkMask
    std::thread thread;
    std::atomic<std::uint64_t> framesWritten{0};
  };

  void run(Worker& worker);
  /// Records the first failure and stops every thread. Takes the lock.
  void fail(const Worker& worker, std::exception_ptr error);
  /// Throws the recorded failure, if any; the caller holds the lock.
  void throwIfFailed() const;
  void stopAndJoin();

  std::vector<Frame> frames_;  ///< the pool; never resized after construction
  std::size_t particleCount_;
  std::vector<std::unique_ptr<Worker>> workers_;
  std::atomic<std::uint64_t> acquireWaits_{0};

  std::mutex mutex_;
  std::condition_variable queued_;  ///< sinks wait here for frames (or for the end)
  std::condition_variable freed_;   ///< the producer waits here for a free buffer
  // Everything below is guarded by mutex_.
  std::vector<SlotState> state_;
  std::vector<std::size_t> pendingSinks_;  ///< per slot: sinks yet to write it
  std::vector<std::size_t> freeSlots_;     ///< a stack; capacity reserved for every slot
  /// Slot of submitted frame `s` at [s % depth]. A sink reads entry s before frame s can be
  /// released, and only `depth` frames are ever out, so no entry is overwritten while needed.
  std::vector<std::size_t> order_;
  std::uint64_t submitted_ = 0;
  bool finishing_ = false;
  bool stopping_ = false;
  std::string failure_;        ///< the first sink failure's message; empty while all is well
  bool outputFailed_ = false;  ///< that failure was an OutputFailure: rethrown as one
};

}  // namespace softbake
