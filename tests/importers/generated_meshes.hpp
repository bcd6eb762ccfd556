#pragma once
/// Stand-ins for the two shared meshes whose licence keeps them out of the repository
/// (tests/data/meshes/README.md): the same traits, written by the test, with counts known from
/// how they are built rather than from the code under test.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

namespace softbake::test {

namespace detail {

/// Vertex (ring, segment) of a latitude-longitude sphere: ring 0 and `rings` are the poles, one
/// vertex each; the rings between have `segments` vertices. Index 0 is the top pole.
inline std::size_t sphereVertex(int ring, int segment, int rings, int segments) {
  if (ring == 0) return 0;
  if (ring == rings) return 1 + std::size_t(rings - 1) * std::size_t(segments);
  return 1 + std::size_t(ring - 1) * std::size_t(segments) + std::size_t(segment % segments);
}

inline std::string number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", x);
  return text;
}

}  // namespace detail

/// For spot.obj: a closed, textured ellipsoid in OBJ with `v` and `vt` and no normals, no `o` or
/// `g` (so assimp names it "defaultobject"). The texture wraps around it, so the seam and the
/// poles give positions several UVs: assimp splits those vertices, and only a weld by position
/// makes one body again.
struct TexturedObj {
  static constexpr int kSegments = 48, kRings = 24;
  static constexpr std::size_t kPositions = 2 + std::size_t(kRings - 1) * kSegments;
  static constexpr std::size_t kTriangles = 2 * std::size_t(kSegments) * (kRings - 1);
  /// Semi-axes: x is the largest, and the equator has vertices at x = ±kRadiusX exactly.
  static constexpr double kRadiusX = 0.86, kRadiusY = 0.55, kRadiusZ = 0.4;
  static constexpr double kLargestSide = 2 * kRadiusX;  // metre-sized: not rescaled

  static std::string text() {
    std::string obj = "# softbake test stand-in for spot.obj: a textured ellipsoid\n";
    const double pi = std::numbers::pi;
    // Positions: top pole, the rings, bottom pole (detail::sphereVertex's order).
    auto position = [&](int ring, int segment) {
      const double polar = pi * ring / kRings, azimuth = 2 * pi * segment / kSegments;
      obj += "v " + detail::number(kRadiusX * std::sin(polar) * std::cos(azimuth)) + " " +
             detail::number(kRadiusY * std::cos(polar)) + " " +
             detail::number(-kRadiusZ * std::sin(polar) * std::sin(azimuth)) + "\n";
    };
    position(0, 0);
    for (int ring = 1; ring < kRings; ++ring)
      for (int segment = 0; segment < kSegments; ++segment) position(ring, segment);
    position(kRings, 0);
    // UVs on a (segments + 1) × (rings + 1) grid: column kSegments repeats column 0 at u = 1.
    for (int ring = 0; ring <= kRings; ++ring)
      for (int segment = 0; segment <= kSegments; ++segment)
        obj += "vt " + detail::number(double(segment) / kSegments) + " " +
               detail::number(1 - double(ring) / kRings) + "\n";
    auto corner = [&](int ring, int segment) {
      const std::size_t v = detail::sphereVertex(ring, segment, kRings, kSegments) + 1;
      const std::size_t vt = std::size_t(ring) * (kSegments + 1) + std::size_t(segment) + 1;
      return std::to_string(v) + "/" + std::to_string(vt);
    };
    // Counter-clockwise seen from outside: azimuth runs from +x towards -z, polar downwards.
    for (int ring = 0; ring < kRings; ++ring)
      for (int segment = 0; segment < kSegments; ++segment) {
        const std::string a = corner(ring, segment), b = corner(ring + 1, segment),
                          c = corner(ring + 1, segment + 1), d = corner(ring, segment + 1);
        if (ring != 0) obj += "f " + a + " " + b + " " + d + "\n";
        if (ring != kRings - 1) obj += "f " + b + " " + c + " " + d + "\n";
      }
    return obj;
  }
};

/// For bunny.ply: an ASCII PLY scan with per-vertex `confidence` and `intensity`, far below a
/// metre, that is not watertight in the ways a scan is not: an open base (its pole left
/// unreferenced), a hole in its side, two non-manifold fins, and two stray points no face uses.
struct ScanPly {
  static constexpr int kSegments = 32, kRings = 16;
  static constexpr double kRadius = 0.08;
  static constexpr double kLargestSide = 2 * kRadius;  // the equator's x and z extents
  static constexpr std::size_t kSphereVertices = 2 + std::size_t(kRings - 1) * kSegments;
  static constexpr std::size_t kFins = 2, kStrayPoints = 2;
  static constexpr std::size_t kFileVertices = kSphereVertices + kFins + kStrayPoints;
  /// The bottom pole, once its fan is gone, and the stray points.
  static constexpr std::size_t kUnreferencedVertices = 1 + kStrayPoints;
  /// The sphere less the base's fan and one quad of the side, plus the fins.
  static constexpr std::size_t kTriangles =
      2 * std::size_t(kSegments) * (kRings - 1) - std::size_t(kSegments) - 2 + kFins;

  static std::string text() {
    const double pi = std::numbers::pi;
    std::vector<std::array<double, 3>> vertices;
    for (int ring = 0; ring <= kRings; ++ring)
      for (int segment = 0; segment < (ring == 0 || ring == kRings ? 1 : kSegments); ++segment) {
        const double polar = pi * ring / kRings, azimuth = 2 * pi * segment / kSegments;
        vertices.push_back({kRadius * std::sin(polar) * std::cos(azimuth),
                            kRadius * std::cos(polar),
                            -kRadius * std::sin(polar) * std::sin(azimuth)});
      }
    std::vector<std::array<std::size_t, 3>> faces;
    auto at = [&](int ring, int segment) {
      return detail::sphereVertex(ring, segment, kRings, kSegments);
    };
    for (int ring = 0; ring < kRings - 1; ++ring)  // not the last ring: the base stays open
      for (int segment = 0; segment < kSegments; ++segment) {
        const bool hole = ring == kRings / 2 && segment == kSegments / 4;
        if (ring != 0 && !hole)
          faces.push_back({at(ring, segment), at(ring + 1, segment), at(ring, segment + 1)});
        if (!hole)
          faces.push_back(
              {at(ring + 1, segment), at(ring + 1, segment + 1), at(ring, segment + 1)});
      }
    // Each fin stands on an edge of the surface, which then has three faces; its tip is inside.
    for (int fin = 0; fin < int(kFins); ++fin) {
      const std::size_t a = at(4, 8 * fin), b = at(4, 8 * fin + 1);
      std::array<double, 3> tip{};
      for (int k = 0; k < 3; ++k) tip[std::size_t(k)] = 0.4 * (vertices[a][k] + vertices[b][k]);
      faces.push_back({a, b, vertices.size()});
      vertices.push_back(tip);
    }
    vertices.push_back({0, 0, 0});
    vertices.push_back({0.01, -0.02, 0.005});

    std::string ply = "ply\nformat ascii 1.0\ncomment softbake test stand-in for bunny.ply\n";
    ply += "element vertex " + std::to_string(vertices.size()) + "\n";
    ply += "property float x\nproperty float y\nproperty float z\n";
    ply += "property float confidence\nproperty float intensity\n";
    ply += "element face " + std::to_string(faces.size()) + "\n";
    ply += "property list uchar int vertex_indices\nend_header\n";
    for (std::size_t i = 0; i < vertices.size(); ++i)
      ply += detail::number(vertices[i][0]) + " " + detail::number(vertices[i][1]) + " " +
             detail::number(vertices[i][2]) + " " + detail::number(0.5 + 0.5 * double(i % 7) / 7) +
             " " + detail::number(double(i % 11) / 11) + "\n";
    for (const auto& f : faces)
      ply += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
             "\n";
    return ply;
  }
};

}  // namespace softbake::test
