#include "core/simulator.hpp"

#include <algorithm>
#include <iterator>

#include "core/collision/plane_contact.hpp"
#include "core/dynamics/integrator.hpp"
#include "core/error.hpp"
#include "core/mesh/weld.hpp"
#include "core/text.hpp"

namespace softbake {

Simulator::Simulator(std::shared_ptr<const SceneTopology> topology, SimulationState state)
    : topology_(std::move(topology)),
      collision_(buildCollisionGeometry(*topology_)),
      state_(std::move(state)),
      forces_(*topology_),
      stepper_(makeStepper(*topology_)),
      substepStart_(state_.position),
      substeps_(chooseSubsteps(*topology_, topology_->settings.substeps)),
      detector_(topology_->settings.collisions),
      edgePushes_(topology_->particleCount()) {
  if (state_.position.size() != topology_->particleCount() ||
      state_.velocity.size() != topology_->particleCount())
    throw Error(cat("a simulation state of ", state_.position.size(), " positions and ",
                    state_.velocity.size(), " velocities does not fit a scene of ",
                    topology_->particleCount(), " particles"));
  const std::vector<CollisionSurface>& surfaces = collision_.surfaces;
  std::size_t moving = 0;
  for (const CollisionSurface& surface : surfaces) {
    moving += surface.moving;
    collides_ = collides_ || surface.selfCollision;
  }
  collides_ = collides_ || (moving > 0 && surfaces.size() > 1);
  // Detection only (response "none", the paper's figure 5b) lets bodies pass into each other.
  const CollisionSettings& collisions = topology_->settings.collisions;
  const bool setAside = collisions.initialOverlap == InitialOverlapMode::SetAside;
  initialOverlaps_ = findInitialOverlaps(*topology_, collision_, state_.position,
                                         setAside ? fittedDistance() : Scalar(0));
  if (collides_ && collisions.failsafe && collisions.response != ResponseMode::None) {
    failsafe_.emplace(*topology_, collision_);
    failsafe_->leaveOverlapping(initialOverlaps_);
  }
  if (collides_ && collisions.contactsInStep && collisions.response != ResponseMode::None &&
      stepper_->keepsContactsApart())
    stepContacts_.emplace(*topology_, collision_);
  if (collisions.initialOverlap == InitialOverlapMode::Ignore) {
    detector_.ignoreOverlaps(initialOverlaps_);
  } else if (setAside) {
    initiallySetAside_ = initialOverlaps_.pairs;
    overlappingSurfaces_ = overlappingSurfaces(initialOverlaps_);
    // A pair set aside that no longer intersects is as close as a fit at first: it is left to
    // the failsafe until it is apart by the skin, or the response would throw the parts apart
    // where their overlap ends.
    std::merge(initialOverlaps_.pairs.begin(), initialOverlaps_.pairs.end(),
               initialOverlaps_.close.begin(), initialOverlaps_.close.end(),
               std::back_inserter(initiallyFitted_));
  } else {
    // "separate": a body cannot be moved apart from itself, so its own pairs are set aside.
    const std::vector<Index>& surfaceOf = collision_.triangleSurface;
    for (const TrianglePair& pair : initialOverlaps_.pairs)
      if (surfaceOf[pair.first] == surfaceOf[pair.second]) initiallySetAside_.push_back(pair);
    if (collides_ && collisions.response != ResponseMode::None &&
        initiallySetAside_.size() < initialOverlaps_.pairs.size()) {
      detangler_.emplace(*topology_, collision_);
      nameTangledSurfaces(initialOverlaps_);
    }
  }
  detector_.setAside(initiallySetAside_);
  detector_.setFitted(initialOverlaps_.close);
  if (stepper_->stableAtAnyStep()) {
    contactEdgeLength_ = contactEdgeLength(*topology_);
    substeps_.stableAtAnyStep = true;
    if (substeps_.automatic) chooseContactAccuracySubsteps();
  }
}

void Simulator::chooseContactAccuracySubsteps() {
  const ContactAccuracy accuracy = contactAccuracySubsteps(
      *topology_, collision_, state_.position, state_.velocity, detector_.candidatePairs(),
      contactEdgeLength_, contactAccuracyScratch_,
      stepContacts_ ? kInStepContactReachFraction : kContactReachFraction);
  substeps_.substeps = std::max(accuracy.substeps, stepper_->fewestAutoSubsteps(substeps_));
  substeps_.closingSpeed = accuracy.closingSpeed;
  substeps_.timeStep = 1.0 / topology_->settings.fps / substeps_.substeps;
}

Simulator::Simulator(std::shared_ptr<const SceneTopology> topology)
    : Simulator(topology, initialState(*topology)) {}

Simulator::Simulator(SceneTopology topology)
    : Simulator(std::make_shared<const SceneTopology>(std::move(topology))) {}

void Simulator::step(int frame) {
  const SceneTopology& topology = *topology_;
  StageClock clock(measureStages_ ? &stepTimes_ : nullptr);
  StageEnergyMeter energy(measureStageEnergy_ ? &stats_.stageEnergy : nullptr, topology, state_);
  ++stepsTaken_;
  const Scalar dt = Scalar(substeps_.timeStep);
  if (stepContacts_) {
    stepper_->keepApart(topology, stepContacts_->find(topology, collision_, detector_, state_, dt,
                                                      overlappingSurfaces_));
    clock.lap(Stage::Contacts);
  }
  if (stepper_->computeForces(topology, state_, forces_)) clock.lap(Stage::Forces);
  if (!stepper_->step(topology, forces_, dt, state_, substepStart_)) reportBlowUp(frame);
  clock.lap(Stage::Integration);
  energy.lap(Stage::Integration);
  const ResponseMode response = topology.settings.collisions.response;
  if (collides_) {
    detector_.detect(topology, collision_, {substepStart_, state_.position}, &clock);
    std::span<const std::pair<Index, Index>> tangled;
    if (detangler_ && detangler_->any()) {
      stats_.detangledBodies += detangler_->apply(topology, collision_, detector_, state_, dt);
      tangled = detangler_->movedPairs();
    }
    // With the contacts kept apart in the step, the edge pushes repair what the solve let through,
    // and an end behind a face's plane but outside the surface is no crossing to repair. Without
    // them the paper's response is the whole answer, and its own test stands.
    const CollisionResponseStats responses = respondToCollisions(
        topology, collision_, detector_, response, state_, contacts_, edgePushes_, tangled,
        stepContacts_ ? InsideTest::NearestFace : InsideTest::StruckFace, overlappingSurfaces_);
    clock.lap(Stage::Response);
    energy.lap(Stage::Response);
    stats_.candidatePairs += detector_.candidatePairs().size();
    stats_.contacts += contacts_.size();
    stats_.responses += responses;
    if (stepContacts_) {
      const std::span<const char> held = stepper_->contactsHeld();
      stats_.heldContacts += std::size_t(std::count(held.begin(), held.end(), char(1)));
      stepContacts_->appendHeld(collision_, held, state_.position, contacts_);
    }
  }
  stats_.planeContacts += resolvePlaneContacts(
      topology, substepStart_, state_, response != ResponseMode::None, stepper_->planeHolds());
  clock.lap(Stage::Planes);
  energy.lap(Stage::Planes);
  if (failsafe_) {
    stats_.failsafe += failsafe_->apply(topology, collision_, detector_, substepStart_, state_, dt);
    clock.lap(Stage::Failsafe);
    energy.lap(Stage::Failsafe);
  }
  stats_.planeContacts += stepper_->endStep();
}

void Simulator::beginFrame() {
  stats_ = {};
  // The collision stage refills contacts_ every substep; without it they would still hold the
  // last frame's plane contacts.
  if (!collides_) contacts_.clear();
  // Surfaces still tangled are left to the detangler and the response until a frame finds them
  // apart.
  if ((failsafe_ && failsafe_->anyTangled()) || (detangler_ && detangler_->any()))
    nameTangledSurfaces(findInitialOverlaps(*topology_, collision_, state_.position));
  // The pairs set aside at the start that still intersect stay set aside; those found apart
  // collide from now on.
  updateSetAside();
  stats_.setAsidePairs = detector_.setAsidePairs().size();
  if (substeps_.stableAtAnyStep && substeps_.automatic) chooseContactAccuracySubsteps();
}

void Simulator::nameTangledSurfaces(const InitialOverlaps& overlaps) {
  // Only pairs of different surfaces: a surface's own pairs are set aside one by one.
  InitialOverlaps between;
  for (const SurfaceOverlap& overlap : overlaps.bySurfaces)
    if (overlap.firstSurface != overlap.secondSurface) between.bySurfaces.push_back(overlap);
  if (failsafe_) failsafe_->leaveTangled(between);
  if (detangler_) detangler_->setTangled(collision_, between);
}

void Simulator::updateSetAside() {
  if (!initiallySetAside_.empty()) {
    stillIntersecting(collision_, state_.position, initiallySetAside_, setAsideScratch_);
    detector_.setAside(setAsideScratch_);
  }
  if (!initiallyFitted_.empty()) {
    // Let go only beyond the reach of two skins, where the boxes of the two no longer meet: a
    // fit that breathes by a little more than one skin was handed back and forth between the
    // failsafe and the response, whose lifts at the rims pushed stacked blocks off each other.
    // A fit whose faces swap sides by rounding (they do, in every substep) is still a fit: let go
    // as a crossing, it was handed to the response and to the contacts of the step, which pushed
    // each of an engine's parts into the next.
    stillClose(collision_, state_.position, initiallyFitted_, 2 * fittedDistance(), Crossing::Kept,
               setAsideScratch_);
    detector_.setFitted(setAsideScratch_);
  }
}

Scalar Simulator::fittedDistance() const {
  return topology_->settings.skin;
}

void Simulator::advanceToFrame(int frame) {
  beginFrame();
  for (int s = 0; s < substeps_.substeps; ++s) step(frame);
  endFrame();
}

void Simulator::endFrame() {
  appendPlaneContacts(*topology_, state_,
                      topology_->settings.collisions.response != ResponseMode::None, contacts_);
}

SimulationCheckpoint Simulator::checkpoint() const {
  SimulationCheckpoint checkpoint;
  checkpoint.state = state_;
  stepper_->save(checkpoint.warmStart, checkpoint.planeHolds);
  checkpoint.touchingPairs = detector_.candidatePairs();
  checkpoint.tangled = (failsafe_ && failsafe_->anyTangled()) || (detangler_ && detangler_->any());
  checkpoint.stepsTaken = stepsTaken_;
  return checkpoint;
}

void Simulator::restore(const SimulationCheckpoint& checkpoint) {
  const std::size_t n = topology_->particleCount();
  if (checkpoint.state.position.size() != n || checkpoint.state.velocity.size() != n ||
      !stepper_->fits(checkpoint.warmStart.size(), checkpoint.planeHolds.size(), n))
    throw Error(cat("a checkpoint of ", checkpoint.state.position.size(), " particles",
                    checkpoint.warmStart.empty() ? "" : " from the implicit integrator",
                    " does not fit this scene of ", n, " particles under the ",
                    integratorName(topology_->settings.integrator), " integrator"));
  for (const TrianglePair& pair : checkpoint.touchingPairs)
    if (pair.second >= collision_.triangleVertices.size())
      throw Error(cat("a checkpoint names triangle ", pair.second, " of a scene of ",
                      collision_.triangleVertices.size(), " collision triangles"));
  state_ = checkpoint.state;
  stepper_->restore(checkpoint.warmStart, checkpoint.planeHolds);
  detector_.restoreCandidatePairs(checkpoint.touchingPairs);
  // The next frame names the tangled surfaces again from the positions whenever any were left
  // (beginFrame), so whether any were is all that carries over.
  nameTangledSurfaces(checkpoint.tangled
                          ? findInitialOverlaps(*topology_, collision_, state_.position)
                          : InitialOverlaps{});
  // Set aside: a function of the positions alone (updateSetAside()), so nothing to carry.
  updateSetAside();
  stepsTaken_ = checkpoint.stepsTaken;
}

void Simulator::reportBlowUp(int frame) const {
  const SceneTopology& topology = *topology_;
  const Index particle = findRunawayParticle(topology, state_);
  const Body& body = topology.bodies[particle == kNoParticle ? 0 : topology.particleBody[particle]];
  const Vec3& v = state_.velocity[particle == kNoParticle ? 0 : particle];
  const Vec3& x = state_.position[particle == kNoParticle ? 0 : particle];
  // A position that is not finite at a bounded speed came from a stage after the integrator.
  const std::string what =
      !x.allFinite() && v.allFinite() && v.norm() <= topology.settings.maxSpeed
          ? std::string(" was moved to a position that is not finite")
          : cat(" reached speed ", v.allFinite() ? std::to_string(v.norm()) : std::string("NaN"),
                " (limit ", topology.settings.maxSpeed, ")");
  throw SimulationFailure(
      cat("the simulation blew up at frame ", frame, ": body '", body.name, "' particle ",
          particle - body.firstParticle, what, ". Use more substeps (now ", substeps_.substeps,
          substeps_.stableAtAnyStep ? std::string()
                                    : cat(", stable from ", substeps_.minimumStableSubsteps),
          ") or a lower stiffness"));
}

}  // namespace softbake
