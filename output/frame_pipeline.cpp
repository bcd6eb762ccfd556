#include "output/frame_pipeline.hpp"

#include <exception>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

FramePipeline::FramePipeline(std::vector<std::unique_ptr<FrameSink>> sinks,
                             std::size_t particleCount, std::size_t depth)
    : frames_(depth), particleCount_(particleCount) {
  if (depth == 0) throw Error("the frame pipeline needs at least one frame buffer");
  for (Frame& frame : frames_) {
    frame.positions.assign(particleCount, Vec3::Zero());
    frame.velocities.assign(particleCount, Vec3::Zero());
  }
  state_.assign(depth, SlotState::Free);
  pendingSinks_.assign(depth, 0);
  order_.assign(depth, 0);
  freeSlots_.reserve(depth);
  // Handed out lowest slot first, which makes runs easier to follow in a debugger.
  for (std::size_t slot = depth; slot-- > 0;) freeSlots_.push_back(slot);

  if (sinks.size() > 64) throw Error("the frame pipeline takes at most 64 sinks");
  for (std::unique_ptr<FrameSink>& sink : sinks) {
    if (!sink) throw Error("the frame pipeline was given an empty sink");
    workers_.push_back(std::make_unique<Worker>());
    workers_.back()->sink = std::move(sink);
    workers_.back()->index = workers_.size() - 1;
  }
  // Threads start last, once every member they read exists. A failed start must not leave
  // joinable threads behind: their destructors would terminate the program.
  try {
    for (auto& worker : workers_) worker->thread = std::thread([this, &w = *worker] { run(w); });
  } catch (...) {
    stopAndJoin();
    throw;
  }
}

FramePipeline::~FramePipeline() {
  stopAndJoin();
}

void FramePipeline::stopAndJoin() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  queued_.notify_all();
  freed_.notify_all();
  for (auto& worker : workers_)
    if (worker->thread.joinable()) worker->thread.join();
}

void FramePipeline::throwIfFailed() const {
  if (!failure_.empty() && outputFailed_) throw OutputFailure(failure_);
  if (!failure_.empty()) throw Error(failure_);
  if (finishing_) throw Error("the frame pipeline has already finished");
}

Frame& FramePipeline::acquire() {
  std::unique_lock lock(mutex_);
  const auto ready = [&] { return !freeSlots_.empty() || !failure_.empty() || finishing_; };
  if (!ready()) ++acquireWaits_;
  freed_.wait(lock, ready);
  throwIfFailed();
  const std::size_t slot = freeSlots_.back();
  freeSlots_.pop_back();
  state_[slot] = SlotState::Filling;
  return frames_[slot];
}

void FramePipeline::submit(Frame& frame) {
  // Address arithmetic is only defined within the pool, so compare before subtracting.
  const bool pooled = &frame >= frames_.data() && &frame < frames_.data() + frames_.size();
  const std::size_t slot = pooled ? std::size_t(&frame - frames_.data()) : 0;
  std::unique_lock lock(mutex_);
  if (!pooled || state_[slot] != SlotState::Filling)
    throw Error("submit() was given a frame that did not come from acquire()");
  if (frame.positions.size() != particleCount_)
    throw Error(cat("frame ", frame.number, " has ", frame.positions.size(),
                    " particle positions; the pipeline was built for ", particleCount_));
  if (!failure_.empty() || finishing_) {
    state_[slot] = SlotState::Free;
    freeSlots_.push_back(slot);
    throwIfFailed();
  }
  if (workers_.empty()) {
    state_[slot] = SlotState::Free;
    freeSlots_.push_back(slot);
    return;
  }
  state_[slot] = SlotState::Queued;
  pendingSinks_[slot] = workers_.size();
  order_[submitted_ % order_.size()] = slot;
  ++submitted_;
  lock.unlock();
  queued_.notify_all();
}

void FramePipeline::finish() {
  {
    std::lock_guard lock(mutex_);
    finishing_ = true;
  }
  queued_.notify_all();
  freed_.notify_all();
  for (auto& worker : workers_)
    if (worker->thread.joinable()) worker->thread.join();
  std::lock_guard lock(mutex_);
  if (!failure_.empty()) throwIfFailed();
}

std::uint64_t FramePipeline::framesWritten(std::size_t index) const {
  return workers_[index]->framesWritten.load(std::memory_order_relaxed);
}

std::uint64_t FramePipeline::bytesWritten() const {
  std::uint64_t bytes = 0;
  for (const auto& worker : workers_) bytes += worker->sink->bytesWritten();
  return bytes;
}

void FramePipeline::fail(const Worker& worker, std::exception_ptr error) {
  std::string reason;
  bool outputFailure = false;
  try {
    std::rethrow_exception(error);
  } catch (const OutputFailure& e) {
    reason = e.what();
    outputFailure = true;
  } catch (const std::exception& e) {
    reason = e.what();
  } catch (...) {
    reason = "unknown error";
  }
  {
    std::lock_guard lock(mutex_);
    if (failure_.empty()) {
      failure_ = cat("writer '", worker.sink->name(), "': ", reason);
      outputFailed_ = outputFailure;
    }
    stopping_ = true;
  }
  queued_.notify_all();
  freed_.notify_all();
}

void FramePipeline::run(Worker& worker) {
  std::uint64_t next = 0;  // sequence number of the next frame this sink writes
  for (;;) {
    std::size_t slot;
    {
      std::unique_lock lock(mutex_);
      queued_.wait(lock, [&] { return stopping_ || finishing_ || next < submitted_; });
      if (stopping_) return;
      if (next == submitted_) break;  // finishing, and every frame is written
      slot = order_[next % order_.size()];
    }
    // The frame is read without the lock: the producer cannot touch it until this sink releases
    // it below, and other sinks only read it.
    try {
      if ((frames_[slot].sinkMask >> worker.index) & 1) worker.sink->write(frames_[slot]);
    } catch (...) {
      fail(worker, std::current_exception());
      return;
    }
    ++next;
    worker.framesWritten.store(next, std::memory_order_relaxed);
    bool released = false;
    {
      std::lock_guard lock(mutex_);
      if (--pendingSinks_[slot] == 0) {
        state_[slot] = SlotState::Free;
        freeSlots_.push_back(slot);
        released = true;
      }
    }
    if (released) freed_.notify_all();
  }
  try {
    worker.sink->finish();
  } catch (...) {
    fail(worker, std::current_exception());
  }
}

}  // namespace softbake
