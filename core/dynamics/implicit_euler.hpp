#pragma once
/// Backward Euler linearised once per step (Baraff & Witkin, "Large Steps in Cloth Simulation",
/// SIGGRAPH 1998), solved matrix-free by preconditioned conjugate gradients.
///
/// With h the step, M the masses, K = ∂f/∂x and D = ∂f/∂v of the springs, one step solves
///
///   (M − h·D − h²·K) Δv = h·(f₀ + h·K·v₀),   then v ← v₀ + Δv,  x ← x₀ + h·v
///
/// f₀ is every force at the start of the step (springs with their damping, gas pressure, gravity),
/// exactly what the explicit integrator uses. Each spring contributes a symmetric 3×3 block
/// S = h·c·d̂d̂ᵀ + h²·k·(d̂d̂ᵀ + max(0, 1 − L/l)·(I − d̂d̂ᵀ)) coupling its two ends; the transverse term
/// is clamped at zero for compressed springs (Choi & Ko 2002), so the system matrix
/// M + Σ S stays symmetric positive definite and CG converges. Gas pressure is soft next to the
/// springs and stays explicit, in f₀. CG starts from the previous step's Δv. Pinned particles are
/// held by the constraint filter of Baraff & Witkin §5.3: their rows and columns are projected out
/// of the residual and the search directions, so Δv is zero there.
///
/// The step is unconditionally stable for the springs: large steps damp high frequencies instead
/// of blowing up. That numerical damping grows with h; more substeps reduce it.
///
/// A block is stored as S = α·d̂d̂ᵀ + β·I (α = h·c + h²·k·L/l, β = h²·k·max(0, 1 − L/l)): five
/// numbers instead of nine, and fewer operations in the product, which is laid out for SIMD
/// (core/dynamics/sliced_spring_matrix.hpp). Each step assembles the blocks in that layout, each
/// particle's springs from its own end in the lanes of its slice, together with its forces and its
/// diagonal block: one pass that scatters nothing, so the product reads memory in order and no
/// Spring. Each CG iteration is three parallel passes: the product
/// with its curvature dot, the update of Δv and the residual with both residual dots, and the new
/// search direction. CG is preconditioned by the inverse 3×3 diagonal blocks.
///
/// Particles resting on a static surface are held by the same filter along the surface's normal
/// alone (§5.3 and §6): their Δv has a prescribed normal part, the one that leaves them at the
/// surface after the step, and the solve moves their neighbours with them. Projected after the
/// step instead, a resting particle moves by up to v·h while its neighbours stay; with springs
/// stiffer than the step (k·h²/m > 1) that stores more energy in them than the particle's own
/// kinetic energy, which the response was meant to remove. The filter removes the normal part of
/// the residual at a held particle, and what it removed is the surface's impulse on the particle:
/// Coulomb friction slows the tangential velocity by μ times that impulse, and a particle whose
/// impulse pulls it towards the surface is let go at the next step.
///
/// A closed body with a bulk modulus (Material::bulkModulus) has the pressure P = nRT/V +
/// K·(1 − V/V_rest), and its forces P·g_i (g_i = ∂V/∂x_i) change with the volume: their Jacobian
/// holds −(K/V_rest)·g·gᵀ, one rank-one block per body. It enters the solve, which is what keeps a
/// loaded body's volume at large steps; the change of g itself is left out, as for the gas. The
/// product adds c·g·(g·p), c = h²·K/V_rest, which needs g·p over the body first: the product's pass
/// sums it per run of a body's particles within a chunk, the serial step between passes per body
/// (in chunk order, so for any thread count), and the next pass adds it. Rank one adds one
/// eigenvalue to the system, which costs CG about one iteration however stiff the body is.
///
/// CG stops at a tolerance, and its residual's sum would change a body's momentum; that sum is
/// removed per body (restoreMomentum), so internal forces conserve momentum to rounding.
///
/// Deterministic: the matrix product gathers each particle's springs in the fixed order of its
/// incidence row, and every dot product sums fixed chunks in parallel, then the chunk sums in
/// order, so the result is the same for any thread count. All buffers are sized at construction:
/// a step allocates nothing.

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/dynamics/chunk_phases.hpp"
#include "core/dynamics/contact_springs.hpp"
#include "core/dynamics/forces.hpp"
#include "core/dynamics/sliced_spring_matrix.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/scene/simulation_state.hpp"

namespace softbake {

/// How the latest solve went.
struct ImplicitSolveStats {
  int iterations = 0;  ///< conjugate-gradient iterations
  /// Those of every solve of the latest step: a step taken again for particles that met a plane
  /// (stepAgain) solves twice.
  int stepIterations = 0;
  /// The phases of the latest step's solves, each a barrier every thread waits at
  /// (chunk_phases.hpp): what limits the gain from more cores, with the step's other parallel
  /// loops.
  std::uint64_t stepPhases = 0;
  double relativeResidual = 0;  ///< |r| / |b − M·h·g| at the end (kGravityShare floors the latter)
  std::size_t contacts = 0;     ///< contact springs active at the end of the latest step
};

class ImplicitEuler;
/// Asked after each solve of a step whether it changed what the step holds (plane holds caught at
/// the solve's predicted end); when it did, the step is solved again within its rounds.
class SolveRounds {
 public:
  virtual std::size_t afterSolve(ImplicitEuler& solver, const SimulationState& state,
                                 Scalar dt) = 0;

 protected:
  ~SolveRounds() = default;
};

class ImplicitEuler {
 public:
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;

  /// Largest number of CG iterations per step; the residual tolerance usually stops it far sooner.
  static constexpr int kMaxIterations = 200;
  /// Relative residual |r|/|b| at which CG stops; Blender's cloth solver stops at the same. 1e-3
  /// costs twice the iterations per step (bench/results/integrators.md) and changes no property
  /// the tests check: rest shape and volume, momentum, energy that only falls.
  static constexpr double kTolerance = 1e-2;
  /// The same for a solve of a step's contact rounds that another round follows (stepAgain()).
  /// 0.3 let figure 7 at one substep a frame gain 140 J; 0.1 gains 4.6 J (38 J with every solve
  /// at kTolerance).
  static constexpr double kRoundTolerance = 1e-1;
  /// The relative residual of a step's first solve, between kTolerance and kRoundTolerance: what
  /// keeps the error it leaves in a step's motion under gravity within the contact springs'
  /// tolerance (implicit_euler.cpp). A first solve stopped at 3e-2 at one substep a frame let
  /// figure 7 gain 365 J.
  static double firstSolveTolerance(const SimulationSettings& settings, Scalar dt);
  /// |b| above measures the load beyond gravity's impulse M·h·g, which moves every free particle
  /// alike and which the springs do not resist; this share of |M·h·g| is its floor. Measured
  /// against the whole |b|, a residual of 1% of gravity's impulse bent bodies in free fall: the
  /// parts of an engine dropped with collisions and pressure off spread at 0.075 m/s by the third
  /// frame, 0.004 m/s with the floor (a thousandth gives 0.003).
  static constexpr double kGravityShare = 1e-2;

  explicit ImplicitEuler(const SceneTopology& topology);

  /// One step of `dt` seconds from the current state. The springs' forces are computed here, with
  /// their Jacobians; `forces` supplies the gas pressure (computePressureForces() at the current
  /// state), and its spring forces are not read.
  /// `substepStart` receives the positions at the start of the step, for the collision stages.
  /// Returns false when some particle's velocity is not finite or exceeds settings.maxSpeed.
  bool step(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
            SimulationState& state, std::span<Vec3> substepStart, SolveRounds* rounds = nullptr);
  /// The latest step again, from the same state (restored by the caller) with more particles
  /// held: the system depends on the state alone, so only the solve is redone, warm-started from
  /// the first one. The result is what step() would give, at about half the cost: for what the
  /// rounds' SolveRounds did not catch.
  bool stepAgain(const SceneTopology& topology, Scalar dt, SimulationState& state,
                 std::span<Vec3> substepStart, SolveRounds* rounds = nullptr);
  /// During a step's rounds: holds `particle` as hold() does, its speed along the normal taken
  /// against `velocity`, the state's (what stepAgain() does for the holds set before the step).
  void holdInRound(Index particle, const Vec3& normal, Scalar normalSpeed, Scalar friction,
                   const Vec3& velocity) {
    hold(particle, normal, normalSpeed, friction);
    holdSpeed_[particle] -= normal.dot(velocity);
  }
  /// During a step's rounds: lets go of `particle`'s hold.
  void releaseInRound(Index particle);
  /// The latest solve's Δv of `particle`.
  const Vec3& deltaV(Index particle) const { return deltaV_[particle]; }

  const ImplicitSolveStats& lastSolve() const { return stats_; }

  /// The contacts the next step keeps apart (contact_springs.hpp), found at the state it starts
  /// from; they replace the previous step's.
  void keepApart(std::span<const ContactStencil> stencils, const SceneTopology& topology) {
    contacts_.set(stencils, topology.inverseMass.data());
  }
  /// Per stencil, whether the latest step's solve held it.
  std::span<const char> contactsHeld() const { return contacts_.active(); }

  /// The latest step's Δv per particle, where the next solve starts from: part of what a
  /// checkpoint must carry for a resumed run to continue bit for bit.
  std::span<const Vec3> warmStart() const { return {deltaV_.data(), rhs_.size()}; }
  void setWarmStart(std::span<const Vec3> deltaV);

  /// Holds `particle` on a static surface during the next step: its velocity along the unit
  /// `normal` becomes `normalSpeed`, and `friction` (Coulomb) slows its tangential velocity by
  /// the surface's impulse. A hold lasts until releaseHolds().
  void hold(Index particle, const Vec3& normal, Scalar normalSpeed, Scalar friction);
  /// After step(): the impulse along its normal (N·s) the surface gave a particle held during it;
  /// negative when the hold kept it from leaving.
  Scalar holdImpulse(Index particle) const { return -holdResidual_[particle]; }
  /// The particles held during the latest step, in the order they were held.
  const std::vector<Index>& heldParticles() const { return held_; }
  void releaseHolds();

 private:
  void assemble(const SceneTopology& topology, const ForceBuffers& forces, Scalar dt,
                const SimulationState& state);
  /// The bulk terms (see above): g·x summed over each run of a body's particles in `chunk`.
  void sumVolumeDots(const Vec3* x, std::size_t chunk);
  /// The runs' sums per body, in order: sets volumeScale_ to c·(g·x) and returns Σ c·(g·x)².
  double finishVolumeDots();
  /// out_i += factor·c·(g·x)·g_i at the particles of `chunk`, with the latest finishVolumeDots().
  void addVolumeProduct(Vec3* out, Scalar factor, std::size_t chunk);
  /// One PCG solve from the current Δv, stopped at |r| ≤ relativeTolerance·|b|; adds its
  /// iterations and phases to the step's.
  void solve(const SceneTopology& topology, double relativeTolerance);
  /// Makes each body without pins or held particles change momentum by exactly its external
  /// impulse.
  void restoreMomentum(const SceneTopology& topology);
  /// x without its part along the hold normal of particle i (x itself when i is not held).
  Vec3 filtered(Index i, const Vec3& x) const {
    const Vec3& n = holdNormal_[i];
    return x - n.dot(x) * n;
  }

  std::vector<Index> freeBodies_;  ///< bodies without pinned particles
  SlicedSpringMatrix matrix_;      ///< M + Σ S, for the product
  /// Per slot of matrix_, its spring's share of h²·K·v₀ in that row, h²·K_s·(v_other − v_i), one
  /// array per coordinate.
  std::vector<Scalar> velocityTermX_, velocityTermY_, velocityTermZ_;
  /// Per particle: gravity plus its springs' forces at the step's start (pressure is added after).
  std::vector<Vec3> springForce_;
  std::vector<Vec3> rhs_;               ///< b, per particle
  Vec3 gravityImpulse_ = Vec3::Zero();  ///< h·g of the latest step
  double massNorm_ = 0;                 ///< |m| over the free particles
  /// Block-Jacobi preconditioner: the inverse of each particle's 3×3 diagonal block of M + Σ S.
  /// A third fewer iterations than the scalar diagonal, since a block holds the springs' axes.
  std::vector<Mat3> inverseDiagonal_;
  /// deltaV_ and direction_, the product's inputs, have matrix_.paddedSize() entries; those past
  /// the particles are always 0.
  std::vector<Vec3> deltaV_, residual_, preconditioned_, direction_, product_;
  bool warmStarted_ = false;                     ///< deltaV_ holds a step's Δv, or a checkpoint's
  std::vector<std::array<double, 3>> chunkSum_;  ///< a pass's sums per chunk
  ChunkPhases phases_;                           ///< the solve's passes, in one parallel region
  ContactSprings contacts_;
  /// Holds of the next step, per particle: the unit normal (zero when not held), the velocity
  /// along it, the friction coefficient; then the normal part of the residual during the solve.
  std::vector<Vec3> holdNormal_;
  std::vector<Scalar> holdSpeed_, holdFriction_, holdResidual_;
  std::vector<Vec3> holdFrictionChange_;  ///< friction's velocity change at held particles
  std::vector<Index> held_;               ///< particles with a hold, reserved for all of them
  std::vector<char> isHeld_;              ///< per particle: it has a hold
  std::vector<char> bodyHeld_;            ///< per body: some particle was held this step
  /// Per body: whether restoreMomentum() corrects its Δv, and by what, for the step's last pass.
  std::vector<char> bodyCorrected_;
  std::vector<Vec3> bodyCorrection_;
  /// restoreMomentum()'s: per body whether it is free and its group (bodies joined by contact
  /// springs, by their lowest body); per group whether it is held, its excess and its mass; per
  /// free body its excess and mass.
  std::vector<char> bodyFree_;
  std::vector<Index> bodyGroup_;
  std::vector<char> groupHeld_;
  std::vector<Vec3d> groupExcess_;
  std::vector<double> groupMass_;
  std::vector<Vec3d> bodyExcess_;
  std::vector<double> bodyMass_;
  /// The bulk terms: the bodies with one; per body its index among them (kNoVolumeBody if none);
  /// the runs of their particles within a chunk, in particle order, and each chunk's first run;
  /// per triangle a third of its ∂V/∂x, per particle g_i (zero where pinned); per run its latest
  /// dot, per body c = h²·K/V_rest and c·(g·x) of the latest dots.
  struct VolumeRun {
    Index volumeBody;  ///< into volumeBodies_
    Index begin, end;  ///< particles
  };
  static constexpr Index kNoVolumeBody = Index(-1);
  std::vector<Index> volumeBodies_, volumeBodyOf_;
  std::vector<VolumeRun> volumeRuns_;
  std::vector<std::size_t> chunkRunStart_;
  std::vector<Vec3> triangleGradient_, volumeGradient_;
  std::vector<double> runDot_, volumeCoefficient_;
  std::vector<Scalar> volumeScale_;
  int stepIterations_ = 0;        ///< CG iterations of the latest step's solves
  std::uint64_t stepPhases_ = 0;  ///< and their phases
  ImplicitSolveStats stats_;
};

}  // namespace softbake
