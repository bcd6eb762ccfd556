#include "tests/core/allocation_counter.hpp"

#include <cstdlib>
#include <new>

namespace softbake::test {
std::atomic<bool> gCountAllocations{false};
std::atomic<long> gAllocations{0};
}  // namespace softbake::test

// GCC sees malloc'd memory reach free through inlined new/delete pairs and calls it a mismatch;
// here both sides are replaced together, so it is not one.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (softbake::test::gCountAllocations.load(std::memory_order_relaxed))
    softbake::test::gAllocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#pragma GCC diagnostic pop
