#pragma once
/// Refusing meshes that cannot fit in memory before allocating for them, so a huge or lying file
/// ends in a clear error instead of the kernel's OOM killer.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace softbake {

/// This machine's physical memory in bytes (sysconf), or 0 when the system does not say.
std::uint64_t physicalMemoryBytes();

/// "1.5 GiB", "640 KiB": sizes for messages.
std::string formatBytes(double bytes);

/// Throws softbake::Error naming `path` when `neededBytes` is more than `availableBytes`;
/// `purpose` says what the memory is for ("importing 3 meshes"). An unknown budget (0) passes.
void requireMemory(const std::filesystem::path& path, double neededBytes, std::string_view purpose,
                   std::uint64_t availableBytes = physicalMemoryBytes());

}  // namespace softbake
