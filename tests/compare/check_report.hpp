#pragma once
/// Runs tests/compare/check_report.py (what CI's JUnit reader and a browser make of compare's
/// outputs) with Python, for the tests that write them.

#include <string>

#include "tests/cli/softbake_process.hpp"

namespace softbake::test {

/// `python3 check_report.py ARGUMENTS`, stdout and stderr together.
inline Result checkReport(const std::string& arguments) {
  return runShell(
      std::string(SOFTBAKE_PYTHON) + " " +
      quoted(std::filesystem::path(SOFTBAKE_SOURCE_DIR) / "tests/compare/check_report.py") + " " +
      arguments + " 2>&1");
}

}  // namespace softbake::test
