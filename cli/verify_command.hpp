#pragma once
/// `softbake verify OUT`: is every frame of every sequence the manifest lists there, exactly once,
/// whole and readable? Cache frames are read and their checksums checked; other files must be
/// non-empty and readable; no temporary file of a killed writer may be left, and no frame beyond
/// the run's. The farm's last job runs it; so can anyone before shipping a folder.

#include <filesystem>

namespace softbake {

struct VerifyOptions {
  std::filesystem::path out;
};

/// Returns 0 when the folder is whole, 1 with every problem listed otherwise.
int verifyCommand(const VerifyOptions& options);

}  // namespace softbake
