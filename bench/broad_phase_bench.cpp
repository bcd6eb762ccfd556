/// Times BroadPhase::findPairs for each kind on jittered, overlapping icospheres of about 10k and
/// 100k faces (brute force at 10k only: it is quadratic). Each call sees the same boxes, as a
/// step whose bodies hardly moved would: the box hash rebuilds its moving leaves, the spatial hash
/// its table, and the BVH refits. Arguments are {faces, self-collision}; items/s counts faces.
///
///   cmake --build build-bench --target broad_phase_bench && build-bench/bench/broad_phase_bench

#include <benchmark/benchmark.h>

#include <cstdint>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bench/scene_sizes.hpp"
#include "core/broad_phase/broad_phase.hpp"
#include "core/mesh/icosphere.hpp"

namespace softbake {
namespace {

using bench::SceneSize;

/// This program's sizes: ~10k and ~100k faces (brute force at 1M would take hours).
constexpr int kFaces[] = {10240, 102400};

/// Everything BroadPhaseInput views.
struct Scene {
  std::vector<Box3> boxes;
  std::vector<Triangle> triangles;
  std::vector<Index> triangleSurface;
  std::vector<CollisionSurface> surfaces;
  BroadPhaseInput input() const {
    return {.triangleBox = boxes,
            .triangleVertices = triangles,
            .triangleSurface = triangleSurface,
            .surfaces = surfaces};
  }
};

/// Balls of radius 0.5 m in a row, 0.8 m apart, so neighbours overlap by 0.2 m; every vertex
/// jittered by up to 2 mm, and boxes grown by 5 mm, about what a substep sweeps plus the skin.
Scene ballsScene(const SceneSize& size, bool selfCollision) {
  constexpr float kRadius = 0.5f, kSpacing = 0.8f;
  constexpr Scalar kJitter = Scalar(0.002), kMargin = Scalar(0.005);
  std::mt19937 rng(1);
  std::uniform_real_distribution<Scalar> noise(-kJitter, kJitter);
  Scene scene;
  std::vector<Vec3> positions;
  for (int b = 0; b < size.balls; ++b) {
    const TriangleMesh mesh =
        makeIcosphere(size.subdivisions, kRadius, Vec3f(kSpacing * float(b), 0, 0));
    const Index base = Index(positions.size());
    for (const Vec3f& p : mesh.positions)
      positions.push_back(p.cast<Scalar>() + Vec3(noise(rng), noise(rng), noise(rng)));
    scene.surfaces.push_back(
        {Index(scene.triangles.size()), Index(mesh.triangles.size()), true, selfCollision});
    for (const Triangle& t : mesh.triangles) {
      scene.triangles.push_back({base + t[0], base + t[1], base + t[2]});
      scene.triangleSurface.push_back(Index(b));
    }
  }
  for (const Triangle& t : scene.triangles) {
    Box3 box(positions[t[0]]);
    box.extend(positions[t[1]]);
    box.extend(positions[t[2]]);
    scene.boxes.emplace_back(box.min().array() - kMargin, box.max().array() + kMargin);
  }
  return scene;
}

const Scene& preparedScene(int faces, bool selfCollision) {
  static std::map<std::pair<int, bool>, Scene> cache;
  const auto key = std::make_pair(faces, selfCollision);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  return cache.emplace(key, ballsScene(bench::sceneSize(faces), selfCollision)).first->second;
}

void BM_FindPairs(benchmark::State& state, BroadPhaseKind kind) {
  const Scene& scene = preparedScene(int(state.range(0)), state.range(1) != 0);
  const auto broadPhase = makeBroadPhase(kind);
  std::vector<TrianglePair> pairs;
  broadPhase->findPairs(scene.input(), pairs);  // warm-up: trees, static data, buffers
  for (auto _ : state) {
    broadPhase->findPairs(scene.input(), pairs);
    benchmark::DoNotOptimize(pairs.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(scene.triangles.size()));
  state.counters["faces"] = double(scene.triangles.size());
  state.counters["pairs"] = double(pairs.size());
}

void allSizes(benchmark::internal::Benchmark* b) {
  for (int faces : kFaces)
    for (int self : {0, 1}) b->Args({faces, self});
}

void smallestSize(benchmark::internal::Benchmark* b) {
  for (int self : {0, 1}) b->Args({kFaces[0], self});
}

BENCHMARK_CAPTURE(BM_FindPairs, sbhash, BroadPhaseKind::Sbhash)
    ->Apply(allSizes)
    ->ArgNames({"faces", "self"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_FindPairs, spatialhash, BroadPhaseKind::SpatialHash)
    ->Apply(allSizes)
    ->ArgNames({"faces", "self"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_FindPairs, bvh, BroadPhaseKind::Bvh)
    ->Apply(allSizes)
    ->ArgNames({"faces", "self"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_FindPairs, brute, BroadPhaseKind::BruteForce)
    ->Apply(smallestSize)
    ->ArgNames({"faces", "self"})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace softbake

BENCHMARK_MAIN();
