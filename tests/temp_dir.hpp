#pragma once
// Shared by the test executables: a scratch folder per test.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace drench::test {

/// An empty folder in GoogleTest's temp directory for the running test, removed with its contents at the
/// end. Named drench_<suite>_<test>[_<tag>]_<pid>: tests that ctest runs in parallel, each in its own
/// process, never share one, and a folder left by a crashed run of the same test is emptied first.
class TempDir {
 public:
  /// @param tag  tells apart several folders of one test; "" for one
  /// @throws std::filesystem::filesystem_error when the folder cannot be made
  explicit TempDir(const std::string& tag = "") {
    const testing::TestInfo* test = testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(test->test_suite_name()) + "_" + test->name();
    if (!tag.empty()) name += "_" + tag;
    // Parameterised tests are named Suite/Test/0: one folder, not three.
    std::replace(name.begin(), name.end(), '/', '_');
    m_path =
        std::filesystem::path(testing::TempDir()) / ("drench_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(m_path);
    std::filesystem::create_directories(m_path);
  }
  ~TempDir() {
    std::error_code ignored;  // a destructor must not throw; what is left is removed by the next run
    std::filesystem::remove_all(m_path, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return m_path; }

  /// Writes `contents` to `name` inside the folder, making its subfolders, and returns the file's path.
  /// @param name  a relative path such as "scene.json" or "a/b.obj"
  std::string write(const std::string& name, const std::string& contents) const {
    const std::filesystem::path file = m_path / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << contents;
    return file.string();
  }

 private:
  std::filesystem::path m_path;
};

}  // namespace drench::test
