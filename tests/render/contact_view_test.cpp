// The contact view (issue 18): bodies translucent through weighted blended order-independent
// transparency, contacts opaque in a colour that stands out. Checked on the paper's figure 4,
// simulated here from examples/fig4_two_bodies.json to the first frame where the bodies press
// into each other with at least 100 contacts: the spheres change the frame visibly, every contact
// inside the frame shows its colour, a frame without contacts is untouched; and on one ball: a
// contact behind the body shows only in the contact view, plane contacts show, the translucent
// layers do not depend on the order the bodies are drawn in.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh/icosphere.hpp"
#include "core/simulator.hpp"
#include "importers/scene_file.hpp"
#include "render/frame_renderer.hpp"
#include "tests/render/render_support.hpp"

namespace softbake {
namespace {

using test::decodePng;
using test::Image;
using test::makeRenderer;
using test::showsContactColor;

constexpr int kViewWidth = 640, kViewHeight = 360;  // the size the issue measured at
constexpr int kTolerance = 8;  // per channel, as `softbake compare --metric pixel`

RenderOptions figureOptions() {
  RenderOptions options;
  options.width = kViewWidth;
  options.height = kViewHeight;
  return options;
}

/// The contact view of figureOptions() with the spheres off: what the spheres add, and nothing
/// else, is the difference.
RenderOptions optionsWithoutSpheres() {
  RenderOptions options = figureOptions();
  options.contacts = false;
  options.contactsView = ContactsView::XRay;
  return options;
}

/// Figure 4 at frame 1 (apart, no contacts) and at the first frame with ≥ 100 contacts between
/// the two bodies. Simulated once per test program; a missing or broken example fails the tests
/// that use it.
struct Figure4 {
  std::shared_ptr<const SceneTopology> topology;
  Frame apart, pressed;
};

std::size_t contactsBetweenSurfaces(const Frame& frame) {
  return std::size_t(std::count_if(frame.contacts.begin(), frame.contacts.end(),
                                   [](const Contact& c) { return c.kind != ContactKind::Plane; }));
}

const Figure4& figure4() {
  static const Figure4 figure = [] {
    const SceneFile scene =
        loadSceneFile(std::string(SOFTBAKE_SOURCE_DIR) + "/examples/fig4_two_bodies.json");
    Figure4 result;
    result.topology = std::make_shared<const SceneTopology>(buildSceneTopology(scene.setup));
    Simulator simulator(result.topology);
    result.apart.number = 1;
    result.apart.positions = simulator.state().position;
    result.apart.contacts = simulator.contacts();
    for (int frame = 2; frame <= 48; ++frame) {
      simulator.advanceToFrame(frame);
      result.pressed.number = frame;
      result.pressed.positions = simulator.state().position;
      result.pressed.contacts = simulator.contacts();
      if (contactsBetweenSurfaces(result.pressed) >= 100) break;
    }
    return result;
  }();
  return figure;
}

/// Pixels whose largest channel difference is over kTolerance.
std::size_t differingPixels(const std::vector<std::uint8_t>& a,
                            const std::vector<std::uint8_t>& b) {
  std::size_t count = 0;
  for (std::size_t i = 0; i + 2 < a.size(); i += 3) {
    int difference = 0;
    for (int c = 0; c < 3; ++c)
      difference = std::max(difference, std::abs(int(a[i + c]) - b[i + c]));
    count += difference > kTolerance;
  }
  return count;
}

Image imageOf(FrameRenderer& renderer, const Frame& frame) {
  Image image;
  image.width = renderer.options().width;
  image.height = renderer.options().height;
  image.rgb = renderer.renderRgb(frame);
  return image;
}

/// One ball of radius 0.5 at `center` for each entry, over the ground plane y = 0.
std::shared_ptr<const SceneTopology> ballsTopology(const std::vector<Vec3f>& centers,
                                                   bool selfCollision = false) {
  SceneSetup setup;
  setup.name = "balls";
  for (const Vec3f& center : centers) {
    BodySetup body;
    body.name = "ball" + std::to_string(setup.bodies.size());
    body.mesh = makeIcosphere(3, 0.5f, center);
    body.selfCollision = selfCollision;
    setup.bodies.push_back(std::move(body));
  }
  setup.planes.push_back(PlaneCollider{});
  return std::make_shared<const SceneTopology>(buildSceneTopology(setup));
}

Frame restFrame(const SceneTopology& topology) {
  Frame frame;
  frame.positions = topology.restPosition;
  return frame;
}

Contact contactAt(const Vec3f& position, ContactKind kind = ContactKind::EdgeTriangle) {
  Contact contact;
  contact.position = position.cast<Scalar>();
  contact.kind = kind;
  return contact;
}

TEST(ContactView, IsTheDefaultWhereSurfacesCanTouchEachOther) {
  const RenderOptions options;
  EXPECT_EQ(contactsViewFor(options, *figure4().topology), ContactsView::XRay);
  EXPECT_EQ(contactsViewFor(options, *ballsTopology({{0, 1, 0}})), ContactsView::Opaque)
      << "one body on the ground: its contacts are on the ground, in sight";
  EXPECT_EQ(contactsViewFor(options, *ballsTopology({{0, 1, 0}}, true)), ContactsView::XRay)
      << "a body that collides with itself";
  RenderOptions noSpheres;
  noSpheres.contacts = false;
  EXPECT_EQ(contactsViewFor(noSpheres, *figure4().topology), ContactsView::Opaque);
  for (const ContactsView view : {ContactsView::XRay, ContactsView::Opaque}) {
    RenderOptions chosen;
    chosen.contactsView = view;
    EXPECT_EQ(contactsViewFor(chosen, *figure4().topology), view);
    EXPECT_EQ(contactsViewFor(chosen, *ballsTopology({{0, 1, 0}})), view);
  }
  EXPECT_EQ(contactsViewName(ContactsView::XRay), "xray");
  EXPECT_EQ(contactsViewName(ContactsView::Opaque), "opaque");
}

TEST(ContactView, Figure4sContactsChangeAtLeastAFifthOfAPercentOfItsPixels) {
  const Figure4& figure = figure4();
  ASSERT_GE(contactsBetweenSurfaces(figure.pressed), 100u)
      << "figure 4 never pressed its bodies together with 100 contacts by frame 48";
  MAKE_RENDERER_OR_SKIP(withSpheres, figure.topology, figureOptions());
  ASSERT_TRUE(withSpheres->scene().xray) << "figure 4's default view";
  // The same view with the spheres off: what they add, and nothing else.
  auto withoutSpheres = makeRenderer(figure.topology, optionsWithoutSpheres(), whyNot_);
  ASSERT_TRUE(withoutSpheres) << whyNot_;
  const std::size_t changed = differingPixels(withSpheres->renderRgb(figure.pressed),
                                              withoutSpheres->renderRgb(figure.pressed));
  RecordProperty("changed_pixels", std::to_string(changed));
  EXPECT_GE(double(changed), 0.002 * kViewWidth * kViewHeight)
      << "frame " << figure.pressed.number << ", " << figure.pressed.contacts.size()
      << " contacts: " << changed << " pixels changed";
}

TEST(ContactView, AFrameWithoutContactsIsTheSameWithAndWithoutSpheres) {
  const Figure4& figure = figure4();
  ASSERT_TRUE(figure.apart.contacts.empty()) << "figure 4 starts with its bodies apart";
  MAKE_RENDERER_OR_SKIP(withSpheres, figure.topology, figureOptions());
  auto withoutSpheres = makeRenderer(figure.topology, optionsWithoutSpheres(), whyNot_);
  ASSERT_TRUE(withoutSpheres) << whyNot_;
  EXPECT_TRUE(withSpheres->renderRgb(figure.apart) == withoutSpheres->renderRgb(figure.apart));
}

/// The projected radius of a sphere of `radius` at `center`, in pixels (at least 1).
float projectedRadius(const Camera& camera, const Vec3f& center, float radius) {
  const Vec3f forward = (camera.target - camera.position).normalized();
  const Vec3f side = forward.cross(camera.up).normalized();
  const auto middle = projectToPixel(camera, kViewWidth, kViewHeight, center);
  const auto edge = projectToPixel(camera, kViewWidth, kViewHeight, center + radius * side);
  if (!middle || !edge) return 1;
  return std::max(1.0f, (*edge - *middle).norm());
}

TEST(ContactView, EveryContactInsideTheFrameCoversAPixelOfTheContactColour) {
  const Figure4& figure = figure4();
  ASSERT_GE(contactsBetweenSurfaces(figure.pressed), 100u);
  MAKE_RENDERER_OR_SKIP(renderer, figure.topology, figureOptions());
  auto withoutSpheres = makeRenderer(figure.topology, optionsWithoutSpheres(), whyNot_);
  ASSERT_TRUE(withoutSpheres) << whyNot_;
  const Image with = imageOf(*renderer, figure.pressed);
  const Image without = imageOf(*withoutSpheres, figure.pressed);
  // The colour test means something only if nothing else in the frame passes it.
  std::size_t colouredWithout = 0;
  for (std::size_t i = 0; i < without.rgb.size(); i += 3)
    colouredWithout += showsContactColor(&without.rgb[i]);
  EXPECT_EQ(colouredWithout, 0u) << "pixels of the contact colour with no sphere drawn";

  const Camera& camera = renderer->scene().camera;
  int inside = 0, missing = 0;
  for (const Contact& contact : figure.pressed.contacts) {
    const Vec3f center = contact.position.cast<float>();
    const auto pixel = projectToPixel(camera, kViewWidth, kViewHeight, center);
    if (!pixel || pixel->x() < 0 || pixel->y() < 0 || pixel->x() >= kViewWidth ||
        pixel->y() >= kViewHeight)
      continue;
    ++inside;
    // Any pixel the sphere covers: those within its projected radius of the centre's pixel.
    const float radius = projectedRadius(camera, center, renderer->scene().contactRadius);
    const int reach = int(std::ceil(radius));
    const int cx = int(pixel->x()), cy = int(pixel->y());
    bool shown = false;
    for (int y = std::max(0, cy - reach); y <= std::min(kViewHeight - 1, cy + reach) && !shown; ++y)
      for (int x = std::max(0, cx - reach); x <= std::min(kViewWidth - 1, cx + reach) && !shown;
           ++x)
        shown = float((x - cx) * (x - cx) + (y - cy) * (y - cy)) <= radius * radius &&
                showsContactColor(with.at(x, y));
    if (!shown) {
      ++missing;
      const std::uint8_t* p = with.at(cx, cy);
      ADD_FAILURE() << "contact at (" << center.transpose() << "), "
                    << contactKindName(contact.kind) << ", pixel " << cx << ", " << cy
                    << " (radius " << radius << " px): " << int(p[0]) << " " << int(p[1]) << " "
                    << int(p[2]);
    }
  }
  EXPECT_GE(inside, 100) << "figure 4's contacts should be in the picture";
  EXPECT_EQ(missing, 0) << "of " << inside << " contacts inside the frame";
}

TEST(ContactView, AContactBehindABodyShowsThroughItOnlyInTheContactView) {
  const auto world = ballsTopology({{0, 1, 0}});
  RenderOptions options = figureOptions();
  options.contactsView = ContactsView::Opaque;
  MAKE_RENDERER_OR_SKIP(opaque, world, options);
  options.contactsView = ContactsView::XRay;
  auto xray = makeRenderer(world, options, whyNot_);
  ASSERT_TRUE(xray) << whyNot_;
  // On the ball's far side, seen through its middle.
  const Camera& camera = opaque->scene().camera;
  const Vec3f center(0, 1, 0);
  const Vec3f behind = center - 0.5f * (camera.position - center).normalized();
  const auto pixel = projectToPixel(camera, kViewWidth, kViewHeight, behind);
  ASSERT_TRUE(pixel.has_value());
  Frame frame = restFrame(*world);
  const std::vector<std::uint8_t> opaqueWithout = opaque->renderRgb(frame);
  const Image xrayWithout = imageOf(*xray, frame);
  frame.contacts = {contactAt(behind)};
  EXPECT_TRUE(opaque->renderRgb(frame) == opaqueWithout) << "the ball hides it when opaque";
  const Image xrayWith = imageOf(*xray, frame);
  const std::uint8_t* p = xrayWith.at(int(pixel->x()), int(pixel->y()));
  EXPECT_TRUE(showsContactColor(p)) << int(p[0]) << " " << int(p[1]) << " " << int(p[2]);
  EXPECT_FALSE(showsContactColor(xrayWithout.at(int(pixel->x()), int(pixel->y()))));
  // The ball stays visible in front of it: the contact's red is mixed with the ball's colour.
  EXPECT_FALSE(xrayWith.rgb == xrayWithout.rgb);
}

TEST(ContactView, PlaneContactsAreDrawnAndKindsTakeTheirColours) {
  const auto world = ballsTopology({{0, 1, 0}});
  RenderOptions options = figureOptions();
  MAKE_RENDERER_OR_SKIP(renderer, world, options);
  options.contactColorsByKind = true;
  auto byKind = makeRenderer(world, options, whyNot_);
  ASSERT_TRUE(byKind) << whyNot_;
  // On the ground beside the ball, in front of it as the camera sees it.
  const Camera& camera = renderer->scene().camera;
  Vec3f toCamera = camera.position - Vec3f(0, 1, 0);
  toCamera.y() = 0;
  const Vec3f onGround = Vec3f(0, 0, 0) + 0.9f * toCamera.normalized();
  const auto pixel = projectToPixel(camera, kViewWidth, kViewHeight, onGround);
  ASSERT_TRUE(pixel.has_value());
  const int x = int(pixel->x()), y = int(pixel->y());
  Frame frame = restFrame(*world);
  frame.contacts = {contactAt(onGround, ContactKind::Plane)};
  const Image single = imageOf(*renderer, frame);
  EXPECT_TRUE(showsContactColor(single.at(x, y)));
  const Image kinds = imageOf(*byKind, frame);
  const std::uint8_t* p = kinds.at(x, y);
  EXPECT_GE(int(p[2]) - int(std::max(p[0], p[1])), 60)
      << "a plane contact is blue by kind: " << int(p[0]) << " " << int(p[1]) << " " << int(p[2]);
  for (const ContactKind kind : {ContactKind::EdgeTriangle, ContactKind::ParticleTriangle,
                                 ContactKind::Corner, ContactKind::Plane}) {
    const Vec3f colour = contactKindColor(kind);
    const float saturation = (colour.maxCoeff() - colour.minCoeff()) / colour.maxCoeff();
    EXPECT_GT(saturation, 0.9f) << contactKindName(kind) << ": saturated, unlike the palette";
  }
}

TEST(ContactView, TheTranslucentLayersDoNotDependOnTheBodiesOrder) {
  // Two balls overlapping as the camera sees them, drawn in either order, each in its colour.
  const Vec3f a(0, 1, 0), b(0.45f, 1.1f, 0.35f);
  RenderOptions options = figureOptions();
  options.contactsView = ContactsView::XRay;
  options.bodyColors = {bodyColor(0), bodyColor(1)};
  const auto first = ballsTopology({a, b});
  MAKE_RENDERER_OR_SKIP(ab, first, options);
  options.bodyColors = {bodyColor(1), bodyColor(0)};
  auto ba = makeRenderer(ballsTopology({b, a}), options, whyNot_);
  ASSERT_TRUE(ba) << whyNot_;
  const std::vector<std::uint8_t> one = ab->renderRgb(restFrame(*first));
  const std::vector<std::uint8_t> other = ba->renderRgb(restFrame(*ba->scene().topology));
  int largest = 0;
  for (std::size_t i = 0; i < one.size(); ++i)
    largest = std::max(largest, std::abs(int(one[i]) - int(other[i])));
  EXPECT_LE(largest, 2) << "sums of the same layers in another order round differently, no more";
}

}  // namespace
}  // namespace softbake
