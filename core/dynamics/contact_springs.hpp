#pragma once
/// Contacts kept apart inside the implicit solve, between bodies as against static meshes:
/// stiff one-sided springs along a fixed normal whose Jacobian enters the conjugate-gradient
/// product (Baraff & Witkin 1998 treat cloth–cloth contact by such springs, §6; Macklin et al.
/// 2019, "Small Steps", compare them with constraints).
///
/// Why inside the solve: the paper's response corrects a crossing after the step, one particle at
/// a time, while the rest of the body stays where the step left it. At steps larger than a
/// contact's time scale that correction stores energy in the springs to the particle's neighbours
/// and lets the next step cross again, so the step count was set by the collision stages
/// (kContactReachFraction), not by the dynamics. Here the contact force is part of the same
/// backward-Euler step as the springs, so the struck triangle moves in the solve too: the one-
/// sided plane holds (contact_holds.hpp) cannot do that for soft–soft contacts.
///
/// A stencil is a particle against a triangle's plane (found up front by the collision stage,
/// core/collision/step_contacts.hpp): C(x) = n·Σ w_k x_k + offset, with w = (1, −b₀, −b₁, −b₂) for
/// a particle and the barycentric coordinates b of its foot on the triangle, and offset holding
/// the corners that cannot move and the gap the contact keeps (C ≥ 0 is apart). C is affine in x
/// for the fixed normal, so the spring's energy ½·k·C² at the end of the step linearises exactly:
/// with c = h²·k and g the stencil's gradient, the system gains c·g·gᵀ and the right-hand side
/// −c·g·(C₀/h + g·v₀). c is set from the stencil's own effective mass, c·Σ w_k²/m_k = kStiffness,
/// so the solve removes all but 1/(1 + kStiffness) of a penetration, for any mass and step.
///
/// A spring acts only where it pushes (an active set): at the start those whose particle would end
/// the step within the gap under its own motion and gravity; after each solve, a spring whose
/// result pulls (C > 0 at the end) is let go and a stencil that ends within the gap is taken in,
/// and the step is solved again from its Δv (at most kRounds times). Friction is in the solve too:
/// a sticking contact damps the relative tangential velocity with the same c (two more rank-one
/// rows, along two tangents), and one whose impulse would exceed μ times the normal impulse slides
/// instead, damped by μ·J_n/|u_t|: a damping, so it never turns the motion round (a constant
/// impulse did, and gained energy in the piles).
/// Applied after the solve, friction could only stop the contact's own particles, which the rest of
/// the body dragged on: a block on a 20° slope slid at friction 4.
///
/// Products stay deterministic: each particle computes its stencils' terms, dots included, in
/// stencil order through an incidence list sorted by particle, so the result is the same for any
/// thread count, and a product is one pass over particles with no barrier of its own. Buffers keep
/// their capacity: a step allocates nothing once the contacts have settled.

#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/scene/contact_stencil.hpp"
#include "core/types.hpp"

namespace softbake {

class ContactSprings {
 public:
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  static constexpr Index kNoRow = Index(-1);
  /// c·Σ w_k²/m_k: the solve leaves 1/(1 + kStiffness) of a penetration. Stiffer costs CG more
  /// iterations where many contacts couple (bench/results/integrators.md).
  static constexpr Scalar kStiffness = 100;
  /// Most solves taken again per step for springs that pulled or stencils that ended inside.
  static constexpr int kRounds = 3;
  /// A change of a contact's friction damping by more than this share takes the step again.
  static constexpr Scalar kFrictionSlack = Scalar(0.05);

  explicit ContactSprings(std::size_t particles) : rowOf_(particles, kNoRow) {}

  /// Replaces the stencils for the next step; `inverseMass` per particle. A pinned corner may be
  /// named: it counts in C and never moves.
  void set(std::span<const ContactStencil> stencils, const Scalar* inverseMass);
  bool empty() const { return stencils_.empty(); }
  std::size_t size() const { return stencils_.size(); }
  std::size_t activeCount() const { return activeCount_; }
  /// Per stencil, whether its spring acts.
  std::span<const char> active() const { return active_; }

  /// The particles some stencil moves, ascending; row(i) is i's place among them or kNoRow.
  std::span<const Index> touched() const { return touched_; }
  Index row(Index particle) const { return rowOf_[particle]; }

  /// At the start of a step of `h` from x₀, v₀: C₀ of every stencil and the first active set.
  void begin(const Vec3* x0, const Vec3* v0, const Vec3& gravity, Scalar h);
  /// The solve's rows of the touched particle `row`: its diagonal block and right-hand side
  /// without contacts, kept by the assembly.
  void keepBaseDiagonal(std::size_t row, const Mat3& diagonal) { baseDiagonal_[row] = diagonal; }
  void keepBaseRhs(std::size_t row, const Vec3& rhs) { baseRhs_[row] = rhs; }
  /// The right-hand side and inverse diagonal block, with the active springs, of the touched
  /// particles in [begin, end).
  void applyRows(Vec3* rhs, Mat3* inverseDiagonal, std::size_t begin, std::size_t end) const;
  /// The springs' part of the product over the touched particles in [begin, end):
  /// out_i += Σ c·(g·x)·g_i. Returns Σ x_i·(what it added), their share of xᵀ·A·x. Reads x of
  /// any particle, writes out only in the range: one pass of a parallel loop over particles.
  double multiply(const Vec3* x, Vec3* out, std::size_t begin, std::size_t end) const;

  /// After a solve that gave `deltaV`: lets go of springs that pull, takes in stencils that end
  /// within the gap, raises the force of springs that end more than `tolerance` inside it (an
  /// augmented-Lagrangian step: a spring stiff enough for its own particles yields under a whole
  /// body's load; never a `fitted` stencil's, beside holds that cannot give way), and moves
  /// friction between sticking and sliding. Returns how many changed.
  std::size_t update(const Vec3* v0, const Vec3* deltaV, Scalar h, Scalar tolerance);
  /// Joins in `group` (per body, its group's lowest body; each body its own on entry) the bodies
  /// an active spring couples, and marks in `held` a body of each group with a spring against a
  /// corner that cannot move: the group takes an outside impulse (restoreMomentum() takes a group
  /// as held when any of its bodies is marked).
  void joinBodies(const Index* particleBody, std::vector<Index>& group,
                  std::vector<char>& held) const;

 private:
  /// The rows [first, last) of touched() whose particles lie in [begin, end).
  std::pair<std::size_t, std::size_t> rowsIn(std::size_t begin, std::size_t end) const;
  /// Σ w_k·x_k over a stencil's corners that are particles.
  Vec3 weightedSum(const ContactStencil& stencil, const Vec3* x) const;
  /// Stencil s's three rows' coefficients and right-hand-side scales from its state.
  void refresh(std::size_t s, Scalar h);

  std::vector<ContactStencil> stencils_;
  std::vector<Scalar> stiffness_;  ///< c per stencil: kStiffness / Σ w²/m
  /// Σ w over the corners that move: gravity moves them alike, and the fixed ones not at all.
  std::vector<Scalar> freeWeight_;
  std::vector<Scalar> gap0_;  ///< C₀ per stencil
  /// Per stencil, where its spring's force vanishes: 0, raised by what the latest solves left
  /// inside (update()).
  std::vector<Scalar> bias_;
  std::vector<char> active_;
  std::size_t activeCount_ = 0;
  /// Friction per stencil: the damping of the tangential velocity, c while it sticks, μ·J_n/|u_t|
  /// while it slides.
  std::vector<Scalar> tangentCoefficient_;
  /// Three rows per stencil, along its normal and two tangents: the direction, g·v₀ along it, the
  /// matrix coefficient (the spring's c along the normal, the friction damping along the
  /// tangents; 0 where inactive) and the right-hand side's scale.
  std::vector<Vec3> direction_;
  std::vector<Scalar> approach_, coefficient_, rhsScale_;
  std::vector<Index> rowOf_;  ///< per particle
  std::vector<Index> touched_;
  /// Per touched particle its incidences, (stencil, corner), in stencil order.
  std::vector<Index> incidenceStart_;
  std::vector<std::pair<Index, Index>> incidence_;
  std::vector<std::pair<Index, std::pair<Index, Index>>> sortScratch_;
  std::vector<Mat3> baseDiagonal_;
  std::vector<Vec3> baseRhs_;
};

}  // namespace softbake
