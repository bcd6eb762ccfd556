/// The peer: the same scene in Bullet's btSoftBody (Debian's libbullet-dev), so a user sees what
/// they would get instead of softbake. Same welded meshes, per-particle masses, initial
/// velocities, gravity, ground plane, time step and step count as `softbake bench` on the same
/// scene; pressure on (kPR = nRT of each body, Bullet's pressure being kPR / V like ours), and
/// soft–soft collision on (vertex–face, VF_SS, plus SDF_RS against the ground).
///
/// Where the scenes differ, and cannot be made equal: Bullet's "springs" are position-based
/// links with a stiffness fraction in [0, 1] solved by iteration, not Hookean forces in N/m with
/// damping; its integration is its own; its collision response is its own. So the two do not
/// produce the same motion, only the same amount of work to do per step.
///
///   build/bench/bullet_peer_bench SCENE [--steps N] [--warmup N] [--csv FILE]
///   build/bench/bullet_peer_bench SCENE --frames F [--substeps-per-frame N]
///
/// SCENE as for `softbake bench` (a file or a built-in name). Bullet's soft bodies run on one
/// thread. With --steps, N steps at softbake's time step. With --frames, the scene's first F
/// frames as a Bullet user runs them, N substeps a frame (default 10, Bullet's usual setting),
/// and after each frame, outside the timing, the result's quality: how deep a node is below the
/// ground, how far a closed body's volume is from its rest volume, and how many triangle pairs of
/// different bodies intersect (the tests' exact checker). Prints one machine-readable line, and
/// with --csv writes it as a CSV row too:
///   peer=bullet scene=balls10k faces=10240 steps=500 steps_per_s=...

#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "bake/scene_input.hpp"
#include "core/error.hpp"
#include "core/mesh/mesh_topology.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"
#include "tests/support/intersection_checker.hpp"

namespace softbake {
namespace {

struct Arguments {
  std::string scene;
  long steps = 500, warmup = 0;
  long frames = 0;             ///< with --frames: simulate the scene's frames 2..frames
  long substepsPerFrame = 10;  ///< Bullet's usual setting
  std::string csv;
};

Arguments parse(int argc, char** argv) {
  Arguments arguments;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    const auto text = [&]() -> std::string {
      if (i + 1 >= argc) throw Error(flag + " needs a value");
      return argv[++i];
    };
    const auto value = [&]() -> long { return std::strtol(text().c_str(), nullptr, 10); };
    if (flag == "--steps")
      arguments.steps = value();
    else if (flag == "--warmup")
      arguments.warmup = value();
    else if (flag == "--frames")
      arguments.frames = value();
    else if (flag == "--substeps-per-frame")
      arguments.substepsPerFrame = value();
    else if (flag == "--csv")
      arguments.csv = text();
    else if (flag.rfind("--", 0) == 0)
      throw Error("unknown option " + flag);
    else
      arguments.scene = flag;
  }
  if (arguments.scene.empty())
    throw Error(
        "usage: bullet_peer_bench SCENE [--steps N] [--warmup N] [--frames F "
        "[--substeps-per-frame N]] [--csv FILE]");
  if (arguments.steps < 1) throw Error("--steps must be at least 1");
  if (arguments.frames == 1 || arguments.frames < 0)
    throw Error("--frames must be at least 2: frame 1 is the start");
  if (arguments.substepsPerFrame < 1) throw Error("--substeps-per-frame must be at least 1");
  return arguments;
}

/// Bullet's world, its parts kept alive in declaration order.
struct BulletWorld {
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDefaultSoftBodySolver softSolver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration, &softSolver};
  // The ground plane as a large thin box: Bullet's sparse SDF samples a plane shape very slowly.
  btBoxShape groundShape{btVector3(50, 0.5f, 50)};
  std::unique_ptr<btRigidBody> ground;
  std::vector<std::unique_ptr<btSoftBody>> bodies;

  ~BulletWorld() {
    for (auto& body : bodies) world.removeSoftBody(body.get());
    if (ground) world.removeRigidBody(ground.get());
  }
};

/// The worst of every frame, as bench/volumes.py and the exact checker measure softbake's.
struct Quality {
  double maxPenetration = 0;        ///< m below a ground plane, over every node
  double maxVolumeError = 0;        ///< max |V / V_rest − 1| over the closed bodies
  std::size_t maxPairsBetween = 0;  ///< intersecting triangle pairs of different bodies

  void add(const Simulator& reference, std::span<const Vec3> positions) {
    const SceneTopology& w = reference.topology();
    for (const PlaneCollider& plane : w.planes)
      for (const Vec3& x : positions)
        maxPenetration = std::max(maxPenetration, -double(heightAbove(plane, x)));
    for (const Body& body : w.bodies) {
      if (!body.closed || body.restVolume <= 0) continue;
      const double volume = signedVolume(positions, w.bodyTriangles(body));
      maxVolumeError = std::max(maxVolumeError, std::abs(volume / body.restVolume - 1));
    }
    maxPairsBetween =
        std::max(maxPairsBetween,
                 test::countIntersectingPairs(reference.collision(), positions).betweenSurfaces);
  }
};

int run(int argc, char** argv) {
  const Arguments arguments = parse(argc, argv);
  const SceneFile scene = loadSceneInput(arguments.scene);
  // For the time step and the welded meshes.
  const Simulator reference(buildSceneTopology(scene.setup));
  const SceneTopology& w = reference.topology();
  const SimulationState& initial = reference.state();
  const bool byFrames = arguments.frames > 0;
  const double dt = byFrames ? 1.0 / w.settings.fps / double(arguments.substepsPerFrame)
                             : reference.substeps().timeStep;

  BulletWorld bullet;
  const Vec3 g = w.settings.gravity;
  bullet.world.setGravity(btVector3(g.x(), g.y(), g.z()));
  btSoftBodyWorldInfo& info = bullet.world.getWorldInfo();
  info.m_gravity = btVector3(g.x(), g.y(), g.z());
  info.m_sparsesdf.Initialize();
  if (!w.planes.empty()) {
    btRigidBody::btRigidBodyConstructionInfo groundInfo(0, nullptr, &bullet.groundShape);
    groundInfo.m_startWorldTransform.setOrigin(btVector3(0, -0.5f, 0));
    bullet.ground = std::make_unique<btRigidBody>(groundInfo);
    bullet.world.addRigidBody(bullet.ground.get());
  }

  std::size_t faces = 0;
  for (const Body& body : w.bodies) {
    std::vector<btScalar> vertices;
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3& p = initial.position[body.firstParticle + i];
      vertices.insert(vertices.end(), {p.x(), p.y(), p.z()});
    }
    std::vector<int> triangles;
    for (Index t = body.firstTriangle; t < body.firstTriangle + body.triangleCount; ++t)
      for (Index v : w.triangles[t]) triangles.push_back(int(v - body.firstParticle));
    faces += body.triangleCount;
    std::unique_ptr<btSoftBody> soft(btSoftBodyHelpers::CreateFromTriMesh(
        info, vertices.data(), triangles.data(), int(body.triangleCount), false));
    for (Index i = 0; i < body.particleCount; ++i) {
      const Index p = body.firstParticle + i;
      soft->setMass(int(i), w.inverseMass[p] > 0 ? btScalar(1 / w.inverseMass[p]) : 0);
      const Vec3& v = initial.velocity[p];
      soft->m_nodes[int(i)].m_v = btVector3(v.x(), v.y(), v.z());
    }
    soft->m_materials[0]->m_kLST = 0.9f;
    soft->generateBendingConstraints(2, soft->m_materials[0]);
    soft->m_cfg.kPR = btScalar(body.gasAmount);
    soft->m_cfg.kDF = body.material.damping > 0 ? 0.3f : 0.0f;
    soft->m_cfg.piterations = 4;
    soft->m_cfg.collisions = btSoftBody::fCollision::SDF_RS | btSoftBody::fCollision::VF_SS;
    // Bullet's default margin is 0.25 m, which on 0.4 m balls puts every node in contact with
    // every face nearby; softbake's skin is the matching distance.
    soft->getCollisionShape()->setMargin(btScalar(w.settings.skin));
    bullet.world.addSoftBody(soft.get());
    bullet.bodies.push_back(std::move(soft));
  }

  // Bullet's steps alone are timed: the quality checks between frames are not.
  const auto timedSteps = [&](long count) {
    const auto start = std::chrono::steady_clock::now();
    for (long s = 0; s < count; ++s) bullet.world.stepSimulation(btScalar(dt), 0);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  timedSteps(arguments.warmup);
  Quality quality;
  double seconds = 0;
  long steps = arguments.steps;
  if (byFrames) {
    steps = (arguments.frames - 1) * arguments.substepsPerFrame;
    std::vector<Vec3> positions(w.particleCount());
    for (long frame = 2; frame <= arguments.frames; ++frame) {
      seconds += timedSteps(arguments.substepsPerFrame);
      for (std::size_t b = 0; b < w.bodies.size(); ++b) {
        const btAlignedObjectArray<btSoftBody::Node>& nodes = bullet.bodies[b]->m_nodes;
        for (int i = 0; i < nodes.size(); ++i) {
          const btVector3& x = nodes[i].m_x;
          positions[w.bodies[b].firstParticle + Index(i)] = Vec3(x.x(), x.y(), x.z());
        }
      }
      quality.add(reference, positions);
    }
  } else {
    seconds = timedSteps(steps);
  }

  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  const double stepsPerSecond = double(steps) / seconds;
  const double peakMiB = double(usage.ru_maxrss) / 1024.0;
  const std::string frameFields =
      byFrames ? cat(" substeps_per_frame=", arguments.substepsPerFrame,
                     " frames_per_s=", double(arguments.frames - 1) / seconds,
                     " max_penetration_m=", quality.maxPenetration,
                     " max_volume_error=", quality.maxVolumeError,
                     " max_pairs_between_bodies=", quality.maxPairsBetween)
               : std::string();
  std::printf(
      "peer=bullet scene=%s faces=%zu bodies=%zu dt_ms=%.4g warmup=%ld steps=%ld "
      "steps_per_s=%.1f peak_rss_mb=%.1f%s\n",
      scene.setup.name.c_str(), faces, w.bodies.size(), dt * 1e3, arguments.warmup, steps,
      stepsPerSecond, peakMiB, frameFields.c_str());
  if (!arguments.csv.empty())
    writeFileAtomically(
        arguments.csv,
        cat("peer,scene,faces,bodies,dt_ms,warmup,steps,steps_per_s,peak_rss_mb\n", "bullet,",
            scene.setup.name, ",", faces, ",", w.bodies.size(), ",", dt * 1e3, ",",
            arguments.warmup, ",", steps, ",", stepsPerSecond, ",", peakMiB, "\n"));
  return 0;
}

}  // namespace
}  // namespace softbake

int main(int argc, char** argv) {
  try {
    return softbake::run(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bullet_peer_bench: error: %s\n", error.what());
    return 1;
  }
}
