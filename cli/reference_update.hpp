#pragma once
/// `softbake compare --update`: the new frames become the references, when a change to what the
/// frames show is meant.

#include <filesystem>
#include <string>
#include <vector>

#include "cli/image_set_comparison.hpp"

namespace softbake {

/// Accepts the new frames of `frames` into `reference` (a folder, or the reference file itself):
/// every frame that warned or failed gets the new frame's bytes under the new frame's name (a
/// reference of another format under the same name is removed after), and a reference the new
/// frames lack is removed. Frames that passed stay as they are. Each file is written under a
/// temporary name, flushed to disk and renamed over the old one, so an interrupted update leaves
/// every reference whole, old or new. Returns a line per file changed. Throws softbake::Error
/// naming the file that could not be written.
std::vector<std::string> acceptNewFrames(const std::filesystem::path& reference,
                                         const std::vector<FramePair>& frames);

}  // namespace softbake
