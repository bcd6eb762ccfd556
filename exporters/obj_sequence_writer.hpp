#pragma once
/// Wavefront OBJ sequences: one file per frame plus one material library, for Blender, Houdini,
/// Maya or any renderer that reads numbered OBJ files.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <memory>

#include "core/scene/scene_topology.hpp"
#include "output/frame.hpp"
#include "output/frame_naming.hpp"
#include "output/manifest.hpp"

namespace softbake {

/// Writes OUT/obj/<scene>_0001.obj, _0002.obj, ... (the frame number, zero-padded) and
/// OUT/obj/<scene>.mtl. Each body is an `o` block with its particles (`v`), its source UVs (`vt`,
/// each distinct UV once, in order of first use: texcoord_table.hpp),
/// smooth normals of the deformed surface (`vn`) and its triangles (`f v/vt/vn`, or `f v//vn`
/// without UVs), so an importer sees one mesh per body with the original texture layout.
///
/// Everything but positions and normals is the same in every frame, so it is formatted once at
/// construction; a frame formats 6 numbers per particle and hands the fixed text to writev(2) as
/// it lies.
class ObjSequenceWriter : public FrameSink {
 public:
  /// Keeps `topology` (shared, read-only) for the normals. Creates OUT/obj and
  /// writes the material library at once, so an unwritable output or a UV that is not finite
  /// fails before any simulation.
  /// `scene` becomes the file name stem: it must be non-empty and hold no '/' or whitespace.
  /// Body names are written with whitespace replaced by '_' and made unique. Throws
  /// softbake::Error.
  /// `bodyColors` are the bodies' colours in the material library (linear RGB 0..1, as the
  /// scene's `color` keys give them); a body without one, or with a negative red, takes the
  /// palette.
  ObjSequenceWriter(std::shared_ptr<const SceneTopology> topology,
                    const std::filesystem::path& outputDirectory, std::string scene,
                    int framePadding = 4, std::vector<Vec3f> bodyColors = {});

  /// Throws softbake::Error naming the file, and the body and frame, for a position, normal or
  /// time that is not finite, or naming the file when writing fails; no file is left behind for
  /// that frame either way.
  void write(const Frame& frame) override;
  const char* name() const override { return "obj"; }
  std::uint64_t bytesWritten() const override { return bytes_.load(std::memory_order_relaxed); }

  /// OUT/obj/<scene>_<padded number>.obj
  std::filesystem::path framePath(int frameNumber) const;
  std::filesystem::path materialLibraryPath() const;
  /// The sequence as the manifest lists it, with paths relative to OUT.
  OutputSequence sequence() const;

 private:
  FrameNaming naming() const;

  /// The per-body text that does not change between frames.
  struct BodyText {
    std::string object;     ///< "o name\n"
    std::string texcoords;  ///< every "vt" line, one per distinct UV
    std::string faces;      ///< "usemtl", "s 1" and every "f" line
  };

  /// A piece of the file: `fixed` text, or the range [begin, end) of `buffer_`. Ranges rather than
  /// views because the buffer may move while it grows.
  struct Piece {
    const std::string* fixed = nullptr;
    std::size_t begin = 0, end = 0;
  };

  /// Throws softbake::Error naming `path` for a number that is not finite.
  void formatBody(const Frame& frame, const Body& body, const BodyText& text,
                  const std::filesystem::path& path);
  void addFixed(const std::string& text) { pieces_.push_back({&text}); }
  void addFormattedSince(std::size_t begin) { pieces_.push_back({nullptr, begin, buffer_.size()}); }

  std::shared_ptr<const SceneTopology> topology_;
  std::vector<BodyText> text_;
  std::size_t particleCount_ = 0;
  std::filesystem::path objDirectory_;
  std::string scene_;
  int framePadding_;

  // Reused from frame to frame: after the first frames, writing allocates nothing but a path.
  std::string buffer_;  ///< the formatted numbers of one frame
  std::vector<Piece> pieces_;
  std::vector<std::string_view> parts_;
  std::vector<Vec3f> normals_;

  std::atomic<std::uint64_t> bytes_{0};
};

}  // namespace softbake
