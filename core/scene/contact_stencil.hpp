#pragma once
/// One contact a step keeps apart: a particle against a triangle's plane, as a linear function of
/// the positions. The collision stage finds them (core/collision/step_contacts.hpp) and the
/// implicit solve keeps them (core/dynamics/contact_springs.hpp); neither layer sees the other,
/// so the stencil lives below both.

#include <array>

#include "core/types.hpp"

namespace softbake {

struct ContactStencil {
  /// Where a corner cannot move (a static mesh's vertex, a pinned particle).
  static constexpr Index kFixed = Index(-1);
  std::array<Index, 4> particle{kFixed, kFixed, kFixed, kFixed};
  std::array<Scalar, 4> weight{0, 0, 0, 0};
  Vec3 normal = Vec3::Zero();  ///< unit, towards the side the particle is kept on
  Scalar offset = 0;           ///< C(x) = normal·Σ weight_k·x_k + offset
  Scalar friction = 0;         ///< Coulomb coefficient
  /// Of a surface fitted onto another (core/collision/step_contacts.hpp): the solve never raises
  /// its force beyond the spring's own.
  bool fitted = false;
};

}  // namespace softbake
