#pragma once
/// The tests' own count of intersecting triangle pairs, exact: what "no interpenetration" means in
/// every collision test, computed independently of the code under test (core/collision).
///
/// Triangle pairs whose bounding boxes overlap (a sweep along x) are decided by CGAL's
/// triangle–triangle intersection test on the exact-predicates kernel (Epick): each orientation
/// predicate is evaluated in interval arithmetic first and, only when the interval straddles zero,
/// again in exact multi-precision arithmetic. Float coordinates convert to double exactly, so the
/// answer is exact for the geometry the simulation holds: touching counts as intersecting, and no
/// tolerance hides a crossing.
///
/// Counted:
/// - between surfaces: every pair of triangles of two different surfaces (bodies and static
///   meshes);
/// - within a surface: pairs of one surface's triangles that share no vertex (triangles that share
///   one touch there by construction; a fold across a shared edge or vertex is not counted).
/// Zero-area triangles are skipped: they have no inside to cross.

#include <array>
#include <cstddef>
#include <map>
#include <span>
#include <utility>
#include <vector>

#include "core/collision/geometry.hpp"
#include "core/collision/triangle_pair_intersection.hpp"
#include "core/types.hpp"

namespace softbake::test {

struct IntersectionCount {
  std::size_t betweenSurfaces = 0;
  std::size_t withinSurfaces = 0;
  /// Per pair of surfaces (lower index first; a surface with itself for the pairs within one).
  std::map<std::pair<Index, Index>, std::size_t> bySurfaces;
  /// Every intersecting pair of triangles, lower index first, sorted.
  std::vector<std::pair<Index, Index>> pairs;
  std::size_t total() const { return betweenSurfaces + withinSurfaces; }
};

/// Counts the intersecting triangle pairs of `geometry` with its particles at `positions`.
IntersectionCount countIntersectingPairs(const CollisionGeometry& geometry,
                                         std::span<const Vec3> positions);

/// How far one of two triangles must move to part them (their penetration depth), in double: the
/// least overlap of their projections onto their separating axes (both normals, the cross
/// products of their edges, and each edge's normal within its plane), which for two convex
/// polygons is the least over every direction. 0 for triangles apart. How deep a crossing is,
/// where which side of a plane is which says nothing: faces fitted onto each other at a slight
/// angle cross each other's planes far from where they meet.
double penetrationDepth(const TriangleCorners& a, const TriangleCorners& b);

/// The distance between two closed triangles, in double: the least over each one's edges of the
/// edge's distance from the other triangle; 0 where they meet.
double triangleDistance(const TriangleCorners& a, const TriangleCorners& b);

/// How two intersecting triangles cross: how many edges of `a` meet `b`, and how many of `b` meet
/// `a`, in double. Two of one and none of the other: a corner of that one has gone through the
/// other's face, which a vertex–face contact sees. One of each: their edges are linked, a crossing
/// of edge against edge that no corner of either shows.
std::array<int, 2> edgesThrough(const TriangleCorners& a, const TriangleCorners& b);

/// Float spacings within which two triangles count as touching (see touchingWithinRounding()).
inline constexpr double kTouchingSpacings = 4;

/// Whether two triangles lie within kTouchingSpacings spacings of a float at their largest
/// coordinate of each other, touching included: so close that rounding their coordinates alone
/// decides whether they meet. Faces modelled onto each other (the parts of a CAD assembly fitted
/// face to face) come out of a float mesh that close, a step to one side or the other, and which
/// side says nothing about the model: the exact checker calls them apart or intersecting by it.
bool touchingWithinRounding(const TriangleCorners& a, const TriangleCorners& b);

}  // namespace softbake::test
