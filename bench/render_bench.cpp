/// Times the off-screen EGL renderer (render/frame_renderer.hpp) frame by frame on procedural
/// icosphere ball scenes of about 10k and 100k faces (bench/scene_sizes.hpp), so the same program
/// measures Mesa's llvmpipe on a CPU and a GPU's own EGL driver. No files are read: the scene is
/// built in code, and each frame squashes the balls a little towards the ground (plain arithmetic,
/// the same on every machine), so every frame uploads new vertices and normals.
///
///   render_bench --faces 10240 --width 1280 --height 720 --frames 30 --png last.png
///   render_bench --faces 102400 --contacts 500 --contacts-view opaque,xray
///   render_bench --compare a.png b.png [--tolerance 8]
///
/// Per frame it times FrameRenderer::renderRgb (upload, draw, multisample resolve, glReadPixels,
/// which waits for the GPU) and, apart from it, the PNG encoding. The first frame (lazy shader
/// compilation, first uploads) and the renderer's construction (EGL context, shaders,
/// framebuffers) are reported separately and left out of the mean and minimum. Each view of
/// --contacts-view (opaque, xray: the contact view with translucent bodies; default: the
/// renderer's automatic choice) is timed on the same frames, each ending on a machine-readable
/// line:
///
///   render_bench faces=... width=... height=... frames=... contacts_view=... ms_per_frame=...
///
/// and with two views, a last line with their ratios (render_bench_ratio xray_over_opaque
/// mean=... median=... min=...). The views take turns frame by frame, so load from other work on
/// the machine falls on both alike.
/// --contacts N puts N contacts on the balls' surfaces every frame (evenly over the particles),
/// drawn as spheres in either view.
///
/// --compare reads two PNGs and counts the pixels whose channels differ by more than the
/// tolerance in any channel, the first ten of them by position (the check that a GPU draws the
/// picture llvmpipe draws). How it was run: bench/results/render_gpu.md.

#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bench/scene_sizes.hpp"
#include "core/error.hpp"
#include "core/mesh/icosphere.hpp"
#include "core/scene/material.hpp"
#include "core/scene/scene_setup.hpp"
#include "core/scene/scene_topology.hpp"
#include "output/frame.hpp"
#include "render/frame_renderer.hpp"
#include "render/png_encoder.hpp"

namespace softbake {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct Options {
  int faces = 10240;
  int width = 1280, height = 720;
  int frames = 30;
  int samples = 4;
  std::string png;       ///< where the last frame goes; empty: nowhere
  std::string platform;  ///< EglOptions::platform; empty: SOFTBAKE_EGL_PLATFORM, else "auto"
  int contacts = 0;      ///< contact spheres per frame
  std::vector<ContactsView> views{ContactsView::Automatic};
};

[[noreturn]] void usage(const char* message) {
  std::fprintf(stderr,
               "render_bench: %s\n"
               "usage: render_bench [--faces 1280|10240|102400|983040] [--width W] [--height H]\n"
               "                    [--frames F] [--samples S] [--png PATH] [--contacts N]\n"
               "                    [--contacts-view opaque|xray|automatic[,...]]\n"
               "                    [--platform auto|surfaceless|device|default]\n"
               "       render_bench --compare A.png B.png [--tolerance T]\n",
               message);
  std::exit(2);
}

int toInt(const char* text, const char* flag) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (!end || *end != '\0' || value < 0 || value > 1 << 24)
    usage((std::string("bad value for ") + flag + ": " + text).c_str());
  return int(value);
}

/// Frame `number` (1-based): the rest state with every ball squashed towards the ground by up to
/// 10% and widened to match, a cycle of 16 frames. Multiplications only, so the same on every
/// machine: the images of two machines differ only where their renderers do.
void fillFrame(const SceneTopology& topology, int number, int contacts, Frame& frame) {
  frame.number = number;
  frame.time = (number - 1) / 24.0;
  frame.positions.resize(topology.restPosition.size());
  frame.velocities.assign(topology.restPosition.size(), Vec3::Zero());
  frame.contacts.clear();
  const int phase = (number - 1) % 16;
  const Scalar squash = Scalar(1) - Scalar(0.1) * Scalar(phase < 8 ? phase : 16 - phase) / 8;
  const Scalar widen = Scalar(1) + (Scalar(1) - squash) / 2;
  for (const Body& body : topology.bodies) {
    Vec3 center = Vec3::Zero();
    Scalar bottom = 0;
    for (Index i = 0; i < body.particleCount; ++i) {
      center += topology.restPosition[body.firstParticle + i];
      bottom = i == 0 ? topology.restPosition[body.firstParticle].y()
                      : std::min(bottom, topology.restPosition[body.firstParticle + i].y());
    }
    center /= Scalar(body.particleCount);
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3& p = topology.restPosition[body.firstParticle + i];
      frame.positions[body.firstParticle + i] =
          Vec3(center.x() + (p.x() - center.x()) * widen, bottom + (p.y() - bottom) * squash,
               center.z() + (p.z() - center.z()) * widen);
    }
  }
  // Contacts on the squashed surfaces, every (particles / contacts)-th particle.
  const std::size_t particles = frame.positions.size();
  for (int c = 0; c < contacts && particles > 0; ++c) {
    Contact contact;
    contact.particle = Index(std::size_t(c) * particles / std::size_t(contacts));
    contact.position = frame.positions[contact.particle];
    contact.kind = ContactKind::ParticleTriangle;
    frame.contacts.push_back(contact);
  }
}

struct Stats {
  double mean = 0, median = 0, min = 0, max = 0;
};
Stats stats(std::vector<double> values) {
  Stats s;
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  s.median = values.size() % 2 ? values[values.size() / 2]
                               : 0.5 * (values[values.size() / 2 - 1] + values[values.size() / 2]);
  s.min = *std::min_element(values.begin(), values.end());
  s.max = *std::max_element(values.begin(), values.end());
  for (double v : values) s.mean += v;
  s.mean /= double(values.size());
  return s;
}

/// Spaces in a value of the machine-readable line become underscores.
std::string token(std::string text) {
  std::replace(text.begin(), text.end(), ' ', '_');
  return text;
}

/// One view's renderer and its times.
struct ViewRun {
  std::string name;
  std::unique_ptr<FrameRenderer> renderer;
  PngEncoder encoder;  ///< one per sequence, as a PNG sequence has
  double setupMs = 0, firstRenderMs = 0, firstEncodeMs = 0;
  std::vector<double> renderMs, encodeMs;
  std::string png;
};

int runBench(const Options& options) {
  const bench::SceneSize& size = bench::sceneSize(options.faces);
  const Clock::time_point buildStart = Clock::now();
  auto topology = std::make_shared<const SceneTopology>(
      buildSceneTopology(bench::ballsScene(size, "render_bench")));
  const double buildMs = msSince(buildStart);
  std::printf("scene: %d balls, %zu faces, %zu particles (built in %.1f ms)\n", size.balls,
              topology->triangles.size(), topology->restPosition.size(), buildMs);
  std::printf("image: %dx%d, %d samples asked; %d contacts a frame\n", options.width,
              options.height, options.samples, options.contacts);

  std::vector<ViewRun> runs;
  for (const ContactsView view : options.views) {
    RenderOptions render;
    render.width = options.width;
    render.height = options.height;
    render.samples = options.samples;
    render.egl.platform = options.platform;
    render.contactsView = view;
    ViewRun& run = runs.emplace_back();
    run.name = contactsViewName(contactsViewFor(render, *topology));
    const Clock::time_point setupStart = Clock::now();
    run.renderer = std::make_unique<FrameRenderer>(makeRenderScene(topology, render), render);
    run.setupMs = msSince(setupStart);
  }
  const EglContext& context = runs.front().renderer->context();
  std::printf("EGL platform: %s\nGL: %s\n", context.platform().c_str(), context.describe().c_str());

  // The views take turns frame by frame, so a machine busy with other work slows them alike.
  Frame frame;
  for (int f = 1; f <= options.frames; ++f) {
    fillFrame(*topology, f, options.contacts, frame);
    for (ViewRun& run : runs) {
      run.renderer->makeCurrent();
      const Clock::time_point renderStart = Clock::now();
      const std::vector<std::uint8_t> rgb = run.renderer->renderRgb(frame);
      const double rendered = msSince(renderStart);
      const Clock::time_point encodeStart = Clock::now();
      run.png = run.encoder.encode(rgb, options.width, options.height);
      const double encoded = msSince(encodeStart);
      if (f == 1) {
        run.firstRenderMs = rendered;
        run.firstEncodeMs = encoded;
      } else {
        run.renderMs.push_back(rendered);
        run.encodeMs.push_back(encoded);
      }
    }
  }

  for (const ViewRun& run : runs) {
    std::printf("\ncontacts view: %s\n", run.name.c_str());
    std::printf("renderer setup (EGL context, shaders, framebuffers, ground): %.2f ms\n",
                run.setupMs);
    if (!options.png.empty()) {
      const std::string path = runs.size() > 1 ? run.name + "_" + options.png : options.png;
      std::ofstream file(path, std::ios::binary | std::ios::trunc);
      file.write(run.png.data(), std::streamsize(run.png.size()));
      if (!file.flush()) throw Error("cannot write " + path);
      std::printf("last frame (%d): %s, %zu bytes\n", options.frames, path.c_str(), run.png.size());
    }
    const Stats r = stats(run.renderMs), e = stats(run.encodeMs);
    std::printf("first frame: render %.2f ms, PNG encode %.2f ms\n", run.firstRenderMs,
                run.firstEncodeMs);
    std::printf(
        "frames 2..%d: render mean %.3f ms, median %.3f ms, min %.3f ms, max %.3f ms; PNG encode "
        "mean %.3f ms, min %.3f ms\n",
        options.frames, r.mean, r.median, r.min, r.max, e.mean, e.min);
    std::printf(
        "render_bench faces=%zu width=%d height=%d frames=%d samples=%d contacts=%d "
        "contacts_view=%s ms_per_frame=%.3f ms_median=%.3f ms_min=%.3f encode_ms=%.3f "
        "first_frame_ms=%.2f setup_ms=%.2f platform=%s renderer=%s\n",
        topology->triangles.size(), options.width, options.height, options.frames, options.samples,
        options.contacts, run.name.c_str(), r.mean, r.median, r.min, e.mean, run.firstRenderMs,
        run.setupMs, token(context.platform()).c_str(), token(context.describe()).c_str());
  }
  if (runs.size() == 2) {
    const Stats a = stats(runs[0].renderMs), b = stats(runs[1].renderMs);
    std::printf("render_bench_ratio %s_over_%s mean=%.3f median=%.3f min=%.3f\n",
                runs[1].name.c_str(), runs[0].name.c_str(), b.mean / a.mean, b.median / a.median,
                b.min / a.min);
  }
  return 0;
}

std::vector<ContactsView> parseViews(std::string_view list) {
  std::vector<ContactsView> views;
  while (!list.empty()) {
    const std::size_t comma = list.find(',');
    const std::string_view name = list.substr(0, comma);
    if (name == "xray")
      views.push_back(ContactsView::XRay);
    else if (name == "opaque")
      views.push_back(ContactsView::Opaque);
    else if (name == "automatic")
      views.push_back(ContactsView::Automatic);
    else
      usage(("unknown contacts view " + std::string(name)).c_str());
    list = comma == std::string_view::npos ? std::string_view() : list.substr(comma + 1);
  }
  if (views.empty()) usage("--contacts-view needs a view");
  return views;
}

/// Counts the pixels of two same-sized PNGs that differ by more than `tolerance` in any channel.
int runCompare(const char* a, const char* b, int tolerance) {
  int wa = 0, ha = 0, ca = 0, wb = 0, hb = 0, cb = 0;
  std::unique_ptr<unsigned char, void (*)(void*)> pa(stbi_load(a, &wa, &ha, &ca, 3),
                                                     stbi_image_free);
  std::unique_ptr<unsigned char, void (*)(void*)> pb(stbi_load(b, &wb, &hb, &cb, 3),
                                                     stbi_image_free);
  if (!pa || !pb) {
    std::fprintf(stderr, "render_bench: cannot read %s\n", !pa ? a : b);
    return 1;
  }
  if (wa != wb || ha != hb) {
    std::fprintf(stderr, "render_bench: %s is %dx%d, %s is %dx%d\n", a, wa, ha, b, wb, hb);
    return 1;
  }
  const std::size_t pixels = std::size_t(wa) * std::size_t(ha);
  std::size_t differing = 0, exact = 0;
  int maxDiff = 0;
  for (std::size_t i = 0; i < pixels; ++i) {
    int d = 0;
    for (int c = 0; c < 3; ++c)
      d = std::max(d, std::abs(int(pa.get()[i * 3 + c]) - int(pb.get()[i * 3 + c])));
    maxDiff = std::max(maxDiff, d);
    if (d > tolerance && differing++ < 10)
      std::printf("  differs at x=%zu y=%zu by %d: %d,%d,%d vs %d,%d,%d\n", i % std::size_t(wa),
                  i / std::size_t(wa), d, pa.get()[i * 3], pa.get()[i * 3 + 1], pa.get()[i * 3 + 2],
                  pb.get()[i * 3], pb.get()[i * 3 + 1], pb.get()[i * 3 + 2]);
    exact += d == 0;
  }
  std::printf(
      "render_compare a=%s b=%s size=%dx%d tolerance=%d differing=%zu differing_pct=%.4f "
      "identical=%zu max_diff=%d\n",
      a, b, wa, ha, tolerance, differing, 100.0 * double(differing) / double(pixels), exact,
      maxDiff);
  return 0;
}

}  // namespace
}  // namespace softbake

int main(int argc, char** argv) {
  using namespace softbake;
  Options options;
  const char* compare[2] = {nullptr, nullptr};
  int tolerance = 8;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    auto value = [&](const char* flag) {
      if (i + 1 >= argc) usage((std::string(flag) + " needs a value").c_str());
      return argv[++i];
    };
    if (arg == "--faces")
      options.faces = toInt(value("--faces"), "--faces");
    else if (arg == "--width")
      options.width = toInt(value("--width"), "--width");
    else if (arg == "--height")
      options.height = toInt(value("--height"), "--height");
    else if (arg == "--frames")
      options.frames = toInt(value("--frames"), "--frames");
    else if (arg == "--samples")
      options.samples = toInt(value("--samples"), "--samples");
    else if (arg == "--png")
      options.png = value("--png");
    else if (arg == "--platform")
      options.platform = value("--platform");
    else if (arg == "--contacts")
      options.contacts = toInt(value("--contacts"), "--contacts");
    else if (arg == "--contacts-view")
      options.views = parseViews(value("--contacts-view"));
    else if (arg == "--tolerance")
      tolerance = toInt(value("--tolerance"), "--tolerance");
    else if (arg == "--compare") {
      compare[0] = value("--compare");
      compare[1] = value("--compare");
    } else if (arg == "--help" || arg == "-h")
      usage("help");
    else
      usage(("unknown argument " + std::string(arg)).c_str());
  }
  if (options.frames < 2) usage("--frames must be at least 2 (the first is timed apart)");
  try {
    if (compare[0]) return runCompare(compare[0], compare[1], tolerance);
    return runBench(options);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "render_bench: %s\n", error.what());
    return 1;
  }
}
