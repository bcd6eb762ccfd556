#pragma once
/// What each fuzz target does with one input, as plain functions: the libFuzzer programs in this
/// folder call them, and so does the ordinary test suite, which replays every input that ever
/// crashed one (tests/data/fuzz/<target>/) without needing clang or libFuzzer.
///
/// Each returns how the input ended when it ended well: refused with softbake::Error, whose
/// message names the input, or loaded into a world that holds together. Anything else escapes as
/// an exception other than softbake::Error (FuzzFinding for a broken promise): libFuzzer reports
/// it as a crash, and a test fails on it.

#include <stdexcept>
#include <string>
#include <string_view>

namespace softbake {
struct SceneTopology;
}

namespace softbake::fuzz {

enum class Outcome { kRefused, kLoaded };

/// A promise the code broke on this input: an error that does not name the file, a world with a
/// non-finite mass or an index out of range.
class FuzzFinding : public std::logic_error {
 public:
  explicit FuzzFinding(const std::string& what) : std::logic_error(what) {}
};

/// The input as a scene file's text ("fuzz.json"): the JSON reader, the scene parser and world
/// building (buildSceneTopology). Mesh paths resolve against examples/, so the examples' own
/// `sheet_24.obj` loads.
Outcome sceneText(std::string_view bytes);

/// The input as a PLY file ("fuzz.ply"): the header check, the row count of the data and, for a
/// file with triangle strips, softbake's own reader of them. Never reaches assimp.
Outcome plyGuard(std::string_view bytes);

/// The file formats the mesh target feeds assimp, picked by the input's first byte.
inline constexpr std::string_view kMeshFormats[] = {".obj",  ".ply", ".stl",
                                                    ".gltf", ".glb", ".fbx"};

/// The input's first byte picks the format (its value modulo the number of kMeshFormats), the
/// rest is the file, imported from memory ("fuzz.<format>") as `softbake run FILE` imports a
/// file: the import, the scene made of its meshes, welding, topology and world building.
Outcome meshImport(std::string_view bytes);

/// The first byte meshImport() reads as `format` (".obj" ... ".fbx").
char meshFormatByte(std::string_view format);

/// Throws FuzzFinding when `world` breaks what every stage after world building relies on: a
/// non-finite position or mass, an index out of range, render triangles that do not match the
/// simulated ones.
void checkWorld(const SceneTopology& world);

}  // namespace softbake::fuzz
