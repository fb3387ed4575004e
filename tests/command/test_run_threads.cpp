// `drench run --threads N` as a user runs it: the summary reports the threads used, and a count outside
// [1, 1024] is refused before anything is written. The scene is the hydrostatic tank made small (864
// particles of 4 cm, 10 steps).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "../temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

int run_drench(const std::string& arguments, const fs::path& log) {
  const std::string command =
      std::string(DRENCH_EXECUTABLE) + " " + arguments + " > " + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

const std::string kSmallTank = std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/hydrostatic_tank.json" +
                               " --set fluid.particle_spacing=0.04 --steps 10 --quiet";

TEST(RunThreads, SummaryReportsTheThreadsAskedFor) {
  const drench::test::TempDir dir;
  for (const int threads : {1, 2}) {
    const fs::path out = dir.path() / ("t" + std::to_string(threads));
    ASSERT_EQ(
        run_drench("run " + kSmallTank + " --out " + out.string() + " --threads " + std::to_string(threads),
                   dir.path() / "log.txt"),
        0)
        << read_text(dir.path() / "log.txt");
    const nlohmann::json summary = nlohmann::json::parse(read_text(out / "summary.json"));
    EXPECT_EQ(summary.at("threads").get<int>(), threads);
  }
}

TEST(RunThreads, ACountAboveTheLimitIsRefusedBeforeAnythingIsWritten) {
  const drench::test::TempDir dir;
  const fs::path out = dir.path() / "out";
  EXPECT_EQ(
      run_drench("run " + kSmallTank + " --out " + out.string() + " --threads 5000", dir.path() / "log.txt"),
      1);
  EXPECT_NE(read_text(dir.path() / "log.txt").find("thread count must be in [1, 1024], got 5000"),
            std::string::npos)
      << read_text(dir.path() / "log.txt");
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
