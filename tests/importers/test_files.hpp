#pragma once
/// Where the importer tests find their meshes, and scratch folders for the files they write.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace softbake::test {

inline std::filesystem::path sharedMeshes() {
  return SOFTBAKE_SHARED_MESHES_DIR;
}
inline std::filesystem::path sourceDir() {
  return SOFTBAKE_SOURCE_DIR;
}

/// The shared meshes live outside the repository; a checkout without them skips, not fails.
#define SOFTBAKE_REQUIRE_SHARED_MESHES()                                                 \
  do {                                                                                   \
    if (!std::filesystem::is_directory(::softbake::test::sharedMeshes()))                \
      GTEST_SKIP() << "shared meshes not found at " << ::softbake::test::sharedMeshes(); \
  } while (false)

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
