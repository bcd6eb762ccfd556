#pragma once
/// Renders simulated frames off-screen to PNG: soft bodies shaded in per-body colours, static
/// colliders in grey, the ground plane with a grid and soft blob shadows, contacts as small
/// spheres (the paper's grey spheres of figures 4-6, here in a colour that stands out). In the
/// contact view (x-ray) the bodies are translucent, so the contacts where they press into each
/// other show through them. OpenGL 3.3 core through EGL, so it runs without a display on Mesa's
/// llvmpipe or on a GPU.
///
/// Deterministic: the image depends only on the world, the options and the frame (no clock, no
/// frame counter), so the same input gives byte-identical PNGs on the same machine and driver.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "core/scene/scene_topology.hpp"
#include "output/frame.hpp"
#include "render/camera.hpp"
#include "render/changed_pixels.hpp"
#include "render/egl_context.hpp"

namespace softbake {

/// The default contact colour, linear RGB: a saturated red, which no body of the soft palette
/// (saturation 0.55) and not the grey ground (0.5) comes near. A function, since an Eigen
/// constant would be initialised at run time, in no set order with other files' globals.
inline Vec3f defaultContactColor() {
  return {1.0f, 0.06f, 0.03f};
}

struct RenderOptions {
  int width = 1280, height = 720;  ///< pixels
  int samples = 4;                 ///< multisampling; 1 or less renders without it
  /// Camera; when position or target is unset, framed automatically (see frameCamera()).
  std::optional<Vec3f> cameraPosition;
  std::optional<Vec3f> cameraTarget;
  float fovDegrees = 40;                       ///< vertical field of view
  bool contacts = true;                        ///< draw the frame's contacts as spheres
  Vec3f contactColor = defaultContactColor();  ///< linear RGB, 0..1
  bool contactColorsByKind = false;  ///< colour each contact by its kind (contactKindColor())
  float contactRadius = 0;           ///< m; 0: 1.5% of the scene's size
  ContactsView contactsView = ContactsView::Automatic;
  bool wireframe = false;  ///< draw the bodies' edges over their surfaces
  /// Per body, linear RGB 0..1; bodies without an entry (or with a negative red) take the palette.
  std::vector<Vec3f> bodyColors;
  /// Where the bodies go over the whole shot (every frame's particles), when known: automatic
  /// framing then covers all of it, so bodies that roll away stay in the picture. Unset: the
  /// initial state's bounds and their shadow on the ground.
  std::optional<Eigen::AlignedBox3f> shotBounds;
  /// Draw every pixel of every frame instead of only those the frame can change
  /// (render/changed_pixels.hpp): the same image, the reference the tests hold it to.
  bool redrawWholeFrame = false;
  EglOptions egl;
};

/// What the renderer draws besides the frame: the scene's topology (bodies, static meshes, the
/// ground), and the camera and sizes fixed once for the whole sequence. Built on any thread;
/// holds no GL state.
struct RenderScene {
  std::shared_ptr<const SceneTopology> topology;  ///< shared with the simulator, read-only
  Camera camera;
  Vec3f boundsMin = Vec3f::Zero(), boundsMax = Vec3f::Zero();  ///< the framed region
  float size = 1;                                              ///< diagonal of the framed region, m
  float contactRadius = 0;                                     ///< m
  bool xray = false;  ///< the contact view: bodies translucent (options' view, resolved)
};

/// The view `options` asks for, with Automatic resolved for `topology`: XRay when contact spheres
/// are drawn and contacts between surfaces can happen (more than one collision surface, or a body
/// that collides with itself), since those contacts lie where surfaces press into each other,
/// inside the bodies; contacts with the ground alone show without it.
ContactsView contactsViewFor(const RenderOptions& options, const SceneTopology& topology);

/// The colour of contacts of `kind` when RenderOptions::contactColorsByKind, linear RGB: red for
/// edge-triangle, orange for particle-triangle, magenta for corner, blue for plane contacts.
Vec3f contactKindColor(ContactKind kind);

/// Keeps `topology` and fixes the camera for the whole sequence, since a camera fitted per frame
/// would jump. Automatic framing covers the bodies over the shot (options.shotBounds) or, when
/// frames are rendered as they are simulated and the shot is not known yet, their initial bounds;
/// then the static meshes and the bodies' shadow on the first plane (where falling bodies end
/// up), with a margin. Throws softbake::Error for options out of range.
RenderScene makeRenderScene(std::shared_ptr<const SceneTopology> topology,
                            const RenderOptions& options);

/// The per-body colour of body `index`: golden-ratio hue steps at soft saturation, linear RGB.
Vec3f bodyColor(std::size_t index);
/// Body `index`'s colour from `options.bodyColors` when given there, else bodyColor(index).
Vec3f bodyColor(const RenderOptions& options, std::size_t index);

/// Owns an EGL context (current on the thread that constructs it) and the GL objects of one scene.
/// Every call must come from that thread.
class FrameRenderer {
 public:
  /// Creates the context, compiles the shaders and allocates the framebuffers. Throws
  /// softbake::Error (EGL missing, GL too old, a framebuffer the driver refuses).
  FrameRenderer(RenderScene scene, RenderOptions options);
  ~FrameRenderer();
  FrameRenderer(const FrameRenderer&) = delete;
  FrameRenderer& operator=(const FrameRenderer&) = delete;

  /// The frame as RGB8, top row first, width·height·3 bytes.
  std::vector<std::uint8_t> renderRgb(const Frame& frame);
  /// The frame as PNG file bytes.
  std::string renderPng(const Frame& frame);
  /// Renders and writes the PNG atomically (temporary file, then rename); returns its size.
  std::size_t writePng(const Frame& frame, const std::filesystem::path& path);

  /// Makes this renderer's context current. Every frame does it first (a no-op where it is
  /// current already), so renderers that take turns on one thread need not.
  void makeCurrent() { context_->makeCurrent(); }

  const RenderScene& scene() const { return scene_; }
  /// The pixels the last frame drew; the rest of it was the ground as every frame starts.
  PixelRect changedPixels() const;
  const RenderOptions& options() const { return options_; }
  const EglContext& context() const { return *context_; }

 private:
  struct Gl;
  /// The view and the two lights of a frame.
  struct Lighting {
    Eigen::Matrix4f viewProjection;
    Vec3f key, fill;  ///< unit directions towards the lights
  };

  void createMeshes();
  void createFramebuffers();
  void uploadBodies(const Frame& frame, ChangedPixels& changed, ChangedPixels& bodies);
  void addShadow(const Vec3f& center, float radius, ChangedPixels& changed);
  void createContactView();
  void useSurfaceProgram(unsigned program, const Lighting& lighting);
  void drawBodies();
  void drawBodySurfaces(unsigned program);
  /// Body b's triangles in `color`, with `program` in use.
  void drawBody(unsigned program, std::size_t b, const Vec3f& color);
  /// The wireframe: every body's edges as flat lines in a dark shade of its colour.
  void drawBodyEdges(unsigned program);
  void drawStatics();
  void drawTranslucentBodies(const Lighting& lighting);
  void drawContacts(const Frame& frame, const Lighting& lighting);
  void compositeTranslucent();
  void drawGround(const Lighting& lighting);
  void drawShadows(const Lighting& lighting);
  Lighting lighting() const;
  Eigen::Vector2f groundFade() const;
  std::vector<std::uint8_t> readImage(int frameNumber);
  void scissor(const PixelRect& r);
  void blit(const PixelRect& r, unsigned mask);
  void readPixels(unsigned framebuffer, const PixelRect& r, std::vector<std::uint8_t>& image);
  RenderScene scene_;
  RenderOptions options_;
  std::unique_ptr<EglContext> context_;
  std::unique_ptr<Gl> gl_;
};

}  // namespace softbake
