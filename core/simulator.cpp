#include "core/simulator.hpp"

#include "core/error.hpp"
#include "core/dynamics/forces.hpp"
#include "core/dynamics/integrator.hpp"
#include "core/collision/plane_contact.hpp"
#include "core/text.hpp"
#include "core/mesh/weld.hpp"

namespace softbake {

Simulator::Simulator(World world)
    : world_(std::move(world)),
      substeps_(chooseSubsteps(world_, world_.settings.substeps)),
      detector_(world_.settings.collisions) {
  const std::vector<CollisionSurface>& surfaces = world_.collision.surfaces;
  std::size_t moving = 0;
  for (const CollisionSurface& surface : surfaces) {
    moving += surface.moving;
    collides_ = collides_ || surface.selfCollision;
  }
  collides_ = collides_ || (moving > 0 && surfaces.size() > 1);
}

void Simulator::step(int frame) {
  StageClock clock(measureStages_ ? &stepTimes_ : nullptr);
  computeSpringForces(world_);
  computeVolumes(world_);
  computePressureForces(world_);
  clock.lap(Stage::Forces);
  if (!integrate(world_, Scalar(substeps_.timeStep))) reportBlowUp(frame);
  clock.lap(Stage::Integration);
  const ResponseMode response = world_.settings.collisions.response;
  if (collides_) {
    updateCollisionBoxes(world_);
    clock.lap(Stage::Boxes);
    detector_.detect(world_, &clock);
    const CollisionResponseStats responses =
        respondToCollisions(world_, detector_, response, contacts_);
    clock.lap(Stage::Response);
    stats_.candidatePairs += detector_.candidatePairs().size();
    stats_.contacts += contacts_.size();
    stats_.responses.particleResponses += responses.particleResponses;
    stats_.responses.cornerResponses += responses.cornerResponses;
    stats_.responses.edgePushes += responses.edgePushes;
  }
  stats_.planeContacts += resolvePlaneContacts(world_, response != ResponseMode::None);
  clock.lap(Stage::Planes);
}

void Simulator::advanceToFrame(int frame) {
  stats_ = {};
  for (int s = 0; s < substeps_.substeps; ++s) step(frame);
}

void Simulator::reportBlowUp(int frame) const {
  const Index particle = findRunawayParticle(world_);
  const Body& body = world_.bodies[particle == kNoParticle ? 0 : world_.particleBody[particle]];
  const Vec3& v = world_.velocity[particle == kNoParticle ? 0 : particle];
  throw Error(cat("the simulation blew up at frame ", frame, ": body '", body.name, "' particle ",
                  particle - body.firstParticle, " reached speed ",
                  v.allFinite() ? std::to_string(v.norm()) : std::string("NaN"), " (limit ",
                  world_.settings.maxSpeed, "). Use more substeps (now ", substeps_.substeps,
                  ", stable from ", substeps_.minimumStableSubsteps, ") or a lower stiffness"));
}

}  // namespace softbake
