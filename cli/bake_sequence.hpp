#pragma once
/// A bake as `softbake compare` reads it: its bodies, and per frame every particle's position and
/// each body's contact count. Three sources:
///  - a run's output folder (manifest.json) with its simulation cache: positions and contacts
///    from the cache frames, the bodies from the manifest;
///  - a run's output folder without a cache: positions from its OBJ sequence;
///  - a folder of OBJ files: an OBJ sequence from anywhere, one body per `o` object, frames
///    numbered by the digits that end each file's name; no contacts.
/// Triangles (for volumes and topology) come from the OBJ sequence's first frame, or, for a
/// cache alone, from the scene the manifest records, rebuilt as `export` rebuilds it.

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace softbake {

struct BakeBody {
  std::string name;
  std::size_t firstParticle = 0, particles = 0;
  std::size_t triangleCount = 0;  ///< as the source states it
  /// Within the body; empty when the triangles are not known.
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

struct BakeFrame {
  std::vector<Vec3f> positions;       ///< every body's particles, body after body
  std::vector<std::size_t> contacts;  ///< per body: contacts it takes part in; empty: unknown
};

class BakeSequence {
 public:
  /// Opens the bake in `folder`. Throws softbake::Error naming the folder when it is neither a
  /// run's output folder nor a folder of OBJ files, or when its manifest or first frame is
  /// damaged.
  static BakeSequence open(const std::filesystem::path& folder);

  /// Whether `folder` looks like a bake: it holds manifest.json or OBJ files.
  static bool isBake(const std::filesystem::path& folder);

  const std::string& description() const { return description_; }
  const std::vector<BakeBody>& bodies() const { return bodies_; }
  /// The frame numbers present, ascending.
  std::vector<int> frames() const;
  bool hasContacts() const { return source_ == Source::Cache; }
  /// What could not be read, one sentence each (triangles not known, and why).
  const std::vector<std::string>& notes() const { return notes_; }

  /// Frame `number`'s positions and contacts. Throws softbake::Error naming the file when it is
  /// damaged or holds another number of particles than the bodies.
  BakeFrame read(int number) const;

 private:
  enum class Source { Cache, Obj };
  Source source_ = Source::Obj;
  std::string description_;
  std::vector<BakeBody> bodies_;
  std::map<int, std::filesystem::path> files_;
  std::vector<std::string> notes_;
};

}  // namespace softbake
