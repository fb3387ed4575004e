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

#include "../drench_command.hpp"
#include "../temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kSmallTank = std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/hydrostatic_tank.json" +
                               " --set fluid.particle_spacing=0.04 --steps 10 --quiet";

TEST(RunThreads, SummaryReportsTheThreadsAskedFor) {
  const drench::test::TempDir dir;
  for (const int threads : {1, 2}) {
    const fs::path out = dir.path() / ("t" + std::to_string(threads));
    ASSERT_EQ(drench::test::run_drench(
                  "run " + kSmallTank + " --out " + out.string() + " --threads " + std::to_string(threads),
                  dir.path() / "log.txt"),
              0)
        << drench::test::read_text(dir.path() / "log.txt");
    const nlohmann::json summary = nlohmann::json::parse(drench::test::read_text(out / "summary.json"));
    EXPECT_EQ(summary.at("threads").get<int>(), threads);
  }
}

TEST(RunThreads, ACountAboveTheLimitIsRefusedBeforeAnythingIsWritten) {
  const drench::test::TempDir dir;
  const fs::path out = dir.path() / "out";
  EXPECT_EQ(drench::test::run_drench("run " + kSmallTank + " --out " + out.string() + " --threads 5000",
                                     dir.path() / "log.txt"),
            1);
  // The command line's own check refuses it, before drench::set_thread_count would (test_thread_pool).
  EXPECT_NE(drench::test::read_text(dir.path() / "log.txt")
                .find("--threads: must be a whole number in [1, 1024], got '5000'"),
            std::string::npos)
      << drench::test::read_text(dir.path() / "log.txt");
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
