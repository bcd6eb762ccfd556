#pragma once
/// Where the importer tests find their meshes, and scratch folders for the files they write.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "importers/mesh_import.hpp"

namespace softbake::test {

/// The message importing `file` fails with; a test failure when it does not fail.
inline std::string importError(const std::filesystem::path& file,
                               const MeshImportOptions& options = {}) {
  try {
    importMeshFile(file, options);
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "no error for " << file;
  return {};
}

/// The meshes the suite imports, kept in the repository (tests/data/meshes/README.md says where
/// each comes from). A missing file makes its test fail, never skip.
inline std::filesystem::path testMeshes() {
  return SOFTBAKE_TEST_MESHES_DIR;
}
inline std::filesystem::path sourceDir() {
  return SOFTBAKE_SOURCE_DIR;
}

/// A fresh folder for one test, removed with everything in it when the test ends.
class ScratchDir {
 public:
  ScratchDir() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            (std::string("softbake_importers_") + info->test_suite_name() + "_" + info->name() +
             "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(std::string_view name) const { return path_ / name; }

  /// Writes `contents` to `name` inside the folder and returns its path.
  std::filesystem::path write(std::string_view name, std::string_view contents) const {
    const std::filesystem::path file = path_ / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary).write(contents.data(), std::streamsize(contents.size()));
    return file;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace softbake::test
