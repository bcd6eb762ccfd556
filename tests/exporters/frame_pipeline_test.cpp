#include "output/frame_pipeline.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>

#include "core/error.hpp"
#include "exporters/obj_sequence_writer.hpp"
#include "test_world.hpp"

namespace softbake {
namespace {

using test::listDirectory;
using test::makeBallsTopology;
using test::ScratchDirectory;

/// What a sink saw, kept outside it because the pipeline owns the sink.
struct Record {
  std::vector<int> numbers;
  std::vector<bool> contentMatched;  ///< every position carried the frame's number
  int finishCalls = 0;
  std::thread::id writeThread, finishThread;
};

class RecordingSink : public FrameSink {
 public:
  RecordingSink(Record& record, int failAt = 0) : record_(record), failAt_(failAt) {}
  void write(const Frame& frame) override {
    if (frame.number == failAt_) throw Error("disk full");
    record_.numbers.push_back(frame.number);
    bool matched = true;
    for (const Vec3& p : frame.positions) matched = matched && p.x() == Scalar(frame.number);
    record_.contentMatched.push_back(matched);
    record_.writeThread = std::this_thread::get_id();
  }
  void finish() override {
    ++record_.finishCalls;
    record_.finishThread = std::this_thread::get_id();
  }
  const char* name() const override { return failAt_ ? "failing" : "recording"; }
  std::uint64_t bytesWritten() const override { return 10; }

 private:
  Record& record_;
  int failAt_;
};

/// A gate the test opens, and what went through it; kept outside the sink, which the pipeline
/// owns and destroys.
class Gate {
 public:
  void open() {
    {
      std::lock_guard lock(mutex_);
      open_ = true;
    }
    opened_.notify_all();
  }
  std::vector<int> numbers() {
    std::lock_guard lock(mutex_);
    return numbers_;
  }
  int finishCalls() {
    std::lock_guard lock(mutex_);
    return finishCalls_;
  }
  /// Waits until a write is held at the gate.
  void waitForAWrite() {
    std::unique_lock lock(mutex_);
    arrived_.wait(lock, [&] { return waiting_ > 0; });
  }

 private:
  friend class GateSink;
  std::mutex mutex_;
  std::condition_variable opened_, arrived_;
  int waiting_ = 0;
  bool open_ = false;
  std::vector<int> numbers_;
  int finishCalls_ = 0;
};

/// Blocks every write until the test opens its gate: a disk that is as slow as the test wants.
class GateSink : public FrameSink {
 public:
  explicit GateSink(Gate& gate) : gate_(gate) {}
  void write(const Frame& frame) override {
    std::unique_lock lock(gate_.mutex_);
    ++gate_.waiting_;
    gate_.arrived_.notify_all();
    gate_.opened_.wait(lock, [&] { return gate_.open_; });
    --gate_.waiting_;
    gate_.numbers_.push_back(frame.number);
  }
  void finish() override {
    std::lock_guard lock(gate_.mutex_);
    ++gate_.finishCalls_;
  }
  const char* name() const override { return "gate"; }

 private:
  Gate& gate_;
};

void fill(Frame& frame, int number) {
  frame.number = number;
  frame.time = number / 24.0;
  for (Vec3& p : frame.positions) p = Vec3::Constant(Scalar(number));
}

std::vector<std::unique_ptr<FrameSink>> sinks(std::unique_ptr<FrameSink> a,
                                              std::unique_ptr<FrameSink> b = nullptr) {
  std::vector<std::unique_ptr<FrameSink>> list;
  list.push_back(std::move(a));
  if (b) list.push_back(std::move(b));
  return list;
}

TEST(FramePipeline, EverySinkSeesEveryFrameInOrder) {
  Record first, second;
  constexpr int kFrames = 60;
  {
    FramePipeline pipeline(
        sinks(std::make_unique<RecordingSink>(first), std::make_unique<RecordingSink>(second)), 100,
        3);
    for (int n = 1; n <= kFrames; ++n) {
      Frame& frame = pipeline.acquire();
      ASSERT_EQ(frame.positions.size(), 100u);
      fill(frame, n);
      pipeline.submit(frame);
    }
    pipeline.finish();
    EXPECT_EQ(pipeline.framesWritten(0), std::uint64_t(kFrames));
    EXPECT_EQ(pipeline.framesWritten(1), std::uint64_t(kFrames));
    EXPECT_EQ(pipeline.bytesWritten(), 20u);
    EXPECT_STREQ(pipeline.sink(1).name(), "recording");
  }
  std::vector<int> expected(kFrames);
  for (int n = 1; n <= kFrames; ++n) expected[std::size_t(n - 1)] = n;
  for (const Record* record : {&first, &second}) {
    EXPECT_EQ(record->numbers, expected);
    EXPECT_EQ(record->contentMatched, std::vector<bool>(kFrames, true));
    EXPECT_EQ(record->finishCalls, 1);
    EXPECT_NE(record->writeThread, std::this_thread::get_id());
    EXPECT_EQ(record->finishThread, record->writeThread);
  }
  EXPECT_NE(first.writeThread, second.writeThread);
}

TEST(FramePipeline, SlowSinkHoldsTheProducerBackWithoutNewBuffers) {
  constexpr std::size_t kDepth = 2;
  constexpr int kFrames = 10;
  Gate gate;
  FramePipeline pipeline(sinks(std::make_unique<GateSink>(gate)), 50, kDepth);

  std::atomic<int> submitted{0};
  std::atomic<bool> produced{false};
  std::set<const Frame*> frames;
  std::set<const Vec3*> buffers;
  std::thread producer([&] {
    for (int n = 1; n <= kFrames; ++n) {
      Frame& frame = pipeline.acquire();
      frames.insert(&frame);
      buffers.insert(frame.positions.data());
      fill(frame, n);
      pipeline.submit(frame);
      ++submitted;
    }
    produced = true;
  });
  // Every buffer is queued behind the closed gate; the next acquire() must wait for the sink.
  // A pipeline that handed out another buffer would let the producer run to its end instead.
  while (pipeline.acquireWaits() == 0 && !produced) std::this_thread::yield();
  EXPECT_EQ(pipeline.acquireWaits(), 1u);
  EXPECT_EQ(submitted.load(), int(kDepth));
  EXPECT_EQ(pipeline.framesWritten(0), 0u);

  gate.open();
  producer.join();
  pipeline.finish();
  std::vector<int> expected(kFrames);
  for (int n = 1; n <= kFrames; ++n) expected[std::size_t(n - 1)] = n;
  EXPECT_EQ(gate.numbers(), expected);
  EXPECT_EQ(frames.size(), kDepth);
  EXPECT_EQ(buffers.size(), kDepth);
}

TEST(FramePipeline, SinkErrorSurfacesOnTheProducerSideNamingTheSink) {
  Record healthy, failing;
  FramePipeline pipeline(
      sinks(std::make_unique<RecordingSink>(healthy), std::make_unique<RecordingSink>(failing, 3)),
      10, 2);
  std::string error;
  int n = 1;
  // The failure shows at the latest once the failed frame's buffer is needed again.
  for (; n <= 100 && error.empty(); ++n) {
    try {
      Frame& frame = pipeline.acquire();
      fill(frame, n);
      pipeline.submit(frame);
    } catch (const Error& e) {
      error = e.what();
    }
  }
  EXPECT_NE(error.find("writer 'failing'"), std::string::npos) << error;
  EXPECT_NE(error.find("disk full"), std::string::npos) << error;
  EXPECT_LT(n, 100);
  EXPECT_THROW(pipeline.acquire(), Error);
  EXPECT_THROW(pipeline.finish(), Error);
  EXPECT_EQ(failing.numbers, (std::vector<int>{1, 2}));
  EXPECT_EQ(failing.finishCalls, 0);
  EXPECT_EQ(healthy.finishCalls, 0);
}

TEST(FramePipeline, SinkFinishErrorIsRethrownFromFinish) {
  class FinishFails : public FrameSink {
   public:
    void write(const Frame&) override {}
    void finish() override { throw Error("cannot close the archive"); }
    const char* name() const override { return "archive"; }
  };
  FramePipeline pipeline(sinks(std::make_unique<FinishFails>()), 10, 2);
  for (int n = 1; n <= 3; ++n) {
    Frame& frame = pipeline.acquire();
    fill(frame, n);
    pipeline.submit(frame);
  }
  try {
    pipeline.finish();
    FAIL() << "expected softbake::Error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "writer 'archive': cannot close the archive");
  }
  EXPECT_EQ(pipeline.framesWritten(0), 3u);
}

TEST(FramePipeline, AFailureStopsEverySinkAfterTheFrameItIsWritingAndFinishesNone) {
  // The gate holds frame 1 in its sink while the other sink writes frames 1 and 2 and fails on
  // 3, the last of them: not before every frame is submitted, which would throw from submit().
  Record failing;
  Gate slow;
  auto pipeline = std::make_unique<FramePipeline>(
      sinks(std::make_unique<GateSink>(slow), std::make_unique<RecordingSink>(failing, 3)), 10, 3);
  for (int n = 1; n <= 3; ++n) {
    if (n == 3) slow.waitForAWrite();  // frame 1 is being written when the failure comes
    Frame& frame = pipeline->acquire();
    fill(frame, n);
    pipeline->submit(frame);
  }
  // Every buffer is out, so acquire() returns only through the failure, which has stopped the
  // threads by the time it is seen.
  EXPECT_THROW(pipeline->acquire(), Error);
  slow.open();
  pipeline.reset();
  EXPECT_EQ(slow.numbers(), std::vector<int>{1}) << "frames 2 and 3 are dropped, not written";
  EXPECT_EQ(slow.finishCalls(), 0);
  EXPECT_EQ(failing.numbers, (std::vector<int>{1, 2}));
  EXPECT_EQ(failing.finishCalls, 0);
}

TEST(FramePipeline, DestructorWithoutFinishStopsTheThreadsAndFinishesNoSink) {
  Record idle, busy;
  {
    // No frame at all: the threads are waiting for one when the destructor comes.
    FramePipeline pipeline(sinks(std::make_unique<RecordingSink>(idle)), 10);
    EXPECT_EQ(pipeline.depth(), 3u);
  }
  EXPECT_TRUE(idle.numbers.empty());
  EXPECT_EQ(idle.finishCalls, 0) << "the destructor is an abort, not finish()";
  {
    // Frames written, then the destructor instead of finish(): still no finish() on the sink.
    FramePipeline pipeline(sinks(std::make_unique<RecordingSink>(busy)), 10, 2);
    for (int n = 1; n <= 2; ++n) {
      Frame& frame = pipeline.acquire();
      fill(frame, n);
      pipeline.submit(frame);
    }
    while (pipeline.framesWritten(0) < 2) std::this_thread::yield();
  }
  EXPECT_EQ(busy.numbers, (std::vector<int>{1, 2}));
  EXPECT_EQ(busy.finishCalls, 0);
}

TEST(FramePipeline, RejectsFramesItDidNotHandOut) {
  Record record;
  FramePipeline pipeline(sinks(std::make_unique<RecordingSink>(record)), 10);
  Frame foreign;
  foreign.positions.resize(10);
  EXPECT_THROW(pipeline.submit(foreign), Error);
  Frame& frame = pipeline.acquire();
  fill(frame, 1);
  pipeline.submit(frame);
  EXPECT_THROW(pipeline.submit(frame), Error);  // already queued
  pipeline.finish();
  EXPECT_THROW(pipeline.acquire(), Error);
  EXPECT_EQ(record.numbers, std::vector<int>{1});
}

TEST(FramePipeline, RunsWithoutSinksHandingTheSameBufferBackAtOnce) {
  // With nobody to write it, a submitted frame is free again at once: one buffer serves every
  // frame, where a frame kept queued would leave the second acquire() waiting.
  FramePipeline pipeline({}, 5, 1);
  EXPECT_EQ(pipeline.sinkCount(), 0u);
  const Frame* first = nullptr;
  for (int n = 1; n <= 3; ++n) {
    Frame& frame = pipeline.acquire();
    if (!first) first = &frame;
    EXPECT_EQ(&frame, first) << "frame " << n;
    EXPECT_EQ(frame.positions.size(), 5u);
    fill(frame, n);
    pipeline.submit(frame);
  }
  pipeline.finish();
  EXPECT_EQ(pipeline.bytesWritten(), 0u);
  EXPECT_THROW(pipeline.acquire(), Error);
}

TEST(FramePipeline, ObjWriteFailingMidRunLeavesNoPartialFile) {
  const auto world = makeBallsTopology({1.0f, 0.5f});
  ScratchDirectory dir;
  auto writer = std::make_unique<ObjSequenceWriter>(world, dir.path(), "balls");
  // Frame 3 cannot be renamed into place: the writer fails after formatting and writing it.
  const std::filesystem::path blocked = writer->framePath(3);
  std::filesystem::create_directory(blocked);
  FramePipeline pipeline(sinks(std::move(writer)), world->particleCount(), 2);

  std::string error;
  for (int n = 1; n <= 8 && error.empty(); ++n) {
    try {
      Frame& frame = pipeline.acquire();
      frame.number = n;
      std::copy(world->restPosition.begin(), world->restPosition.end(), frame.positions.begin());
      pipeline.submit(frame);
    } catch (const Error& e) {
      error = e.what();
    }
  }
  if (error.empty()) {
    try {
      pipeline.finish();
    } catch (const Error& e) {
      error = e.what();
    }
  }
  EXPECT_NE(error.find("writer 'obj'"), std::string::npos) << error;
  EXPECT_NE(error.find(blocked.string()), std::string::npos) << error;
  EXPECT_EQ(listDirectory(dir.path() / "obj"),
            (std::vector<std::string>{"balls.mtl", "balls_0001.obj", "balls_0002.obj",
                                      "balls_0003.obj"}));
  EXPECT_TRUE(std::filesystem::is_directory(blocked));
  EXPECT_EQ(pipeline.framesWritten(0), 2u);
  std::uint64_t onDisk = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path() / "obj"))
    if (entry.is_regular_file()) onDisk += entry.file_size();
  EXPECT_EQ(pipeline.bytesWritten(), onDisk);
}

}  // namespace
}  // namespace softbake
