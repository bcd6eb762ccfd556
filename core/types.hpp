#pragma once
/// Scalar and vector types shared by every stage of the simulation.
///
/// The simulation scalar is float unless SOFTBAKE_DOUBLE_PRECISION is set: float halves the bytes
/// moved by the gather-heavy spring and pressure loops, and explicit Euler's own error dwarfs float
/// round-off. Sums over whole meshes (volume) are always accumulated in double.
/// bench/layout_bench measures both choices.

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <array>
#include <cstdint>

namespace softbake {

#ifdef SOFTBAKE_DOUBLE_PRECISION
using Scalar = double;
#else
using Scalar = float;
#endif

using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
using Vec3f = Eigen::Vector3f;
using Vec2f = Eigen::Vector2f;
using Vec3d = Eigen::Vector3d;

/// Index of a particle, triangle or spring. 32 bits: a 1M-face scene uses ~0.5M particles.
using Index = std::uint32_t;
using Triangle = std::array<Index, 3>;

// Positions are stored as packed xyz triples (array of structs): the spring and pressure loops
// gather two or three random particles each, and one cache line then serves all three components.
static_assert(sizeof(Vec3) == 3 * sizeof(Scalar), "Vec3 must be a packed triple");

}  // namespace softbake
