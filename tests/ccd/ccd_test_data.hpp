#pragma once
/// Where the CCD tests find the outside query set (../shared/data/ccd-vertex-face, next to the repository;
/// see the README.md there). The set is not part of the repository, so a test that needs it skips on a
/// developer machine without it and fails in CI, where missing data must not pass silently.
///
///   TEST(PointTriangleCcd, MatchesGroundTruth) {
///     DRENCH_REQUIRE_CCD_DATA(dir);  // std::string dir, or the test ends here
///     for (const std::string& file : drench::ccd::list_ccd_query_files(dir)) ...
///   }

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

namespace drench::ccd::test {

/// The data folder as the build saw it: DRENCH_SOURCE_DIR "/../shared/data/ccd-vertex-face".
inline std::string ccd_test_data_expected_path() {
  return std::filesystem::path(DRENCH_SOURCE_DIR "/../shared/data/ccd-vertex-face")
      .lexically_normal()
      .string();
}

/// The data folder (absolute, `..` resolved), or std::nullopt when it is not a directory.
inline std::optional<std::string> ccd_test_data_dir() {
  std::error_code error;
  const std::filesystem::path dir =
      std::filesystem::weakly_canonical(DRENCH_SOURCE_DIR "/../shared/data/ccd-vertex-face", error);
  if (error || !std::filesystem::is_directory(dir, error)) return std::nullopt;
  return dir.string();
}

/// CI services (GitHub Actions, GitLab CI, ...) set CI=true.
inline bool running_in_ci() {
  const char* value = std::getenv("CI");
  return value != nullptr && std::strcmp(value, "true") == 0;
}

/// Why a test did not run, printed by GTEST_SKIP and FAIL.
inline std::string ccd_test_data_missing_reason() {
  return "CCD query data not found at " + ccd_test_data_expected_path() +
         " (the ccd-vertex-face set lives next to the repository, in ../shared/data)";
}

}  // namespace drench::ccd::test

/// Declares `const std::string dir` holding the data folder. When the folder is missing, ends the test: a
/// failure when the environment variable CI is "true", else a skip. Use in a TEST body only (it returns).
#define DRENCH_REQUIRE_CCD_DATA(dir)                                                                      \
  const std::optional<std::string> dir##_or_missing = ::drench::ccd::test::ccd_test_data_dir();           \
  if (!dir##_or_missing) {                                                                                \
    if (::drench::ccd::test::running_in_ci()) {                                                           \
      FAIL() << ::drench::ccd::test::ccd_test_data_missing_reason() << "; CI=true, so this is a failure"; \
    }                                                                                                     \
    GTEST_SKIP() << ::drench::ccd::test::ccd_test_data_missing_reason()                                   \
                 << "; skipped (set CI=true to fail)";                                                    \
  }                                                                                                       \
  const std::string dir = *dir##_or_missing
