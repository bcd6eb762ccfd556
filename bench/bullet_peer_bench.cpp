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
///
/// SCENE as for `softbake bench` (a file or a built-in name). Bullet's soft bodies run on one
/// thread. Prints one machine-readable line, and with --csv writes it as a CSV row too:
///   peer=bullet scene=balls10k faces=10240 steps=500 steps_per_s=...

#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "cli/scene_input.hpp"
#include "core/error.hpp"
#include "core/simulator.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {
namespace {

struct Arguments {
  std::string scene;
  long steps = 500, warmup = 0;
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
    else if (flag == "--csv")
      arguments.csv = text();
    else if (flag.rfind("--", 0) == 0)
      throw Error("unknown option " + flag);
    else
      arguments.scene = flag;
  }
  if (arguments.scene.empty())
    throw Error("usage: bullet_peer_bench SCENE [--steps N] [--warmup N] [--csv FILE]");
  if (arguments.steps < 1) throw Error("--steps must be at least 1");
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

int run(int argc, char** argv) {
  const Arguments arguments = parse(argc, argv);
  const SceneFile scene = loadSceneInput(arguments.scene);
  // For the time step and the welded meshes.
  const Simulator reference(buildSceneTopology(scene.setup));
  const SceneTopology& w = reference.topology();
  const SimulationState& initial = reference.state();
  const double dt = reference.substeps().timeStep;

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

  for (long s = 0; s < arguments.warmup; ++s) bullet.world.stepSimulation(btScalar(dt), 0);
  const auto start = std::chrono::steady_clock::now();
  for (long s = 0; s < arguments.steps; ++s) bullet.world.stepSimulation(btScalar(dt), 0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  const double stepsPerSecond = double(arguments.steps) / seconds;
  const double peakMiB = double(usage.ru_maxrss) / 1024.0;
  std::printf(
      "peer=bullet scene=%s faces=%zu bodies=%zu dt_ms=%.4g warmup=%ld steps=%ld "
      "steps_per_s=%.1f peak_rss_mb=%.1f\n",
      scene.setup.name.c_str(), faces, w.bodies.size(), dt * 1e3, arguments.warmup, arguments.steps,
      stepsPerSecond, peakMiB);
  if (!arguments.csv.empty())
    writeFileAtomically(
        arguments.csv,
        cat("peer,scene,faces,bodies,dt_ms,warmup,steps,steps_per_s,peak_rss_mb\n", "bullet,",
            scene.setup.name, ",", faces, ",", w.bodies.size(), ",", dt * 1e3, ",",
            arguments.warmup, ",", arguments.steps, ",", stepsPerSecond, ",", peakMiB, "\n"));
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
