#pragma once
/// A FrameSink that renders every frame to OUT/png/<scene>_0001.png (the OBJ sequence's naming).
///
/// The EGL context belongs to the thread that renders: the sink is constructed on the main thread
/// but FramePipeline calls write() from the sink's own thread, so the context and every GL object
/// are created by the first write(), and the simulation never waits for a frame to render. Each
/// frame's PNG encoding and file write run on a helper thread while the next frame renders, so a
/// frame costs the longer of the two, not their sum; an error there surfaces from the next
/// write() or from finish().

#include <atomic>
#include <filesystem>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "core/scene/scene_topology.hpp"
#include "output/frame.hpp"
#include "output/frame_naming.hpp"
#include "output/manifest.hpp"
#include "render/frame_renderer.hpp"
#include "render/png_encoder.hpp"

namespace softbake {

class PngSequenceRenderer : public FrameSink {
 public:
  /// Keeps `topology` (its rest positions, the initial state, frame the camera). Creates
  /// OUT/png. Throws softbake::Error; EGL errors come from the first write().
  PngSequenceRenderer(std::shared_ptr<const SceneTopology> topology,
                      const std::filesystem::path& outputDirectory, std::string scene,
                      RenderOptions options = {}, int framePadding = 4);
  ~PngSequenceRenderer() override;

  /// Throws softbake::Error naming the PNG for a position or contact that is not finite; nothing
  /// is rendered or written for that frame.
  void write(const Frame& frame) override;
  /// Releases the context and the GL objects on the rendering thread.
  void finish() override;
  const char* name() const override { return "png"; }
  std::uint64_t bytesWritten() const override { return bytes_.load(std::memory_order_relaxed); }

  std::filesystem::path framePath(int frameNumber) const;
  OutputSequence sequence() const;
  /// The camera, fixed for the whole sequence.
  const Camera& camera() const { return scene_.camera; }

 private:
  std::filesystem::path outputDirectory_;
  FrameNaming naming_;
  RenderScene scene_;
  RenderOptions options_;
  /// Adds the pending frame's bytes once its encoding is done; rethrows its error.
  void collectPending();

  std::unique_ptr<FrameRenderer> renderer_;  ///< made by the first write(), on its thread
  std::future<std::uint64_t> pending_;       ///< the previous frame's encoding and write
  /// Used by one encoding at a time (each waits for the one before), on its thread.
  PngEncoder encoder_;
  std::atomic<std::uint64_t> bytes_{0};
};

}  // namespace softbake
