/// Which memory layout should particle positions and velocities use? Times the spring-force kernel
/// and the per-particle gather + explicit Euler integration (core's computeSpringForces and
/// integrate, without TBB) in three layouts over the same real topology:
///
///   packed   std::vector<Eigen::Vector3f>: packed xyz triples, what core uses (array of structs)
///   eigen3n  Eigen::Matrix3Xf: column-major 3×N, so also interleaved xyz in memory; only the code
///            Eigen generates for .col(i) differs from `packed`
///   split    three std::vector<float> x, y, z per quantity (structure of arrays)
///
/// The springs and the incidence rows come from buildSceneTopology() of icosphere scenes of 10k and
/// ~1M faces. Single-threaded, float. Before timing, all three layouts run the same steps and must
/// agree to a tiny tolerance; the program stops otherwise.

#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "core/collision/contact_accuracy.hpp"
#include "core/dynamics/stability.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/scene/material.hpp"
#include "core/scene/scene_topology.hpp"

namespace softbake {
namespace {

using Vector3f = Eigen::Vector3f;

/// A spring in float whatever Scalar core was built with; the same array serves all layouts.
struct FloatSpring {
  Index a, b;
  float restLength, stiffness, damping;
};

/// Everything except the particle state: shared by the three layouts.
struct Case {
  std::string name;
  std::size_t faces = 0;
  std::vector<FloatSpring> springs;
  std::vector<Index> rowStart, refs;  ///< core's spring incidence: ref = 2·spring + (is `b` end)
  std::vector<float> mass, inverseMass;
  std::vector<Vector3f> startPosition, startVelocity;
  Vector3f gravity = Vector3f(0, -9.81f, 0);
  float dt = 0;
  std::size_t particles() const { return mass.size(); }
};

/// `balls` rubber icospheres of `subdivisions` levels, no ground. Positions are jittered by ~1% of
/// an edge so the springs start stretched and every term of the kernel does work.
Case makeCase(std::string name, int subdivisions, int balls) {
  SceneSetup scene;
  for (int i = 0; i < balls; ++i) {
    BodySetup body;
    body.name = "ball" + std::to_string(i);
    body.mesh =
        makeIcosphere(subdivisions, 0.5f, Vector3f(1.2f * float(i % 4), 1, 1.2f * float(i / 4)));
    body.material = *findMaterialPreset("rubber");
    scene.bodies.push_back(std::move(body));
  }
  const SceneTopology world = buildSceneTopology(scene);
  Case c;
  c.name = std::move(name);
  c.faces = world.triangles.size();
  for (const Spring& s : world.springs)
    c.springs.push_back({s.a, s.b, float(s.restLength), float(s.stiffness), float(s.damping)});
  c.rowStart = world.springRowStart;
  c.refs = world.springRefs;
  for (std::size_t i = 0; i < world.particleCount(); ++i) {
    c.mass.push_back(float(world.mass[i]));
    c.inverseMass.push_back(float(world.inverseMass[i]));
  }
  const float edge = 0.5f * 1.1f / float(1 << subdivisions);
  std::uint32_t random = 12345;
  auto jitter = [&] {
    random = random * 1664525u + 1013904223u;  // fixed LCG: the same start on every run
    return (float(random >> 8) / float(1 << 24) - 0.5f) * 0.02f * edge;
  };
  for (const Vec3& p : world.restPosition) {
    const Vector3f q = p.cast<float>();
    c.startPosition.push_back(q + Vector3f(jitter(), jitter(), jitter()));
    c.startVelocity.push_back(Vector3f::Zero());
  }
  c.dt = float(chooseSubsteps(world, 0).timeStep);
  return c;
}

// Each layout: state from a Case, springs() fills the per-spring force on the `a` end,
// integrate() sums each particle's gravity and springs in row order, then v += dt·f/m, x += dt·v.
// The arithmetic is written in the same order in all three so their results match.

struct Packed {
  std::vector<Vector3f> x, previous, v, springForce;

  explicit Packed(const Case& c)
      : x(c.startPosition),
        previous(c.startPosition),
        v(c.startVelocity),
        springForce(c.springs.size(), Vector3f::Zero()) {}

  void springs(const Case& c) {
    const std::size_t count = c.springs.size();
    for (std::size_t s = 0; s < count; ++s) {
      const FloatSpring& spring = c.springs[s];
      const Vector3f d = x[spring.b] - x[spring.a];
      const float length = d.norm();
      if (length <= 0) {
        springForce[s].setZero();
        continue;
      }
      const Vector3f axis = d / length;
      const float stretch = spring.stiffness * (length - spring.restLength);
      const float closing = spring.damping * (v[spring.b] - v[spring.a]).dot(axis);
      springForce[s] = (stretch + closing) * axis;
    }
  }

  void integrate(const Case& c) {
    const std::size_t count = c.particles();
    for (std::size_t i = 0; i < count; ++i) {
      previous[i] = x[i];
      if (c.inverseMass[i] == 0) {
        v[i].setZero();
        continue;
      }
      Vector3f force = c.mass[i] * c.gravity;
      for (Index r = c.rowStart[i]; r < c.rowStart[i + 1]; ++r) {
        const Index ref = c.refs[r];
        if (ref & 1)
          force -= springForce[ref >> 1];
        else
          force += springForce[ref >> 1];
      }
      v[i] += (c.dt * c.inverseMass[i]) * force;
      x[i] += c.dt * v[i];
    }
  }

  Vector3f position(std::size_t i) const { return x[i]; }
  Vector3f velocity(std::size_t i) const { return v[i]; }
};

struct Eigen3N {
  Eigen::Matrix3Xf x, previous, v, springForce;

  explicit Eigen3N(const Case& c)
      : x(3, Eigen::Index(c.particles())),
        v(3, Eigen::Index(c.particles())),
        springForce(3, Eigen::Index(c.springs.size())) {
    for (std::size_t i = 0; i < c.particles(); ++i) {
      x.col(Eigen::Index(i)) = c.startPosition[i];
      v.col(Eigen::Index(i)) = c.startVelocity[i];
    }
    previous = x;
    springForce.setZero();
  }

  void springs(const Case& c) {
    const std::size_t count = c.springs.size();
    for (std::size_t s = 0; s < count; ++s) {
      const FloatSpring& spring = c.springs[s];
      const Eigen::Index a = spring.a, b = spring.b, column = Eigen::Index(s);
      const Vector3f d = x.col(b) - x.col(a);
      const float length = d.norm();
      if (length <= 0) {
        springForce.col(column).setZero();
        continue;
      }
      const Vector3f axis = d / length;
      const float stretch = spring.stiffness * (length - spring.restLength);
      const float closing = spring.damping * (v.col(b) - v.col(a)).dot(axis);
      springForce.col(column) = (stretch + closing) * axis;
    }
  }

  void integrate(const Case& c) {
    const std::size_t count = c.particles();
    for (std::size_t i = 0; i < count; ++i) {
      const Eigen::Index column = Eigen::Index(i);
      previous.col(column) = x.col(column);
      if (c.inverseMass[i] == 0) {
        v.col(column).setZero();
        continue;
      }
      Vector3f force = c.mass[i] * c.gravity;
      for (Index r = c.rowStart[i]; r < c.rowStart[i + 1]; ++r) {
        const Index ref = c.refs[r];
        if (ref & 1)
          force -= springForce.col(Eigen::Index(ref >> 1));
        else
          force += springForce.col(Eigen::Index(ref >> 1));
      }
      v.col(column) += (c.dt * c.inverseMass[i]) * force;
      x.col(column) += c.dt * v.col(column);
    }
  }

  Vector3f position(std::size_t i) const { return x.col(Eigen::Index(i)); }
  Vector3f velocity(std::size_t i) const { return v.col(Eigen::Index(i)); }
};

struct Split {
  struct Xyz {
    std::vector<float> x, y, z;
    explicit Xyz(std::size_t n) : x(n, 0.0f), y(n, 0.0f), z(n, 0.0f) {}
  };
  Xyz x, previous, v, springForce;

  explicit Split(const Case& c)
      : x(c.particles()), previous(c.particles()), v(c.particles()), springForce(c.springs.size()) {
    for (std::size_t i = 0; i < c.particles(); ++i) {
      x.x[i] = c.startPosition[i].x(), x.y[i] = c.startPosition[i].y(),
      x.z[i] = c.startPosition[i].z();
      v.x[i] = c.startVelocity[i].x(), v.y[i] = c.startVelocity[i].y(),
      v.z[i] = c.startVelocity[i].z();
    }
    previous = x;
  }

  void springs(const Case& c) {
    const std::size_t count = c.springs.size();
    const float *px = x.x.data(), *py = x.y.data(), *pz = x.z.data();
    const float *vx = v.x.data(), *vy = v.y.data(), *vz = v.z.data();
    float *fx = springForce.x.data(), *fy = springForce.y.data(), *fz = springForce.z.data();
    for (std::size_t s = 0; s < count; ++s) {
      const FloatSpring& spring = c.springs[s];
      const Index a = spring.a, b = spring.b;
      const float dx = px[b] - px[a], dy = py[b] - py[a], dz = pz[b] - pz[a];
      // Eigen sums a 3-vector as x + (y + z): the same order keeps the results bit-identical.
      const float length = std::sqrt(dx * dx + (dy * dy + dz * dz));
      if (length <= 0) {
        fx[s] = fy[s] = fz[s] = 0;
        continue;
      }
      const float ax = dx / length, ay = dy / length, az = dz / length;
      const float stretch = spring.stiffness * (length - spring.restLength);
      const float closing =
          spring.damping * ((vx[b] - vx[a]) * ax + ((vy[b] - vy[a]) * ay + (vz[b] - vz[a]) * az));
      const float magnitude = stretch + closing;
      fx[s] = magnitude * ax, fy[s] = magnitude * ay, fz[s] = magnitude * az;
    }
  }

  void integrate(const Case& c) {
    const std::size_t count = c.particles();
    float *px = x.x.data(), *py = x.y.data(), *pz = x.z.data();
    float *vx = v.x.data(), *vy = v.y.data(), *vz = v.z.data();
    const float *fx = springForce.x.data(), *fy = springForce.y.data(), *fz = springForce.z.data();
    for (std::size_t i = 0; i < count; ++i) {
      previous.x[i] = px[i], previous.y[i] = py[i], previous.z[i] = pz[i];
      if (c.inverseMass[i] == 0) {
        vx[i] = vy[i] = vz[i] = 0;
        continue;
      }
      float sx = c.mass[i] * c.gravity.x(), sy = c.mass[i] * c.gravity.y(),
            sz = c.mass[i] * c.gravity.z();
      for (Index r = c.rowStart[i]; r < c.rowStart[i + 1]; ++r) {
        const Index ref = c.refs[r], s = ref >> 1;
        if (ref & 1)
          sx -= fx[s], sy -= fy[s], sz -= fz[s];
        else
          sx += fx[s], sy += fy[s], sz += fz[s];
      }
      const float scale = c.dt * c.inverseMass[i];
      vx[i] += scale * sx, vy[i] += scale * sy, vz[i] += scale * sz;
      px[i] += c.dt * vx[i], py[i] += c.dt * vy[i], pz[i] += c.dt * vz[i];
    }
  }

  Vector3f position(std::size_t i) const { return {x.x[i], x.y[i], x.z[i]}; }
  Vector3f velocity(std::size_t i) const { return {v.x[i], v.y[i], v.z[i]}; }
};

/// Steps compared before timing: enough for velocities and damping to matter.
constexpr int kCheckSteps = 20;
/// The layouts do the same float operations in the same order, so they agree bit for bit. Even a
/// one-ulp change (summing y² + z² first or last) shows up as ~1e-3 m/s after 20 steps: the
/// stretch |d| − L cancels most digits and the stiff springs amplify the rest.
constexpr float kTolerance = 1e-5f;

template <class Layout>
Layout stepped(const Case& c, int steps) {
  Layout layout(c);
  for (int s = 0; s < steps; ++s) {
    layout.springs(c);
    layout.integrate(c);
  }
  return layout;
}

/// Largest |difference| of position or velocity between the two layouts.
template <class A, class B>
float maxAbsDiff(const Case& c, const A& a, const B& b) {
  float worst = 0;
  for (std::size_t i = 0; i < c.particles(); ++i) {
    worst = std::max(worst, (a.position(i) - b.position(i)).cwiseAbs().maxCoeff());
    worst = std::max(worst, (a.velocity(i) - b.velocity(i)).cwiseAbs().maxCoeff());
  }
  return worst;
}

enum class Pass { springs, integrate, step };
constexpr const char* kPassNames[] = {"springs", "gather_integrate", "step"};

/// integrate alone runs on frozen spring forces; the state is put back this often (timer paused)
/// so it stays near one a real run reaches.
constexpr int kRestorePeriod = 64;

template <class Layout>
void runLayout(benchmark::State& state, const Case* c, Pass pass) {
  Layout layout(*c);
  layout.springs(*c);
  const Layout start = layout;
  int sinceRestore = 0;
  for (auto _ : state) {
    if (pass == Pass::integrate && ++sinceRestore == kRestorePeriod) {
      state.PauseTiming();
      layout = start;
      sinceRestore = 0;
      state.ResumeTiming();
    }
    if (pass != Pass::integrate) layout.springs(*c);
    if (pass != Pass::springs) layout.integrate(*c);
    benchmark::ClobberMemory();
  }
  benchmark::DoNotOptimize(layout.position(0));
  state.SetItemsProcessed(state.iterations() * std::int64_t(c->faces));
  state.counters["faces"] = double(c->faces);
  state.counters["particles"] = double(c->particles());
  state.counters["springs"] = double(c->springs.size());
}

template <class Layout>
void registerLayout(Pass pass, const char* layoutName, const Case& c) {
  const std::string name =
      std::string("BM_Layout/") + kPassNames[int(pass)] + "/" + layoutName + "/" + c.name;
  benchmark::RegisterBenchmark(name.c_str(), runLayout<Layout>, &c, pass)
      ->Unit(benchmark::kMicrosecond)
      ->UseRealTime()
      // On a shared machine the fastest repetition is the one least disturbed by other work.
      ->ComputeStatistics("min", [](const std::vector<double>& v) {
        return *std::min_element(v.begin(), v.end());
      });
}

}  // namespace
}  // namespace softbake

int main(int argc, char** argv) {
  using namespace softbake;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  // Built once and kept alive for the whole run: the benchmarks point at them.
  static const std::vector<Case> cases = {makeCase("faces:10240", 4, 2),
                                          makeCase("faces:983040", 6, 12)};
  for (const Case& c : cases) {
    const Packed packed = stepped<Packed>(c, kCheckSteps);
    const float eigenDiff = maxAbsDiff(c, packed, stepped<Eigen3N>(c, kCheckSteps));
    const float splitDiff = maxAbsDiff(c, packed, stepped<Split>(c, kCheckSteps));
    std::fprintf(stderr,
                 "%s: %zu particles, %zu springs; after %d steps max |diff| vs packed: "
                 "eigen3n %g, split %g\n",
                 c.name.c_str(), c.particles(), c.springs.size(), kCheckSteps, double(eigenDiff),
                 double(splitDiff));
    benchmark::AddCustomContext(c.name + " max_abs_diff eigen3n/split",
                                std::to_string(eigenDiff) + " / " + std::to_string(splitDiff));
    if (!(eigenDiff <= kTolerance && splitDiff <= kTolerance)) {
      std::fprintf(stderr, "layouts disagree beyond %g: not timing them\n", double(kTolerance));
      return 1;
    }
  }
  // The three layouts of one pass and size run one after another, so they share the machine's
  // conditions as closely as a noisy machine allows.
  for (const Case& c : cases)
    for (Pass pass : {Pass::springs, Pass::integrate, Pass::step}) {
      registerLayout<Packed>(pass, "packed", c);
      registerLayout<Eigen3N>(pass, "eigen3n", c);
      registerLayout<Split>(pass, "split", c);
    }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
