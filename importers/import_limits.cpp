#include "importers/import_limits.hpp"

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/memory_budget.hpp"

namespace softbake {

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
  const std::uint64_t machine = physicalMemoryBytes();
  const bool capped =
      limits.maxMemoryBytes > 0 && (machine == 0 || limits.maxMemoryBytes < machine);
  if (capped && neededBytes > double(limits.maxMemoryBytes))
    throw Error(cat(path.string(), ": ", purpose, " needs about ", formatBytes(neededBytes),
                    ", above the import memory limit of ",
                    formatBytes(double(limits.maxMemoryBytes)),
                    " (--max-import-memory or settings.import.max_memory_mib raises it)"));
  requireMemory(path, neededBytes, purpose, machine);
}

}  // namespace softbake
