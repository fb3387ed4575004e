// `drench reference` and `drench sweep --reference` as a user runs them (issue 42), on the jet on a cloth
// made small: 1 cm particles (793 by 0.2 s), a 15 x 15 cloth of 0.3 m, 0.2 s, frames at 50 per second (every
// 20 ms is a whole number of steps of 0.5, 1, 2 and 4 ms and of the reference's 0.125 ms). The reference
// takes about 8 s, each run under 1 s on one thread.
#include <gtest/gtest.h>

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

const std::string kScene = std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/jet_on_cloth.json";
// The scene's bound on the cloth's stretch is 30%: a fabric stretched further is broken, whatever its error
// over the frames before it stopped. The sound runs stretch by 4% (dt 0.5 ms) to 21% (dt 2 ms); one cloth
// sub-step stretches it by about 50%.
const std::string kSmallJet =
    " --set fluid.particle_spacing=0.01 --set emitters[0].max_particles=3000 --set cloth.nodes=[15,15]"
    " --set cloth.size=[0.3,0.3] --set time.duration=0.2 --set time.frame_rate=50 --set cloth.max_strain=0.3"
    " --threads 1";

const std::map<std::string, std::string>& row_of(const std::vector<std::map<std::string, std::string>>& rows,
                                                 const std::string& setting) {
  for (const auto& row : rows)
    if (row.at("setting") == setting) return row;
  throw std::runtime_error("no row " + setting);
}

// One reference, then a sweep against it: a finer dt is closer to the reference in the cloth's RMS node
// distance; one cloth sub-step overstretches the cloth, stops, is drawn apart and is never on the front; and
// the density error stays a column, though it says nothing of this order.
TEST(SweepReference, AFinerStepIsCloserAndABrokenSettingIsOffTheFront) {
  const drench::test::TempDir dir;
  const fs::path reference = dir.path() / "reference";
  ASSERT_EQ(
      drench::test::run_drench("reference " + kScene + kSmallJet + " --quiet --out " + reference.string(),
                               dir.path() / "reference.log"),
      0)
      << drench::test::read_text(dir.path() / "reference.log");
  const nlohmann::json record = nlohmann::json::parse(drench::test::read_text(reference / "reference.json"));
  const nlohmann::json summary = nlohmann::json::parse(drench::test::read_text(reference / "summary.json"));
  EXPECT_EQ(record["run_scene_sha256"], summary["scene_sha256"])
      << "the reference's run is the refined scene";
  EXPECT_DOUBLE_EQ(summary["dt_s"]["max"].get<double>(), 0.001 / 8);

  const fs::path sweep = dir.path() / "sweep";
  const int status = drench::test::run_drench(
      "sweep " + kScene + kSmallJet +
          " --one-at-a-time --vary time.dt=0.0005,0.002 --vary cloth.substeps=1 --reference " +
          reference.string() + " --out " + sweep.string(),
      dir.path() / "sweep.log");
  EXPECT_EQ(status, 2) << "one run is not ok\n" << drench::test::read_text(dir.path() / "sweep.log");
  const auto rows = drench::test::read_csv_rows(sweep / "sweep.csv");
  ASSERT_EQ(rows.size(), 4u) << drench::test::read_text(dir.path() / "sweep.log");
  const double fine = std::stod(row_of(rows, "time.dt=0.0005").at("cloth_rms_m"));
  const double scene = std::stod(row_of(rows, "scene").at("cloth_rms_m"));
  const double coarse = std::stod(row_of(rows, "time.dt=0.002").at("cloth_rms_m"));
  // Measured: 11.6, 17.7 and 30.9 mm, each halving of dt 1.5 to 1.75 times closer.
  EXPECT_LT(fine, scene) << "dt 0.5 ms against 1 ms";
  EXPECT_LT(scene, coarse) << "dt 1 ms against 2 ms";
  for (const char* setting : {"scene", "time.dt=0.0005", "time.dt=0.002"}) {
    EXPECT_EQ(row_of(rows, setting).at("status"), "ok") << setting;
    EXPECT_FALSE(row_of(rows, setting).at("density_error_mean").empty()) << "the solver's residual stays";
    EXPECT_FALSE(row_of(rows, setting).at("mass_l1_kg").empty()) << setting;
    EXPECT_TRUE(row_of(rows, setting).at("front_m").empty()) << "a front only without a cloth";
  }

  const auto& broken = row_of(rows, "cloth.substeps=1");
  EXPECT_NE(broken.at("status").find("CLOTH_OVERSTRETCHED"), std::string::npos) << broken.at("status");
  EXPECT_FALSE(broken.at("cloth_rms_m").empty()) << "compared over the frames it has";
  const std::string front = drench::test::read_text(sweep / "pareto_front.dat");
  const std::string apart = drench::test::read_text(sweep / "pareto_apart.dat");
  EXPECT_EQ(front.find("cloth.substeps=1"), std::string::npos) << front;
  EXPECT_NE(apart.find("cloth.substeps=1 (CLOTH_OVERSTRETCHED)"), std::string::npos) << apart;
  EXPECT_NE(front.find("time.dt=0.0005"), std::string::npos) << "the most accurate sound setting\n" << front;
  const nlohmann::json comparison =
      nlohmann::json::parse(drench::test::read_text(sweep / "runs/001.comparison.json"));
  EXPECT_EQ(comparison["frames"], 11) << "0.2 s at 50 frames/s, frame 0 included";
  const std::string report = drench::test::read_text(sweep / "report.md");
  EXPECT_NE(report.find("pressure solver's residual"), std::string::npos) << report;
}

// Mistakes found before any run: a reference of another scene, and a setting whose frames would fall between
// the reference's (dt 3 ms: the frame at 20 ms would be written at 21 ms).
TEST(SweepReference, AReferenceOfAnotherSceneOrOtherFrameTimesIsRefused) {
  const drench::test::TempDir dir;
  const fs::path reference = dir.path() / "reference";
  // A reference too short to be worth anything, and cheap: its frames' times are all the check needs.
  const std::string tiny = kSmallJet + " --set time.duration=0.02";
  ASSERT_EQ(drench::test::run_drench("reference " + kScene + tiny + " --quiet --out " + reference.string(),
                                     dir.path() / "reference.log"),
            0)
      << drench::test::read_text(dir.path() / "reference.log");
  const fs::path out = dir.path() / "sweep";
  EXPECT_EQ(
      drench::test::run_drench("sweep " + kScene + tiny + " --set cloth.substeps=2 --vary time.dt=0.002" +
                                   " --reference " + reference.string() + " --out " + out.string(),
                               dir.path() / "log.txt"),
      1);
  EXPECT_NE(drench::test::read_text(dir.path() / "log.txt").find("scene_sha256"), std::string::npos)
      << drench::test::read_text(dir.path() / "log.txt");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(drench::test::run_drench("sweep " + kScene + tiny + " --vary time.dt=0.003 --reference " +
                                         reference.string() + " --out " + out.string(),
                                     dir.path() / "log.txt"),
            1);
  const std::string log = drench::test::read_text(dir.path() / "log.txt");
  EXPECT_NE(log.find("time.dt=0.003"), std::string::npos) << log;
  EXPECT_NE(log.find("time.frame_rate"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(drench::test::run_drench("sweep " + kScene + tiny + " --vary time.dt=0.002 --reference " +
                                         (dir.path() / "nothing").string() + " --out " + out.string(),
                                     dir.path() / "log.txt"),
            1);
  EXPECT_NE(drench::test::read_text(dir.path() / "log.txt").find("reference.json"), std::string::npos)
      << drench::test::read_text(dir.path() / "log.txt");

  // What the reference cannot measure is refused before any run: the surge front of a run with a cloth, a
  // gauge without a reference, a gauge at NaN, cells smaller than a particle.
  const auto refused = [&](const std::string& extra, const std::string& expected) {
    const int status = drench::test::run_drench(
        "sweep " + kScene + tiny + " --vary time.dt=0.002 --out " + out.string() + " " + extra,
        dir.path() / "log.txt");
    const std::string text = drench::test::read_text(dir.path() / "log.txt");
    EXPECT_EQ(status, 1) << extra << ": " << text;
    EXPECT_NE(text.find(expected), std::string::npos) << extra << ": " << text;
    EXPECT_FALSE(fs::exists(out)) << extra;
  };
  const std::string with_reference = "--reference " + reference.string();
  refused(with_reference + " --error front_m", "--error front_m: the reference " + reference.string() +
                                                   " has a cloth and there is no --gauge, so the sweep "
                                                   "measures only cloth_rms_m");
  refused("--gauge 0.5", "--gauge measures the runs against a reference: it needs --reference");
  refused(with_reference + " --gauge nan", "--gauge) must be in [-10000000, 10000000] m, got nan");
  refused(with_reference + " --cell-size 1e-12", "(drench sweep --cell-size) must be 0");

  // A damaged reference frame was found only once every run had finished.
  const fs::path last = reference / "frames/fluid_0001.ply";
  ASSERT_TRUE(fs::exists(last));
  fs::resize_file(last, fs::file_size(last) / 2);
  refused(with_reference, last.string() + ": truncated");
}

}  // namespace
