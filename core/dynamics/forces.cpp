#include "core/dynamics/forces.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/parallel.hpp"

namespace softbake {

namespace {
// Grain sizes keep a task at a few microseconds of work: TBB's scheduling cost is ~1 µs.
constexpr std::size_t kSpringGrain = 4096;
}  // namespace

ForceBuffers::ForceBuffers(const SceneTopology& topology)
    : springForce(topology.springs.size(), Vec3::Zero()),
      triangleForce(topology.triangles.size(), Vec3::Zero()),
      chunkVolume(topology.volumeChunks.size(), 0.0),
      bodyVolume(topology.bodies.size(), 0.0),
      bodyPressure(topology.bodies.size(), 0) {
  for (std::size_t b = 0; b < topology.bodies.size(); ++b)
    bodyVolume[b] = topology.bodies[b].restVolume;
}

void computeSpringForces(const SceneTopology& topology, const SimulationState& state,
                         ForceBuffers& forces) {
  const Spring* springs = topology.springs.data();
  const Vec3* x = state.position.data();
  const Vec3* v = state.velocity.data();
  Vec3* out = forces.springForce.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topology.springs.size(), kSpringGrain),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t s = range.begin(); s != range.end(); ++s) {
                        const Spring& spring = springs[s];
                        const Vec3 d = x[spring.b] - x[spring.a];
                        const Scalar length = d.norm();
                        if (length <= Scalar(0)) {
                          out[s].setZero();
                          continue;
                        }
                        out[s] = springForceOnA(spring, d, length, v);
                      }
                    });
}

void computeVolumes(const SceneTopology& topology, const SimulationState& state,
                    ForceBuffers& forces) {
  const TriangleChunk* chunks = topology.volumeChunks.data();
  const Triangle* triangles = topology.triangles.data();
  const Vec3* x = state.position.data();
  double* chunkVolume = forces.chunkVolume.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topology.volumeChunks.size(), 1),
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
  std::fill(forces.bodyVolume.begin(), forces.bodyVolume.end(), 0.0);
  for (std::size_t c = 0; c < topology.volumeChunks.size(); ++c)
    forces.bodyVolume[chunks[c].body] += chunkVolume[c] / 6.0;
}

void computeTriangleVolumeGradients(const SceneTopology& topology, std::span<const Vec3> positions,
                                    std::span<Vec3> gradient) {
  const Triangle* triangles = topology.triangles.data();
  const Vec3* x = positions.data();
  Vec3* out = gradient.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topology.triangles.size(), kTriangleGrain),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        const Triangle& tri = triangles[t];
                        out[t] = (x[tri[1]] - x[tri[0]]).cross(x[tri[2]] - x[tri[0]]) / 6;
                      }
                    });
}

void computePressureForces(const SceneTopology& topology, const SimulationState& state,
                           ForceBuffers& forces) {
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    forces.bodyPressure[b] = Scalar(bodyPressure(topology.bodies[b], forces.bodyVolume[b]));
  }
  const Triangle* triangles = topology.triangles.data();
  const Vec3* x = state.position.data();
  const Index* body = topology.particleBody.data();
  const Scalar* pressure = forces.bodyPressure.data();
  Vec3* out = forces.triangleForce.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topology.triangles.size(), kTriangleGrain),
                    [=](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        const Triangle& tri = triangles[t];
                        const Scalar p = pressure[body[tri[0]]];
                        // (b−a)×(c−a) is twice the area times the outward normal: P·A·n̂/3 per
                        // corner.
                        out[t] = (p / 6) * (x[tri[1]] - x[tri[0]]).cross(x[tri[2]] - x[tri[0]]);
                      }
                    });
}

}  // namespace softbake
