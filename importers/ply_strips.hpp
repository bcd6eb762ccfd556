#pragma once
/// PLY files that store their faces as triangle strips (`element tristrips` with a
/// `vertex_indices` list, strips separated by -1, as in the classic cow model). assimp 5.2 writes
/// every triangle of such an element into the same face and returns one triangle, so softbake
/// reads these files itself.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/mesh/triangle_mesh.hpp"
#include "importers/ply_guard.hpp"

namespace softbake {

/// Whether the file has a `tristrips` element with rows.
bool hasTriangleStrips(const PlyHeader& header);

/// Appends the triangles of `indices`: strips separated by -1. A strip's triangle k has the
/// corners k, k+1, k+2, the first two swapped for odd k so that every triangle keeps the first
/// one's winding. Triangles with two equal corners join strips and are skipped, but still count
/// for the alternation. Returns how many of the triangles had an index that is negative (other
/// than -1) or not below `vertexCount`; those are skipped too.
std::size_t appendStripTriangles(std::span<const double> indices, std::uint64_t vertexCount,
                                 std::vector<Triangle>& triangles);

struct PlyStripMesh {
  TriangleMesh mesh;                ///< positions, and normals and UVs when the file has them
  std::size_t stripTriangles = 0;   ///< of the triangles, those from strips
  std::size_t pointsAndLines = 0;   ///< faces of fewer than 3 corners, skipped
  std::vector<std::string> losses;  ///< "3 triangles dropped (vertex index out of range)"
};

/// Reads the file's vertices (x, y, z; nx, ny, nz and u, v, s, t or texture_u, texture_v when
/// present), its strips and any `face` lists (as fans) from `data`, the bytes after the header,
/// as far as the data goes. Throws softbake::Error starting with `source` when the file has no
/// vertex positions or its strips are not integer lists, naming what it cannot read.
PlyStripMesh readPlyStripMesh(const PlyHeader& header, std::string_view data,
                              std::string_view source);

}  // namespace softbake
