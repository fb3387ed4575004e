// Hostile input and hard cases (issue 39): physics. A run that leaked or blew up never ends as "ok" with exit
// 0, and the crumpled cloth of the issue, reduced to what CI can run with the same geometry, does not leak.
// Each case runs the drench command as a user does and reads its summary.json.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/scene/simulation.hpp>

#include "../drench_command.hpp"
#include "../temp_dir.hpp"

namespace {

namespace fs = std::filesystem;

std::string scene(const std::string& name) {
  return std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/" + name;
}

/// A drench run's exit code, its log and its summary.json.
struct TankRun {
  int code = 0;
  std::string log;
  nlohmann::json summary;
};

/// The hydrostatic tank run for 5 steps of 0.2 s with `solver`, one thread, in `dir`.
TankRun tank_at_a_fifth_of_a_second(const std::string& solver, const drench::test::TempDir& dir) {
  const fs::path out = dir.path() / "run";
  TankRun run;
  run.code = drench::test::run_drench("run " + scene("hydrostatic_tank.json") + " --out " + out.string() +
                                          " --quiet --threads 1 --steps 5 --set time.dt=0.2 --set "
                                          "fluid.pressure_solver=" +
                                          solver,
                                      dir.path() / "log");
  run.log = drench::test::read_text(dir.path() / "log");
  run.summary = nlohmann::json::parse(drench::test::read_text(out / "summary.json"));
  return run;
}

// The jet at 40 m/s on the default cloth at dt 4 ms tore the cloth (edges 34 times their length, nodes at
// 138 m/s) and ended "ok" with exit 0. Now the cloth's checks stop it within the first steps the jet reaches
// the cloth, with exit 2 and a status naming the node or edge.
TEST(HostilePhysics, A40MetrePerSecondJetThatTearsTheClothStopsWithExit2) {
  drench::test::TempDir dir;
  const fs::path out = dir.path() / "run";
  const int code = drench::test::run_drench(
      "run " + scene("jet_on_cloth.json") + " --out " + out.string() +
          " --quiet --threads 1 --set 'emitters[0].speed=40' --set time.dt=0.004 --set time.duration=0.2",
      dir.path() / "log");
  const std::string log = drench::test::read_text(dir.path() / "log");
  EXPECT_EQ(code, 2) << log;
  const nlohmann::json summary = nlohmann::json::parse(drench::test::read_text(out / "summary.json"));
  const std::string status = summary["status"];
  EXPECT_TRUE(status.find("RUNAWAY_NODE: cloth node ") != std::string::npos ||
              status.find("CLOTH_OVERSTRETCHED: the cloth edge between nodes ") != std::string::npos)
      << status;
  // Stopped when it blew up, not after the 50 steps asked for.
  EXPECT_LT(summary["steps"].get<int>(), 50) << status;
  EXPECT_NE(log.find("drench: simulation stopped: "), std::string::npos) << log;
}

// A step far too large for the pressure solve packs the water flat: the hydrostatic tank at dt 0.2 s ended
// "ok" with exit 0 and a mean density error of 612%, every particle on the floor. PBF, whose sub-steps are
// fixed, now stops at the sub-step where more than half of the particles are packed past twice the rest
// density, with exit 2 and a status that says so.
TEST(HostilePhysics, AStepTooLargeForThePressureSolveStopsAsCollapsedWithExit2) {
  const drench::test::TempDir dir;
  const TankRun run = tank_at_a_fifth_of_a_second("pbf", dir);
  EXPECT_EQ(run.code, 2) << run.log;
  const nlohmann::json& summary = run.summary;
  const std::string status = summary["status"];
  EXPECT_EQ(status.rfind("FLUID_COLLAPSED: ", 0), 0u) << status;
  EXPECT_NE(status.find(" of 6000 particles packed past twice the rest density"), std::string::npos)
      << status;
  EXPECT_LT(summary["steps"].get<int>(), 5) << "stopped where it collapsed";
  EXPECT_GT(summary["density_error"]["max"].get<double>(), 1.0) << "denser than 2 rho0 on average";
}

// The same step with PCISPH and DFSPH: their CFL limit counts the tank's surface waves (FluidSettings::cfl),
// so the 0.2 s steps are cut into sub-steps the solves hold, as WCSPH's speed of sound cuts them; taken
// whole, PCISPH packs the tank flat and DFSPH becomes non-finite.
TEST(HostilePhysics, AStepTooLargeForThePressureSolveIsSubsteppedByPcisphAndDfsph) {
  for (const std::string solver : {"pcisph", "dfsph"}) {
    const drench::test::TempDir dir;
    const TankRun run = tank_at_a_fifth_of_a_second(solver, dir);
    EXPECT_EQ(run.code, 0) << solver << ": " << run.log;
    const nlohmann::json& summary = run.summary;
    // PCISPH may spend its max_iterations in a sub-step (PRESSURE_NOT_CONVERGED, which does not stop a
    // run); nothing collapsed, blew up or became non-finite.
    const std::string status = summary["status"];
    EXPECT_TRUE(status == "ok" || status.rfind("PRESSURE_NOT_CONVERGED: ", 0) == 0)
        << solver << ": " << status;
    EXPECT_EQ(summary["steps"].get<int>(), 5) << solver;
    EXPECT_GT(summary["fluid_substeps"]["max_per_step"].get<int>(), 1) << solver << ": sub-stepped";
    // Each sub-step's mean density error, at most 0.1% (PCISPH's eta) or 0.05% (DFSPH's), with margin.
    EXPECT_LT(summary["density_error"]["max"].get<double>(), 0.01) << solver;
  }
}

// Fig. 4's scene, repulsion only at dt 4 ms, lets particles through the cloth (the paper's point). The run
// goes to its end, but it says LEAKED, names the first particle and face, counts the leaks and exits 2.
TEST(HostilePhysics, ARunThatLeakedEndsWithExit2AndNamesTheParticle) {
  drench::test::TempDir dir;
  const fs::path out = dir.path() / "run";
  const int code =
      drench::test::run_drench("run " + scene("leak_comparison.json") + " --out " + out.string() +
                                   " --quiet --threads 1 --set time.dt=0.004 --set time.frame_rate=0",
                               dir.path() / "log");
  const std::string log = drench::test::read_text(dir.path() / "log");
  EXPECT_EQ(code, 2) << log;
  const nlohmann::json summary = nlohmann::json::parse(drench::test::read_text(out / "summary.json"));
  EXPECT_GT(summary["leaks"].get<int>(), 0);
  const std::string status = summary["status"];
  EXPECT_EQ(status.rfind("LEAKED: particle id ", 0), 0u) << status;
  EXPECT_NE(status.find(" crossed face "), std::string::npos) << status;
  EXPECT_EQ(summary["steps"].get<int>(), 38) << "a leak does not stop the run: 0.15 s in steps of 4 ms";
  EXPECT_NE(log.find("drench: simulation failed: LEAKED"), std::string::npos) << log;
}

// The crumpled cloth: a cloth held at one corner with no bending stiffness folds under a jet, and
// at dt 4 ms particles caught between its layers leaked (77 leaks, 88 fail-safe activations in 1 s) while
// the run said "ok". The same cloth for CI: 0.35 s of a jet of 3,000 particles, by when its folds have
// needed the fail-safe and the last resort (docs/accuracy.md runs the whole scene). No leak, and an "ok"
// that is true.
TEST(HostilePhysics, ACrumpledClothAtDt4msDoesNotLeak) {
  drench::test::TempDir dir;
  const fs::path out = dir.path() / "run";
  const int code = drench::test::run_drench(
      "run " + scene("crumpled_cloth.json") + " --out " + out.string() +
          " --quiet --threads 1 --set time.dt=0.004 --set time.duration=0.35 --set time.frame_rate=0"
          " --set 'emitters[0].max_particles=3000'",
      dir.path() / "log");
  const std::string log = drench::test::read_text(dir.path() / "log");
  const nlohmann::json summary = nlohmann::json::parse(drench::test::read_text(out / "summary.json"));
  EXPECT_EQ(summary["leaks"].get<int>(), 0) << log;
  EXPECT_EQ(summary["status"], "ok") << log;
  EXPECT_EQ(code, 0) << log;
  EXPECT_GT(summary["failsafe_activations"].get<int>(), 0) << "the folds must need the fail-safe";
  EXPECT_GT(summary["stopped_particles"].get<int>(), 0) << "and the last resort: else this tests neither";
}

// An unpinned cloth carrying water fell straight through the scene's V (the water stayed in the V): the
// obstacles held the water but not the cloth. Now the cloth's nodes are coupled with the obstacles' faces as
// the particles are. A 0.2 m cloth with a puddle of 192 particles dropped 0.2 m into the V of Fig. 8 (90
// degrees) must land on it and no node may pass its surface over 0.4 s; a node may be within the cloth
// thickness (1 mm) of it, and the V's flat faces are exact up to rounding.
TEST(HostilePhysics, AnUnpinnedClothLandsOnTheSceneObstaclesInsteadOfFallingThrough) {
  using namespace drench;
  SceneConfig c;
  c.fluid.particle_spacing = 0.01;
  EmitterSettings puddle;
  puddle.kind = EmitterSettings::Kind::BOX;
  puddle.box.min = Vec3(-0.04, 0.21, -0.04);
  puddle.box.max = Vec3(0.04, 0.24, 0.04);
  c.emitters.push_back(puddle);
  ClothSettings cloth;
  cloth.center = Vec3(0, 0.2, 0);
  cloth.size_x = cloth.size_z = 0.2;
  cloth.nodes_x = cloth.nodes_z = 11;
  cloth.pinned = "none";
  c.cloth = cloth;
  ObstacleSettings v;  // apex at the origin, 90 degrees, arms 0.25 m, 0.3 m wide
  c.obstacles.push_back(v);
  c.time.dt = 0.002;
  c.time.duration = 0.4;
  c.effects = {"coupling", "leak_audit"};
  Simulation sim(c, bullet::cloth_engine_factory());
  const double half_span = v.size * std::sin(0.25 * 3.141592653589793);
  double lowest = 1.0;
  while (!sim.finished()) {
    const StepStatus status = sim.step();
    ASSERT_TRUE(status.ok()) << status.describe();
    for (const Vec3& x : sim.cloth()->mesh().positions_t1) {
      lowest = std::min(lowest, x.y());
      if (std::abs(x.x()) < half_span && std::abs(x.z()) < 0.5 * v.width) {
        ASSERT_GT(x.y(), std::abs(x.x()) - 1e-9) << "a cloth node went through the V at t = " << sim.time();
      }
    }
  }
  EXPECT_LT(lowest, 0.1) << "the cloth never fell onto the V: the test tests nothing";
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
}

}  // namespace
