// The coupling's broad phase, grid against FCL side by side, and the whole Coupler::step, on a 57 x 57 node
// cloth patch 0.6 m square (6,272 triangles) at y = 0, the size the notes' measurements used
// (../shared/notes/bullet-and-fcl.md).
//
//   <build>/bench/bench_coupling --benchmark_out=bench/results/<machine>/coupling.csv
//       --benchmark_out_format=csv --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//       [--benchmark_filter=...]
// Thread count: OMP_NUM_THREADS (drench::thread_count()). On a shared machine, compare medians of
// repetitions.
//
// find_pairs/particles:<N>/margin_mm:<m>/<grid|fcl>: one TriangleBroadPhase::find_pairs call per iteration,
// the object kept across iterations as the coupler keeps it. N particles spread uniformly in a
// 0.6 x 0.02 x 0.6 m slab around the cloth, each moving 3 mm in a random direction; the cloth waves by up to
// 1 mm a step, and successive iterations alternate between two steps of that motion, so the boxes change.
// Margins 1, 2.5 and 5 mm. Before any benchmark, main checks that both broad phases return the same pairs.
//
// coupler_step/particles:15000/<grid|fcl>: one Coupler::step (default CouplingSettings but the broad phase)
// at dt = 1 ms per iteration, timed alone (the state is restored, untimed, before each). 14,700 particles
// rest about one cloth thickness above the cloth, moving down by g dt^2; 300 fall through it at 3 m/s. The
// cloth sags by g dt^2, pinned at its four corners.
//
// Time is wall time (real_time, ms per call). Counters: particles, triangles, threads; find_pairs: pairs (of
// the first of the two steps); coupler_step: contacts, ccd_impacts, ccd_iterations, failsafe, status,
// ms_repulsion, ms_ccd (the coupler's own stage times). A counter that does not apply to a row is nan.

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <drench/common/parallel.hpp>
#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/coupling_settings.hpp>

namespace {

using drench::BroadPhaseKind;
using drench::ClothMesh;
using drench::Index;
using drench::Vec3;
using drench::Vec3Array;

constexpr int kClothNodesPerSide = 57;
constexpr double kClothSize = 0.6;  // (unit: m)
constexpr double kGravity = 9.81;   // (unit: m/s^2)

ClothMesh patch(int n, double size, double inverse_mass) {
  return ClothMesh::grid(n, size, 0.0, inverse_mass);
}

/// Height of the waving cloth at step k (unit: m): a travelling wave of 1 mm amplitude.
double wave(const Vec3& x, int k) {
  return 0.001 * std::sin(20.0 * x.x() + 15.0 * x.z() + 0.3 * k);
}

/// One broad-phase input: particles and cloth at the start and end of a step.
struct BroadPhaseCase {
  Vec3Array x0, x1;
  ClothMesh cloth;
};

/// Two successive steps of the slab case with `particles` particles (deterministic).
std::vector<BroadPhaseCase> slab_case(std::size_t particles) {
  std::mt19937_64 rng(2013);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Vec3Array x0(particles), direction(particles);
  for (std::size_t p = 0; p < particles; ++p) {
    x0[p] = Vec3(kClothSize * u(rng), 0.02 * u(rng) - 0.01, kClothSize * u(rng));
    direction[p] = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
  }
  const ClothMesh flat = patch(kClothNodesPerSide, kClothSize, 1.0);
  std::vector<BroadPhaseCase> steps(2);
  for (int k = 0; k < 2; ++k) {
    BroadPhaseCase& s = steps[static_cast<std::size_t>(k)];
    s.cloth = flat;
    for (std::size_t v = 0; v < flat.node_count(); ++v) {
      s.cloth.positions_t0[v].y() = wave(flat.positions_t0[v], k);
      s.cloth.positions_t1[v].y() = wave(flat.positions_t0[v], k + 1);
    }
    s.x0.resize(particles);
    s.x1.resize(particles);
    for (std::size_t p = 0; p < particles; ++p) {
      s.x0[p] = x0[p] + k * 0.003 * direction[p];
      s.x1[p] = s.x0[p] + 0.003 * direction[p];
    }
  }
  return steps;
}

/// Google Benchmark's CSV reporter needs every counter in every row: those that do not apply are NaN.
void add_missing_counters(benchmark::State& state) {
  for (const char* name : {"particles", "triangles", "threads", "pairs", "contacts", "ccd_impacts",
                           "ccd_iterations", "failsafe", "status", "ms_repulsion", "ms_ccd"}) {
    if (state.counters.find(name) == state.counters.end())
      state.counters[name] = std::numeric_limits<double>::quiet_NaN();
  }
}

const char* kind_name(BroadPhaseKind kind) {
  return kind == BroadPhaseKind::FCL ? "fcl" : "grid";
}

void find_pairs(benchmark::State& state, const std::vector<BroadPhaseCase>& steps, BroadPhaseKind kind,
                double margin) {
  const std::unique_ptr<drench::TriangleBroadPhase> broad_phase = drench::make_broad_phase(kind);
  std::vector<std::pair<Index, Index>> pairs;
  std::vector<std::size_t> pair_counts(steps.size(), 0);  // of the last call on each step
  std::size_t k = 0;
  for (auto _ : state) {
    const std::size_t step = k++ % steps.size();
    broad_phase->find_pairs(steps[step].x0, steps[step].x1, steps[step].cloth, margin, nullptr, pairs);
    benchmark::DoNotOptimize(pairs.data());
    pair_counts[step] = pairs.size();
  }
  state.counters["particles"] = static_cast<double>(steps[0].x0.size());
  state.counters["triangles"] = static_cast<double>(steps[0].cloth.triangle_count());
  state.counters["pairs"] = static_cast<double>(pair_counts[0]);
  state.counters["threads"] = drench::thread_count();
  add_missing_counters(state);
}

/// The realistic coupling step: start state of particles and cloth.
struct StepCase {
  Vec3Array x0, x1, v;
  drench::ScalarArray m;
  ClothMesh cloth;
};

StepCase resting_layer_case(double dt, double thickness) {
  StepCase s;
  // Cloth: 0.1 kg over 57^2 nodes, pinned at the four corners, sagging by g dt^2 over the step.
  const double node_mass = 0.1 / (kClothNodesPerSide * kClothNodesPerSide);
  s.cloth = patch(kClothNodesPerSide, kClothSize, 1.0 / node_mass);
  const int n = kClothNodesPerSide;
  for (int corner : {0, n - 1, n * (n - 1), n * n - 1})
    s.cloth.inverse_masses[static_cast<std::size_t>(corner)] = 0.0;
  for (std::size_t v = 0; v < s.cloth.node_count(); ++v) {
    if (s.cloth.inverse_masses[v] > 0.0) s.cloth.positions_t1[v].y() -= kGravity * dt * dt;
  }
  // Particles: water of spacing 5 mm (m = 1000 kg/m^3 * (5 mm)^3), on a jittered 121 x 121 layout.
  std::mt19937_64 rng(2013);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double mass = 1000.0 * 0.005 * 0.005 * 0.005;
  const std::size_t resting = 14700, falling = 300;
  for (std::size_t p = 0; p < resting; ++p) {
    const double i = static_cast<double>(p % 121), j = static_cast<double>(p / 121);
    const Vec3 x(kClothSize * (i + 0.5 + 0.3 * u(rng)) / 121, thickness * (1.0 + 0.2 * u(rng)),
                 kClothSize * (j + 0.5 + 0.3 * u(rng)) / 121);
    const Vec3 velocity(0.0, -kGravity * dt, 0.0);
    s.x0.push_back(x);
    s.x1.push_back(x + velocity * dt);
    s.v.push_back(velocity);
    s.m.push_back(mass);
  }
  for (std::size_t p = 0; p < falling; ++p) {
    const Vec3 x(kClothSize * (0.5 + 0.45 * u(rng)), 0.002 + 0.001 * u(rng),
                 kClothSize * (0.5 + 0.45 * u(rng)));
    const Vec3 velocity(0.0, -3.0, 0.0);
    s.x0.push_back(x);
    s.x1.push_back(x + velocity * dt);
    s.v.push_back(velocity);
    s.m.push_back(mass);
  }
  return s;
}

void coupler_step(benchmark::State& state, BroadPhaseKind kind) {
  constexpr double dt = 0.001;
  drench::CouplingSettings settings;
  settings.broad_phase = kind;
  drench::Coupler coupler(settings);
  const StepCase start = resting_layer_case(dt, settings.cloth_thickness);
  StepCase s = start;
  drench::CouplingStepStats stats;
  std::uint32_t status = 0;
  for (auto _ : state) {
    s.x1 = start.x1;
    s.v = start.v;
    s.cloth.positions_t1 = start.cloth.positions_t1;
    stats = drench::CouplingStepStats();
    const auto t = std::chrono::steady_clock::now();
    status = coupler.step(drench::FluidView{&s.x0, &s.x1, &s.v, &s.m}, s.cloth, dt, stats);
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count());
  }
  state.counters["particles"] = static_cast<double>(s.x0.size());
  state.counters["triangles"] = static_cast<double>(s.cloth.triangle_count());
  state.counters["contacts"] = static_cast<double>(stats.contacts);
  state.counters["ccd_impacts"] = static_cast<double>(stats.ccd_impacts);
  state.counters["ccd_iterations"] = static_cast<double>(stats.ccd_iterations);
  state.counters["failsafe"] = static_cast<double>(stats.failsafe_activations);
  state.counters["status"] = static_cast<double>(status);
  state.counters["ms_repulsion"] = 1e3 * stats.seconds_repulsion;
  state.counters["ms_ccd"] = 1e3 * stats.seconds_ccd;
  state.counters["threads"] = drench::thread_count();
  add_missing_counters(state);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  // Built once, before any benchmark, never timed; they live until the end of main.
  std::vector<std::pair<std::size_t, std::vector<BroadPhaseCase>>> cases;
  for (std::size_t particles : {15000u, 150000u})
    cases.emplace_back(particles, slab_case(particles));

  for (const auto& [particles, steps] : cases) {
    for (double margin : {0.001, 0.0025, 0.005}) {
      // Both broad phases must agree before their times mean anything.
      std::vector<std::pair<Index, Index>> grid, fcl;
      drench::make_broad_phase(BroadPhaseKind::GRID)
          ->find_pairs(steps[0].x0, steps[0].x1, steps[0].cloth, margin, nullptr, grid);
      drench::make_broad_phase(BroadPhaseKind::FCL)
          ->find_pairs(steps[0].x0, steps[0].x1, steps[0].cloth, margin, nullptr, fcl);
      if (grid != fcl) {
        std::fprintf(stderr, "bench_coupling: grid and FCL disagree (%zu particles, margin %g): %zu vs %zu\n",
                     particles, margin, grid.size(), fcl.size());
        return 1;
      }
      char margin_mm[16];
      std::snprintf(margin_mm, sizeof margin_mm, "%g", 1e3 * margin);
      for (BroadPhaseKind kind : {BroadPhaseKind::GRID, BroadPhaseKind::FCL}) {
        const std::string name = "find_pairs/particles:" + std::to_string(particles) +
                                 "/margin_mm:" + margin_mm + "/" + kind_name(kind);
        benchmark::RegisterBenchmark(name.c_str(),
                                     [&steps = steps, kind, margin](benchmark::State& state) {
                                       find_pairs(state, steps, kind, margin);
                                     })
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
      }
    }
  }
  for (BroadPhaseKind kind : {BroadPhaseKind::GRID, BroadPhaseKind::FCL}) {
    benchmark::RegisterBenchmark((std::string("coupler_step/particles:15000/") + kind_name(kind)).c_str(),
                                 [kind](benchmark::State& state) { coupler_step(state, kind); })
        ->Unit(benchmark::kMillisecond)
        ->UseManualTime();
  }

  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
