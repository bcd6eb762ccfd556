#include "bake/output_budget.hpp"

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/memory_budget.hpp"

namespace softbake {

namespace {

constexpr double kObjBytesPerVertex = 80;  // v, vt and vn lines
constexpr double kObjBytesPerTriangle = 50;
constexpr double kVdbBytesPerTriangle = 100;
constexpr double kPngBytesPerPixel = 1;

}  // namespace

double estimatedFrameBytes(const SceneFile& scene, int pngWidth, int pngHeight) {
  double vertices = 0, triangles = 0;
  for (const BodySetup& body : scene.setup.bodies) {
    vertices += double(body.mesh.positions.size());
    triangles += double(body.mesh.triangles.size());
  }
  double bytes = 0;
  if (scene.output.obj) bytes += kObjBytesPerVertex * vertices + kObjBytesPerTriangle * triangles;
  if (scene.output.vdb) bytes += kVdbBytesPerTriangle * triangles;
  if (scene.output.png) bytes += kPngBytesPerPixel * double(pngWidth) * double(pngHeight);
  return bytes;
}

void requireOutputWithin(const SceneFile& scene, int pngWidth, int pngHeight, double maxBytes) {
  const double frame = estimatedFrameBytes(scene, pngWidth, pngHeight);
  const int frames = scene.setup.settings.frames;
  const double total = frame * frames;
  if (total <= maxBytes) return;
  throw Error(cat("scene '", scene.setup.name, "': ", frames, " frames of about ",
                  formatBytes(frame), " each make about ", formatBytes(total),
                  " of output, above the limit of ", formatBytes(maxBytes),
                  " (--max-output-gib raises it)"));
}

}  // namespace softbake
