#pragma once
/// The icosphere ball scenes the Google Benchmark programs share, by face count: `balls`
/// icospheres of `subdivisions` levels, 20·4^subdivisions faces each.

#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/mesh/icosphere.hpp"
#include "core/scene/scene_setup.hpp"

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

/// Rubber balls of radius 0.5 m on a grid of 4 a row, 2 cm into the ground plane: about 2% of the
/// particles are in contact from the first substep on.
inline SceneSetup ballsScene(const SceneSize& size, std::string name = "bench") {
  const std::optional<Material> rubber = findMaterialPreset("rubber");
  if (!rubber) throw std::runtime_error("no 'rubber' material preset");
  SceneSetup scene;
  scene.name = std::move(name);
  constexpr float kRadius = 0.5f, kSpacing = 1.2f;
  for (int i = 0; i < size.balls; ++i) {
    BodySetup body;
    body.name = "ball" + std::to_string(i);
    body.mesh =
        makeIcosphere(size.subdivisions, kRadius,
                      Vec3f(kSpacing * float(i % 4), kRadius - 0.02f, kSpacing * float(i / 4)));
    body.material = *rubber;
    body.mass = 1;
    scene.bodies.push_back(std::move(body));
  }
  scene.planes.push_back(PlaneCollider{});
  return scene;
}

}  // namespace softbake::bench
