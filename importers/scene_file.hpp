#pragma once
/// Scene files (JSON) and the two scenes that need no file: the built-in default scene and a single
/// mesh dropped on the ground. All three produce the same SceneFile.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/scene/scene_setup.hpp"
#include "importers/import_limits.hpp"
#include "importers/mesh_import.hpp"

namespace softbake {

/// What the scene asks of the writers. Command-line options override these.
struct OutputOptions {
  int framePadding = 4;   ///< digits of the frame number in file names: scene_0001.obj
  bool obj = true;        ///< write the OBJ sequence
  bool contacts = false;  ///< write each frame's contacts as JSON
  bool png = false;       ///< render each frame to PNG
  bool vdb = false;       ///< write each frame as OpenVDB grids
  bool pc2 = false;       ///< write a PC2 point cache and a rest mesh per body
  bool mdd = false;       ///< write an MDD point cache and a rest mesh per body
};

/// How the scene asks to be rendered; unset values keep the renderer's defaults. Plain values, so
/// importers know nothing of the renderer.
struct RenderSettings {
  std::optional<int> width, height;
  std::optional<int> samples;
  std::optional<Vec3f> cameraPosition, cameraTarget;
  std::optional<float> fovDegrees;
  std::optional<bool> contactSpheres;
  std::optional<Vec3f> contactColor;
  bool contactColorsByKind = false;  ///< contact_color: "kind"
  std::optional<float> contactRadius;
  std::optional<std::string> contactsView;  ///< "xray" or "opaque"; unset: automatic
  std::optional<bool> wireframe;
  std::vector<std::optional<Vec3f>> bodyColors;  ///< per body of setup.bodies, linear RGB 0..1
};

struct SceneFile {
  SceneSetup setup;
  OutputOptions output;
  RenderSettings render;
  std::vector<std::string> notes;     ///< what loading did that the user should hear about
  std::vector<std::string> warnings;  ///< what may be wrong with the meshes it read
  /// The files loading read, as it found them: the scene file, then each mesh file. A run's
  /// manifest records their SHA-256.
  std::vector<std::filesystem::path> inputFiles;
};

/// How the command line asks scenes to be loaded; a scene file's `settings.import` adds to it.
struct SceneLoadOptions {
  /// Import what is left of mesh files that lost geometry, with a warning (MeshImportOptions).
  /// A scene's `settings.import.accept_lossy` turns it on too.
  bool acceptLossyImport = false;
  /// Caps per mesh file (ImportLimits); unset ones are the scene's `settings.import` values, or
  /// the defaults.
  std::optional<std::uint64_t> maxVertices{}, maxFaces{}, maxImportMemoryMib{}, maxImportSeconds{};
  /// `scene` (the defaults, or a scene's settings.import) with the caps set here written over it.
  ImportLimits importLimits(ImportLimits scene = {}) const;
  /// Bodies a scene may have, counted before its meshes are read and again as files split into
  /// several. Only the command line sets it: it bounds what a scene may ask for.
  std::size_t maxBodies = 10'000;
};

/// Loads and validates a scene file. Mesh paths are relative to the scene file's folder. Throws
/// softbake::Error naming the file and the key path: "scene.json: bodies[1].material.stiffness:
/// expected number".
SceneFile loadSceneFile(const std::filesystem::path& path, const SceneLoadOptions& options = {});

/// The same, from JSON already parsed; `source` names it in messages, `baseDirectory` resolves
/// mesh paths.
SceneFile parseScene(const nlohmann::json& json, std::string_view source,
                     const std::filesystem::path& baseDirectory,
                     const SceneLoadOptions& options = {});

/// The same from a scene file's text (parseJsonText(), then parseScene()), as loadSceneFile()
/// reads it; the scene fuzz target starts here.
SceneFile parseSceneText(std::string_view text, std::string_view source,
                         const std::filesystem::path& baseDirectory,
                         const SceneLoadOptions& options = {});

/// Writes a partial scene document's settings, output and render keys over `scene`, read and
/// checked as a scene file's are; `source` names it in messages. The option table's values land
/// in the scene through it (importers/option_table.hpp).
void applySceneKeys(SceneFile& scene, const nlohmann::json& document, std::string_view source);

/// The JSON text of the built-in default scene: two soft balls thrown at each other over a ground
/// plane, 240 frames at 24 fps. examples/default.json is a copy, checked by a test.
std::string_view defaultSceneJson();

/// parseScene(defaultSceneJson()).
SceneFile defaultScene();

/// A scene of one mesh file: the file's meshes as soft bodies of the default material, scaled to
/// about a metre when far from it (noted), dropped from above a ground plane.
SceneFile sceneFromMeshFile(const std::filesystem::path& path,
                            const SceneLoadOptions& options = {});

/// The import options sceneFromMeshFile() reads its file with.
MeshImportOptions meshSceneImportOptions(const SceneLoadOptions& options);

/// The scene sceneFromMeshFile() makes, from meshes already imported (from memory, say) with
/// meshSceneImportOptions(); `path` names the file in messages and the scene after its stem.
SceneFile sceneFromMeshes(ImportedMeshes imported, const std::filesystem::path& path,
                          const SceneLoadOptions& options = {});

/// `name` with every '/', '\\' and whitespace replaced by '_', so it can be a file stem and an OBJ
/// `mtllib` argument ("my ball.fbx" gives the scene "my_ball").
std::string fileSafeSceneName(std::string name);

}  // namespace softbake
