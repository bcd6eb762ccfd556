#pragma once
/// What the renderer's test programs share: decoded images, and a renderer that skips the test
/// only where the machine has no EGL display at all.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/frame_renderer.hpp"

namespace softbake::test {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  const std::uint8_t* at(int x, int y) const {
    return &rgb[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3];
  }
};

/// Whether a pixel shows the default contact colour (defaultContactColor(), a saturated red),
/// shaded or seen through a translucent body: red well above green and blue. No body of the
/// palette's first colours, the ground, the grid or the background passes.
inline bool showsContactColor(const std::uint8_t* p) {
  return p[0] >= 100 && int(p[0]) - int(std::max(p[1], p[2])) >= 60;
}

/// Throws std::runtime_error when stb_image cannot decode it.
Image decodePng(const std::string& png);

/// Set in CI (.ci/run), which has Mesa's llvmpipe: there, no EGL display fails the test too, so
/// a CI whose renderer tests all skip cannot pass.
bool eglDisplayRequired();

/// A renderer, or null with the reason when this machine has no EGL display at all: nothing can
/// render here, and the tests skip (unless eglDisplayRequired()). Every other failure (a display
/// without OpenGL 3.3, a shader the driver rejects, a framebuffer it refuses) is thrown and fails
/// the test.
std::unique_ptr<FrameRenderer> makeRenderer(const std::shared_ptr<const SceneTopology>& world,
                                            const RenderOptions& options, std::string& whyNot);

}  // namespace softbake::test

#define MAKE_RENDERER_OR_SKIP(name, world, options)                    \
  std::string whyNot_;                                                 \
  auto name = ::softbake::test::makeRenderer(world, options, whyNot_); \
  if (!name) {                                                         \
    GTEST_SKIP() << "no EGL display: " << whyNot_;                     \
  }                                                                    \
  static_assert(true)
