#pragma once
// Shared by the tests that run the drench command as a user does (DRENCH_EXECUTABLE, set by CMake).

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace drench::test {

/// Runs `drench ARGUMENTS` through the shell, its standard output and error into `log`.
/// @return its exit status, or -1 when a signal ended it
inline int run_drench(const std::string& arguments, const std::filesystem::path& log) {
  const std::string command =
      std::string(DRENCH_EXECUTABLE) + " " + arguments + " > " + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// The whole file, byte for byte; empty when it cannot be read.
inline std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace drench::test
