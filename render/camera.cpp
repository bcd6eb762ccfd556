#include "render/camera.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"

namespace softbake {

namespace {

constexpr float kDegrees = std::numbers::pi_v<float> / 180.0f;

Eigen::Matrix4f lookAt(const Camera& camera) {
  const Vec3f forward = (camera.target - camera.position).normalized();
  const Vec3f side = forward.cross(camera.up).normalized();
  const Vec3f up = side.cross(forward);
  Eigen::Matrix4f view = Eigen::Matrix4f::Identity();
  view.block<1, 3>(0, 0) = side.transpose();
  view.block<1, 3>(1, 0) = up.transpose();
  view.block<1, 3>(2, 0) = -forward.transpose();
  view(0, 3) = -side.dot(camera.position);
  view(1, 3) = -up.dot(camera.position);
  view(2, 3) = forward.dot(camera.position);
  return view;
}

Eigen::Matrix4f perspective(float fovDegrees, float aspect, float near, float far) {
  const float f = 1.0f / std::tan(0.5f * fovDegrees * kDegrees);
  Eigen::Matrix4f projection = Eigen::Matrix4f::Zero();
  projection(0, 0) = f / aspect;
  projection(1, 1) = f;
  projection(2, 2) = (far + near) / (near - far);
  projection(2, 3) = 2 * far * near / (near - far);
  projection(3, 2) = -1;
  return projection;
}

}  // namespace

Vec3f perpendicular(const Vec3f& n) {
  const Vec3f other = std::abs(n.z()) < 0.9f ? Vec3f::UnitZ() : Vec3f::UnitX();
  return (other - n * n.dot(other)).normalized();
}

Eigen::Matrix4f viewProjection(const Camera& camera, int width, int height) {
  return perspective(camera.fovDegrees, float(width) / float(height), camera.near, camera.far) *
         lookAt(camera);
}

std::optional<Eigen::Vector2f> projectToPixel(const Camera& camera, int width, int height,
                                              const Vec3f& point) {
  const Eigen::Vector4f clip = viewProjection(camera, width, height) * point.homogeneous();
  if (clip.w() <= 0) return std::nullopt;
  const float x = clip.x() / clip.w(), y = clip.y() / clip.w();
  return Eigen::Vector2f(0.5f * (x + 1) * float(width), 0.5f * (1 - y) * float(height));
}

Camera frameCamera(const Eigen::AlignedBox3f& bounds, float size, const Vec3f& up,
                   const CameraRequest& request) {
  Camera camera;
  camera.fovDegrees = request.fovDegrees;
  camera.up = up;
  const Vec3f center = bounds.center();
  camera.target = request.target.value_or(center);
  if (request.position) {
    camera.position = *request.position;
  } else {
    // Fixed view direction, 30° around and 22° above the scene; the distance is the least at
    // which every corner of the bounds lies inside 85% of both fields of view.
    const float aspect = request.aspect;
    const float tanY = 0.85f * std::tan(0.5f * request.fovDegrees * kDegrees), tanX = tanY * aspect;
    const Vec3f front = std::abs(camera.up.dot(Vec3f::UnitZ())) < 0.9f
                            ? Vec3f(Vec3f::UnitZ() - camera.up * camera.up.z()).normalized()
                            : perpendicular(camera.up);
    const Vec3f side = camera.up.cross(front).normalized();
    const float azimuth = 30 * kDegrees, elevation = 22 * kDegrees;
    const Vec3f horizontalDirection = front * std::cos(azimuth) + side * std::sin(azimuth);
    const Vec3f direction =
        horizontalDirection * std::cos(elevation) + camera.up * std::sin(elevation);
    const Vec3f viewRight = (-direction).cross(camera.up).normalized();
    const Vec3f viewUp = viewRight.cross(-direction);
    float distance = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3f offset = bounds.corner(Eigen::AlignedBox3f::CornerType(corner)) - camera.target;
      // Depth along the view is distance − offset·direction; the offset must fit in it.
      distance = std::max({distance, std::abs(offset.dot(viewRight)) / tanX + offset.dot(direction),
                           std::abs(offset.dot(viewUp)) / tanY + offset.dot(direction)});
    }
    distance = std::max(distance, 0.1f * size);
    camera.position = camera.target + direction * distance;
  }
  if ((camera.position - camera.target).norm() < 1e-6f)
    throw Error("renderer: the camera position and target are the same point");
  if (std::abs((camera.target - camera.position).normalized().dot(camera.up)) > 0.999f)
    camera.up = perpendicular(camera.up);
  const float distance = (camera.position - camera.target).norm();
  camera.near = 0.02f * distance;
  camera.far = distance + 12 * size;
  return camera;
}

}  // namespace softbake
