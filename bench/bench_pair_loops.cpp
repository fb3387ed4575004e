// The fluid's pair loops alone, on the 59K reference dam break (bench_dam_break's pcisph_59k scene) after 60
// steps of 2.5 ms, when the block has collapsed into a wave: densities at the particles' positions
// (sph_densities), pressure accelerations with a made-up positive pressure field (pressure_accelerations) and
// XSPH, and the exact neighbor lists they read (search and gradient factors); the densities and pressure
// loops also in single precision (densities_float, pressure_accelerations_float), as PCISPH runs them.
// Densities and pressure on all 59,319 particles (lists, factors and points exceed the cache) and on the
// first 2,048 (within it), the others on all. Counter time_per_pair: wall time per fluid neighbor pair.
//
//   build-bench/bench/bench_pair_loops --benchmark_repetitions=5
// Thread count: OMP_NUM_THREADS. Setting up (the 60 steps) takes about 10 s on one thread.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <drench/common/parallel.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/simulation.hpp>
#include <drench/sph/fluid_context.hpp>
#include <drench/sph/forces/viscosity.hpp>
#include <drench/sph/pressure/pressure_pcisph.hpp>
#include <drench/sph/verlet_neighbor_lists.hpp>

namespace {

/// The dam break's particles after 60 steps, their exact neighbor lists and the packed inputs of the loops.
struct Fixture {
  std::unique_ptr<drench::Simulation> sim;
  std::unique_ptr<drench::VerletNeighborLists> lists;
  drench::PackedPointArray boundary;       // w = Psi_b, taken as rest density x spacing^3 (unit: kg)
  drench::PackedPointArray x_mass;         // w = mass (unit: kg)
  drench::PackedPointArray x_p_over_rho2;  // w = p / rho0^2, p in [0, 2000] Pa
  // The same three in single precision, relative to the fluid's bounding-box centre, as PCISPH makes them.
  drench::PackedPointFArray boundary_float, x_mass_float, x_p_over_rho2_float;
  std::unique_ptr<drench::FluidContext> ctx;

  Fixture() {
    const double spacing = 0.025;  // m
    sim = std::make_unique<drench::Simulation>(drench::load_scene_file(
        std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/dam_break.json",
        {"fluid.particle_spacing=0.025", "fluid.pcisph.eta=0.0005", "emitters[0].max=[0.975,0.975,0.975]",
         "time.dt=0.0025", "time.frame_rate=0"}));
    for (int s = 0; s < 60; ++s)
      sim->step();
    drench::FluidSolver& fluid = sim->fluid();
    drench::ParticleSet& p = fluid.particles();
    lists = std::make_unique<drench::VerletNeighborLists>(fluid.kernel(), 0.0, fluid.boundary_positions());
    lists->update(p.positions, p.ids, 0.0);
    const double rho0 = fluid.settings().rest_density;
    for (const drench::Vec3& b : fluid.boundary_positions())
      boundary.push_back(drench::packed(b, rho0 * spacing * spacing * spacing));
    for (std::size_t i = 0; i < p.size(); ++i) {
      x_mass.push_back(drench::packed(p.positions[i], p.masses[i]));
      const double pressure = 1000.0 * (1.0 + std::cos(static_cast<double>(i)));  // Pa
      x_p_over_rho2.push_back(drench::packed(p.positions[i], pressure / (rho0 * rho0)));
    }
    // The centre of the fluid's bounding box, as PCISPH takes it (unit: m).
    drench::Vec3 lo = p.positions[0], hi = p.positions[0];
    for (const drench::Vec3& x : p.positions) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    const drench::Vec3 centre = 0.5 * (lo + hi);
    const auto to_float = [&](const drench::PackedPointArray& from, drench::PackedPointFArray& to) {
      for (const drench::PackedPoint& q : from)
        to.push_back(drench::packed_float(drench::Vec3(q.x, q.y, q.z) - centre, q.w));
    };
    to_float(boundary, boundary_float);
    to_float(x_mass, x_mass_float);
    to_float(x_p_over_rho2, x_p_over_rho2_float);
    ctx = std::make_unique<drench::FluidContext>(drench::FluidContext{
        fluid.kernel(), p, lists->fluid(), lists->boundary(), boundary, rho0, spacing,
        lists->fluid_gradient_factors(), lists->boundary_gradient_factors(), p.common_mass()});
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

/// The particles a benchmark runs over: all, or the first 2,048.
std::size_t particles(const benchmark::State& state) {
  return state.range(0) ? std::min<std::size_t>(fixture().x_mass.size(), state.range(0))
                        : fixture().x_mass.size();
}

void report(benchmark::State& state, std::size_t n) {
  const double pairs = fixture().ctx->fluid_neighbors.offsets[n];
  state.counters["particles"] = static_cast<double>(n);
  state.counters["pairs"] = pairs;
  state.counters["time_per_pair"] =
      benchmark::Counter(pairs, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// Also counts the chunks each thread took (for_each_chunk's deal written out): with two threads,
/// chunks_last_thread is the share of the last one, 0.5 when both cores ran at the same speed throughout.
void densities(benchmark::State& state) {
  const Fixture& f = fixture();
  const std::size_t n = particles(state);
  drench::ScalarArray out(n);
  const int threads = drench::thread_count();
  std::vector<double> taken(static_cast<std::size_t>(threads), 0.0);
  for (auto _ : state) {
    drench::parallel_for_slots(n, drench::kParticleChunk, threads,
                               [&](std::size_t begin, std::size_t end, int slot) {
                                 drench::sph_densities(*f.ctx, f.x_mass, begin, end, &out[begin]);
                                 taken[static_cast<std::size_t>(slot)] += 1.0;
                               });
    benchmark::DoNotOptimize(out.data());
  }
  report(state, n);
  double all = 0.0;
  for (double t : taken)
    all += t;
  state.counters["chunks_last_thread"] = taken.back() / all;
}

/// sph_densities_float, PCISPH's density pass in single precision; counter max_relative_difference: the
/// largest relative difference from sph_densities over the particles.
void densities_float(benchmark::State& state) {
  const Fixture& f = fixture();
  const std::size_t n = particles(state);
  drench::ScalarArray out(n);
  for (auto _ : state) {
    drench::for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
      drench::sph_densities_float(*f.ctx, f.x_mass_float, f.boundary_float, begin, end, &out[begin]);
    });
    benchmark::DoNotOptimize(out.data());
  }
  report(state, n);
  // Against the double loop: the accuracy that the single precision costs on this state.
  drench::ScalarArray reference(n);
  drench::sph_densities(*f.ctx, f.x_mass, 0, n, reference.data());
  double largest = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    largest = std::max(largest, std::abs(out[i] - reference[i]) / reference[i]);
  state.counters["max_relative_difference"] = largest;
}

/// pressure_accelerations_float, PCISPH's pressure pass in single precision.
void pressure_accelerations_float(benchmark::State& state) {
  const Fixture& f = fixture();
  const std::size_t n = particles(state);
  drench::Vec3Array out(n);
  for (auto _ : state) {
    drench::for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
      drench::pressure_accelerations_float(*f.ctx, f.x_p_over_rho2_float, f.boundary_float, begin, end,
                                           &out[begin]);
    });
    benchmark::DoNotOptimize(out.data());
  }
  report(state, n);
}

void pressure_accelerations(benchmark::State& state) {
  const Fixture& f = fixture();
  const std::size_t n = particles(state);
  drench::Vec3Array out(n);
  for (auto _ : state) {
    drench::for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
      drench::pressure_accelerations(*f.ctx, f.x_p_over_rho2, begin, end, &out[begin]);
    });
    benchmark::DoNotOptimize(out.data());
  }
  report(state, n);
}

/// XSPH over all particles (ViscosityXsph packs its own inputs each call, as in a sub-step).
void xsph(benchmark::State& state) {
  const Fixture& f = fixture();
  const drench::ViscosityXsph viscosity(0.01);
  drench::Vec3Array out(f.x_mass.size(), drench::Vec3::Zero());
  for (auto _ : state) {
    viscosity.add_accelerations(*f.ctx, 0.0025, out);
    benchmark::DoNotOptimize(out.data());
  }
  report(state, f.x_mass.size());
}

/// The exact neighbor lists of all particles from scratch, as a PCISPH sub-step updates them: grid build,
/// search and the gradient factors of every pair (fluid and boundary).
void neighbor_lists(benchmark::State& state) {
  const Fixture& f = fixture();
  const drench::FluidSolver& fluid = f.sim->fluid();
  const drench::ParticleSet& p = fluid.particles();
  drench::VerletNeighborLists lists(fluid.kernel(), 0.0, fluid.boundary_positions());
  for (auto _ : state) {
    lists.update(p.positions, p.ids, 0.0);
    benchmark::DoNotOptimize(lists.fluid_gradient_factors().data());
  }
  report(state, p.size());
}

/// One PCISPH pressure solve of the state (sub-step 1.25 ms, the dam break's at this time; velocities plus
/// gravity as the advected ones): its iterations are a density and a pressure pass each, so its time over
/// (densities + pressure_accelerations) x iterations shows what the solve adds around the two loops.
/// Argument: 0 in single precision (the default, the _float loops), 1 in double.
void pcisph_solve(benchmark::State& state) {
  const Fixture& f = fixture();
  const drench::FluidSolver& fluid = f.sim->fluid();
  const drench::ParticleSet& p = fluid.particles();
  const double dt = 0.00125;  // s
  drench::Vec3Array velocities_adv(p.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    velocities_adv[i] = p.velocities[i] + dt * drench::Vec3(0.0, -9.81, 0.0);
  drench::FluidSettings settings = fluid.settings();
  if (state.range(0)) settings.pcisph.precision = drench::IterationPrecision::DOUBLE;
  drench::PressurePcisph solver(settings);
  drench::Vec3Array accelerations;
  drench::PressureStats stats;
  for (auto _ : state) {
    stats = solver.solve(*f.ctx, velocities_adv, dt, accelerations);
    benchmark::DoNotOptimize(accelerations.data());
  }
  report(state, p.size());
  state.counters["iterations"] = stats.iterations;
}

}  // namespace

BENCHMARK(neighbor_lists)->Unit(benchmark::kMillisecond);
BENCHMARK(densities)->Arg(0)->Arg(2048)->Unit(benchmark::kMillisecond);
BENCHMARK(pressure_accelerations)->Arg(0)->Arg(2048)->Unit(benchmark::kMillisecond);
BENCHMARK(densities_float)->Arg(0)->Arg(2048)->Unit(benchmark::kMillisecond);
BENCHMARK(pressure_accelerations_float)->Arg(0)->Arg(2048)->Unit(benchmark::kMillisecond);
BENCHMARK(xsph)->Unit(benchmark::kMillisecond);
BENCHMARK(pcisph_solve)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
