#include "render/png_sequence_renderer.hpp"

#include "core/text.hpp"
#include "output/atomic_file.hpp"
#include "output/finite_values.hpp"

namespace softbake {

PngSequenceRenderer::PngSequenceRenderer(std::shared_ptr<const SceneTopology> topology,
                                         const std::filesystem::path& outputDirectory,
                                         std::string scene, RenderOptions options, int framePadding)
    : outputDirectory_(outputDirectory),
      naming_{"png", std::move(scene), ".png", framePadding},
      scene_(makeRenderScene(std::move(topology), options)),
      options_(std::move(options)) {
  makeDirectories(outputDirectory_ / naming_.folder);
}

// Out of line: FrameRenderer is complete here. When finish() did not run (a failed run), the
// renderer is destroyed on this thread; its GL objects go with the context.
PngSequenceRenderer::~PngSequenceRenderer() {
  if (pending_.valid()) pending_.wait();  // a failed run: its error was reported elsewhere
}

void PngSequenceRenderer::collectPending() {
  if (pending_.valid()) bytes_.fetch_add(pending_.get(), std::memory_order_relaxed);
}

void PngSequenceRenderer::write(const Frame& frame) {
  // A vertex that is not finite draws as nothing or as a streak across the image, which looks
  // like a rendering bug: the frame is refused instead, as the OBJ writer refuses it.
  const std::filesystem::path path = framePath(frame.number);
  for (const Body& body : scene_.topology->bodies)
    for (Index i = 0; i < body.particleCount && body.firstParticle + i < frame.positions.size();
         ++i)
      requireFinite(path, frame.positions[body.firstParticle + i], [&] {
        return cat("frame ", frame.number, ": body '", body.name, "': the position of particle ",
                   i);
      });
  for (std::size_t i = 0; i < frame.contacts.size(); ++i)
    requireFinite(path, frame.contacts[i].position,
                  [&] { return cat("frame ", frame.number, ": the position of contact ", i); });
  if (!renderer_) renderer_ = std::make_unique<FrameRenderer>(scene_, options_);
  std::vector<std::uint8_t> rgb = renderer_->renderRgb(frame);
  // The previous frame's encoding ran while this one rendered; its error, if any, surfaces here.
  collectPending();
  pending_ = std::async(std::launch::async, [this, rgb = std::move(rgb), path] {
    const std::string png = encoder_.encode(rgb, options_.width, options_.height);
    writeFileAtomically(path, png);
    return std::uint64_t(png.size());
  });
}

void PngSequenceRenderer::finish() {
  collectPending();
  renderer_.reset();
}

std::filesystem::path PngSequenceRenderer::framePath(int frameNumber) const {
  return outputDirectory_ / naming_.relativePath(frameNumber);
}

OutputSequence PngSequenceRenderer::sequence() const {
  return {"png", naming_.pattern(), naming_.printfPattern(), {}};
}

}  // namespace softbake
