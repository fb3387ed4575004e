// `drench sweep` as a user runs it: one `drench run` per setting, a row per run (failures included), the
// report and the plot. The scene is the hydrostatic tank made small (864 particles of 4 cm, 0.1 s).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../csv_rows.hpp"
#include "../drench_command.hpp"
#include "../temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kTank =
    std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/hydrostatic_tank.json" +
    " --set fluid.particle_spacing=0.04 --set time.duration=0.1 --set time.frame_rate=0";

// Each row is its run's summary.json, the run that cannot start (a cloth mesh file that is not there) is a
// row with its error, and the closed tank neither gains energy nor loses more than the settling costs.
TEST(SweepCommand, EveryRunIsARowWithItsSummarysFiguresFailuresIncluded) {
  const drench::test::TempDir dir;
  const int status = drench::test::run_drench(
      "sweep " + kTank + " --vary time.dt=0.0025,0.01 --case 'no cloth file:cloth.mesh=\"absent.obj\"'" +
          " --out " + (dir.path() / "sweep").string(),
      dir.path() / "log.txt");
  EXPECT_EQ(status, 2) << "a sweep with a failed run exits 2\n"
                       << drench::test::read_text(dir.path() / "log.txt");
  const auto rows = drench::test::read_csv_rows(dir.path() / "sweep/sweep.csv");
  ASSERT_EQ(rows.size(), 3u) << drench::test::read_text(dir.path() / "log.txt");
  for (int i = 0; i < 2; ++i) {
    const auto& row = rows[i];
    EXPECT_EQ(row.at("status"), "ok");
    const nlohmann::json summary = nlohmann::json::parse(
        drench::test::read_text(dir.path() / "sweep/runs" / ("00" + std::to_string(i + 1)) / "summary.json"));
    EXPECT_NEAR(std::stod(row.at("density_error_mean")), summary["density_error"]["mean"].get<double>(),
                1e-5 * summary["density_error"]["mean"].get<double>());
    EXPECT_EQ(std::stod(row.at("steps")), summary["steps"].get<double>());
    EXPECT_EQ(std::stod(row.at("time.dt")), i == 0 ? 0.0025 : 0.01);
    // A tank of water at rest only settles: it must not gain energy, and settling by a few tenths of a
    // spacing costs a few percent of its potential energy at most.
    const double drift = std::stod(row.at("energy_drift"));
    EXPECT_LT(drift, 1e-3) << row.at("setting");
    EXPECT_GT(drift, -0.05) << row.at("setting");
    EXPECT_TRUE(row.at("leaks").empty()) << "the tank has no cloth and no leak audit";
  }
  EXPECT_EQ(rows[2].at("setting"), "no cloth file");
  EXPECT_NE(rows[2].at("status").find("absent.obj"), std::string::npos) << rows[2].at("status");
  EXPECT_TRUE(rows[2].at("wall_s").empty());
  const std::string report = drench::test::read_text(dir.path() / "sweep/report.md");
  EXPECT_NE(report.find("1 runs did not end \"ok\""), std::string::npos) << report;
  EXPECT_TRUE(fs::exists(dir.path() / "sweep/pareto.png")) << "gnuplot is in scripts/setup";
}

// A run that would take minutes is stopped at --timeout and is a row that says so; the sweep goes on.
TEST(SweepCommand, ARunPastTheTimeoutIsStoppedAndIsARow) {
  const drench::test::TempDir dir;
  const auto start = std::chrono::steady_clock::now();
  const int status =
      drench::test::run_drench("sweep " + kTank + " --vary time.duration=0.02,600 --timeout 2 --out " +
                                   (dir.path() / "sweep").string(),
                               dir.path() / "log.txt");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(status, 2) << drench::test::read_text(dir.path() / "log.txt");
  EXPECT_LT(seconds, 60.0) << "the 600 s run was not stopped";
  const auto rows = drench::test::read_csv_rows(dir.path() / "sweep/sweep.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("status"), "ok");
  EXPECT_NE(rows[1].at("status").find("timed out"), std::string::npos) << rows[1].at("status");
}

// A run that ends "ok" yet goes faster than the scene's speed bound (--speed-bound) is drawn apart and kept
// off the Pareto front, its row unchanged (issue 42). The dam break made coarse (10 cm particles, 0.3 s):
// under the scene's gravity its fastest particle reaches 7.3 m/s, under 1 m/s^2 0.70 m/s (measured); the
// bound, 3 m/s, lies between them by a factor of two and more either way.
TEST(SweepCommand, ARunFasterThanTheSpeedBoundIsOffTheFront) {
  const drench::test::TempDir dir;
  const std::string dam = std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/dam_break.json" +
                          " --set fluid.particle_spacing=0.1 --set time.duration=0.3 --set time.frame_rate=0";
  const fs::path out = dir.path() / "sweep";
  ASSERT_EQ(drench::test::run_drench("sweep " + dam + " --one-at-a-time --vary 'gravity=[0,-1,0]'" +
                                         " --speed-bound 3 --threads 1 --out " + out.string(),
                                     dir.path() / "log.txt"),
            0)
      << "a run too fast still ends ok\n"
      << drench::test::read_text(dir.path() / "log.txt");
  const auto rows = drench::test::read_csv_rows(out / "sweep.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("status"), "ok");
  EXPECT_GT(std::stod(rows[0].at("max_particle_speed_mps")), 3.0) << "the scene's gravity";
  EXPECT_LT(std::stod(rows[1].at("max_particle_speed_mps")), 3.0) << "1 m/s^2";
  const std::string front = drench::test::read_text(out / "pareto_front.dat");
  const std::string apart = drench::test::read_text(out / "pareto_apart.dat");
  EXPECT_EQ(front.find("scene"), std::string::npos) << front;
  EXPECT_NE(apart.find("scene (faster than 3 m/s)"), std::string::npos) << apart;
  EXPECT_NE(front.find("gravity"), std::string::npos) << front;
  const std::string report = drench::test::read_text(out / "report.md");
  EXPECT_NE(report.find("ok, faster than 3 m/s"), std::string::npos) << report;
}

TEST(SweepCommand, ABadSettingFailsBeforeAnyRunAndWritesNothing) {
  const drench::test::TempDir dir;
  const fs::path out = dir.path() / "sweep";
  EXPECT_EQ(drench::test::run_drench("sweep " + kTank + " --vary time.dt=0.001,-1 --out " + out.string(),
                                     dir.path() / "log.txt"),
            1);
  EXPECT_NE(drench::test::read_text(dir.path() / "log.txt").find("time.dt"), std::string::npos)
      << drench::test::read_text(dir.path() / "log.txt");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(
      drench::test::run_drench("sweep " + kTank + " --vary time.dt=0.001 --error speed --out " + out.string(),
                               dir.path() / "log.txt"),
      1);
  EXPECT_NE(drench::test::read_text(dir.path() / "log.txt").find("density_error_mean"), std::string::npos)
      << "the error lists the columns: " << drench::test::read_text(dir.path() / "log.txt");
  EXPECT_FALSE(fs::exists(out));
}

// Too many runs are refused at once (--repeat 1e9 was never refused), and runs side by side that do not fit
// the memory say it is each run's share (--jobs 1024 blamed the emitter alone).
TEST(SweepCommand, TooManyRunsOrJobsAreRefusedAtOnceNamingWhy) {
  const drench::test::TempDir dir;
  const fs::path out = dir.path() / "sweep";
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(drench::test::run_drench(
                "sweep " + kTank + " --vary time.dt=0.001 --repeat 1000000000 --out " + out.string(),
                dir.path() / "log.txt"),
            1);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  const std::string repeat = drench::test::read_text(dir.path() / "log.txt");
  EXPECT_NE(repeat.find("sweep: 1000000000 runs"), std::string::npos) << repeat;
  EXPECT_FALSE(fs::exists(out));
  // The dam break at 2 cm (125,000 particles, about 1 GB) needs more than MemAvailable / 1024 below 1 TB.
  EXPECT_EQ(
      drench::test::run_drench("sweep " + std::string(DRENCH_SOURCE_DIR) +
                                   "/demos/scenes/dam_break.json --set fluid.particle_spacing=0.02 --vary "
                                   "time.dt=0.001 --jobs 1024 --out " +
                                   out.string(),
                               dir.path() / "log.txt"),
      1);
  const std::string jobs = drench::test::read_text(dir.path() / "log.txt");
  EXPECT_NE(jobs.find("available to each of --jobs 1024 runs (MemAvailable / 1024)"), std::string::npos)
      << jobs;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
