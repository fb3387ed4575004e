// drench sweep's plan, rows and Pareto front (src/drench/scene/sweep.hpp); the command itself is run in
// tests/command/test_sweep_command.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>

#include <drench/common/error.hpp>
#include <drench/scene/sweep.hpp>
#include "../assertions.hpp"

namespace drench {
namespace {

const nlohmann::json kScene = nlohmann::json::parse(R"({
  "fluid": {"pressure_solver": "pcisph", "pcisph": {"eta": 0.001}},
  "time": {"dt": 0.001, "duration": 0.5},
  "effects": ["viscosity", "coupling"]
})");

TEST(Sweep, AxisValuesSplitAtCommasOutsideJson) {
  const SweepAxis axis = parse_sweep_axis(R"(effects=["a","b"],[],["c,d"])");
  EXPECT_EQ(axis.key, "effects");
  ASSERT_EQ(axis.values.size(), 3u);
  EXPECT_EQ(axis.values[0], R"(["a","b"])");
  EXPECT_EQ(axis.values[1], "[]");
  EXPECT_EQ(axis.values[2], R"(["c,d"])");
  EXPECT_EQ(parse_sweep_axis("time.dt=0.001,0.002").values, (std::vector<std::string>{"0.001", "0.002"}));
}

TEST(Sweep, MalformedAxesAndCasesNameTheArgument) {
  for (const char* bad : {"time.dt", "=1,2", "time.dt=1,,2", "effects=[\"a\"", "effects=\"a"}) {
    try {
      parse_sweep_axis(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("--vary ") + bad), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(parse_sweep_case("no label"), SceneError);
  EXPECT_THROW(parse_sweep_case(":time.dt=1"), SceneError);
  EXPECT_THROW(parse_sweep_case("x:time.dt"), SceneError);
  const SweepCase c = parse_sweep_case(R"(no-slip:coupling.slip="no_slip";effects=["a";"b"])");
  EXPECT_EQ(c.label, "no-slip");
  EXPECT_EQ(c.assignments, (std::vector<std::string>{R"(coupling.slip="no_slip")", R"(effects=["a";"b"])"}));
}

TEST(Sweep, TheGridHasEveryCombinationOnceAndTheCasesAfter) {
  const std::vector<SweepAxis> axes = {parse_sweep_axis("time.dt=0.001,0.002,0.004"),
                                       parse_sweep_axis(R"(fluid.pressure_solver="wcsph","pcisph")")};
  const std::vector<SweepRun> runs =
      plan_sweep(kScene, axes, {parse_sweep_case("thick:coupling.cloth_thickness=0.005")}, false, 2);
  ASSERT_EQ(runs.size(), 2u * (3 * 2 + 1));
  std::set<std::string> labels;
  for (std::size_t i = 0; i < runs.size(); i += 2) {
    EXPECT_EQ(runs[i].label, runs[i + 1].label);
    EXPECT_EQ(runs[i].repeat, 0);
    EXPECT_EQ(runs[i + 1].repeat, 1);
    labels.insert(runs[i].label);
  }
  EXPECT_EQ(labels.size(), 7u);
  EXPECT_EQ(runs[0].assignments,
            (std::vector<std::string>{"time.dt=0.001", R"(fluid.pressure_solver="wcsph")"}));
  EXPECT_EQ(runs.back().label, "thick");
}

TEST(Sweep, OneAtATimeVariesEachKeyAloneAndSkipsTheScenesOwnValue) {
  const std::vector<SweepAxis> axes = {parse_sweep_axis("time.dt=0.001,0.002,0.004"),
                                       parse_sweep_axis("fluid.pcisph.eta=0.01,0.001,0.03")};
  const std::vector<SweepRun> runs = plan_sweep(kScene, axes, {}, true, 1);
  std::vector<std::string> labels;
  for (const SweepRun& r : runs)
    labels.push_back(r.label);
  EXPECT_EQ(labels, (std::vector<std::string>{"scene", "time.dt=0.002", "time.dt=0.004",
                                              "fluid.pcisph.eta=0.01", "fluid.pcisph.eta=0.03"}));
  for (const SweepRun& r : runs)
    EXPECT_LE(r.assignments.size(), 1u);
}

TEST(Sweep, AnAssignmentThatCannotApplyFailsThePlan) {
  EXPECT_THROW(plan_sweep(kScene, {parse_sweep_axis("effects[5]=1")}, {}, true, 1), SceneError);
  EXPECT_THROW(plan_sweep(kScene, {}, {}, false, 0), SceneError);
}

TEST(Sweep, MoreThan10000RunsAreRefusedBeforeAnyIsPlanned) {
  // --repeat 1e9 was never refused (its billion runs were being built), and a 99 x 99 x 100 grid took 28 s
  // to refuse: both are counted first, so the refusal comes at once.
  const auto values = [](int n) {
    std::string list;
    for (int i = 0; i < n; ++i)
      list += (i ? "," : "") + std::to_string(i + 1);
    return list;
  };
  const std::vector<SweepAxis> grid = {parse_sweep_axis("fluid.sort_interval=" + values(99)),
                                       parse_sweep_axis("fluid.pcisph.max_iterations=" + values(99)),
                                       parse_sweep_axis("fluid.pcisph.min_iterations=" + values(100))};
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(test::throws_containing<SceneError>([&] { plan_sweep(kScene, grid, {}, false, 1); },
                                                  {"sweep: 980100 runs", "at most 10000"}));
  EXPECT_TRUE(test::throws_containing<SceneError>([&] { plan_sweep(kScene, {}, {}, false, 1000000000); },
                                                  {"sweep: 1000000000 runs", "--repeat 1000000000"}));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
  // One at a time the axes add up: 1 + 99 + 99 + 100 settings x 33 repeats is 9,867 runs, within the bound.
  EXPECT_EQ(plan_sweep(kScene, grid, {}, true, 33).size() % 33, 0u);
  EXPECT_EQ(plan_sweep(kScene, {grid[0], grid[1]}, {}, false, 1).size(), 9801u);
}

// Two --vary of one key ran once, and two cases of one label ran under one name.
TEST(Sweep, ASettingGivenTwiceIsRefusedNamingIt) {
  const auto refused = [](const std::vector<SweepAxis>& axes, const std::vector<SweepCase>& cases,
                          const std::string& expected) {
    return test::throws_containing<SceneError>([&] { plan_sweep(kScene, axes, cases, false, 1); },
                                               {expected});
  };
  EXPECT_TRUE(refused({parse_sweep_axis("time.dt=0.001"), parse_sweep_axis("time.dt=0.002")}, {},
                      "--vary time.dt is given twice"));
  EXPECT_TRUE(
      refused({parse_sweep_axis("time.dt=0.001,1e-3")}, {}, "--vary time.dt: the value 1e-3 is given twice"));
  EXPECT_TRUE(refused({}, {parse_sweep_case("a:time.dt=0.001"), parse_sweep_case("a:time.dt=0.002")},
                      "--case a is given twice"));
  EXPECT_TRUE(
      refused({}, {parse_sweep_case("a:time.dt=0.001;time.dt=0.002")}, "--case a: time.dt is set twice"));
  EXPECT_EQ(plan_sweep(kScene, {parse_sweep_axis("time.dt=0.001,0.002")},
                       {parse_sweep_case("a:time.dt=0.003")}, false, 1)
                .size(),
            3u);
}

TEST(Sweep, RowsTakeTheSummarysFiguresAndKeepFailures) {
  const nlohmann::json summary = nlohmann::json::parse(R"({
    "status": "ok", "wall_s": 2.5, "timings_s": {"fluid": 1.25, "coupling": 0.5},
    "leaks": 0, "density_error": {"mean": 0.0001, "max": 0.002}, "max_speed_mps": {"particle": 3.5}
  })");
  const std::vector<std::string>& columns = sweep_columns();
  const std::vector<std::string> row = sweep_row(&summary, "");
  ASSERT_EQ(row.size(), columns.size());
  auto at = [&](const std::string& column) {
    return row[static_cast<std::size_t>(std::find(columns.begin(), columns.end(), column) - columns.begin())];
  };
  EXPECT_EQ(at("status"), "ok");
  EXPECT_DOUBLE_EQ(sweep_number(at("wall_s")), 2.5);
  EXPECT_DOUBLE_EQ(sweep_number(at("coupling_s")), 0.5);
  EXPECT_DOUBLE_EQ(sweep_number(at("density_error_max")), 0.002);
  EXPECT_DOUBLE_EQ(sweep_number(at("max_particle_speed_mps")), 3.5);
  EXPECT_EQ(at("leaks"), "0");
  EXPECT_EQ(at("cloth_s"), "") << "a figure the run does not have is empty, not 0";
  EXPECT_TRUE(std::isnan(sweep_number(at("surface_intersections"))));

  const std::vector<std::string> died = sweep_row(nullptr, "killed by signal 9");
  ASSERT_EQ(died.size(), columns.size());
  EXPECT_EQ(died[0], "killed by signal 9");
  const nlohmann::json blown = {{"status", "NON_FINITE_STATE: particle id 7"}, {"wall_s", 1.0}};
  EXPECT_EQ(sweep_row(&blown, "")[0], "NON_FINITE_STATE: particle id 7");
}

TEST(Sweep, TheParetoFrontHoldsExactlyTheUnbeatenPoints) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // (time, error): 1 beats 2; 0 is fastest; 3 is the most accurate; 4 ties 0 but is worse; 5 has no error.
  const std::vector<std::pair<double, double>> points = {{1.0, 0.5}, {2.0, 0.2}, {3.0, 0.3},
                                                         {5.0, 0.1}, {1.0, 0.7}, {0.5, nan}};
  EXPECT_EQ(pareto_front(points), (std::vector<std::size_t>{0, 1, 3}));
  // Every point off the front is beaten by one on it, on both coordinates.
  const std::vector<std::size_t> front = pareto_front(points);
  for (std::size_t i = 0; i < 5; ++i) {
    if (std::find(front.begin(), front.end(), i) != front.end()) continue;
    EXPECT_TRUE(std::any_of(front.begin(), front.end(), [&](std::size_t f) {
      return points[f].first <= points[i].first && points[f].second <= points[i].second;
    })) << i;
  }
}

}  // namespace
}  // namespace drench
