#include "render/frame_renderer.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"
#include "render/changed_pixels.hpp"
#include "render/gl_resources.hpp"
#include "render/png_encoder.hpp"
#include "render/shaders.hpp"

namespace softbake {

namespace {

/// Background, written to the image as is (sRGB).
constexpr float kBackground[3] = {0.86f, 0.87f, 0.89f};
/// The blob shadows of this many bodies, the first ones, reach the ground shader.
constexpr int kMaxShadows = 16;

/// A body's soft shadow on the ground: a Gaussian around the point under its centre, drawn over
/// a square that reaches as far as it can change an 8-bit channel.
struct BlobShadow {
  Vec3f center;  ///< on the ground
  float sigma, strength;
  /// Half the square's side. The shader darkens by 1 − (1 − s·exp(−d²/σ²))^(1/2.2), about
  /// s·exp(−d²/σ²)/2.2; beyond the distance where that is a quarter of a step of 255 it rounds
  /// to nothing. At most 3σ (where it is 1/36 of a step at full strength), so a weak shadow,
  /// a high body's, covers far fewer pixels than its Gaussian's 3σ. 0: no pixel changes.
  float extent() const {
    const float reach = std::log(strength * 255 / (2.2f * 0.25f));
    return reach > 0 ? sigma * std::min(std::sqrt(reach), 3.0f) : 0;
  }
};

/// The ground: the first plane as a point, its unit normal and two axes in it.
struct GroundPlane {
  Vec3f point, normal, u, v;
};
GroundPlane groundPlane(const SceneTopology& topology) {
  const PlaneCollider& plane = topology.planes.front();
  GroundPlane ground;
  ground.point = plane.point.cast<float>();
  ground.normal = plane.normal.cast<float>().normalized();
  ground.u = perpendicular(ground.normal);
  ground.v = ground.normal.cross(ground.u);
  return ground;
}

/// Area-weighted vertex normals of a static mesh (its own render vertices).
std::vector<Vec3f> meshNormals(const TriangleMesh& mesh) {
  std::vector<Vec3f> normals(mesh.positions.size(), Vec3f::Zero());
  for (const Triangle& t : mesh.triangles) {
    const Vec3f n = (mesh.positions[t[1]] - mesh.positions[t[0]])
                        .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (Index v : t) normals[v] += n;
  }
  for (Vec3f& n : normals) {
    const float length = n.norm();
    n = length > 0 && std::isfinite(length) ? Vec3f(n / length) : Vec3f::UnitY();
  }
  return normals;
}

}  // namespace

// ---- scene ---------------------------------------------------------------------------------

ContactsView contactsViewFor(const RenderOptions& options, const SceneTopology& topology) {
  if (options.contactsView != ContactsView::Automatic) return options.contactsView;
  if (!options.contacts) return ContactsView::Opaque;
  const bool selfCollision = std::any_of(topology.bodies.begin(), topology.bodies.end(),
                                         [](const Body& body) { return body.selfCollision; });
  return topology.bodies.size() + topology.staticMeshes.size() > 1 || selfCollision
             ? ContactsView::XRay
             : ContactsView::Opaque;
}

Vec3f contactKindColor(ContactKind kind) {
  switch (kind) {
    case ContactKind::EdgeTriangle:
      return defaultContactColor();
    case ContactKind::ParticleTriangle:
      return {1.0f, 0.42f, 0.0f};
    case ContactKind::Corner:
      return {0.85f, 0.0f, 0.75f};
    case ContactKind::Plane:
      return {0.0f, 0.25f, 1.0f};
    case ContactKind::Held:
      return {0.1f, 0.7f, 0.25f};
  }
  return defaultContactColor();
}

Vec3f bodyColor(const RenderOptions& options, std::size_t index) {
  if (index < options.bodyColors.size() && options.bodyColors[index].x() >= 0)
    return options.bodyColors[index];
  return bodyColor(index);
}

Vec3f bodyColor(std::size_t index) {
  // Hues a golden-ratio turn apart never repeat and stay far from their neighbours.
  const float hue = std::fmod(0.58f + 0.618034f * float(index), 1.0f);
  const float saturation = 0.55f, value = 0.85f;
  const float h = hue * 6;
  const int sector = int(h) % 6;
  const float f = h - std::floor(h);
  const float p = value * (1 - saturation), q = value * (1 - saturation * f),
              t = value * (1 - saturation * (1 - f));
  Vec3f srgb;
  switch (sector) {
    case 0:
      srgb = {value, t, p};
      break;
    case 1:
      srgb = {q, value, p};
      break;
    case 2:
      srgb = {p, value, t};
      break;
    case 3:
      srgb = {p, q, value};
      break;
    case 4:
      srgb = {t, p, value};
      break;
    default:
      srgb = {value, p, q};
      break;
  }
  return srgb.array().pow(2.2f).matrix();  // the shaders light in linear RGB
}

RenderScene makeRenderScene(std::shared_ptr<const SceneTopology> shared,
                            const RenderOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384)
    throw Error(cat("renderer: image size ", options.width, "x", options.height,
                    " is out of range (1 to 16384 pixels a side)"));
  if (!(options.fovDegrees > 1 && options.fovDegrees < 170))
    throw Error(
        cat("renderer: field of view ", options.fovDegrees, " degrees is out of range (1 to 170)"));
  RenderScene scene;
  scene.topology = std::move(shared);
  const SceneTopology& topology = *scene.topology;

  Eigen::AlignedBox3f bounds;
  if (options.shotBounds)
    bounds = *options.shotBounds;
  else
    for (const Vec3& p : topology.restPosition) bounds.extend(p.cast<float>());
  for (const StaticMeshCollider& collider : topology.staticMeshes)
    for (const Vec3f& p : collider.mesh.positions) bounds.extend(p);
  if (!topology.planes.empty() && !bounds.isEmpty()) {
    // Falling bodies end on the ground: the bounds reach down to their shadow on it.
    const Vec3f point = topology.planes.front().point.cast<float>();
    const Vec3f normal = topology.planes.front().normal.cast<float>().normalized();
    const Eigen::AlignedBox3f bodies = bounds;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3f c = bodies.corner(Eigen::AlignedBox3f::CornerType(corner));
      bounds.extend(c - normal * (c - point).dot(normal));
    }
  }
  if (bounds.isEmpty()) bounds = Eigen::AlignedBox3f(Vec3f::Constant(-1), Vec3f::Constant(1));
  scene.boundsMin = bounds.min();
  scene.boundsMax = bounds.max();
  scene.size = std::max(bounds.diagonal().norm(), 1e-3f);
  scene.contactRadius = options.contactRadius > 0 ? options.contactRadius : 0.015f * scene.size;
  scene.xray = contactsViewFor(options, topology) == ContactsView::XRay;

  const Vec3f up = topology.planes.empty()
                       ? Vec3f::UnitY()
                       : Vec3f(topology.planes.front().normal.cast<float>().normalized());
  scene.camera = frameCamera(bounds, scene.size, up,
                             {options.cameraPosition, options.cameraTarget, options.fovDegrees,
                              float(options.width) / float(options.height)});
  return scene;
}

// ---- renderer --------------------------------------------------------------------------------

struct FrameRenderer::Gl {
  GLuint surfaceProgram = 0, groundProgram = 0, shadowProgram = 0;
  GLuint translucentProgram = 0, compositeProgram = 0;  ///< the contact view's
  /// Core profile draws need a vertex array; the shadow and the composite have no attributes.
  GLuint emptyVao = 0;
  std::vector<MeshBuffers> bodies;
  MeshBuffers statics, sphere, ground;
  GLuint contactInstances = 0;     ///< per contact: offset, then tint (6 floats)
  GLsizeiptr contactCapacity = 0;  ///< contacts the instance buffer holds
  GLuint multisampleFbo = 0, multisampleColor = 0, multisampleDepth = 0;
  GLuint resolveFbo = 0, resolveColor = 0, resolveDepth = 0;
  /// The background and the ground without shadows, colour and depth, as every frame starts.
  GLuint groundFbo = 0, groundColor = 0, groundDepth = 0;
  /// The contact view's accumulation and weight targets: multisampled renderbuffers sharing the
  /// opaque pass's depth (so bodies behind a contact or the ground are hidden), resolved into
  /// textures the composite reads. Without multisampling the textures are drawn into directly.
  GLuint oitFbo = 0, oitAccumulation = 0, oitWeight = 0;
  GLuint oitResolveFbo = 0, oitAccumulationTexture = 0, oitWeightTexture = 0;
  int samples = 0;
  /// The ground as every frame starts, resolved and read back once, RGB top row first: the image
  /// outside the pixels a frame changes.
  std::vector<std::uint8_t> groundImage;
  Eigen::AlignedBox3f staticBounds;  ///< the static meshes, drawn every frame
  PixelRect changed;                 ///< the pixels this frame draws, resolves and reads back
  /// Of those, the bodies': the contact view's translucent layers lie there, not over the
  /// shadows around them.
  PixelRect bodyPixels;
  // Per-frame scratch, kept to avoid allocating every frame.
  std::vector<BlobShadow> shadows;
  std::vector<Vec3f> normals;
  std::vector<float> interleaved;
  std::vector<float> instances;
  std::vector<std::uint8_t> pixels;
};

FrameRenderer::FrameRenderer(RenderScene scene, RenderOptions options)
    : scene_(std::move(scene)),
      options_(std::move(options)),
      context_(std::make_unique<EglContext>(options_.egl)),
      gl_(std::make_unique<Gl>()) {
  Gl& gl = *gl_;
  gl.surfaceProgram = linkProgram(kSurfaceVertexShader, kSurfaceFragmentShader.c_str());
  gl.groundProgram = linkProgram(kGroundVertexShader, kGroundFragmentShader);
  gl.shadowProgram = linkProgram(kShadowVertexShader, kShadowFragmentShader);
  glGenVertexArrays(1, &gl.emptyVao);
  createMeshes();
  createFramebuffers();
  if (scene_.xray) createContactView();
  // The camera and the planes are fixed for the sequence: the ground is drawn once, and each frame
  // starts from a copy of it (the ground shader, with its per-pixel loop over the shadows, cost
  // llvmpipe 40% of every frame).
  glBindFramebuffer(GL_FRAMEBUFFER, gl.groundFbo);
  glViewport(0, 0, options_.width, options_.height);
  glClearColor(kBackground[0], kBackground[1], kBackground[2], 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  drawGround(lighting());
  glBindVertexArray(0);
  const int w = options_.width, h = options_.height;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, gl.groundFbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl.resolveFbo);
  glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  gl.groundImage.resize(std::size_t(w) * std::size_t(h) * 3);
  readPixels(gl.resolveFbo, {0, 0, w, h}, gl.groundImage);
  for (const StaticMeshCollider& collider : scene_.topology->staticMeshes)
    for (const Vec3f& p : collider.mesh.positions) gl.staticBounds.extend(p);
  checkGl("while setting up the renderer");
}

/// The bodies' buffers (refilled every frame), the static meshes, the contact sphere and the
/// ground quad.
void FrameRenderer::createMeshes() {
  Gl& gl = *gl_;
  const SceneTopology& topology = *scene_.topology;
  for (const Body& body : topology.bodies) {
    std::vector<Index> indices;
    indices.reserve(std::size_t(body.triangleCount) * 3);
    for (Index t = body.firstTriangle; t < body.firstTriangle + body.triangleCount; ++t)
      for (Index v : topology.triangles[t]) indices.push_back(v - body.firstParticle);
    MeshBuffers buffers;
    buffers.create(std::vector<float>(std::size_t(body.particleCount) * 6, 0.0f), indices,
                   GL_DYNAMIC_DRAW);
    gl.bodies.push_back(buffers);
  }

  std::vector<float> interleaved;
  std::vector<Index> indices;
  for (const StaticMeshCollider& collider : topology.staticMeshes) {
    const Index first = Index(interleaved.size() / 6);
    const std::vector<Vec3f> normals = meshNormals(collider.mesh);
    for (std::size_t i = 0; i < collider.mesh.positions.size(); ++i) {
      const Vec3f& p = collider.mesh.positions[i];
      interleaved.insert(interleaved.end(),
                         {p.x(), p.y(), p.z(), normals[i].x(), normals[i].y(), normals[i].z()});
    }
    for (const Triangle& t : collider.mesh.triangles)
      for (Index v : t) indices.push_back(first + v);
  }
  gl.statics.create(interleaved, indices, GL_STATIC_DRAW);

  // Contacts: a unit icosphere drawn once per contact, per instance its offset in attribute 2
  // and its tint in attribute 3.
  const TriangleMesh sphere = makeIcosphere(1, 1.0f);
  interleaved.clear();
  indices.clear();
  for (const Vec3f& p : sphere.positions)
    interleaved.insert(interleaved.end(), {p.x(), p.y(), p.z(), p.x(), p.y(), p.z()});
  for (const Triangle& t : sphere.triangles) indices.insert(indices.end(), t.begin(), t.end());
  gl.sphere.create(interleaved, indices, GL_STATIC_DRAW);
  glGenBuffers(1, &gl.contactInstances);
  glBindVertexArray(gl.sphere.vao);
  glBindBuffer(GL_ARRAY_BUFFER, gl.contactInstances);
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glVertexAttribDivisor(2, 1);
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glVertexAttribDivisor(3, 1);
  glBindVertexArray(0);

  // The ground: one large quad on the first plane, centred under the scene.
  if (!topology.planes.empty()) {
    const auto [point, normal, u, v] = groundPlane(topology);
    const Vec3f center = 0.5f * (scene_.boundsMin + scene_.boundsMax);
    const Vec3f origin = center - normal * (center - point).dot(normal);
    const float half = scene_.camera.far;
    interleaved.clear();
    for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
      const Vec3f p = origin + half * (float(a) * u + float(b) * v);
      interleaved.insert(interleaved.end(),
                         {p.x(), p.y(), p.z(), normal.x(), normal.y(), normal.z()});
    }
    // Counter-clockwise seen from above: u × v = normal.
    gl.ground.create(interleaved, {0, 1, 2, 0, 2, 3}, GL_STATIC_DRAW);
  }
}

/// Multisampled colour + depth, resolved into a single-sampled framebuffer for reading.
void FrameRenderer::createFramebuffers() {
  Gl& gl = *gl_;
  GLint maxSamples = 1;
  glGetIntegerv(GL_MAX_SAMPLES, &maxSamples);
  gl.samples = std::clamp(options_.samples, 1, std::max(1, int(maxSamples)));
  const int w = options_.width, h = options_.height;
  auto makeFramebuffer = [&](GLuint& fbo, GLuint& color, GLuint& depth, int samples) {
    glGenFramebuffers(1, &fbo);
    glGenRenderbuffers(1, &color);
    glGenRenderbuffers(1, &depth);
    glBindRenderbuffer(GL_RENDERBUFFER, color);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, depth);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
      throw Error(cat("renderer: the OpenGL driver refused a ", w, "x", h, " framebuffer with ",
                      samples, " samples (status 0x", std::hex, status, ")"));
  };
  makeFramebuffer(gl.resolveFbo, gl.resolveColor, gl.resolveDepth, 0);
  if (gl.samples > 1)
    makeFramebuffer(gl.multisampleFbo, gl.multisampleColor, gl.multisampleDepth, gl.samples);
  makeFramebuffer(gl.groundFbo, gl.groundColor, gl.groundDepth, gl.samples > 1 ? gl.samples : 0);
}

/// The contact view's programs and its two transparency targets (see Gl::oitFbo).
void FrameRenderer::createContactView() {
  Gl& gl = *gl_;
  gl.translucentProgram = linkProgram(kSurfaceVertexShader, kTranslucentFragmentShader.c_str());
  gl.compositeProgram = linkProgram(kFullScreenVertexShader, kCompositeFragmentShader);
  const int w = options_.width, h = options_.height;
  const auto texture = [&](GLuint& name, GLenum format, GLenum channels) {
    glGenTextures(1, &name);
    glBindTexture(GL_TEXTURE_2D, name);
    glTexImage2D(GL_TEXTURE_2D, 0, GLint(format), w, h, 0, channels, GL_HALF_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  };
  texture(gl.oitAccumulationTexture, GL_RGBA16F, GL_RGBA);
  texture(gl.oitWeightTexture, GL_R16F, GL_RED);
  glBindTexture(GL_TEXTURE_2D, 0);
  glGenFramebuffers(1, &gl.oitResolveFbo);
  glBindFramebuffer(GL_FRAMEBUFFER, gl.oitResolveFbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                         gl.oitAccumulationTexture, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, gl.oitWeightTexture,
                         0);
  if (gl.samples > 1) {
    glGenRenderbuffers(1, &gl.oitAccumulation);
    glGenRenderbuffers(1, &gl.oitWeight);
    glBindRenderbuffer(GL_RENDERBUFFER, gl.oitAccumulation);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, gl.samples, GL_RGBA16F, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, gl.oitWeight);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, gl.samples, GL_R16F, w, h);
    glGenFramebuffers(1, &gl.oitFbo);
    glBindFramebuffer(GL_FRAMEBUFFER, gl.oitFbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                              gl.oitAccumulation);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, gl.oitWeight);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              gl.multisampleDepth);
  } else {
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              gl.resolveDepth);
    gl.oitFbo = gl.oitResolveFbo;
  }
  const GLenum targets[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  for (GLuint fbo : {gl.oitFbo, gl.oitResolveFbo}) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glDrawBuffers(2, targets);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
      throw Error(cat("renderer: the OpenGL driver refused the contact view's ", w, "x", h,
                      " half-float framebuffer with ", gl.samples, " samples (status 0x", std::hex,
                      status, "); render with --contacts-view opaque"));
  }
}

FrameRenderer::~FrameRenderer() {
  // The GL objects go with the context; delete them explicitly only where it is current.
  if (!gl_ || !context_) return;
  try {
    context_->makeCurrent();
  } catch (const Error&) {
    return;
  }
  Gl& gl = *gl_;
  for (MeshBuffers& buffers : gl.bodies) buffers.destroy();
  gl.statics.destroy();
  gl.sphere.destroy();
  gl.ground.destroy();
  glDeleteBuffers(1, &gl.contactInstances);
  glDeleteVertexArrays(1, &gl.emptyVao);
  // Names 0 and repeats are ignored by the glDelete* calls.
  const GLuint framebuffers[] = {gl.multisampleFbo, gl.resolveFbo, gl.groundFbo, gl.oitFbo,
                                 gl.oitResolveFbo};
  glDeleteFramebuffers(gl.oitFbo == gl.oitResolveFbo ? 4 : 5, framebuffers);
  const GLuint renderbuffers[] = {gl.multisampleColor, gl.multisampleDepth, gl.resolveColor,
                                  gl.resolveDepth,     gl.groundColor,      gl.groundDepth,
                                  gl.oitAccumulation,  gl.oitWeight};
  glDeleteRenderbuffers(8, renderbuffers);
  const GLuint textures[] = {gl.oitAccumulationTexture, gl.oitWeightTexture};
  glDeleteTextures(2, textures);
  for (GLuint program : {gl.surfaceProgram, gl.groundProgram, gl.shadowProgram,
                         gl.translucentProgram, gl.compositeProgram})
    glDeleteProgram(program);
}

std::vector<std::uint8_t> FrameRenderer::renderRgb(const Frame& frame) {
  const SceneTopology& topology = *scene_.topology;
  if (!topology.bodies.empty()) {
    const Body& last = topology.bodies.back();
    if (frame.positions.size() < std::size_t(last.firstParticle) + last.particleCount)
      throw Error(cat("renderer: frame ", frame.number, " has ", frame.positions.size(),
                      " positions, the scene has ", last.firstParticle + last.particleCount));
  }
  // Another renderer on this thread may have made its own context current since the last frame:
  // its GL object names are not ours (a second renderer's frame drawn between two of ours once
  // bound names this context never made, GL_INVALID_OPERATION).
  context_->makeCurrent();
  Gl& gl = *gl_;
  const int w = options_.width, h = options_.height;
  const Lighting light = lighting();
  ChangedPixels changed(light.viewProjection, w, h), bodies(light.viewProjection, w, h);
  uploadBodies(frame, changed, bodies);
  if (options_.contacts)
    for (const Contact& c : frame.contacts)
      changed.addBox(c.position.cast<float>() - Vec3f::Constant(scene_.contactRadius),
                     c.position.cast<float>() + Vec3f::Constant(scene_.contactRadius));
  if (!gl.staticBounds.isEmpty()) changed.addBox(gl.staticBounds.min(), gl.staticBounds.max());
  gl.changed = options_.redrawWholeFrame ? PixelRect{0, 0, w, h} : changed.rect();
  gl.bodyPixels = options_.redrawWholeFrame ? gl.changed : bodies.rect();
  const PixelRect& r = gl.changed;
  if (r.empty()) return readImage(frame.number);

  // Every pass below touches the changed pixels only; the rest of the image is the ground.
  glEnable(GL_SCISSOR_TEST);
  scissor(r);
  const GLuint target = gl.samples > 1 ? gl.multisampleFbo : gl.resolveFbo;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, gl.groundFbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, target);
  blit(r, GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glBindFramebuffer(GL_FRAMEBUFFER, target);
  glViewport(0, 0, w, h);
  glDisable(GL_CULL_FACE);  // open meshes show their inside

  drawShadows(light);
  glEnable(GL_DEPTH_TEST);
  useSurfaceProgram(gl.surfaceProgram, light);
  if (!scene_.xray) drawBodies();
  drawStatics();
  drawContacts(frame, light);
  if (scene_.xray) drawTranslucentBodies(light);
  glBindVertexArray(0);
  return readImage(frame.number);
}

FrameRenderer::Lighting FrameRenderer::lighting() const {
  const Camera& camera = scene_.camera;
  Lighting lighting;
  lighting.viewProjection = viewProjection(camera, options_.width, options_.height);
  const Vec3f forward = (camera.target - camera.position).normalized();
  const Vec3f side = forward.cross(camera.up).normalized();
  const Vec3f up = side.cross(forward);
  // Key from above, left and behind the camera; fill from the right, low.
  lighting.key = (-forward * 0.6f + up * 1.0f - side * 0.5f).normalized();
  lighting.fill = (-forward * 0.8f + up * 0.1f + side * 0.9f).normalized();
  return lighting;
}

/// Bodies' positions and smooth normals for this frame, and the blob shadows of the first
/// kMaxShadows bodies (into Gl::shadows); adds the pixels both can cover to `changed`, and those
/// of the bodies alone to `bodies`.
void FrameRenderer::uploadBodies(const Frame& frame, ChangedPixels& changed,
                                 ChangedPixels& bodies) {
  Gl& gl = *gl_;
  const SceneTopology& topology = *scene_.topology;
  gl.shadows.clear();
  const std::span<const Vec3> positions(frame.positions);
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    const Body& body = topology.bodies[b];
    computeBodyNormals(topology, positions, body, gl.normals);
    gl.interleaved.resize(std::size_t(body.particleCount) * 6);
    Vec3d sum = Vec3d::Zero();
    Eigen::AlignedBox3f bounds;
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3f p = positions[body.firstParticle + i].cast<float>();
      const Vec3f& n = gl.normals[i];
      std::copy_n(p.data(), 3, &gl.interleaved[std::size_t(i) * 6]);
      std::copy_n(n.data(), 3, &gl.interleaved[std::size_t(i) * 6 + 3]);
      sum += p.cast<double>();
      bounds.extend(p);
    }
    glBindBuffer(GL_ARRAY_BUFFER, gl.bodies[b].vertices);
    glBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(gl.interleaved.size() * sizeof(float)),
                    gl.interleaved.data());
    if (body.particleCount == 0) continue;
    changed.addBox(bounds.min(), bounds.max());
    bodies.addBox(bounds.min(), bounds.max());
    if (b < kMaxShadows && gl.ground.indexCount > 0) {
      const Vec3f center = (sum / double(body.particleCount)).cast<float>();
      float radius = 0;
      for (Index i = 0; i < body.particleCount; ++i)
        radius = std::max(radius,
                          (positions[body.firstParticle + i].cast<float>() - center).squaredNorm());
      addShadow(center, std::sqrt(radius), changed);
    }
  }
}

/// The blob shadow of a body with centroid `center` and `radius` (into Gl::shadows), and the
/// pixels its square covers.
void FrameRenderer::addShadow(const Vec3f& center, float radius, ChangedPixels& changed) {
  const auto [point, normal, u, v] = groundPlane(*scene_.topology);
  // A higher body casts a wider, fainter shadow.
  const float height = std::max((center - point).dot(normal), 0.0f);
  const float sigma = radius * 0.9f + 0.5f * std::max(height - radius, 0.0f);
  if (!(sigma > 0)) return;
  const BlobShadow shadow{Vec3f(center - normal * (center - point).dot(normal)), sigma,
                          0.6f * std::clamp(radius / std::max(height, radius), 0.0f, 1.0f)};
  if (!(shadow.extent() > 0)) return;
  gl_->shadows.push_back(shadow);
  for (const float a : {-1.0f, 1.0f})
    for (const float b : {-1.0f, 1.0f})
      changed.add(shadow.center + shadow.extent() * (a * u + b * v));
}

/// Binds `program` (the opaque or the translucent surface shader) with the frame's view and
/// lights.
void FrameRenderer::useSurfaceProgram(unsigned program, const Lighting& lighting) {
  const Camera& camera = scene_.camera;
  glUseProgram(program);
  uniform(program, "uViewProjection", lighting.viewProjection);
  uniform(program, "uEye", camera.position);
  uniform(program, "uKey", lighting.key);
  uniform(program, "uFill", lighting.fill);
  uniform(program, "uUp", camera.up);
  uniform(program, "uScale", 1.0f);
  uniform(program, "uFlat", 0);
  glVertexAttrib3f(2, 0, 0, 0);  // meshes have no per-instance offset
  glVertexAttrib3f(3, 1, 1, 1);  // nor a tint
}

/// Bodies in their colours, opaque; with the wireframe, the edges over them. Expects the surface
/// program in use (useSurfaceProgram()).
void FrameRenderer::drawBodies() {
  Gl& gl = *gl_;
  if (options_.wireframe) {
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1, 1);  // the edges drawn afterwards win the depth test
  }
  uniform(gl.surfaceProgram, "uSpecular", 0.25f);
  drawBodySurfaces(gl.surfaceProgram);
  if (options_.wireframe) {
    glDisable(GL_POLYGON_OFFSET_FILL);
    drawBodyEdges(gl.surfaceProgram);
  }
}

/// Every body's triangles in its colour. A closed body's back faces are culled: seen from outside
/// they lie behind its front ones (opaque, hidden; translucent, a layer that would add little to
/// the picture and as much again to llvmpipe's blending), and llvmpipe sets up half the
/// triangles. An open mesh shows both sides.
void FrameRenderer::drawBodySurfaces(unsigned program) {
  const SceneTopology& topology = *scene_.topology;
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    if (topology.bodies[b].closed)
      glEnable(GL_CULL_FACE);
    else
      glDisable(GL_CULL_FACE);
    drawBody(program, b, bodyColor(options_, b));
  }
  glDisable(GL_CULL_FACE);
}

void FrameRenderer::drawBody(unsigned program, std::size_t b, const Vec3f& color) {
  const MeshBuffers& mesh = gl_->bodies[b];
  uniform(program, "uColor", color);
  glBindVertexArray(mesh.vao);
  glDrawElements(GL_TRIANGLES, mesh.indexCount, GL_UNSIGNED_INT, nullptr);
}

void FrameRenderer::drawBodyEdges(unsigned program) {
  glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  uniform(program, "uFlat", 1);
  for (std::size_t b = 0; b < scene_.topology->bodies.size(); ++b)
    drawBody(program, b, Vec3f(bodyColor(options_, b) * 0.3f));
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  uniform(program, "uFlat", 0);
}

/// Static meshes in grey, opaque in either view: contacts on them show through the bodies.
/// Expects the surface program in use (useSurfaceProgram()).
void FrameRenderer::drawStatics() {
  Gl& gl = *gl_;
  if (gl.statics.indexCount == 0) return;
  uniform(gl.surfaceProgram, "uSpecular", 0.08f);
  uniform(gl.surfaceProgram, "uColor", Vec3f(Vec3f::Constant(0.45f)));
  glBindVertexArray(gl.statics.vao);
  glDrawElements(GL_TRIANGLES, gl.statics.indexCount, GL_UNSIGNED_INT, nullptr);
}

/// The contact view's bodies: their layers (a closed body's front layer only, both sides of an
/// open one) accumulated into the transparency targets, tested against the opaque pass's depth
/// but not writing it, so the order they are drawn in does not matter; the wireframe's edges go
/// in as more opaque layers.
void FrameRenderer::drawTranslucentBodies(const Lighting& lighting) {
  Gl& gl = *gl_;
  if (gl.bodyPixels.empty()) return;
  scissor(gl.bodyPixels);
  glBindFramebuffer(GL_FRAMEBUFFER, gl.oitFbo);
  const GLfloat clearAccumulation[] = {0, 0, 0, 1}, clearWeight[] = {0, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, clearAccumulation);
  glClearBufferfv(GL_COLOR, 1, clearWeight);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFuncSeparate(GL_ONE, GL_ONE, GL_ZERO, GL_ONE_MINUS_SRC_ALPHA);
  useSurfaceProgram(gl.translucentProgram, lighting);
  uniform(gl.translucentProgram, "uDepthScale", scene_.size);
  uniform(gl.translucentProgram, "uSpecular", 0.25f);
  uniform(gl.translucentProgram, "uAlpha", 0.3f);
  drawBodySurfaces(gl.translucentProgram);
  if (options_.wireframe) {
    uniform(gl.translucentProgram, "uAlpha", 0.6f);
    drawBodyEdges(gl.translucentProgram);
  }
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
  scissor(gl.changed);
}

/// The contacts as instanced spheres, opaque, in the contact colour or their kind's.
void FrameRenderer::drawContacts(const Frame& frame, const Lighting& lighting) {
  Gl& gl = *gl_;
  if (!options_.contacts || frame.contacts.empty()) return;
  gl.instances.clear();
  for (const Contact& c : frame.contacts) {
    const Vec3f p = c.position.cast<float>();
    const Vec3f tint =
        options_.contactColorsByKind ? contactKindColor(c.kind) : Vec3f(Vec3f::Ones());
    gl.instances.insert(gl.instances.end(), {p.x(), p.y(), p.z(), tint.x(), tint.y(), tint.z()});
  }
  const auto count = GLsizeiptr(frame.contacts.size());
  glBindBuffer(GL_ARRAY_BUFFER, gl.contactInstances);
  if (count > gl.contactCapacity) {
    gl.contactCapacity = std::max(count, 2 * gl.contactCapacity);
    glBufferData(GL_ARRAY_BUFFER, gl.contactCapacity * 6 * GLsizeiptr(sizeof(float)), nullptr,
                 GL_STREAM_DRAW);
  }
  glBufferSubData(GL_ARRAY_BUFFER, 0, count * 6 * GLsizeiptr(sizeof(float)), gl.instances.data());
  useSurfaceProgram(gl.surfaceProgram, lighting);
  uniform(gl.surfaceProgram, "uScale", scene_.contactRadius);
  uniform(gl.surfaceProgram, "uColor",
          options_.contactColorsByKind ? Vec3f(Vec3f::Ones()) : options_.contactColor);
  uniform(gl.surfaceProgram, "uSpecular", 0.45f);
  glBindVertexArray(gl.sphere.vao);
  // A sphere's front faces cover every pixel its back faces do, and hide them (but for a few
  // silhouette samples where a back face won the depth test by rounding): llvmpipe sets up each
  // triangle at a cost that, for spheres this small, is most of their drawing.
  glEnable(GL_CULL_FACE);
  glDrawElementsInstanced(GL_TRIANGLES, gl.sphere.indexCount, GL_UNSIGNED_INT, nullptr,
                          GLsizei(count));
  glDisable(GL_CULL_FACE);
}

/// The contact view's translucent layers over the resolved opaque image (in resolveFbo), over the
/// bodies' pixels, where drawTranslucentBodies() left them.
void FrameRenderer::compositeTranslucent() {
  Gl& gl = *gl_;
  const int w = options_.width, h = options_.height;
  if (gl.bodyPixels.empty()) return;
  scissor(gl.bodyPixels);
  if (gl.oitFbo != gl.oitResolveFbo) {
    // Each target resolved on its own: a blit copies the read buffer into every draw buffer.
    glBindFramebuffer(GL_READ_FRAMEBUFFER, gl.oitFbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl.oitResolveFbo);
    for (GLenum target : {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1}) {
      glReadBuffer(target);
      glDrawBuffer(target);
      blit(gl.bodyPixels, GL_COLOR_BUFFER_BIT);
    }
    const GLenum targets[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, targets);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, gl.resolveFbo);
  glViewport(0, 0, w, h);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(gl.compositeProgram);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, gl.oitAccumulationTexture);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, gl.oitWeightTexture);
  uniform(gl.compositeProgram, "uAccumulation", 0);
  uniform(gl.compositeProgram, "uWeight", 1);
  glBindVertexArray(gl.emptyVao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glBindTexture(GL_TEXTURE_2D, 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, 0);
  glDisable(GL_BLEND);
  scissor(gl.changed);
}

/// The ground quad: grid and fade towards the horizon.
void FrameRenderer::drawGround(const Lighting& lighting) {
  Gl& gl = *gl_;
  const SceneTopology& topology = *scene_.topology;
  const Camera& camera = scene_.camera;
  if (gl.ground.indexCount == 0) return;
  const auto [point, normal, u, v] = groundPlane(topology);
  // Bold lines every power of ten below the scene's size, thin ones at a quarter of that.
  const float spacing = 0.25f * std::pow(10.0f, std::floor(std::log10(scene_.size)));
  glUseProgram(gl.groundProgram);
  uniform(gl.groundProgram, "uViewProjection", lighting.viewProjection);
  uniform(gl.groundProgram, "uOrigin", point);
  uniform(gl.groundProgram, "uAxisU", u);
  uniform(gl.groundProgram, "uAxisV", v);
  uniform(gl.groundProgram, "uNormal", normal);
  uniform(gl.groundProgram, "uEye", camera.position);
  uniform(gl.groundProgram, "uKey", lighting.key);
  uniform(gl.groundProgram, "uSpacing", spacing);
  const Eigen::Vector2f fade = groundFade();
  glUniform2f(glGetUniformLocation(gl.groundProgram, "uFade"), fade.x(), fade.y());
  uniform(gl.groundProgram, "uBackground", Vec3f(kBackground[0], kBackground[1], kBackground[2]));
  glBindVertexArray(gl.ground.vao);
  glDrawElements(GL_TRIANGLES, gl.ground.indexCount, GL_UNSIGNED_INT, nullptr);
}

/// Where the ground fades into the background: from the scene's far side to six sizes behind.
Eigen::Vector2f FrameRenderer::groundFade() const {
  const float distance = (scene_.camera.position - scene_.camera.target).norm();
  return {distance + 0.5f * scene_.size, distance + 6 * scene_.size};
}

/// Each body's blob shadow multiplied into the ground copied in: a square around the point under
/// the body, before the bodies are drawn, so no depth test is needed.
void FrameRenderer::drawShadows(const Lighting& lighting) {
  Gl& gl = *gl_;
  const SceneTopology& topology = *scene_.topology;
  if (gl.ground.indexCount == 0 || gl.shadows.empty()) return;
  const GroundPlane ground = groundPlane(topology);
  const Eigen::Vector2f fade = groundFade();
  glUseProgram(gl.shadowProgram);
  uniform(gl.shadowProgram, "uViewProjection", lighting.viewProjection);
  uniform(gl.shadowProgram, "uAxisU", ground.u);
  uniform(gl.shadowProgram, "uAxisV", ground.v);
  uniform(gl.shadowProgram, "uEye", scene_.camera.position);
  glUniform2f(glGetUniformLocation(gl.shadowProgram, "uFade"), fade.x(), fade.y());
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_DST_COLOR, GL_ZERO);
  glBindVertexArray(gl.emptyVao);
  for (const BlobShadow& shadow : gl.shadows) {
    uniform(gl.shadowProgram, "uCenter", shadow.center);
    uniform(gl.shadowProgram, "uSigma", shadow.sigma);
    uniform(gl.shadowProgram, "uStrength", shadow.strength);
    uniform(gl.shadowProgram, "uExtent", shadow.extent());
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  }
  glDisable(GL_BLEND);
}

/// The ground image with the changed pixels resolved, composited and read back over it, top row
/// first.
std::vector<std::uint8_t> FrameRenderer::readImage(int frameNumber) {
  Gl& gl = *gl_;
  std::vector<std::uint8_t> image = gl.groundImage;
  if (gl.changed.empty()) return image;
  if (gl.samples > 1) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, gl.multisampleFbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl.resolveFbo);
    blit(gl.changed, GL_COLOR_BUFFER_BIT);
  }
  if (scene_.xray) compositeTranslucent();
  readPixels(gl.resolveFbo, gl.changed, image);
  glDisable(GL_SCISSOR_TEST);
  checkGl(cat("while rendering frame ", frameNumber).c_str());
  return image;
}

PixelRect FrameRenderer::changedPixels() const {
  return gl_->changed;
}

void FrameRenderer::scissor(const PixelRect& r) {
  glScissor(r.x0, r.y0, r.width(), r.height());
}

/// The same rectangle from the bound read framebuffer to the bound draw framebuffer.
void FrameRenderer::blit(const PixelRect& r, unsigned mask) {
  glBlitFramebuffer(r.x0, r.y0, r.x1, r.y1, r.x0, r.y0, r.x1, r.y1, mask, GL_NEAREST);
}

/// Reads `r` of `framebuffer`'s colour into the same pixels of `image` (RGB, the whole image's
/// size, top row first).
void FrameRenderer::readPixels(unsigned framebuffer, const PixelRect& r,
                               std::vector<std::uint8_t>& image) {
  Gl& gl = *gl_;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  const std::size_t rectRow = std::size_t(r.width()) * 3;
  gl.pixels.resize(rectRow * std::size_t(r.height()));
  glReadPixels(r.x0, r.y0, r.width(), r.height(), GL_RGB, GL_UNSIGNED_BYTE, gl.pixels.data());
  // OpenGL's rows start at the bottom, PNG's at the top.
  const std::size_t row = std::size_t(options_.width) * 3;
  for (int y = 0; y < r.height(); ++y)
    std::copy_n(
        &gl.pixels[std::size_t(y) * rectRow], rectRow,
        &image[std::size_t(options_.height - 1 - (r.y0 + y)) * row + std::size_t(r.x0) * 3]);
}

std::string FrameRenderer::renderPng(const Frame& frame) {
  return encodePng(renderRgb(frame), options_.width, options_.height);
}

std::size_t FrameRenderer::writePng(const Frame& frame, const std::filesystem::path& path) {
  const std::string png = renderPng(frame);
  writeFileAtomically(path, png);
  return png.size();
}

}  // namespace softbake
