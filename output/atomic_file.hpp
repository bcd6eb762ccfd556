#pragma once
/// Whole-file writes that never leave a torn file behind.
///
/// Readers (a renderer picking up frames as they appear, a user opening the folder) see either no
/// file, the old file or the complete new one: the data goes to a temporary name in the same
/// directory and rename(2) swaps it in, which POSIX makes atomic within one file system.

#include <filesystem>
#include <span>
#include <string_view>

namespace softbake {

/// How far a written file is guaranteed to survive.
enum class Durability {
  /// A killed process: the kernel has the data. The outputs use this; an fsync per frame of every
  /// sequence would cost more than formatting it.
  ProcessCrash,
  /// A power cut too: the data is fsync'ed before the rename and the directory after it. The
  /// simulation cache uses this, because `--resume` trusts what it finds there.
  PowerLoss,
};

/// Writes `data` to `path` through `.<name>.tmp-<pid>-<n>` beside it, replacing any existing file.
/// On failure the temporary file is removed and softbake::Error names `path` and the system's
/// reason.
void writeFileAtomically(const std::filesystem::path& path, std::string_view data,
                         Durability durability = Durability::ProcessCrash);

/// The same for a file made of `parts` in order, written with writev(2): text that is the same in
/// every frame goes to the kernel from where it lies instead of being copied into one buffer.
void writeFileAtomically(const std::filesystem::path& path, std::span<const std::string_view> parts,
                         Durability durability = Durability::ProcessCrash);

/// Creates `directory` and its missing parents. Throws softbake::Error naming the directory when
/// that fails or when something other than a directory is in the way.
void makeDirectories(const std::filesystem::path& directory);

}  // namespace softbake
