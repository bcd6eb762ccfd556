#include "cli/bake_sequence.hpp"

#include <algorithm>
#include <cctype>

#include "bake/run_outputs.hpp"
#include "bake/run_record.hpp"
#include "bake/scene_input.hpp"
#include "cli/obj_frame.hpp"
#include "core/error.hpp"
#include "core/scene/scene_topology.hpp"
#include "core/text.hpp"
#include "importers/ply_data.hpp"
#include "output/cache_format.hpp"
#include "output/manifest.hpp"

namespace softbake {

namespace fs = std::filesystem;

namespace {

/// The frame number a name ends in: "ball_0012.obj" is 12; -1 when it ends in no digits.
int trailingNumber(const std::string& stem) {
  std::size_t start = stem.size();
  while (start > 0 && std::isdigit(static_cast<unsigned char>(stem[start - 1]))) --start;
  if (start == stem.size() || stem.size() - start > 9) return -1;
  return std::stoi(stem.substr(start));
}

/// The OBJ files of `folder` by frame number. Throws softbake::Error naming two files with one
/// number.
std::map<int, fs::path> objFrames(const fs::path& folder) {
  std::map<int, fs::path> frames;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".obj") continue;
    const int number = trailingNumber(entry.path().stem().string());
    if (number < 0) continue;  // a rest mesh or another file beside the sequence
    const auto [at, added] = frames.emplace(number, entry.path());
    if (!added)
      throw Error(cat(folder.string(), ": two OBJ files are frame ", number, ": ",
                      at->second.filename().string(), " and ", entry.path().filename().string()));
  }
  return frames;
}

/// Bodies from an OBJ frame: one per object, its triangles known.
std::vector<BakeBody> bodiesOf(const ObjFrame& frame) {
  std::vector<BakeBody> bodies;
  for (const ObjObject& object : frame.objects)
    bodies.push_back({object.name, object.firstVertex, object.vertexCount, object.triangles.size(),
                      object.triangles});
  return bodies;
}

/// The triangles of each body of the scene `manifest` records, rebuilt from its input. Throws
/// softbake::Error when the input is gone or changed.
std::vector<std::vector<std::array<std::uint32_t, 3>>> trianglesFromScene(const Manifest& manifest,
                                                                          const fs::path& folder) {
  const std::string source = (folder / "manifest.json").string();
  RunOptions run = runOptionsFromRecord(manifest.run, folder, source);
  SceneFile scene = loadSceneInput(run.input, run.load);
  applySceneOptions(run.given, scene);
  const std::vector<std::string> differences = runRecordDifferences(
      manifest.run, runRecord(run, scene, recordedCheckpointInterval(manifest.run)));
  if (!differences.empty())
    throw Error(
        cat("the run in ", source, " was made from other inputs:", listedDifferences(differences)));
  const SceneTopology topology = buildSceneTopology(scene.setup);
  std::vector<std::vector<std::array<std::uint32_t, 3>>> triangles;
  for (const Body& body : topology.bodies) {
    triangles.emplace_back();
    for (Index t = 0; t < body.triangleCount; ++t) {
      const Triangle& triangle = topology.triangles[body.firstTriangle + t];
      triangles.back().push_back({std::uint32_t(triangle[0] - body.firstParticle),
                                  std::uint32_t(triangle[1] - body.firstParticle),
                                  std::uint32_t(triangle[2] - body.firstParticle)});
    }
  }
  return triangles;
}

}  // namespace

bool BakeSequence::isBake(const fs::path& folder) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return false;
  if (fs::exists(folder / "manifest.json", error)) return true;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, error))
    if (entry.path().extension() == ".obj") return true;
  return false;
}

BakeSequence BakeSequence::open(const fs::path& folder) {
  BakeSequence bake;
  std::error_code error;
  if (!fs::exists(folder / "manifest.json", error)) {
    bake.files_ = objFrames(folder);
    if (bake.files_.empty())
      throw Error(cat(folder.string(),
                      ": neither a run's output folder (manifest.json) nor a "
                      "folder of numbered OBJ frames"));
    bake.bodies_ = bodiesOf(readObjFrame(bake.files_.begin()->second));
    bake.description_ = cat("OBJ sequence ", folder.string());
    return bake;
  }

  const Manifest manifest = readManifest(folder);
  std::size_t first = 0;
  for (const ManifestBody& body : manifest.bodies) {
    bake.bodies_.push_back({body.name, first, body.particles, body.triangles, {}});
    first += body.particles;
  }
  const auto sequence = [&](const std::string& format) -> const OutputSequence* {
    for (const OutputSequence& s : manifest.sequences)
      if (s.format == format) return &s;
    return nullptr;
  };
  const auto framesOf = [&](const OutputSequence& s) {
    std::map<int, fs::path> files;
    for (int frame = manifest.firstFrame; frame < manifest.firstFrame + manifest.framesWritten;
         ++frame) {
      const fs::path path = folder / sequenceFilePath(s, manifest.framePadding, frame);
      if (fs::exists(path, error)) files.emplace(frame, path);
    }
    return files;
  };
  const OutputSequence* cache = sequence("cache");
  const OutputSequence* obj = sequence("obj");
  if (!cache && !obj)
    throw Error(cat(folder.string(),
                    "/manifest.json: the run kept neither a cache nor an OBJ "
                    "sequence to compare"));
  bake.source_ = cache ? Source::Cache : Source::Obj;
  bake.files_ = framesOf(cache ? *cache : *obj);
  bake.description_ = cat(cache ? "cache" : "OBJ sequence", " of scene '", manifest.scene, "' in ",
                          folder.string());

  // Triangles: from the first OBJ frame, else from the recorded scene.
  const std::map<int, fs::path> objFiles = obj ? framesOf(*obj) : std::map<int, fs::path>{};
  try {
    if (!objFiles.empty()) {
      const std::vector<BakeBody> fromObj = bodiesOf(readObjFrame(objFiles.begin()->second));
      for (std::size_t b = 0; b < bake.bodies_.size() && b < fromObj.size(); ++b)
        if (fromObj[b].particles == bake.bodies_[b].particles)
          bake.bodies_[b].triangles = fromObj[b].triangles;
    } else {
      const auto triangles = trianglesFromScene(manifest, folder);
      for (std::size_t b = 0; b < bake.bodies_.size() && b < triangles.size(); ++b)
        bake.bodies_[b].triangles = triangles[b];
    }
  } catch (const Error& problem) {
    bake.notes_.push_back(
        cat(folder.string(), ": volumes and triangles not compared: ", problem.what()));
  }
  return bake;
}

std::vector<int> BakeSequence::frames() const {
  std::vector<int> numbers;
  for (const auto& [number, path] : files_) numbers.push_back(number);
  return numbers;
}

BakeFrame BakeSequence::read(int number) const {
  const fs::path& path = files_.at(number);
  std::size_t particles = 0;
  for (const BakeBody& body : bodies_) particles += body.particles;
  BakeFrame frame;
  if (source_ == Source::Cache) {
    const Frame decoded = decodeCacheFrame(readWholeFile(path.string()), path.string());
    frame.positions.reserve(decoded.positions.size());
    for (const Vec3& p : decoded.positions) frame.positions.push_back(p.cast<float>());
    // A body takes part in a contact as A, or as B unless B is a plane (planes are numbered apart).
    frame.contacts.assign(bodies_.size(), 0);
    for (const Contact& contact : decoded.contacts) {
      if (contact.surfaceA < bodies_.size()) ++frame.contacts[contact.surfaceA];
      if (contact.kind != ContactKind::Plane && contact.surfaceB < bodies_.size() &&
          contact.surfaceB != contact.surfaceA)
        ++frame.contacts[contact.surfaceB];
    }
  } else {
    frame.positions = readObjFrame(path).positions;
  }
  if (frame.positions.size() != particles)
    throw Error(cat(path.string(), ": ", frame.positions.size(), " vertices where the bodies have ",
                    particles));
  return frame;
}

}  // namespace softbake
