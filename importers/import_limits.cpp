#include "importers/import_limits.hpp"

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/memory_budget.hpp"

namespace softbake {

namespace {

// "1.0 KiB", or "11.7 GiB, half of this machine's memory" for the default.
std::string memoryCapText(const ImportLimits& limits) {
  const std::string bytes = formatBytes(double(importMemoryBytes(limits)));
  return limits.maxMemoryBytes > 0 ? bytes : cat(bytes, ", half of this machine's memory");
}

}  // namespace

std::uint64_t importMemoryBytes(const ImportLimits& limits) {
  return limits.maxMemoryBytes > 0 ? limits.maxMemoryBytes : physicalMemoryBytes() / 2;
}

void requireWithinLimits(const std::filesystem::path& path, std::uint64_t vertices,
                         std::uint64_t faces, const ImportLimits& limits) {
  if (faces > limits.maxFaces)
    throw Error(cat(path.string(), ": ", faces, " faces, above the limit of ", limits.maxFaces,
                    " per file (--max-faces or settings.import.max_faces raises it)"));
  if (vertices > limits.maxVertices)
    throw Error(cat(path.string(), ": ", vertices, " vertices, above the limit of ",
                    limits.maxVertices,
                    " per file (--max-vertices or settings.import.max_vertices raises it)"));
}

void requireImportMemory(const std::filesystem::path& path, double neededBytes,
                         std::string_view purpose, const ImportLimits& limits) {
  // More than the machine has is the machine's limit, which no flag raises.
  requireMemory(path, neededBytes, purpose, physicalMemoryBytes());
  const std::uint64_t cap = importMemoryBytes(limits);
  if (cap > 0 && neededBytes > double(cap))
    throw Error(cat(path.string(), ": ", purpose, " needs about ", formatBytes(neededBytes),
                    ", above the import memory limit of ", memoryCapText(limits),
                    " (--max-import-memory or settings.import.max_memory_mib raises it)"));
}

std::string importTimeLimitMessage(std::string_view file, const ImportLimits& limits) {
  return cat(file, ": reading the file took longer than the import time limit of ",
             limits.maxSeconds,
             " s (--max-import-seconds or settings.import.max_seconds raises it)");
}

std::string importMemoryLimitMessage(std::string_view file, const ImportLimits& limits) {
  return cat(file, ": reading the file took more memory than the import memory limit of ",
             memoryCapText(limits),
             " (--max-import-memory or settings.import.max_memory_mib raises it)");
}

}  // namespace softbake
