/// Cost of the narrow phase (Mesit & Guha §2.3), per call: intersectSegmentTriangle and the
/// multi-pass intersectTrianglePair on random inputs in the proportions the tests use (unit-size
/// triangles near each other, about 40% of segments and 30% of pairs intersecting). Each
/// iteration takes the next of 4096 pre-generated inputs, so the branch predictor cannot learn
/// one case and the inputs stay in L1/L2. Single-threaded; one iteration is one call.

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "core/collision/line_triangle.hpp"
#include "core/collision/triangle_pair_intersection.hpp"

namespace softbake {
namespace {

constexpr std::size_t kInputs = 4096;  // a power of two: the index wraps with a mask

struct SegmentCase {
  Vec3 start, end;
  TriangleCorners triangle;
};

/// Segments of 0.1…3 through a point of a unit triangle grown by 30% about its centroid.
std::vector<SegmentCase> segmentCases() {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> unit(-1, 1), zeroOne(0, 1);
  auto vec = [&] { return Vec3(unit(rng), unit(rng), unit(rng)); };
  std::vector<SegmentCase> cases(kInputs);
  for (SegmentCase& c : cases) {
    c.triangle = {vec(), vec(), vec()};
    const TriangleCorners& t = c.triangle;
    float u = zeroOne(rng), v = zeroOne(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3 centroid = (t[0] + t[1] + t[2]) / 3;
    const Vec3 target = centroid + 1.3f * (t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]) - centroid);
    const Vec3 direction = vec().normalized() * (0.1f + 2.9f * zeroOne(rng));
    c.start = target - (1.4f * zeroOne(rng) - 0.2f) * direction;
    c.end = c.start + direction;
  }
  return cases;
}

/// Pairs of triangles with corners in [−1, 1]³, the second offset by up to `offsetScale` per axis.
std::vector<std::array<TriangleCorners, 2>> pairCases(float offsetScale) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> unit(-1, 1);
  auto vec = [&] { return Vec3(unit(rng), unit(rng), unit(rng)); };
  std::vector<std::array<TriangleCorners, 2>> cases(kInputs);
  for (auto& pair : cases) {
    const Vec3 offset = offsetScale * vec();
    pair[0] = {vec(), vec(), vec()};
    pair[1] = {offset + vec(), offset + vec(), offset + vec()};
  }
  return cases;
}

void BM_SegmentTriangle(benchmark::State& state) {
  const std::vector<SegmentCase> cases = segmentCases();
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    const SegmentCase& c = cases[i++ & (kInputs - 1)];
    SegmentTriangleHit hit;
    const bool found =
        intersectSegmentTriangle(c.start, c.end, c.triangle[0], c.triangle[1], c.triangle[2], hit);
    benchmark::DoNotOptimize(hit);
    hits += found;
  }
  state.counters["hit_fraction"] = double(hits) / double(state.iterations());
}
BENCHMARK(BM_SegmentTriangle);

/// range(0): the second triangle's offset in hundredths of the triangle size; 20 gives ~30%
/// intersecting pairs, 300 almost none (every edge misses: the cost of a culled candidate).
void BM_TrianglePair(benchmark::State& state) {
  const auto cases = pairCases(float(state.range(0)) / 100);
  std::size_t i = 0, intersecting = 0;
  for (auto _ : state) {
    const auto& pair = cases[i++ & (kInputs - 1)];
    TrianglePairHits hits;
    const bool found = intersectTrianglePair(pair[0], pair[1], hits);
    benchmark::DoNotOptimize(hits);
    intersecting += found;
  }
  // The same counter name as the segment test's, as the CSV reporter wants: calls that hit.
  state.counters["hit_fraction"] = double(intersecting) / double(state.iterations());
}
BENCHMARK(BM_TrianglePair)->Arg(20)->Arg(300);

}  // namespace
}  // namespace softbake

BENCHMARK_MAIN();
