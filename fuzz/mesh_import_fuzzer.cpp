// libFuzzer target: softbake::fuzz::meshImport() (fuzz_entries.hpp) on every input.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  softbake::fuzz::meshImport(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
