#include "core/collision/triangle_pair_intersection.hpp"

namespace softbake {

int intersectEdgesWithTriangle(const TriangleCorners& edgeTriangle, const TriangleCorners& face,
                               std::array<EdgeHit, 2>& hits) {
  const Vec3 faceNormal = triangleNormal(face);
  return intersectEdgesWithTriangle(edgeTriangle, triangleNormal(edgeTriangle), face, faceNormal,
                                    sidesOfPlane(edgeTriangle, face, faceNormal), hits);
}

int intersectEdgesWithTriangle(const TriangleCorners& edgeTriangle, const Vec3& edgeNormal,
                               const TriangleCorners& face, const Vec3& faceNormal,
                               const std::array<Scalar, 3>& side, std::array<EdgeHit, 2>& hits) {
  // All three corners strictly on one side of the face's plane: no edge can cross it. The sides
  // are computed exactly as intersectSegmentTriangle computes them, so this only skips tests that
  // would fail; most broad-phase pairs are near misses and end here. The segment tests take them
  // as their edges' ends' sides.
  if ((side[0] > 0 && side[1] > 0 && side[2] > 0) || (side[0] < 0 && side[1] < 0 && side[2] < 0))
    return 0;
  // A zero-area edge triangle lies on one line, and its longest edge covers the other two: testing
  // all three would report one crossing up to three times, at points a rounding error apart.
  int firstEdge = 0, passes = 3;
  if (edgeNormal == Vec3::Zero()) {
    passes = 1;
    Scalar longest = -1;
    for (int edge = 0; edge < 3; ++edge) {
      const Scalar length = (edgeTriangle[(edge + 1) % 3] - edgeTriangle[edge]).squaredNorm();
      if (length > longest) {
        longest = length;
        firstEdge = edge;
      }
    }
  }

  int count = 0;
  for (int pass = 0; pass < passes && count < 2; ++pass) {
    const int edge = firstEdge + pass;
    SegmentTriangleHit hit;
    const int next = (edge + 1) % 3;
    if (!intersectSegmentTriangle(edgeTriangle[edge], edgeTriangle[next], face[0], face[1], face[2],
                                  faceNormal, side[edge], side[next], hit))
      continue;
    // Two edges of a proper triangle share only corners, and a corner hit is returned exactly:
    // equality is the whole duplicate test.
    if (count == 1 && hit.point == hits[0].hit.point) continue;
    hits[count].hit = hit;
    hits[count].edge = static_cast<std::uint8_t>(edge);
    ++count;
  }
  return count;
}

bool intersectTrianglePair(const TriangleCorners& first, const TriangleCorners& second,
                           TrianglePairHits& hits) {
  hits.firstCount = intersectEdgesWithTriangle(first, second, hits.firstEdges);
  hits.secondCount = intersectEdgesWithTriangle(second, first, hits.secondEdges);
  return hits.firstCount + hits.secondCount > 0;
}

}  // namespace softbake
