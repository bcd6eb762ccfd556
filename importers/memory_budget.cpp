#include "importers/memory_budget.hpp"

#include <unistd.h>

#include <array>
#include <iomanip>
#include <sstream>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

std::uint64_t physicalMemoryBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long pageSize = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || pageSize <= 0) return 0;
  return std::uint64_t(pages) * std::uint64_t(pageSize);
}

std::string formatBytes(double bytes) {
  constexpr std::array kUnits = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  std::size_t unit = 0;
  while (bytes >= 1024 && unit + 1 < kUnits.size()) {
    bytes /= 1024;
    ++unit;
  }
  std::ostringstream out;
  out << std::setprecision(unit == 0 ? 0 : 1) << std::fixed << bytes << ' ' << kUnits[unit];
  return out.str();
}

void requireMemory(const std::filesystem::path& path, double neededBytes, std::string_view purpose,
                   std::uint64_t availableBytes) {
  if (availableBytes == 0 || neededBytes <= double(availableBytes)) return;
  throw Error(cat(path.string(), ": mesh too large for this machine: ", purpose, " needs about ",
                  formatBytes(neededBytes), ", but it has ", formatBytes(double(availableBytes)),
                  " of memory"));
}

}  // namespace softbake
