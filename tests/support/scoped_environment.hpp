#pragma once
/// An environment variable set for as long as one object lives: the importers' test hooks
/// (importers/assimp_snapshot.hpp) read theirs in the process that reads a file, and the softbake
/// processes a test starts inherit it.

#include <cstdlib>

namespace softbake::test {

class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* variable, const char* value) : variable_(variable) {
    ::setenv(variable, value, 1);
  }
  ~ScopedEnvironment() { ::unsetenv(variable_); }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* variable_;
};

}  // namespace softbake::test
