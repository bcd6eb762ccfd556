#pragma once
/// Counts heap allocations while a CountedAllocations is alive, for the tests that a warmed-up
/// step allocates nothing. allocation_counter.cpp replaces the global operator new of the whole
/// core_test program; it forwards to malloc and adds one relaxed atomic load.

#include <atomic>

namespace softbake::test {

extern std::atomic<bool> gCountAllocations;
extern std::atomic<long> gAllocations;

/// Allocations made from construction to allocations().
class CountedAllocations {
 public:
  CountedAllocations() {
    gAllocations = 0;
    gCountAllocations = true;
  }
  ~CountedAllocations() { gCountAllocations = false; }
  long allocations() const { return gAllocations.load(); }
};

}  // namespace softbake::test
