#pragma once
/// OUT/manifest.json: what a run wrote, for pipeline tools that pick the frames up. It holds no
/// wall-clock time or machine-specific path, so the same run writes the same bytes every time.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "core/scene/scene_topology.hpp"

namespace softbake {

/// A numbered file sequence, paths relative to the output directory.
struct OutputSequence {
  std::string format;              ///< "obj"
  std::string pattern;             ///< "obj/default_####.obj": one # per digit of the frame number
  std::string printfPattern;       ///< "obj/default_%04d.obj"
  std::vector<std::string> files;  ///< written once beside the sequence: "obj/default.mtl"
};

struct ManifestBody {
  std::string name;
  std::size_t particles = 0;
  std::size_t triangles = 0;
  bool closed = false;
  bool pressure = false;  ///< the gas pressure acts: closed and a non-zero pressure
};

struct Manifest {
  std::string scene;
  double fps = 24;
  int framesWritten = 0;
  int firstFrame = 1;
  int framePadding = 4;
  std::string units = "m";
  std::vector<ManifestBody> bodies;
  std::vector<OutputSequence> sequences;
};

/// The scene, fps, units and bodies of `topology`; sequences are left for the caller to add.
Manifest describeScene(const SceneTopology& topology, std::string scene, int framesWritten,
                       int framePadding = 4);

/// The JSON text, keys in a fixed order, ending in a newline.
std::string manifestJson(const Manifest& manifest);

/// Writes OUT/manifest.json atomically. Throws softbake::Error naming the file when writing fails
/// or the fps is not finite (then nothing is written).
void writeManifest(const std::filesystem::path& outputDirectory, const Manifest& manifest);

}  // namespace softbake
