#include "render/png_sequence_renderer.hpp"

#include "exporters/atomic_file.hpp"

namespace softbake {

PngSequenceRenderer::PngSequenceRenderer(const World& world,
                                         const std::filesystem::path& outputDirectory,
                                         std::string scene, RenderOptions options, int framePadding)
    : outputDirectory_(outputDirectory),
      naming_{"png", std::move(scene), ".png", framePadding},
      scene_(makeRenderScene(world, options)),
      options_(std::move(options)) {
  makeDirectories(outputDirectory_ / naming_.folder);
}

// Out of line: FrameRenderer is complete here. When finish() did not run (a failed run), the
// renderer is destroyed on this thread; its GL objects go with the context.
PngSequenceRenderer::~PngSequenceRenderer() = default;

void PngSequenceRenderer::write(const Frame& frame) {
  if (!renderer_) renderer_ = std::make_unique<FrameRenderer>(scene_, options_);
  bytes_.fetch_add(renderer_->writePng(frame, framePath(frame.number)), std::memory_order_relaxed);
}

void PngSequenceRenderer::finish() {
  renderer_.reset();
}

std::filesystem::path PngSequenceRenderer::framePath(int frameNumber) const {
  return outputDirectory_ / naming_.relativePath(frameNumber);
}

OutputSequence PngSequenceRenderer::sequence() const {
  return {"png", naming_.pattern(), naming_.printfPattern(), {}};
}

}  // namespace softbake
