#pragma once
/// The renderer's pinhole camera: OpenGL's projection conventions, where a point lands in the
/// image, and the automatic framing that fixes one camera for a whole sequence.

#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/types.hpp"

namespace softbake {

/// A pinhole camera looking from `position` at `target`, `up` the world's up (the ground's normal).
struct Camera {
  Vec3f position = Vec3f(0, 0, 5);
  Vec3f target = Vec3f::Zero();
  Vec3f up = Vec3f::UnitY();
  float fovDegrees = 40;
  float near = 0.01f, far = 100;  ///< clip distances, m
};

/// World → clip space (OpenGL conventions: right-handed view, depth −1..1).
Eigen::Matrix4f viewProjection(const Camera& camera, int width, int height);

/// Where `point` lands in the PNG: x to the right, y down from the top row, in pixels (the centre
/// of pixel (i, j) is (i + 0.5, j + 0.5)). Empty when the point is behind the camera.
std::optional<Eigen::Vector2f> projectToPixel(const Camera& camera, int width, int height,
                                              const Vec3f& point);

/// Any unit vector perpendicular to the unit vector `n`.
Vec3f perpendicular(const Vec3f& n);

/// What the scene asks of the camera; an unset position or target is chosen by frameCamera().
struct CameraRequest {
  std::optional<Vec3f> position;
  std::optional<Vec3f> target;
  float fovDegrees = 40;        ///< vertical
  float aspect = 16.0f / 9.0f;  ///< width / height
};

/// The camera for a framed region `bounds` of diagonal `size`, `up` the world's up. Automatic
/// framing looks at the centre from a fixed direction, 30° around and 22° above, from the least
/// distance at which every corner of the bounds lies inside 85% of both fields of view; the clip
/// distances follow the distance and the size. Throws softbake::Error when the position is the
/// target.
Camera frameCamera(const Eigen::AlignedBox3f& bounds, float size, const Vec3f& up,
                   const CameraRequest& request);

}  // namespace softbake
