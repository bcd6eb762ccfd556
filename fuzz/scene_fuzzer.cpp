// libFuzzer target: softbake::fuzz::sceneText() (fuzz_entries.hpp) on every input.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  softbake::fuzz::sceneText(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
