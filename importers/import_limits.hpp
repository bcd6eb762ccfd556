#pragma once
/// Caps on what one mesh file may bring in, so that a huge or lying file ends in a clear error
/// naming it instead of minutes of work and a machine out of memory. Generous by default: they
/// stop mistakes, not big scenes.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace softbake {

struct ImportLimits {
  /// Vertices as the file stores them, over every placed mesh: STL stores three per triangle, so
  /// the default admits a 50M-triangle STL.
  std::uint64_t maxVertices = 150'000'000;
  /// Triangles after triangulation, over every placed mesh.
  std::uint64_t maxFaces = 50'000'000;
  /// Memory one import may take, bytes; 0: half of this machine's physical memory
  /// (importMemoryBytes()). It bounds softbake's estimates before it allocates, and the process
  /// that reads a file with assimp (assimp_snapshot.hpp) may map at most this much memory beyond
  /// what it started with.
  std::uint64_t maxMemoryBytes = 0;
  /// Seconds that reading one file with assimp may take, in its own process: past them the
  /// process is killed and the import fails.
  std::uint64_t maxSeconds = 120;
};

/// The most seconds ImportLimits::maxSeconds may be: a deadline that far off still fits
/// std::chrono::steady_clock.
inline constexpr std::uint64_t kMaxImportSeconds = 1'000'000'000;

/// limits.maxMemoryBytes, or half of this machine's physical memory when that is 0 (0 when the
/// system does not say how much it has: no cap).
std::uint64_t importMemoryBytes(const ImportLimits& limits);

/// Throws softbake::Error naming `path` when `vertices` or `faces` is above its cap, saying how to
/// raise it: "x.ply: 60000000 faces, above the limit of 50000000 per file (--max-faces or
/// settings.import.max_faces raises it)".
void requireWithinLimits(const std::filesystem::path& path, std::uint64_t vertices,
                         std::uint64_t faces, const ImportLimits& limits);

/// requireMemory() (memory_budget.hpp) against this machine's memory, then against
/// importMemoryBytes(), naming the cap and how to raise it when it is what refuses.
void requireImportMemory(const std::filesystem::path& path, double neededBytes,
                         std::string_view purpose, const ImportLimits& limits);

/// The errors of a reading that went past a limit, naming `file`, the limit and how to raise it:
/// "x.iqm: reading the file took longer than the import time limit of 120 s (--max-import-seconds
/// or settings.import.max_seconds raises it)".
std::string importTimeLimitMessage(std::string_view file, const ImportLimits& limits);
/// "x.iqm: reading the file needed more memory than the import memory limit of 11.7 GiB, half of
/// this machine's memory (--max-import-memory or settings.import.max_memory_mib raises it)".
std::string importMemoryLimitMessage(std::string_view file, const ImportLimits& limits);

}  // namespace softbake
