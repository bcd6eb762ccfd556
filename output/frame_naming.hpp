#pragma once
/// How every per-frame sequence is named: OUT/<folder>/<scene>_<zero-padded frame><extension>.
/// One place, so the OBJ, contact, VDB and PNG sequences of a run always line up by name.

#include <string>

namespace softbake {

struct FrameNaming {
  std::string folder;     ///< "obj", relative to the output directory
  std::string scene;      ///< file stem
  std::string extension;  ///< ".obj"
  int padding = 4;        ///< digits of the frame number

  /// "default_0001.obj"
  std::string fileName(int frameNumber) const;
  /// "obj/default_0001.obj"
  std::string relativePath(int frameNumber) const;
  /// "obj/default_####.obj": one # per digit, as Houdini and the manifest write sequences.
  std::string pattern() const;
  /// "obj/default_%04d.obj"
  std::string printfPattern() const;
};

}  // namespace softbake
