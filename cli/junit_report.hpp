#pragma once
/// A comparison as JUnit XML, which GitLab, Jenkins and GitHub (through a reporter action) show
/// test by test: one test case per item (a frame), failing with its numbers; a warning passes,
/// its numbers in the case's system-out.

#include <filesystem>
#include <string>

#include "cli/comparison.hpp"

namespace softbake {

std::string junitXml(const Comparison& comparison);
/// Writes junitXml() to `path` atomically. Throws softbake::Error naming the file.
void writeJunit(const std::filesystem::path& path, const Comparison& comparison);

}  // namespace softbake
