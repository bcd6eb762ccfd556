#pragma once
/// Each frame's contacts as JSON, OUT/contacts/<scene>_0001.json, for effects and checks:
///
///   {"frame": 12, "time": 0.458333, "scene": "default", "contacts": [
///     {"kind": "particle-triangle", "position": [x, y, z], "normal": [x, y, z],
///      "bodies": ["ballA", "ballB"], "triangles": [null, 431], "particle": 87}, ...]}
///
/// `bodies` names the surface that moved into the contact, then the one it struck (a body or a
/// static mesh collider); `triangles` and `particle` are indices within those surfaces, in the
/// order of the OBJ export's faces and vertices (null where the kind has none).

#include <filesystem>
#include <string>
#include <vector>

#include "core/scene/scene_topology.hpp"
#include "output/frame.hpp"
#include "output/frame_naming.hpp"
#include "output/manifest.hpp"

namespace softbake {

class ContactWriter : public FrameSink {
 public:
  /// Copies what it needs from `topology`. Creates OUT/contacts. Throws softbake::Error.
  ContactWriter(const SceneTopology& topology, const std::filesystem::path& outputDirectory,
                std::string scene, int framePadding = 4);
  /// Throws softbake::Error naming the file for a time, contact position or normal that is not
  /// finite (and writes nothing), or when writing fails.
  void write(const Frame& frame) override;
  const char* name() const override { return "contacts"; }
  std::uint64_t bytesWritten() const override { return bytes_.load(std::memory_order_relaxed); }

  std::filesystem::path framePath(int frameNumber) const;
  OutputSequence sequence() const;
  /// The JSON text of one frame.
  std::string frameJson(const Frame& frame) const;

 private:
  /// What the contact's surface A met: a body or static mesh, or a plane.
  const std::string& partnerName(const Contact& contact) const;

  std::filesystem::path outputDirectory_;
  FrameNaming naming_;
  std::vector<std::string> surfaceNames_;
  std::vector<std::string> planeNames_;
  std::vector<Index> surfaceFirstTriangle_;
  std::vector<Index> bodyFirstParticle_;
  std::atomic<std::uint64_t> bytes_{0};
};

}  // namespace softbake
