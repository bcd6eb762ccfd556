#pragma once
/// Narrow-band distance field of one triangle mesh, for the VDB export: exact Euclidean distance to
/// the nearest triangle in every voxel within `band` voxels of the surface, signed by the
/// angle-weighted pseudonormal of the nearest feature (Bærentzen & Aanæs, "Signed distance
/// computation using the angle weighted pseudonormal", IEEE TVCG 11(3), 2005) for closed meshes,
/// unsigned for open ones, together with the surface velocity at the nearest point.
///
/// Why not openvdb::tools::meshToVolume: it reaches the same distances by voxelizing a thin band
/// and growing it a voxel at a time through sparse-tree lookups, and at a voxel of 1/200 of a
/// 100k-face body spends ~1.4 CPU-seconds a frame on that (most of it in tree access, not in the
/// geometry). Here the triangles are sorted into the 8³ leaves their band touches, and each leaf
/// is filled in flat arrays, one leaf per task, so the cost is the geometry itself. The
/// pseudonormal sign is exact for closed, edge-manifold meshes that do not cross themselves; where
/// a deformed body does cross itself, a voxel between the crossing sheets takes the sign of its
/// nearest sheet (meshToVolume smooths such spots instead). The result is identical for any thread
/// count.
///
/// Index space: voxel (i, j, k) is centred at (i, j, k) · voxelSize in world space, as OpenVDB's
/// linear transforms place it; points are given already divided by the voxel size.

#include <array>
#include <cstdint>
#include <vector>

#include <openvdb/openvdb.h>

namespace softbake {

class MeshLevelSet {
 public:
  using TriangleIndices = std::array<std::uint32_t, 3>;

  /// `triangles` index `vertexCount` vertices; `closed` meshes get a signed level set, open ones
  /// an unsigned distance. The adjacency the pseudonormals need is built once, here.
  MeshLevelSet(std::vector<TriangleIndices> triangles, std::size_t vertexCount, bool closed);

  struct Grids {
    /// World-space distance, class level set (closed) or unknown (open), background band ·
    /// voxelSize, active where the distance is below band voxels; interior tiles −background.
    openvdb::FloatGrid::Ptr distance;
    /// The velocity at each active voxel's nearest surface point (barycentric blend of the nearest
    /// triangle's vertex velocities), same active voxels; null when no velocities were given.
    openvdb::Vec3SGrid::Ptr velocity;
  };

  /// `points`: vertex positions in index space (world / voxelSize), finite and within ±2^22
  /// voxels of the origin. `velocities`: one per vertex, or nullptr. `band` ≥ 1 voxel.
  Grids build(const std::vector<openvdb::Vec3s>& points, const openvdb::Vec3s* velocities,
              float band, double voxelSize) const;

  bool closed() const { return closed_; }

 private:
  std::vector<TriangleIndices> triangles_;
  std::size_t vertexCount_ = 0;
  bool closed_ = false;
  // Pseudonormal adjacency (closed meshes): edge e of triangle t (corners e, e+1) is edge
  // edgeOfCorner_[3t+e]; the triangles around edge k are edgeTriangles_[edgeStart_[k] ..
  // edgeStart_[k+1]); the (triangle·3 + corner) uses of vertex v are vertexCorners_[vertexStart_[v]
  // .. vertexStart_[v+1]).
  std::vector<std::uint32_t> edgeOfCorner_, edgeStart_, edgeTriangles_;
  std::vector<std::uint32_t> vertexStart_, vertexCorners_;
};

}  // namespace softbake
