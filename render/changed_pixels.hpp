#pragma once
/// Which pixels a frame can change. The camera and the ground are fixed for a sequence, so most
/// of a frame is the ground drawn once; only the pixels the bodies, their shadows, the contacts and
/// the static meshes can cover are drawn, resolved, composited and read back each frame. On
/// llvmpipe every one of those passes costs in proportion to the pixels it touches.

#include <Eigen/Core>

#include "core/types.hpp"

namespace softbake {

/// Pixels [x0, x1) × [y0, y1) in OpenGL's window coordinates (rows from the bottom).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  int width() const { return empty() ? 0 : x1 - x0; }
  int height() const { return empty() ? 0 : y1 - y0; }
};

/// Grows a rectangle over the projections of boxes and points in world space. Conservative: it
/// holds every pixel that a triangle, line or point with its vertices inside what was added can
/// cover, with a margin for line width and rasterisation rules. Anything at or behind the
/// camera's plane makes it the whole image, since its projection has no bound.
class ChangedPixels {
 public:
  ChangedPixels(const Eigen::Matrix4f& viewProjection, int width, int height);

  void add(const Vec3f& point);
  /// Every corner of the box [lo, hi]; what lies inside it projects inside their projections.
  void addBox(const Vec3f& lo, const Vec3f& hi);

  /// The pixels, clipped to the image; empty when nothing was added.
  PixelRect rect() const;

 private:
  Eigen::Matrix4f viewProjection_;
  int width_, height_;
  bool wholeImage_ = false;
  float xMin_, yMin_, xMax_, yMax_;  ///< window coordinates of what was added
};

}  // namespace softbake
