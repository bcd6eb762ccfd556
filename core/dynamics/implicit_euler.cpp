#include "core/dynamics/implicit_euler.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <tuple>

#include "core/dynamics/for_each_particle.hpp"
#include "core/dynamics/integrator.hpp"
#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {
/// Particles per chunk of the fused CG passes: the chunks, not the threads, fix the summation
/// order; small enough that two threads share the work of a 5 000-particle scene evenly (ten
/// chunks; at 1 024 the six were split three to two, and figure 7 ran 5% slower).
constexpr std::size_t kChunk = 512;
/// How far inside its gap, as a share of the skin, a contact spring may end before its force is
/// raised and the step solved again.
constexpr Scalar kContactTolerance = Scalar(0.1);
/// Solves a step may take beyond the contact springs' rounds for what SolveRounds changes: plane
/// holds caught at a solve's predicted end need one more solve after the springs' last.
constexpr int kPlaneRounds = 1;

/// y[k] += a·x[k] for k < count, over arrays that do not overlap.
void addScaled(Scalar* __restrict y, Scalar a, const Scalar* __restrict x, std::size_t count) {
  for (std::size_t k = 0; k < count; ++k) y[k] += a * x[k];
}

double dot(const Vec3& a, const Vec3& b) {
  return double(a.x()) * b.x() + double(a.y()) * b.y() + double(a.z()) * b.z();
}
}  // namespace

ImplicitEuler::ImplicitEuler(const SceneTopology& topology)
    : matrix_(topology),
      velocityTermX_(matrix_.slotCount(), 0),
      velocityTermY_(matrix_.slotCount(), 0),
      velocityTermZ_(matrix_.slotCount(), 0),
      springForce_(topology.particleCount(), Vec3::Zero()),
      rhs_(topology.particleCount(), Vec3::Zero()),
      inverseDiagonal_(topology.particleCount(), Mat3::Zero()),
      deltaV_(matrix_.paddedSize(), Vec3::Zero()),
      residual_(topology.particleCount(), Vec3::Zero()),
      preconditioned_(topology.particleCount(), Vec3::Zero()),
      direction_(matrix_.paddedSize(), Vec3::Zero()),
      product_(topology.particleCount(), Vec3::Zero()),
      chunkSum_((topology.particleCount() + kChunk - 1) / kChunk),
      contacts_(topology.particleCount()),
      holdNormal_(topology.particleCount(), Vec3::Zero()),
      holdSpeed_(topology.particleCount(), 0),
      holdFriction_(topology.particleCount(), 0),
      holdResidual_(topology.particleCount(), 0),
      holdFrictionChange_(topology.particleCount(), Vec3::Zero()),
      isHeld_(topology.particleCount(), 0),
      bodyHeld_(topology.bodies.size(), 0),
      bodyCorrected_(topology.bodies.size(), 0),
      bodyCorrection_(topology.bodies.size(), Vec3::Zero()),
      bodyFree_(topology.bodies.size(), 0),
      bodyGroup_(topology.bodies.size(), 0),
      groupHeld_(topology.bodies.size(), 0),
      groupExcess_(topology.bodies.size(), Vec3d::Zero()),
      groupMass_(topology.bodies.size(), 0.0) {
  static_assert(kChunk % SlicedSpringMatrix::kLanes == 0, "a chunk holds whole slices");
  held_.reserve(topology.particleCount());
  const std::size_t n = topology.particleCount();
  for (std::size_t i = 0; i < n; ++i)
    if (topology.inverseMass[i] != 0) massNorm_ += double(topology.mass[i]) * topology.mass[i];
  massNorm_ = std::sqrt(massNorm_);
  volumeBodyOf_.assign(topology.bodies.size(), kNoVolumeBody);
  for (Index b = 0; b < topology.bodies.size(); ++b) {
    const Body& body = topology.bodies[b];
    if (!(bulkStiffness(body) > 0) || body.particleCount == 0) continue;
    volumeBodyOf_[b] = Index(volumeBodies_.size());
    // The body's particles, cut where a chunk ends.
    for (std::size_t begin = body.firstParticle; begin < body.firstParticle + body.particleCount;) {
      const std::size_t end = std::min<std::size_t>(body.firstParticle + body.particleCount,
                                                    (begin / kChunk + 1) * kChunk);
      volumeRuns_.push_back({Index(volumeBodies_.size()), Index(begin), Index(end)});
      begin = end;
    }
    volumeBodies_.push_back(b);
  }
  if (!volumeBodies_.empty()) {
    chunkRunStart_.assign(chunkSum_.size() + 1, 0);
    for (const VolumeRun& run : volumeRuns_) ++chunkRunStart_[run.begin / kChunk + 1];
    for (std::size_t c = 0; c < chunkSum_.size(); ++c) chunkRunStart_[c + 1] += chunkRunStart_[c];
    triangleGradient_.assign(topology.triangles.size(), Vec3::Zero());
    volumeGradient_.assign(n, Vec3::Zero());
    runDot_.assign(volumeRuns_.size(), 0.0);
    volumeCoefficient_.assign(volumeBodies_.size(), 0.0);
    volumeScale_.assign(volumeBodies_.size(), 0);
  }
  for (Index b = 0; b < topology.bodies.size(); ++b) {
    const Body& body = topology.bodies[b];
    bool pinned = false;
    for (Index i = body.firstParticle; i < body.firstParticle + body.particleCount; ++i)
      pinned = pinned || topology.inverseMass[i] == 0;
    if (!pinned && body.particleCount > 0) freeBodies_.push_back(b);
  }
  for (Index b : freeBodies_) bodyFree_[b] = 1;
  bodyExcess_.assign(freeBodies_.size(), Vec3d::Zero());
  bodyMass_.assign(freeBodies_.size(), 0.0);
}

void ImplicitEuler::hold(Index particle, const Vec3& normal, Scalar normalSpeed, Scalar friction) {
  if (!isHeld_[particle]) held_.push_back(particle);
  isHeld_[particle] = 1;
  holdNormal_[particle] = normal;
  holdSpeed_[particle] = normalSpeed;
  holdFriction_[particle] = friction;
}

void ImplicitEuler::setWarmStart(std::span<const Vec3> deltaV) {
  if (deltaV.size() != rhs_.size())
    throw Error(cat("a warm start of ", deltaV.size(), " velocities does not fit ", rhs_.size(),
                    " particles"));
  std::copy(deltaV.begin(), deltaV.end(), deltaV_.begin());
  warmStarted_ = true;
}

void ImplicitEuler::releaseHolds() {
  for (Index i : held_) {
    holdNormal_[i].setZero();
    isHeld_[i] = 0;
    holdResidual_[i] = 0;
    holdFrictionChange_[i].setZero();
  }
  held_.clear();
}

void ImplicitEuler::restoreMomentum(const SceneTopology& topology) {
  // Internal forces cancel within a body, in b and in A·Δv alike, so the exact solution changes a
  // free body's momentum by Σ b (its external impulse) alone. CG stops at a residual whose sum is
  // not zero; the body's share of it, spread as one velocity, is removed. Contact springs between
  // bodies are internal to the group of bodies they join (their weights sum to zero), so a group
  // is restored as one. A body with held particles, a pin, or a spring against a static mesh also
  // takes outside impulses, which the residual's sum holds: its group is left alone.
  std::fill(bodyHeld_.begin(), bodyHeld_.end(), 0);
  for (Index i : held_) bodyHeld_[topology.particleBody[i]] = 1;
  std::iota(bodyGroup_.begin(), bodyGroup_.end(), Index(0));
  contacts_.joinBodies(topology.particleBody.data(), bodyGroup_, bodyHeld_);
  tbb::parallel_for(std::size_t(0), freeBodies_.size(), [&](std::size_t k) {
    const Body& body = topology.bodies[freeBodies_[k]];
    const Index end = body.firstParticle + body.particleCount;
    Vec3d excess = Vec3d::Zero();
    double mass = 0;
    for (Index i = body.firstParticle; i < end; ++i) {
      excess += rhs_[i].cast<double>() - double(topology.mass[i]) * deltaV_[i].cast<double>();
      mass += double(topology.mass[i]);
    }
    bodyExcess_[k] = excess;
    bodyMass_[k] = mass;
  });
  // Per group, in body order: the same sums for any thread count. A group with a pinned body
  // (not among the free ones) is held.
  std::fill(groupExcess_.begin(), groupExcess_.end(), Vec3d::Zero());
  std::fill(groupMass_.begin(), groupMass_.end(), 0.0);
  std::fill(groupHeld_.begin(), groupHeld_.end(), 0);
  for (Index b = 0; b < bodyGroup_.size(); ++b) {
    const Index group = bodyGroup_[b];
    groupHeld_[group] |= char(bodyHeld_[b] || !bodyFree_[b]);
  }
  for (std::size_t k = 0; k < freeBodies_.size(); ++k) {
    const Index group = bodyGroup_[freeBodies_[k]];
    groupExcess_[group] += bodyExcess_[k];
    groupMass_[group] += bodyMass_[k];
  }
  // Each body's correction is added to its Δv by the step's last pass over the particles
  // (stepAgain), not by a parallel loop of its own: each loop is a barrier of the step.
  std::fill(bodyCorrected_.begin(), bodyCorrected_.end(), 0);
  for (const Index b : freeBodies_) {
    const Index group = bodyGroup_[b];
    if (groupHeld_[group]) continue;
    bodyCorrection_[b] = (groupExcess_[group] / groupMass_[group]).cast<Scalar>();
    bodyCorrected_[b] = 1;
  }
}

void ImplicitEuler::sumVolumeDots(const Vec3* x, std::size_t chunk) {
  for (std::size_t r = chunkRunStart_[chunk]; r < chunkRunStart_[chunk + 1]; ++r) {
    double sum = 0;
    for (Index i = volumeRuns_[r].begin; i < volumeRuns_[r].end; ++i)
      sum += dot(volumeGradient_[i], x[i]);
    runDot_[r] = sum;
  }
}

double ImplicitEuler::finishVolumeDots() {
  double curvature = 0;
  std::size_t r = 0;
  for (std::size_t k = 0; k < volumeBodies_.size(); ++k) {
    double sum = 0;
    for (; r < volumeRuns_.size() && volumeRuns_[r].volumeBody == k; ++r) sum += runDot_[r];
    volumeScale_[k] = Scalar(volumeCoefficient_[k] * sum);
    curvature += volumeCoefficient_[k] * sum * sum;
  }
  return curvature;
}

void ImplicitEuler::addVolumeProduct(Vec3* out, Scalar factor, std::size_t chunk) {
  for (std::size_t r = chunkRunStart_[chunk]; r < chunkRunStart_[chunk + 1]; ++r) {
    const Scalar scale = factor * volumeScale_[volumeRuns_[r].volumeBody];
    for (Index i = volumeRuns_[r].begin; i < volumeRuns_[r].end; ++i)
      out[i] += scale * volumeGradient_[i];
  }
}

void ImplicitEuler::assemble(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
                             const SimulationState& state) {
  // The springs' forces, blocks and h²·K·v₀ terms, and each particle's diagonal block, in one
  // pass over the matrix's slices (SlicedSpringMatrix::assemble()); then per particle the gas
  // pressure, b = h·f₀ + h²·K·v₀ and the block-Jacobi preconditioner.
  const SlicedSpringMatrix::AssemblyInput input{state.position.data(), state.velocity.data(),
                                                topology.settings.gravity, dt};
  const SlicedSpringMatrix::AssemblyOutput output{
      springForce_.data(), inverseDiagonal_.data()->data(), velocityTermX_.data(),
      velocityTermY_.data(), velocityTermZ_.data()};
  static_assert(sizeof(Mat3) == 9 * sizeof(Scalar), "a block is its nine entries, column-major");
  const std::size_t n = topology.particleCount();
  constexpr std::size_t kLanes = SlicedSpringMatrix::kLanes;
  const Scalar h = dt;
  gravityImpulse_ = h * topology.settings.gravity;
  const bool volume = !volumeBodies_.empty();
  if (volume) {
    for (std::size_t k = 0; k < volumeBodies_.size(); ++k)
      volumeCoefficient_[k] =
          double(h) * double(h) * bulkStiffness(topology.bodies[volumeBodies_[k]]);
    computeTriangleVolumeGradients(topology, state.position, triangleGradient_);
  }
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, (n + kLanes - 1) / kLanes, kParticleGrain / kLanes),
      [&](const tbb::blocked_range<std::size_t>& slices) {
        const std::size_t begin = slices.begin() * kLanes;
        const std::size_t end = std::min(n, slices.end() * kLanes);
        matrix_.assemble(input, output, begin, end);
        for (std::size_t i = begin; i < end; ++i) {
          if (topology.inverseMass[i] == 0) {
            rhs_[i].setZero();
            inverseDiagonal_[i].setZero();
            if (volume) volumeGradient_[i].setZero();  // the filter: a pinned row is empty
            continue;
          }
          Vec3 b = h * addPressureForces(topology, forces, Index(i), springForce_[i]);
          const Index rowLength = topology.springRowStart[i + 1] - topology.springRowStart[i];
          for (Index k = 0; k < rowLength; ++k) {
            const std::size_t at = matrix_.slot(Index(i), k);
            b += Vec3(velocityTermX_[at], velocityTermY_[at], velocityTermZ_[at]);
          }
          rhs_[i] = b;
          Mat3 diagonal = inverseDiagonal_[i];
          const Index volumeBody = volume ? volumeBodyOf_[topology.particleBody[i]] : kNoVolumeBody;
          if (volumeBody != kNoVolumeBody) {
            Vec3 gradient = Vec3::Zero();
            for (Index r = topology.triangleRowStart[i]; r < topology.triangleRowStart[i + 1]; ++r)
              gradient += triangleGradient_[topology.triangleRefs[r]];
            volumeGradient_[i] = gradient;
            diagonal += Scalar(volumeCoefficient_[volumeBody]) * gradient * gradient.transpose();
          }
          if (const Index row = contacts_.row(Index(i)); row != ContactSprings::kNoRow)
            contacts_.keepBaseDiagonal(row, diagonal);
          inverseDiagonal_[i] = diagonal.inverse();
        }
      });
  if (volume) {
    // The bulk terms' share of h²·K·v₀: −c·g·(g·v₀).
    const std::size_t chunks = chunkSum_.size();
    tbb::parallel_for(std::size_t(0), chunks,
                      [&](std::size_t chunk) { sumVolumeDots(state.velocity.data(), chunk); });
    finishVolumeDots();
    tbb::parallel_for(std::size_t(0), chunks,
                      [&](std::size_t chunk) { addVolumeProduct(rhs_.data(), -1, chunk); });
  }
  const std::span<const Index> touched = contacts_.touched();
  for (std::size_t row = 0; row < touched.size(); ++row)
    contacts_.keepBaseRhs(row, rhs_[touched[row]]);
  contacts_.begin(state.position.data(), state.velocity.data(), topology.settings.gravity, h);
}

void ImplicitEuler::solve(const SceneTopology& topology, double relativeTolerance) {
  // Preconditioned CG (Shewchuk 1994, B3), warm-started from the previous step's Δv: successive
  // steps change velocity alike, so the first residual is already small. Pinned entries stay 0.
  // Held particles start, and stay, with their prescribed normal part (modified PCG, Baraff &
  // Witkin §5.3): the residual, its preconditioned form and so every search direction are
  // filtered, and the filtered-out normal part of the residual is kept as the surface's impulse.
  //
  // The passes run as the phases of one parallel region (chunk_phases.hpp): the warm start's
  // product, the first residual with its norm, then per iteration the product of the direction,
  // the update of Δv and the residual, and the next direction. Each between() reads the chunk sums
  // in chunk order and picks the next pass.
  const std::size_t n = topology.particleCount();
  const Scalar* inverseMass = topology.inverseMass.data();
  for (Index i : held_) deltaV_[i] = filtered(i, deltaV_[i]) + holdSpeed_[i] * holdNormal_[i];
  // Contact springs: their rows of the right-hand side and the preconditioner are set by the
  // first pass, which the residual's pass follows; each product adds theirs, particle by particle.
  const bool rows = !contacts_.empty();
  const bool contacts = contacts_.activeCount() > 0;
  enum class Pass { WarmProduct, Residual, Product, Update, Direction };
  Pass pass = Pass::WarmProduct;
  const std::size_t chunks = chunkSum_.size();
  double rz = 0, rhsNorm = 0, tolerance = 0;
  Scalar alpha = 0, beta = 0;
  int iteration = 0;
  bool zeroRhs = false;
  const bool volume = !volumeBodies_.empty();
  stats_ = {};
  const auto runPass = [&](std::size_t chunk) {
    const std::size_t begin = chunk * kChunk, end = std::min(n, (chunk + 1) * kChunk);
    double first = 0, second = 0, third = 0;
    switch (pass) {
      case Pass::WarmProduct:
        if (rows) contacts_.applyRows(rhs_.data(), inverseDiagonal_.data(), begin, end);
        matrix_.multiply(deltaV_.data(), product_.data(), inverseMass, begin, end);
        if (contacts) contacts_.multiply(deltaV_.data(), product_.data(), begin, end);
        if (volume) sumVolumeDots(deltaV_.data(), chunk);
        break;
      case Pass::Residual:
        if (volume) addVolumeProduct(product_.data(), 1, chunk);
        for (std::size_t i = begin; i < end; ++i) {
          const Vec3 residual = rhs_[i] - product_[i];
          holdResidual_[i] = holdNormal_[i].dot(residual);
          residual_[i] = residual - holdResidual_[i] * holdNormal_[i];
          preconditioned_[i] = filtered(Index(i), inverseDiagonal_[i] * residual_[i]);
          direction_[i] = preconditioned_[i];
          first += dot(residual_[i], preconditioned_[i]);
          third += dot(residual_[i], residual_[i]);
          if (inverseMass[i] == 0) continue;
          const Vec3 load = filtered(Index(i), rhs_[i] - topology.mass[i] * gravityImpulse_);
          second += dot(load, load);
        }
        break;
      case Pass::Product:
        first = matrix_.multiply(direction_.data(), product_.data(), inverseMass, begin, end);
        if (contacts) first += contacts_.multiply(direction_.data(), product_.data(), begin, end);
        if (volume) sumVolumeDots(direction_.data(), chunk);
        break;
      case Pass::Update: {
        if (volume) addVolumeProduct(product_.data(), 1, chunk);
        // A held particle's product loses its normal part, the surface's, which its hold
        // residual takes; then Δv and the residual are two updates over plain arrays of
        // coordinates, which the compiler vectorises (the same operations, coordinate by
        // coordinate, as on the vectors).
        for (std::size_t i = begin; i < end; ++i) {
          if (!isHeld_[i]) continue;
          const Scalar normalPart = holdNormal_[i].dot(product_[i]);
          holdResidual_[i] -= alpha * normalPart;
          product_[i] = product_[i] - normalPart * holdNormal_[i];
        }
        addScaled(deltaV_[begin].data(), alpha, direction_[begin].data(), 3 * (end - begin));
        addScaled(residual_[begin].data(), -alpha, product_[begin].data(), 3 * (end - begin));
        for (std::size_t i = begin; i < end; ++i) {
          preconditioned_[i] = isHeld_[i] ? filtered(Index(i), inverseDiagonal_[i] * residual_[i])
                                          : inverseDiagonal_[i] * residual_[i];
          first += dot(residual_[i], residual_[i]);
          second += dot(residual_[i], preconditioned_[i]);
        }
        break;
      }
      case Pass::Direction: {
        Scalar* direction = direction_[begin].data();
        const Scalar* preconditioned = preconditioned_[begin].data();
        for (std::size_t k = 0; k < 3 * (end - begin); ++k)
          direction[k] = preconditioned[k] + beta * direction[k];
        break;
      }
    }
    chunkSum_[chunk] = {first, second, third};
  };
  const auto between = [&] {
    std::array<double, 3> total{0, 0, 0};
    for (const std::array<double, 3>& sum : chunkSum_)
      for (int k = 0; k < 3; ++k) total[k] += sum[k];
    switch (pass) {
      case Pass::WarmProduct:
        if (volume) finishVolumeDots();
        pass = Pass::Residual;
        return true;
      case Pass::Residual:
        rz = total[0];
        rhsNorm = std::max(std::sqrt(total[1]),
                           kGravityShare * double(gravityImpulse_.norm()) * massNorm_);
        zeroRhs = rhsNorm == 0;
        if (zeroRhs) return false;
        tolerance = relativeTolerance * rhsNorm;
        stats_.relativeResidual = std::sqrt(total[2]) / rhsNorm;
        iteration = 1;
        pass = Pass::Product;
        return stats_.relativeResidual > relativeTolerance && iteration <= kMaxIterations;
      case Pass::Product: {
        const double curvature = volume ? total[0] + finishVolumeDots() : total[0];
        alpha = Scalar(rz / curvature);
        pass = Pass::Update;
        return curvature > 0;  // else converged to rounding, or a degenerate direction
      }
      case Pass::Update: {
        stats_.iterations = iteration;
        stats_.relativeResidual = std::sqrt(total[0]) / rhsNorm;
        if (std::sqrt(total[0]) <= tolerance) return false;
        beta = Scalar(total[1] / rz);
        rz = total[1];
        pass = Pass::Direction;
        return true;
      }
      case Pass::Direction:
        pass = Pass::Product;
        return ++iteration <= kMaxIterations;
    }
    return false;
  };
  stepPhases_ += phases_.run(chunks, runPass, between);
  stepIterations_ += stats_.iterations;
  if (zeroRhs) forEachParticle(n, [&](Index i) { deltaV_[i] = holdSpeed_[i] * holdNormal_[i]; });
}

double ImplicitEuler::firstSolveTolerance(const SimulationSettings& settings, Scalar dt) {
  // The rounds start from the contacts the first solve finds, so its error must not move a
  // particle by more than the springs' own tolerance (kContactTolerance of the skin). A relative
  // residual ε leaves an error of about ε·h·g in Δv, so ε·h²·g a step in the position: at one
  // substep a frame ε is held to kTolerance, from four (0.094 at 24 frames/s, a 1 mm skin and
  // Earth's gravity) it is about kRoundTolerance.
  const double g = double(settings.gravity.norm());
  if (!(g > 0) || !(dt > 0)) return kTolerance;
  return std::clamp(double(kContactTolerance) * double(settings.skin) / (double(dt) * dt * g),
                    kTolerance, kRoundTolerance);
}

void ImplicitEuler::releaseInRound(Index particle) {
  held_.erase(std::find(held_.begin(), held_.end(), particle));
  holdNormal_[particle].setZero();
  isHeld_[particle] = 0;
  holdSpeed_[particle] = 0;
  holdResidual_[particle] = 0;
  holdFrictionChange_[particle].setZero();
}

bool ImplicitEuler::step(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
                         SimulationState& state, std::span<Vec3> substepStart,
                         SolveRounds* rounds) {
  assemble(topology, forces, dt, state);
  if (!warmStarted_) {
    // The first solve starts from free fall, as every later one starts from the step before. From
    // Δv = 0, CG stopped by its residual, which weighs each particle by its mass, left the light
    // particles of small parts (a house's fittings: 2 µg a particle) millimetres out of place in
    // free fall, and their neighbours' failsafe then worked for seconds a step.
    forEachParticle(topology.particleCount(), [&](Index i) {
      if (topology.inverseMass[i] != 0) deltaV_[i] = gravityImpulse_;
    });
    warmStarted_ = true;
  }
  stepIterations_ = 0;
  stepPhases_ = 0;
  return stepAgain(topology, dt, state, substepStart, rounds);
}

bool ImplicitEuler::stepAgain(const SceneTopology& topology, Scalar dt, SimulationState& state,
                              std::span<Vec3> substepStart, SolveRounds* rounds) {
  // A hold prescribes the velocity along its normal; Δv's part is what that takes from v₀.
  for (Index i : held_) holdSpeed_[i] -= holdNormal_[i].dot(state.velocity[i]);
  const double firstTolerance = firstSolveTolerance(topology.settings, dt);
  solve(topology, firstTolerance);
  // The contact springs' active set: those that pulled let go, stencils that ended inside taken
  // in; the plane holds: particles the solve would leave on a plane held, expected ones that the
  // plane pulled let go. Then the step is solved again from its Δv. A solve that another round may
  // follow only has to tell the round which contacts change, so it stops at kRoundTolerance, and
  // the last solve is taken to kTolerance (inexact Newton: Dembo, Eisenstat & Steihaug 1982).
  constexpr int kAllRounds = ContactSprings::kRounds + kPlaneRounds;
  bool exact = firstTolerance == kTolerance;
  for (int round = 0; round < kAllRounds; ++round) {
    std::size_t changed = 0;
    if (round < ContactSprings::kRounds && !contacts_.empty())
      changed += contacts_.update(state.velocity.data(), deltaV_.data(), dt,
                                  kContactTolerance * topology.settings.skin);
    if (rounds) changed += rounds->afterSolve(*this, state, dt);
    if (changed == 0) break;
    exact = round + 1 == kAllRounds;
    solve(topology, exact ? kTolerance : kRoundTolerance);
  }
  if (!exact) solve(topology, kTolerance);
  stats_.stepIterations = stepIterations_;
  stats_.stepPhases = stepPhases_;
  stats_.contacts = contacts_.activeCount();
  restoreMomentum(topology);
  // Coulomb friction at held particles, from the surface's impulse on each. Kept apart from Δv,
  // which warm-starts the next solve: folded into it, friction's change (a particle stopped dead,
  // unlike its neighbours) doubled the iterations of bodies resting on the ground.
  for (Index i : held_) {
    holdFrictionChange_[i].setZero();
    const Scalar impulse = holdImpulse(i);
    if (!(impulse > 0)) continue;
    const Vec3& normal = holdNormal_[i];
    const Vec3 v = state.velocity[i] + deltaV_[i];
    const Vec3 tangential = v - normal.dot(v) * normal;
    const Scalar tangentialSpeed = tangential.norm();
    const Scalar slowdown = holdFriction_[i] * impulse * topology.inverseMass[i];
    holdFrictionChange_[i] =
        -(tangentialSpeed > slowdown ? slowdown / tangentialSpeed : Scalar(1)) * tangential;
  }
  const Scalar* inverseMass = topology.inverseMass.data();
  const Scalar maxSpeedSquared = topology.settings.maxSpeed * topology.settings.maxSpeed;
  std::atomic<bool> runaway{false};
  forEachParticle(topology.particleCount(), [&](Index i) {
    substepStart[i] = state.position[i];
    if (inverseMass[i] == 0) {
      state.velocity[i].setZero();
      return;
    }
    // Friction changes the velocity the next step starts from, not this step's positions: moved
    // after the solve, a particle stopped by friction stretched the springs to its neighbours,
    // which the solve never saw, and a sheet landing on the ground at 4 substeps a frame gained
    // 40 J. In the next solve its neighbours follow it.
    if (const Index body = topology.particleBody[i]; bodyCorrected_[body])
      deltaV_[i] += bodyCorrection_[body];
    state.velocity[i] += deltaV_[i];
    state.position[i] += dt * state.velocity[i];
    state.velocity[i] += holdFrictionChange_[i];
    if (isRunaway(state.velocity[i], maxSpeedSquared))
      runaway.store(true, std::memory_order_relaxed);
  });
  return !runaway.load();
}

}  // namespace softbake
