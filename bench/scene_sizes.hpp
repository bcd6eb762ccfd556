#pragma once
/// The icosphere ball scenes the Google Benchmark programs share, by face count: `balls`
/// icospheres of `subdivisions` levels, 20·4^subdivisions faces each.

#include <stdexcept>
#include <string>

namespace softbake::bench {

struct SceneSize {
  int faces, subdivisions, balls;
};

inline constexpr SceneSize kSceneSizes[] = {
    {1280, 3, 1},     // ~1k
    {10240, 4, 2},    // ~10k
    {102400, 5, 5},   // ~100k
    {983040, 6, 12},  // ~1M
};

/// The scene of `faces` faces; throws std::runtime_error for a count not in kSceneSizes.
inline const SceneSize& sceneSize(int faces) {
  for (const SceneSize& size : kSceneSizes)
    if (size.faces == faces) return size;
  throw std::runtime_error("no benchmark scene of " + std::to_string(faces) + " faces");
}

}  // namespace softbake::bench
