#include "tests/render/render_support.hpp"

#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include <cstdlib>
#include <stdexcept>
#include <string_view>

#include "render/egl_context.hpp"

namespace softbake::test {

Image decodePng(const std::string& png) {
  Image image;
  int channels = 0;
  stbi_uc* data = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(png.data()),
                                        int(png.size()), &image.width, &image.height, &channels, 3);
  if (!data) throw std::runtime_error("stb_image could not decode the PNG");
  image.rgb.assign(data, data + std::size_t(image.width) * std::size_t(image.height) * 3);
  stbi_image_free(data);
  return image;
}

bool eglDisplayRequired() {
  const char* value = std::getenv("SOFTBAKE_REQUIRE_EGL");
  return value != nullptr && std::string_view(value) == "1";
}

std::unique_ptr<FrameRenderer> makeRenderer(const std::shared_ptr<const SceneTopology>& world,
                                            const RenderOptions& options, std::string& whyNot) {
  try {
    return std::make_unique<FrameRenderer>(makeRenderScene(world, options), options);
  } catch (const EglDisplayUnavailable& error) {
    if (eglDisplayRequired()) throw;
    whyNot = error.what();
    return nullptr;
  }
}

}  // namespace softbake::test
