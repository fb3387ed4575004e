#pragma once
// Shared by the adapter tests: settings of small patches, OBJ files in a temporary folder, error checks.

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <drench/common/error.hpp>
#include <drench/coupling/cloth_engine.hpp>

namespace drench::bullet::test {

inline ClothSettings patch_settings(int nodes_x, int nodes_z, const std::string& pinned = "corners") {
  ClothSettings s;
  s.center = Vec3(0.1, 0.5, -0.2);
  s.size_x = 0.6;
  s.size_z = 0.4;
  s.nodes_x = nodes_x;
  s.nodes_z = nodes_z;
  s.area_density = 0.2;
  s.pinned = pinned;
  return s;
}

/// Writes `text` to a fresh file in the temporary folder and returns its path.
inline std::string write_temp_file(const std::string& name, const std::string& text) {
  static std::atomic<int> counter{0};
  const auto dir = std::filesystem::temp_directory_path() /
                   ("drench_bullet_tests_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path.string();
}

/// Expects `f` to throw SceneError whose message contains every one of `parts`.
inline void expect_scene_error(const std::function<void()>& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no SceneError thrown";
  } catch (const SceneError& e) {
    const std::string message = e.what();
    for (const auto& part : parts)
      EXPECT_NE(message.find(part), std::string::npos) << "message: " << message << "\nexpected: " << part;
  }
}

}  // namespace drench::bullet::test
