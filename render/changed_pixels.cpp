#include "render/changed_pixels.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace softbake {

namespace {
/// Pixels around the projected bounds: a one-pixel wide line reaches half a pixel past its
/// vertices, and rasterisation snaps vertices to a sub-pixel grid.
constexpr float kMarginPixels = 2;
}  // namespace

ChangedPixels::ChangedPixels(const Eigen::Matrix4f& viewProjection, int width, int height)
    : viewProjection_(viewProjection),
      width_(width),
      height_(height),
      xMin_(std::numeric_limits<float>::infinity()),
      yMin_(std::numeric_limits<float>::infinity()),
      xMax_(-std::numeric_limits<float>::infinity()),
      yMax_(-std::numeric_limits<float>::infinity()) {}

void ChangedPixels::add(const Vec3f& point) {
  const Eigen::Vector4f clip = viewProjection_ * point.homogeneous();
  // A vertex behind the eye wraps around in projection; a triangle through it is clipped at the
  // near plane and can reach any pixel. Non-finite positions land here too.
  if (!(clip.w() > 0)) {
    wholeImage_ = true;
    return;
  }
  const float x = (clip.x() / clip.w() + 1) * 0.5f * float(width_);
  const float y = (clip.y() / clip.w() + 1) * 0.5f * float(height_);
  if (!std::isfinite(x) || !std::isfinite(y)) {
    wholeImage_ = true;
    return;
  }
  xMin_ = std::min(xMin_, x);
  yMin_ = std::min(yMin_, y);
  xMax_ = std::max(xMax_, x);
  yMax_ = std::max(yMax_, y);
}

void ChangedPixels::addBox(const Vec3f& lo, const Vec3f& hi) {
  for (int corner = 0; corner < 8; ++corner)
    add(Vec3f(corner & 1 ? hi.x() : lo.x(), corner & 2 ? hi.y() : lo.y(),
              corner & 4 ? hi.z() : lo.z()));
}

PixelRect ChangedPixels::rect() const {
  if (wholeImage_) return {0, 0, width_, height_};
  if (!(xMin_ <= xMax_)) return {};
  // Clamped in float first: a point far off screen projects beyond int's range.
  const auto clampTo = [](float v, int limit) { return int(std::clamp(v, 0.0f, float(limit))); };
  PixelRect r;
  r.x0 = clampTo(std::floor(xMin_ - kMarginPixels), width_);
  r.y0 = clampTo(std::floor(yMin_ - kMarginPixels), height_);
  r.x1 = clampTo(std::ceil(xMax_ + kMarginPixels), width_);
  r.y1 = clampTo(std::ceil(yMax_ + kMarginPixels), height_);
  return r;
}

}  // namespace softbake
