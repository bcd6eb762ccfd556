// Which pixels a frame can change (render/changed_pixels.hpp), against the camera's own
// projection (projectToPixel), and the renderer that draws only those pixels against the same
// renderer redrawing every pixel of every frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/mesh/icosphere.hpp"
#include "render/changed_pixels.hpp"
#include "render/frame_renderer.hpp"
#include "tests/render/render_support.hpp"

namespace softbake {
namespace {

constexpr int kPixelsWidth = 200, kPixelsHeight = 150;

Camera testCamera() {
  Camera camera;
  camera.position = Vec3f(2, 1.5f, 4);
  camera.target = Vec3f(0, 0.5f, 0);
  camera.near = 0.1f;
  camera.far = 50;
  return camera;
}

TEST(ChangedPixels, HoldsTheProjectionOfEveryPointAdded) {
  const Camera camera = testCamera();
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-1.5f, 1.5f);
  for (int trial = 0; trial < 200; ++trial) {
    ChangedPixels changed(viewProjection(camera, kPixelsWidth, kPixelsHeight), kPixelsWidth,
                          kPixelsHeight);
    std::vector<Eigen::Vector2f> pixels;
    for (int i = 0; i < 3; ++i) {
      const Vec3f p(coordinate(random), coordinate(random) + 0.5f, coordinate(random));
      changed.add(p);
      pixels.push_back(*projectToPixel(camera, kPixelsWidth, kPixelsHeight, p));
    }
    const PixelRect r = changed.rect();
    for (const Eigen::Vector2f& pixel : pixels) {
      // projectToPixel counts rows from the top, the rectangle from the bottom, as OpenGL does.
      const float y = float(kPixelsHeight) - pixel.y();
      if (pixel.x() < 0 || pixel.x() > kPixelsWidth || y < 0 || y > kPixelsHeight) continue;
      // A pixel's margin, within the image.
      EXPECT_LE(float(r.x0), std::max(pixel.x() - 1, 0.0f));
      EXPECT_GE(float(r.x1), std::min(pixel.x() + 1, float(kPixelsWidth)));
      EXPECT_LE(float(r.y0), std::max(y - 1, 0.0f));
      EXPECT_GE(float(r.y1), std::min(y + 1, float(kPixelsHeight)));
    }
    EXPECT_GE(r.x0, 0);
    EXPECT_LE(r.x1, kPixelsWidth);
    EXPECT_GE(r.y0, 0);
    EXPECT_LE(r.y1, kPixelsHeight);
  }
}

TEST(ChangedPixels, ABoxHoldsWhatIsInsideIt) {
  const Camera camera = testCamera();
  ChangedPixels box(viewProjection(camera, kPixelsWidth, kPixelsHeight), kPixelsWidth,
                    kPixelsHeight);
  box.addBox(Vec3f(-0.3f, 0.2f, -0.1f), Vec3f(0.4f, 0.9f, 0.5f));
  const PixelRect r = box.rect();
  ASSERT_FALSE(r.empty());
  EXPECT_LT(r.width() * r.height(), kPixelsWidth * kPixelsHeight / 2);
  std::mt19937 random(3);
  std::uniform_real_distribution<float> unit(0, 1);
  for (int i = 0; i < 1000; ++i) {
    const Vec3f p(-0.3f + 0.7f * unit(random), 0.2f + 0.7f * unit(random),
                  -0.1f + 0.6f * unit(random));
    const Eigen::Vector2f pixel = *projectToPixel(camera, kPixelsWidth, kPixelsHeight, p);
    EXPECT_GE(pixel.x(), float(r.x0));
    EXPECT_LE(pixel.x(), float(r.x1));
    EXPECT_GE(float(kPixelsHeight) - pixel.y(), float(r.y0));
    EXPECT_LE(float(kPixelsHeight) - pixel.y(), float(r.y1));
  }
}

TEST(ChangedPixels, NothingAddedIsEmptyAndAnythingBehindTheCameraIsTheWholeImage) {
  const Camera camera = testCamera();
  const Eigen::Matrix4f projection = viewProjection(camera, kPixelsWidth, kPixelsHeight);
  EXPECT_TRUE(ChangedPixels(projection, kPixelsWidth, kPixelsHeight).rect().empty());

  ChangedPixels behind(projection, kPixelsWidth, kPixelsHeight);
  behind.add(Vec3f(0, 0.5f, 0));
  behind.add(camera.position + (camera.position - camera.target));  // behind the eye
  const PixelRect whole = behind.rect();
  EXPECT_EQ(whole.x0, 0);
  EXPECT_EQ(whole.y0, 0);
  EXPECT_EQ(whole.x1, kPixelsWidth);
  EXPECT_EQ(whole.y1, kPixelsHeight);

  ChangedPixels offScreen(projection, kPixelsWidth, kPixelsHeight);
  offScreen.add(camera.target + Vec3f(1e9f, 0, 0));
  const PixelRect clipped = offScreen.rect();
  EXPECT_GE(clipped.x0, 0);
  EXPECT_LE(clipped.x1, kPixelsWidth);
}

/// A ball over the ground and a static block beside it, rendered frame by frame as it rises and
/// then around the camera, with contacts on it, by a renderer that draws only the changed pixels
/// and by one that redraws every pixel: the images must be the same bytes, in both contact views,
/// with and without multisampling and the wireframe.
TEST(FrameRenderer, DrawingOnlyTheChangedPixelsGivesTheWholeRedrawsImage) {
  SceneSetup setup;
  BodySetup body;
  body.name = "ball";
  body.mesh = makeIcosphere(2, 0.4f, Vec3f(0, 0.6f, 0));
  setup.bodies.push_back(std::move(body));
  setup.planes.push_back(PlaneCollider{});
  StaticMeshCollider block;
  block.name = "block";
  block.mesh = makeIcosphere(1, 0.3f, Vec3f(1.2f, 0.3f, -0.5f));
  setup.staticMeshes.push_back(std::move(block));
  const auto world = std::make_shared<const SceneTopology>(buildSceneTopology(setup));

  struct Variant {
    ContactsView view;
    int samples;
    bool wireframe;
  };
  for (const Variant variant :
       {Variant{ContactsView::XRay, 4, false}, Variant{ContactsView::Opaque, 4, true},
        Variant{ContactsView::XRay, 1, true}}) {
    RenderOptions options;
    options.width = kPixelsWidth;
    options.height = kPixelsHeight;
    options.contactsView = variant.view;
    options.samples = variant.samples;
    options.wireframe = variant.wireframe;
    options.shotBounds = Eigen::AlignedBox3f(Vec3f(-2, 0, -2), Vec3f(2, 3, 2));
    MAKE_RENDERER_OR_SKIP(changedOnly, world, options);
    options.redrawWholeFrame = true;
    auto whole = test::makeRenderer(world, options, whyNot_);
    ASSERT_TRUE(whole) << whyNot_;

    int partial = 0;
    const Vec3f eye = changedOnly->scene().camera.position;
    for (int step = 0; step < 7; ++step) {
      Frame frame;
      frame.number = step + 1;
      frame.positions = world->restPosition;
      for (Vec3& p : frame.positions) p.y() += Scalar(0.35) * Scalar(step);  // a wider shadow
      if (step ==
          6)  // around the camera: part of the ball behind it, part clipped by the near plane
        for (Vec3& p : frame.positions) p += (eye - Vec3f(0, 0.6f, 0)).cast<Scalar>();
      Contact contact;
      contact.position = frame.positions[0];
      frame.contacts = {contact};
      changedOnly->makeCurrent();
      const std::vector<std::uint8_t> drawn = changedOnly->renderRgb(frame);
      const PixelRect r = changedOnly->changedPixels();
      partial += r.width() * r.height() < kPixelsWidth * kPixelsHeight;
      if (step == 6) {
        EXPECT_EQ(r.width() * r.height(), kPixelsWidth * kPixelsHeight)
            << "a vertex behind the eye";
      }
      whole->makeCurrent();
      EXPECT_EQ(drawn, whole->renderRgb(frame))
          << contactsViewName(variant.view) << ", " << variant.samples << " samples, frame "
          << frame.number;
    }
    // Otherwise the comparison would hold trivially.
    EXPECT_GT(partial, 0);
  }
}

}  // namespace
}  // namespace softbake
