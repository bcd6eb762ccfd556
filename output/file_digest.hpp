#pragma once
/// SHA-256 of input files, so a manifest can say which scene and meshes a run was made from, and
/// `--resume` can tell when one has changed since. The hex digest is what `sha256sum` prints.

#include <filesystem>
#include <string>
#include <string_view>

namespace softbake {

/// The file's SHA-256 as 64 lowercase hex digits. Throws softbake::Error naming the file when it
/// cannot be read.
std::string sha256OfFile(const std::filesystem::path& path);

/// The SHA-256 of `bytes`, 32 raw bytes.
std::string sha256(std::string_view bytes);

}  // namespace softbake
