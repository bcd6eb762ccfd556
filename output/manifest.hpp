#pragma once
/// OUT/manifest.json: what a run wrote, for pipeline tools that pick the frames up. It holds no
/// wall-clock time or machine-specific path, so the same run writes the same bytes every time.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/scene/scene_topology.hpp"

namespace softbake {

/// A numbered file sequence, paths relative to the output directory.
struct OutputSequence {
  std::string format;              ///< "obj"
  std::string pattern;             ///< "obj/default_####.obj": one # per digit of the frame number
  std::string printfPattern;       ///< "obj/default_%04d.obj"
  std::vector<std::string> files;  ///< written once beside the sequence: "obj/default.mtl"
};

/// The path, relative to the output directory, of `sequence`'s file for `frame`, its frame number
/// padded to `padding` digits: "obj/default_0012.obj".
std::string sequenceFilePath(const OutputSequence& sequence, int padding, int frame);

/// A body's point caches: its rest mesh and the PC2 and MDD files that animate it, relative to the
/// output directory; empty where not written.
struct ManifestPointCache {
  std::string body;
  std::string restMesh;
  std::string pc2, mdd;
};

struct ManifestBody {
  std::string name;
  std::size_t particles = 0;
  std::size_t triangles = 0;
  bool closed = false;
  bool pressure = false;  ///< the gas pressure acts: closed and a non-zero pressure
};

/// Where a run stands. A run writes its manifest `incomplete` before its first frame, so a killed
/// run leaves one that `--resume` reads; `complete` once every frame of every output is written.
enum class RunStatus { Complete, Incomplete, Failed };
std::string_view runStatusName(RunStatus status);

struct Manifest {
  std::string scene;
  RunStatus status = RunStatus::Complete;
  std::string reason;      ///< why the run is incomplete or failed; empty when complete
  int framesComplete = 0;  ///< frames 1..framesComplete have every output written
  double fps = 24;
  int framesWritten = 0;  ///< the run's frames: "frames" in the file
  int firstFrame = 1;
  int framePadding = 4;
  std::string units = "m";
  std::vector<ManifestBody> bodies;
  std::vector<OutputSequence> sequences;
  std::vector<ManifestPointCache> pointCaches;
  std::string pointCacheUp = "y";  ///< the axis the point caches and rest meshes hold as up
  /// Per frame (index frame − 1): the triangle pairs that intersected at the start and were still
  /// set aside on that frame (initial_overlap); empty when none intersected.
  std::vector<std::uint64_t> setAsidePairs;
  /// What the run was made from and with (its input files' SHA-256, its options), as the command
  /// records it for `--resume` and `export`; opaque here.
  nlohmann::ordered_json run = nlohmann::ordered_json::object();
};

/// The scene, fps, units and bodies of `topology`; sequences are left for the caller to add.
Manifest describeScene(const SceneTopology& topology, std::string scene, int framesWritten,
                       int framePadding = 4);

/// The JSON text, keys in a fixed order, ending in a newline.
std::string manifestJson(const Manifest& manifest);

/// Reads OUT/manifest.json. Throws softbake::Error naming the file and the key that is missing or
/// of the wrong type.
Manifest readManifest(const std::filesystem::path& outputDirectory);

/// Writes OUT/manifest.json atomically. Throws softbake::Error naming the file when writing fails
/// or the fps is not finite (then nothing is written).
void writeManifest(const std::filesystem::path& outputDirectory, const Manifest& manifest);

}  // namespace softbake
