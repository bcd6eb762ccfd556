// The off-screen renderer on Mesa's llvmpipe (no GPU, no display): image size, a body where the
// camera says it is, contact spheres exactly where contacts are, byte-identical repeats, the PNG
// sequence through FramePipeline, and the error when EGL cannot give a context. The contact view
// has its own file (contact_view_test.cpp).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "core/mesh/icosphere.hpp"
#include "output/frame_pipeline.hpp"
#include "render/egl_context.hpp"
#include "render/frame_renderer.hpp"
#include "render/png_sequence_renderer.hpp"
#include "tests/render/render_support.hpp"
#include "tests/support/scratch_directory.hpp"

namespace softbake {
namespace {

using test::decodePng;
using test::Image;
using test::makeRenderer;
using test::readFile;
using test::ScratchDirectory;

constexpr int kWidth = 160, kHeight = 120;

/// One ball of radius 0.5 at (0, 1, 0) over the ground plane y = 0. It cannot touch itself, so
/// the renderer draws it opaque (the x-ray view has its own tests, contact_view_test.cpp).
std::shared_ptr<const SceneTopology> makeBallTopology() {
  SceneSetup setup;
  setup.name = "ball";
  BodySetup body;
  body.name = "ball";
  body.mesh = makeIcosphere(3, 0.5f, Vec3f(0, 1, 0));
  body.selfCollision = false;
  setup.bodies.push_back(std::move(body));
  setup.planes.push_back(PlaneCollider{});
  return std::make_shared<const SceneTopology>(buildSceneTopology(setup));
}

Frame initialFrame(const std::shared_ptr<const SceneTopology>& world) {
  Frame frame;
  frame.positions = world->restPosition;
  return frame;
}

RenderOptions smallOptions() {
  RenderOptions options;
  options.width = kWidth;
  options.height = kHeight;
  return options;
}

/// A pixel with all three channels within `tolerance` of each other: grey, not a body's colour.
bool isGrey(const std::uint8_t* p, int tolerance = 6) {
  const int low = std::min({p[0], p[1], p[2]}), high = std::max({p[0], p[1], p[2]});
  return high - low <= tolerance;
}

TEST(Camera, AutomaticFramingKeepsTheWholeSceneInTheImage) {
  const auto world = makeBallTopology();
  const RenderScene scene = makeRenderScene(world, smallOptions());
  // The bounds reach down to the ground, where the ball will fall.
  EXPECT_NEAR(scene.boundsMin.y(), 0.0f, 1e-5f);
  const Eigen::AlignedBox3f bounds(scene.boundsMin, scene.boundsMax);
  for (int corner = 0; corner < 8; ++corner) {
    const auto pixel = projectToPixel(scene.camera, kWidth, kHeight,
                                      bounds.corner(Eigen::AlignedBox3f::CornerType(corner)));
    ASSERT_TRUE(pixel.has_value());
    EXPECT_GE(pixel->x(), 0);
    EXPECT_LE(pixel->x(), float(kWidth));
    EXPECT_GE(pixel->y(), 0);
    EXPECT_LE(pixel->y(), float(kHeight));
  }
  // Upright: the ball's top projects above its centre.
  EXPECT_LT(projectToPixel(scene.camera, kWidth, kHeight, Vec3f(0, 1.5f, 0))->y(),
            projectToPixel(scene.camera, kWidth, kHeight, Vec3f(0, 1, 0))->y());
}

TEST(Camera, AnExplicitCameraLooksAtItsTarget) {
  RenderOptions options = smallOptions();
  options.cameraPosition = Vec3f(3, 2, 4);
  options.cameraTarget = Vec3f(0, 0.5f, 0);
  const RenderScene scene = makeRenderScene(makeBallTopology(), options);
  EXPECT_EQ(scene.camera.position, *options.cameraPosition);
  const auto center = projectToPixel(scene.camera, kWidth, kHeight, *options.cameraTarget);
  ASSERT_TRUE(center.has_value());
  EXPECT_NEAR(center->x(), kWidth / 2.0f, 1e-3f);
  EXPECT_NEAR(center->y(), kHeight / 2.0f, 1e-3f);
  EXPECT_FALSE(projectToPixel(scene.camera, kWidth, kHeight, Vec3f(6, 4, 8)).has_value());
  options.width = 0;
  EXPECT_THROW(makeRenderScene(makeBallTopology(), options), Error);
}

TEST(FrameRenderer, RendersTheBodyWhereTheCameraProjectsIt) {
  const auto world = makeBallTopology();
  MAKE_RENDERER_OR_SKIP(renderer, world, smallOptions());
  RecordProperty("context", renderer->context().describe());

  const std::string png = renderer->renderPng(initialFrame(world));
  const Image image = decodePng(png);
  ASSERT_EQ(image.width, kWidth);
  ASSERT_EQ(image.height, kHeight);

  const auto center = projectToPixel(renderer->scene().camera, kWidth, kHeight, Vec3f(0, 1, 0));
  ASSERT_TRUE(center.has_value());
  const int x = int(center->x()), y = int(center->y());
  ASSERT_TRUE(x > 0 && x < kWidth && y > 0 && y < kHeight) << x << ", " << y;
  // The ball is coloured; the corner (background) and the ground are grey.
  EXPECT_FALSE(isGrey(image.at(x, y), 20))
      << int(image.at(x, y)[0]) << " " << int(image.at(x, y)[1]) << " " << int(image.at(x, y)[2]);
  EXPECT_TRUE(isGrey(image.at(0, 0), 12));
  EXPECT_NE(std::vector<std::uint8_t>(image.at(x, y), image.at(x, y) + 3),
            std::vector<std::uint8_t>(image.at(0, 0), image.at(0, 0) + 3));
}

TEST(FrameRenderer, RenderingTwiceGivesByteIdenticalPngs) {
  const auto world = makeBallTopology();
  MAKE_RENDERER_OR_SKIP(renderer, world, smallOptions());
  ScratchDirectory out;
  Frame frame = initialFrame(world);
  Contact contact;
  contact.position = Vec3(0, 0.5f, 0.3f);
  frame.contacts = {contact};
  renderer->writePng(frame, out.path() / "a.png");
  renderer->writePng(frame, out.path() / "b.png");
  // A second renderer starts from nothing: no state carries over from earlier frames either.
  auto second = makeRenderer(world, smallOptions(), whyNot_);
  ASSERT_TRUE(second) << whyNot_;
  second->writePng(frame, out.path() / "c.png");
  const std::string a = readFile(out.path() / "a.png");
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, readFile(out.path() / "b.png"));
  EXPECT_EQ(a, readFile(out.path() / "c.png"));
}

TEST(FrameRenderer, ContactsShowInTheContactColourWhereTheyAre) {
  const auto world = makeBallTopology();
  RenderOptions options = smallOptions();
  options.contactRadius = 0.06f;
  MAKE_RENDERER_OR_SKIP(renderer, world, options);
  const Camera& camera = renderer->scene().camera;
  // On the ball's surface, facing the camera: without the contact the pixel is the ball's colour.
  const Vec3f center(0, 1, 0);
  const Vec3f onSurface = center + 0.5f * (camera.position - center).normalized();
  const auto pixel = projectToPixel(camera, kWidth, kHeight, onSurface);
  ASSERT_TRUE(pixel.has_value());
  const int x = int(pixel->x()), y = int(pixel->y());

  Frame frame = initialFrame(world);
  const Image without = decodePng(renderer->renderPng(frame));
  Contact contact;
  contact.position = onSurface.cast<Scalar>();
  frame.contacts = {contact};
  const Image with = decodePng(renderer->renderPng(frame));

  const std::uint8_t* p = with.at(x, y);
  EXPECT_TRUE(test::showsContactColor(p)) << int(p[0]) << " " << int(p[1]) << " " << int(p[2]);
  EXPECT_FALSE(isGrey(without.at(x, y), 20));
  // Only pixels near the contact change.
  for (int j = 0; j < kHeight; ++j)
    for (int i = 0; i < kWidth; ++i)
      if (std::abs(i - x) > 6 || std::abs(j - y) > 6) {
        ASSERT_TRUE(std::equal(with.at(i, j), with.at(i, j) + 3, without.at(i, j)))
            << "pixel " << i << ", " << j << " changed";
      }

  // Contacts off: the same frame shows none.
  options.contacts = false;
  auto noContacts = makeRenderer(world, options, whyNot_);
  ASSERT_TRUE(noContacts) << whyNot_;
  EXPECT_EQ(noContacts->renderRgb(frame), renderer->renderRgb(initialFrame(world)));
}

TEST(FrameRenderer, RenderersTakingTurnsOnOneThreadEachDrawTheirOwnFrame) {
  // Each renderer has its own context; the one made last is current. A frame of the first drawn
  // after that once bound GL names its context never made (GL_INVALID_OPERATION, 0x502).
  const auto world = makeBallTopology();
  RenderOptions xrayOptions = smallOptions();
  xrayOptions.contactsView = ContactsView::XRay;
  MAKE_RENDERER_OR_SKIP(xray, world, xrayOptions);
  const Frame frame = initialFrame(world);
  const std::vector<std::uint8_t> alone = xray->renderRgb(frame);
  auto opaque = makeRenderer(world, smallOptions(), whyNot_);
  ASSERT_TRUE(opaque) << whyNot_;
  const std::vector<std::uint8_t> opaqueFrame = opaque->renderRgb(frame);
  EXPECT_EQ(xray->renderRgb(frame), alone);
  EXPECT_EQ(opaque->renderRgb(frame), opaqueFrame);
  EXPECT_NE(alone, opaqueFrame) << "the x-ray view draws the ball translucent";
}

TEST(FrameRenderer, WireframeDrawsEdgesOverTheBody) {
  const auto world = makeBallTopology();
  RenderOptions options = smallOptions();
  MAKE_RENDERER_OR_SKIP(plain, world, options);
  options.wireframe = true;
  auto wireframe = makeRenderer(world, options, whyNot_);
  ASSERT_TRUE(wireframe) << whyNot_;
  EXPECT_NE(plain->renderRgb(initialFrame(world)), wireframe->renderRgb(initialFrame(world)));
}

TEST(PngSequenceRenderer, WritesNumberedPngsFromThePipelineThread) {
  const auto world = makeBallTopology();
  {
    std::string whyNot;
    if (!makeRenderer(world, smallOptions(), whyNot)) GTEST_SKIP() << whyNot;
  }
  ScratchDirectory out;
  auto sink = std::make_unique<PngSequenceRenderer>(world, out.path(), "ball", smallOptions(), 4);
  const OutputSequence sequence = sink->sequence();
  EXPECT_EQ(sequence.format, "png");
  EXPECT_EQ(sequence.pattern, "png/ball_####.png");
  EXPECT_EQ(sequence.printfPattern, "png/ball_%04d.png");
  std::vector<std::unique_ptr<FrameSink>> sinks;
  sinks.push_back(std::move(sink));
  FramePipeline pipeline(std::move(sinks), world->particleCount(), 2);
  for (int number = 1; number <= 3; ++number) {
    Frame& frame = pipeline.acquire();
    frame.number = number;
    for (std::size_t i = 0; i < world->particleCount(); ++i)
      frame.positions[i] = world->restPosition[i] - Vec3(0, 0.1f * Scalar(number - 1), 0);
    pipeline.submit(frame);
  }
  pipeline.finish();
  for (const char* name : {"ball_0001.png", "ball_0002.png", "ball_0003.png"}) {
    const std::string png = readFile(out.path() / "png" / name);
    ASSERT_FALSE(png.empty()) << name;
    const Image image = decodePng(png);
    EXPECT_EQ(image.width, kWidth);
    EXPECT_EQ(image.height, kHeight);
  }
  EXPECT_NE(readFile(out.path() / "png" / "ball_0001.png"),
            readFile(out.path() / "png" / "ball_0003.png"));
  EXPECT_GT(pipeline.bytesWritten(), 0u);
}

// Checked before anything is rendered, so it needs no EGL display.
TEST(PngSequenceRenderer, AFrameWithANaNPositionIsRefusedNamingThePngAndWritesNothing) {
  const auto world = makeBallTopology();
  ScratchDirectory out;
  PngSequenceRenderer sink(world, out.path(), "ball", smallOptions(), 4);
  Frame frame = initialFrame(world);
  frame.number = 5;
  frame.positions[17] = Vec3(0, std::numeric_limits<Scalar>::quiet_NaN(), 0);
  try {
    sink.write(frame);
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(std::string(error.what()),
              sink.framePath(5).string() +
                  ": not written: frame 5: body 'ball': the position of particle 17 is not "
                  "finite (0, nan, 0)");
  }
  sink.finish();
  EXPECT_TRUE(std::filesystem::is_empty(out.path() / "png"));
}

TEST(EglContext, AnInvalidPlatformFailsWithTheDebianPackages) {
  EglOptions options;
  options.platform = "0x1234";  // no such EGL platform
  try {
    EglContext context(options);
    FAIL() << "an invalid platform gave a context";
  } catch (const EglDisplayUnavailable& error) {  // no display: the one failure tests skip on
    const std::string message = error.what();
    EXPECT_NE(message.find("platform 0x1234"), std::string::npos) << message;
    for (const char* package : {"libegl1", "libegl-mesa0", "libgl1-mesa-dri", "libegl-dev"})
      EXPECT_NE(message.find(package), std::string::npos) << package << " in: " << message;
  }
}

TEST(EglContext, TheEnvironmentVariableForcesThePlatform) {
  ::setenv("SOFTBAKE_EGL_PLATFORM", "0x1234", 1);
  const auto world = makeBallTopology();
  PngSequenceRenderer sink(world, std::filesystem::temp_directory_path() / "softbake-render-env",
                           "ball", smallOptions());
  // The constructor needs no context; the first write() fails cleanly on the sink's thread.
  EXPECT_THROW(sink.write(initialFrame(world)), Error);
  ::unsetenv("SOFTBAKE_EGL_PLATFORM");
  std::filesystem::remove_all(std::filesystem::temp_directory_path() / "softbake-render-env");
}

TEST(EglContext, AnUnknownPlatformNameIsRejected) {
  EglOptions options;
  options.platform = "wayland-please";
  EXPECT_THROW(EglContext context(options), Error);
}

}  // namespace
}  // namespace softbake
