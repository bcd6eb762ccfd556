#pragma once
/// Caps on what one mesh file may bring in, so that a huge or lying file ends in a clear error
/// naming it instead of minutes of work and a machine out of memory. Generous by default: they
/// stop mistakes, not big scenes.

#include <cstdint>
#include <filesystem>
#include <string_view>

namespace softbake {

struct ImportLimits {
  /// Vertices as the file stores them, over every placed mesh: STL stores three per triangle, so
  /// the default admits a 50M-triangle STL.
  std::uint64_t maxVertices = 150'000'000;
  /// Triangles after triangulation, over every placed mesh.
  std::uint64_t maxFaces = 50'000'000;
  /// Memory one import may take; 0: this machine's physical memory.
  std::uint64_t maxMemoryBytes = 0;
};

/// Throws softbake::Error naming `path` when `vertices` or `faces` is above its cap, saying how to
/// raise it: "x.ply: 60000000 faces, above the limit of 50000000 per file (--max-faces or
/// settings.import.max_faces raises it)".
void requireWithinLimits(const std::filesystem::path& path, std::uint64_t vertices,
                         std::uint64_t faces, const ImportLimits& limits);

/// requireMemory() (memory_budget.hpp) against the smaller of the cap and this machine's memory,
/// naming the cap when it is what refuses.
void requireImportMemory(const std::filesystem::path& path, double neededBytes,
                         std::string_view purpose, const ImportLimits& limits);

}  // namespace softbake
