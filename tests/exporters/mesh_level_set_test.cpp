#include "exporters/mesh_level_set.hpp"

#include <gtest/gtest.h>

#include <openvdb/math/Proximity.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/global_control.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "core/mesh/icosphere.hpp"

namespace softbake {
namespace {

using openvdb::Vec3d;
using openvdb::Vec3s;

/// A mesh in index space (voxel units), as MeshLevelSet takes it.
struct IndexMesh {
  std::vector<Vec3s> points;
  std::vector<MeshLevelSet::TriangleIndices> triangles;
};

/// A torus (genus 1: concave inside the hole, convex outside), outward winding, `rings` ×
/// `sides` quads, radii in voxels.
IndexMesh makeTorus(float major, float minor, int rings, int sides) {
  IndexMesh mesh;
  const float twoPi = 2 * std::numbers::pi_v<float>;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      const float u = twoPi * float(i) / float(rings), v = twoPi * float(j) / float(sides);
      const float r = major + minor * std::cos(v);
      // Off the lattice, so no voxel centre sits on a vertex by construction.
      mesh.points.emplace_back(r * std::cos(u) + 0.31f, minor * std::sin(v) + 0.17f,
                               r * std::sin(u) - 0.23f);
    }
  const auto at = [&](int i, int j) { return std::uint32_t((i % rings) * sides + (j % sides)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sides; ++j) {
      mesh.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j)});
      mesh.triangles.push_back({at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)});
    }
  return mesh;
}

/// An icosphere with a bumpy, partly concave surface: radius 1 ± 0.25 by direction, in voxels.
IndexMesh makeBumpySphere(float radius) {
  const TriangleMesh sphere = makeIcosphere(4, 1.0f);
  IndexMesh mesh;
  for (const Vec3f& p : sphere.positions) {
    const float bump =
        1 + 0.25f * std::sin(5 * p.x()) * std::cos(4 * p.y() + 1) * std::sin(3 * p.z());
    mesh.points.emplace_back(radius * bump * p.x(), radius * bump * p.y(), radius * bump * p.z());
  }
  for (const Triangle& t : sphere.triangles)
    mesh.triangles.push_back({std::uint32_t(t[0]), std::uint32_t(t[1]), std::uint32_t(t[2])});
  return mesh;
}

/// Reference distance: every triangle, in double, through OpenVDB's own closest-point routine.
double bruteForceDistance(const IndexMesh& mesh, const Vec3d& p) {
  double best = std::numeric_limits<double>::max();
  for (const auto& t : mesh.triangles) {
    Vec3d uvw;
    const Vec3d a(mesh.points[t[0]]), b(mesh.points[t[1]]), c(mesh.points[t[2]]);
    const Vec3d q = openvdb::math::closestPointOnTriangleToPoint(a, b, c, p, uvw);
    best = std::min(best, (p - q).length());
  }
  return best;
}

/// Reference inside test: the generalized winding number (solid angles of all triangles, Van
/// Oosterom & Strackee), 1 inside a closed outward mesh, 0 outside, independent of any normal.
bool inside(const IndexMesh& mesh, const Vec3d& p) {
  double total = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3d a = Vec3d(mesh.points[t[0]]) - p, b = Vec3d(mesh.points[t[1]]) - p,
                c = Vec3d(mesh.points[t[2]]) - p;
    const double la = a.length(), lb = b.length(), lc = c.length();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2 * std::atan2(numerator, denominator);
  }
  return total / (4 * std::numbers::pi) > 0.5;
}

/// Every `stride`-th voxel of the box around the mesh, band included: active exactly where the
/// reference distance is below the band, with the reference value and sign.
void expectMatchesBruteForce(const IndexMesh& mesh, bool closed, float band, int stride) {
  const MeshLevelSet levelSet(mesh.triangles, mesh.points.size(), closed);
  const double voxel = 0.5;  // world units, to see the scaling
  const MeshLevelSet::Grids grids = levelSet.build(mesh.points, nullptr, band, voxel);
  ASSERT_TRUE(grids.distance);
  EXPECT_FALSE(grids.velocity);
  EXPECT_EQ(grids.distance->getGridClass(),
            closed ? openvdb::GRID_LEVEL_SET : openvdb::GRID_UNKNOWN);
  EXPECT_FLOAT_EQ(grids.distance->background(), float(band * voxel));

  openvdb::CoordBBox box;
  for (const Vec3s& p : mesh.points) box.expand(openvdb::Coord::round(p));
  box.expand(int(std::ceil(band)) + 1);
  const auto accessor = grids.distance->getConstAccessor();
  int checked = 0, activeChecked = 0;
  long index = 0;
  for (auto ijk = box.begin(); ijk; ++ijk, ++index) {
    if (index % stride != 0) continue;
    const openvdb::Coord coord = *ijk;
    const Vec3d p = coord.asVec3d();
    const double reference = bruteForceDistance(mesh, p);
    float value = 0;
    const bool active = accessor.probeValue(coord, value);
    ++checked;
    // Voxels within float rounding of the band's edge may go either way.
    if (std::abs(reference - band) < 1e-3) continue;
    ASSERT_EQ(active, reference < band) << coord << " at reference distance " << reference;
    if (!closed || reference > 1e-3) {
      const bool isInside = closed && inside(mesh, p);
      if (active) {
        ++activeChecked;
        ASSERT_NEAR(std::abs(value) / voxel, reference, 2e-4) << coord;
        if (closed) {
          ASSERT_EQ(value < 0, isInside) << coord << " distance " << reference;
        } else {
          ASSERT_GE(value, 0.0f);
        }
      } else {
        // Outside the band: ±background, the sign from the flood fill.
        ASSERT_FLOAT_EQ(std::abs(value), float(band * voxel)) << coord;
        if (closed) {
          ASSERT_EQ(value < 0, isInside) << coord;
        }
      }
    }
  }
  EXPECT_GT(activeChecked, 500);
  EXPECT_GT(checked, activeChecked);
}

TEST(MeshLevelSet, TorusMatchesBruteForceDistanceAndWindingNumberSign) {
  expectMatchesBruteForce(makeTorus(14.0f, 5.0f, 36, 18), true, 3.0f, 3);
}

TEST(MeshLevelSet, BumpySphereMatchesBruteForceAtAWideBand) {
  expectMatchesBruteForce(makeBumpySphere(12.0f), true, 5.5f, 5);
}

TEST(MeshLevelSet, OpenMeshGetsTheUnsignedDistance) {
  IndexMesh torus = makeTorus(14.0f, 5.0f, 36, 18);
  torus.triangles.resize(torus.triangles.size() / 2);  // half a torus: open
  expectMatchesBruteForce(torus, false, 3.0f, 3);
}

/// meshToVolume is the second, independent reference. Without its renormalization (which smooths
/// values by up to a few hundredths of a voxel) both hold exact distances next to the surface,
/// and both find the same band.
TEST(MeshLevelSet, AgreesWithOpenVdbMeshToVolumeNextToTheSurface) {
  openvdb::initialize();
  const IndexMesh mesh = makeBumpySphere(20.0f);
  const MeshLevelSet levelSet(mesh.triangles, mesh.points.size(), true);
  const MeshLevelSet::Grids ours = levelSet.build(mesh.points, nullptr, 3.0f, 1.0);

  std::vector<openvdb::Vec3I> triangles;
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  const openvdb::tools::QuadAndTriangleDataAdapter<Vec3s, openvdb::Vec3I> adapter(mesh.points,
                                                                                  triangles);
  const auto theirs = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
      adapter, *openvdb::math::Transform::createLinearTransform(1.0), 3.0f, 3.0f,
      openvdb::tools::DISABLE_RENORMALIZATION);

  const auto their = theirs->getConstAccessor();
  int compared = 0, disputed = 0;
  for (auto v = ours.distance->cbeginValueOn(); v; ++v) {
    float value = 0;
    if (!their.probeValue(v.getCoord(), value) || std::abs(*v) >= 1.0f) continue;
    ASSERT_NEAR(std::abs(*v), std::abs(value), 1e-3f) << v.getCoord();
    ++compared;
    if ((*v < 0) != (value < 0)) {
      // The two disagree on the side: the winding number decides, and must side with us.
      ++disputed;
      ASSERT_EQ(*v < 0, inside(mesh, v.getCoord().asVec3d())) << v.getCoord() << " " << *v;
    }
  }
  EXPECT_GT(compared, 2000);
  // About 1% of these voxels, all within a few hundredths of a voxel of the surface, get
  // meshToVolume's sign wrong before its renormalization; none get ours wrong.
  RecordProperty("sign_disputes", disputed);
  const double ratio =
      double(ours.distance->activeVoxelCount()) / double(theirs->activeVoxelCount());
  EXPECT_NEAR(ratio, 1.0, 0.01);
}

TEST(MeshLevelSet, VelocityIsTheBarycentricBlendAtTheNearestPoint) {
  const IndexMesh mesh = makeBumpySphere(10.0f);
  // A velocity field linear in position: the blend at the nearest point q is exactly f(q).
  const auto field = [](const Vec3d& p) { return Vec3d(0.5 * p.y(), -2.0, 0.25 * p.x() + 1.0); };
  std::vector<Vec3s> velocities;
  for (const Vec3s& p : mesh.points) velocities.emplace_back(field(Vec3d(p)));
  const MeshLevelSet levelSet(mesh.triangles, mesh.points.size(), true);
  const MeshLevelSet::Grids grids = levelSet.build(mesh.points, velocities.data(), 3.0f, 1.0);
  ASSERT_TRUE(grids.velocity);
  EXPECT_EQ(grids.velocity->activeVoxelCount(), grids.distance->activeVoxelCount());
  EXPECT_TRUE(grids.velocity->tree().hasSameTopology(grids.distance->tree()));

  int index = 0, checked = 0, ties = 0;
  for (auto v = grids.velocity->cbeginValueOn(); v; ++v, ++index) {
    if (index % 7 != 0) continue;
    const Vec3d p = v.getCoord().asVec3d();
    // The nearest point, found again by brute force in double.
    double best = std::numeric_limits<double>::max();
    Vec3d nearest(0.0);
    for (const auto& t : mesh.triangles) {
      Vec3d uvw;
      const Vec3d q = openvdb::math::closestPointOnTriangleToPoint(
          Vec3d(mesh.points[t[0]]), Vec3d(mesh.points[t[1]]), Vec3d(mesh.points[t[2]]), p, uvw);
      if ((p - q).lengthSqr() < best) {
        best = (p - q).lengthSqr();
        nearest = q;
      }
    }
    const Vec3d expected = field(nearest), got(*v);
    // Where two nearest points tie, the searches may pick different ones: both lie at distance
    // d from p, so at most 2d apart, and the field changes by at most 0.6 per voxel.
    const double error = (got - expected).length();
    ASSERT_LE(error, 1e-3 + 0.6 * 2 * std::sqrt(best)) << v.getCoord();
    if (error > 1e-3) ++ties;
    ++checked;
  }
  EXPECT_GT(checked, 1000);
  EXPECT_LT(ties, checked / 200);
}

TEST(MeshLevelSet, SameVoxelsForAnyThreadCount) {
  const IndexMesh mesh = makeTorus(30.0f, 9.0f, 80, 40);
  std::vector<Vec3s> velocities(mesh.points.size(), Vec3s(1, 2, 3));
  const MeshLevelSet levelSet(mesh.triangles, mesh.points.size(), true);
  MeshLevelSet::Grids one, two;
  {
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 1);
    one = levelSet.build(mesh.points, velocities.data(), 3.0f, 0.1);
  }
  {
    const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
    two = levelSet.build(mesh.points, velocities.data(), 3.0f, 0.1);
  }
  ASSERT_TRUE(one.distance->tree().hasSameTopology(two.distance->tree()));
  const auto other = two.distance->getConstAccessor();
  for (auto v = one.distance->cbeginValueAll(); v; ++v)
    ASSERT_EQ(*v, other.getValue(v.getCoord())) << v.getCoord();
}

TEST(MeshLevelSet, RejectsOutOfRangeInput) {
  const IndexMesh mesh = makeTorus(10.0f, 3.0f, 12, 8);
  EXPECT_THROW(MeshLevelSet({{0, 1, 5000}}, 10, true), Error);
  const MeshLevelSet levelSet(mesh.triangles, mesh.points.size(), true);
  std::vector<Vec3s> far = mesh.points;
  far[3] = Vec3s(1e8f, 0, 0);
  EXPECT_THROW(levelSet.build(far, nullptr, 3.0f, 1.0), Error);
  EXPECT_THROW(levelSet.build(mesh.points, nullptr, 0.5f, 1.0), Error);
  far.pop_back();
  EXPECT_THROW(levelSet.build(far, nullptr, 3.0f, 1.0), Error);
}

}  // namespace
}  // namespace softbake
