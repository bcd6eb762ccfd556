#include "core/dynamics/forces.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace softbake {

namespace {
// Grain sizes keep a task at a few microseconds of work: TBB's scheduling cost is ~1 µs.
constexpr std::size_t kSpringGrain = 4096;
constexpr std::size_t kTriangleGrain = 4096;
}  // namespace

void computeSpringForces(World& world) {
  const Spring* springs = world.springs.data();
  const Vec3* x = world.position.data();
  const Vec3* v = world.velocity.data();
  Vec3* out = world.springForce.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, world.springs.size(), kSpringGrain),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t s = range.begin(); s != range.end(); ++s) {
                        const Spring& spring = springs[s];
                        const Vec3 d = x[spring.b] - x[spring.a];
                        const Scalar length = d.norm();
                        if (length <= Scalar(0)) {
                          out[s].setZero();
                          continue;
                        }
                        const Vec3 axis = d / length;
                        const Scalar stretch = spring.stiffness * (length - spring.restLength);
                        const Scalar closing = spring.damping * (v[spring.b] - v[spring.a]).dot(axis);
                        out[s] = (stretch + closing) * axis;
                      }
                    });
}

void computeVolumes(World& world) {
  const TriangleChunk* chunks = world.volumeChunks.data();
  const Triangle* triangles = world.triangles.data();
  const Vec3* x = world.position.data();
  double* chunkVolume = world.chunkVolume.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, world.volumeChunks.size(), 1),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t c = range.begin(); c != range.end(); ++c) {
                        double sum = 0;
                        for (Index t = chunks[c].begin; t < chunks[c].end; ++t) {
                          const Vec3d a = x[triangles[t][0]].template cast<double>();
                          const Vec3d b = x[triangles[t][1]].template cast<double>();
                          const Vec3d cc = x[triangles[t][2]].template cast<double>();
                          sum += a.dot(b.cross(cc));
                        }
                        chunkVolume[c] = sum;
                      }
                    });
  std::fill(world.bodyVolume.begin(), world.bodyVolume.end(), 0.0);
  for (std::size_t c = 0; c < world.volumeChunks.size(); ++c)
    world.bodyVolume[chunks[c].body] += chunkVolume[c] / 6.0;
}

void computePressureForces(World& world) {
  for (std::size_t b = 0; b < world.bodies.size(); ++b) {
    const Body& body = world.bodies[b];
    const double volume = std::max(world.bodyVolume[b], kMinVolumeFraction * body.restVolume);
    world.bodyPressure[b] = body.gasAmount > 0 ? Scalar(body.gasAmount / volume) : Scalar(0);
  }
  const Triangle* triangles = world.triangles.data();
  const Vec3* x = world.position.data();
  const Index* body = world.particleBody.data();
  const Scalar* pressure = world.bodyPressure.data();
  Vec3* out = world.triangleForce.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, world.triangles.size(), kTriangleGrain),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        const Triangle& tri = triangles[t];
                        const Scalar p = pressure[body[tri[0]]];
                        // (b−a)×(c−a) is twice the area times the outward normal: P·A·n̂/3 per corner.
                        out[t] = (p / 6) * (x[tri[1]] - x[tri[0]]).cross(x[tri[2]] - x[tri[0]]);
                      }
                    });
}

}  // namespace softbake
