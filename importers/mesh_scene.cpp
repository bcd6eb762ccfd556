#include <iomanip>
#include <sstream>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/scene/material.hpp"
#include "core/text.hpp"
#include "importers/mesh_import.hpp"
#include "importers/mesh_transform.hpp"
#include "importers/scene_file.hpp"

namespace softbake {

namespace {

// Files come in millimetres, centimetres, metres or no unit at all. Within this range a model is
// taken as metres; outside it, it is rescaled so that the default material, tuned on a 1 m ball,
// behaves sensibly.
constexpr double kSmallestSide = 0.25, kLargestSide = 4.0;
constexpr double kDropHeight = 0.5;  // of the lowest point above the ground, m

std::string threeDigits(double x) {
  std::ostringstream out;
  out << std::setprecision(3) << x;
  return out.str();
}

}  // namespace

SceneFile sceneFromMeshFile(const std::filesystem::path& path, const SceneLoadOptions& options) {
  SceneFile scene =
      sceneFromMeshes(importMeshFile(path, meshSceneImportOptions(options)), path, options);
  scene.inputFiles.push_back(path);
  return scene;
}

MeshImportOptions meshSceneImportOptions(const SceneLoadOptions& options) {
  return {.mergeMeshes = false,
          .acceptLossy = options.acceptLossyImport,
          .limits = options.importLimits()};
}

SceneFile sceneFromMeshes(ImportedMeshes imported, const std::filesystem::path& path,
                          const SceneLoadOptions& options) {
  if (imported.meshes.size() > options.maxBodies)
    throw Error(cat(path.string(), ": ", imported.meshes.size(),
                    " meshes make as many bodies, above the limit of ", options.maxBodies,
                    " (--max-bodies raises it)"));
  SceneFile scene;
  scene.notes = std::move(imported.notes);
  scene.warnings = std::move(imported.warnings);
  scene.setup.name = fileSafeSceneName(path.stem().string());
  scene.setup.settings = SimulationSettings();
  scene.setup.settings.fps = 24;
  scene.setup.settings.frames = 240;
  scene.setup.settings.substeps = 0;

  Eigen::AlignedBox3d bounds;
  for (const TriangleMesh& mesh : imported.meshes)
    for (const Triangle& t : mesh.triangles)
      for (Index v : t) bounds.extend(mesh.positions[v].cast<double>());
  const double largestSide = bounds.sizes().maxCoeff();
  if (!(largestSide > 0))
    throw Error(cat(path.string(), ": the mesh has no extent (every vertex is in one place)"));

  double scale = 1;
  if (largestSide < kSmallestSide || largestSide > kLargestSide) {
    scale = 1 / largestSide;
    scene.notes.push_back(cat(path.string(), ": scaled by ", threeDigits(scale),
                              " to about a metre (its largest side was ", threeDigits(largestSide),
                              " units)"));
  }
  const Eigen::Vector3d center = bounds.center();
  const Eigen::Vector3d offset(-center.x() * scale, kDropHeight - bounds.min().y() * scale,
                               -center.z() * scale);
  const Eigen::Affine3d place = Eigen::Translation3d(offset) * Eigen::Scaling(scale);

  const Material material = *findMaterialPreset("rubber");
  const std::string stem = path.stem().string();
  for (TriangleMesh& mesh : imported.meshes) {
    BodySetup body;
    body.name = imported.meshes.size() == 1 ? stem : cat(stem, '/', mesh.name);
    body.material = material;
    transformMesh(mesh, place);
    mesh.name = body.name;
    body.mesh = std::move(mesh);
    scene.setup.bodies.push_back(std::move(body));
  }
  PlaneCollider ground;
  ground.name = "ground";
  scene.setup.planes.push_back(ground);
  return scene;
}

}  // namespace softbake
