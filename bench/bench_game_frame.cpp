// bench_game_frame: issue 41's frame budget. The game-like level of demos/bullet_playground (its world,
// demos/bullet_playground_world.hpp: a hammock, a curtain, two balls, a crate, two jets of 1 cm particles,
// wetting) stepped as a game steps it, one coupled step of 1/60 s per frame, for each pressure solver, with
// drench on 1 thread and on its default (the CPUs), alone and beside one busy thread per CPU (std::threads
// spinning from before the warm-up to the end of the run, as a game's or a renderer's threads would).
//
//   build-bench/bench/bench_game_frame [--frames 600] [--warmup 60] [--solvers dfsph,pcisph,pbf,pbf:2x3,...]
//       [--busy N] [--broad-phase grid|fcl] [--benchmark_filter=...] --benchmark_out=game_frame.json
//       --benchmark_out_format=json
// bench/game_frame.py runs it and writes bench/results/<machine>/game_frame.csv. Built in a build directory
// configured with -DDRENCH_POOL_STATS=ON it also counts, per frame, the parallel and serial loops of drench's
// thread pool and how long their ends waited for a late worker (pool_* counters, detail::pool_stats).
//
// One benchmark iteration is one frame (Iterations(frames), UseManualTime with the frame's wall time): the
// frame count is fixed, not chosen by Google Benchmark, the world is built and warmed up outside the timed
// loop, and the reported time is the mean ms per frame; the median and the 99th percentile per stage, which
// Google Benchmark cannot compute over iterations, are counters. The warm-up (60 frames, 1 s, by default)
// lets the jets' water reach the hammock and the curtain, so that the timed frames are the level in play, not
// its empty first second; the jets run out (4,000 particles each) at about 3-4 s, and the water that stays
// pools in the hammock (pinned all round), so the 600 frames (t = 1 ... 11 s) hold the jets and the pooled
// water.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <drench/bullet/coupled_world.hpp>
#include <drench/common/parallel.hpp>
#include <drench/sph/fluid_settings.hpp>
#include "../demos/bullet_playground_world.hpp"

namespace {

// The solvers --solvers may name, by their scene name (drench::pressure_solver_name). PBF is one more entry.
constexpr drench::PressureSolverKind kKnownSolvers[] = {
    drench::PressureSolverKind::DFSPH,
    drench::PressureSolverKind::PCISPH,
    drench::PressureSolverKind::WCSPH,
    drench::PressureSolverKind::PBF,
};

/// What a token's `-<name>` may leave out of the level: three of its effects and the cloth inside the fluid's
/// sub-steps (coupling.substep_obstacle). The coupling itself stays: without it the water falls through.
constexpr const char* kOptionalParts[] = {"viscosity", "leak_audit", "wetting", "substep_obstacle"};

/// One solver of the run: its kind; for PBF, the sub-steps and iterations per frame when not the level's
/// (the token `pbf:<substeps>x<iterations>`, e.g. `pbf:2x3`); and the parts of the level it leaves out (each
/// `-<name>` of kOptionalParts, e.g. `pbf-leak_audit`), so that the page can show what a cheaper setting or
/// an effect saves and what it costs.
struct SolverRun {
  drench::PressureSolverKind kind = drench::PressureSolverKind::PBF;
  int pbf_substeps = 0;              // 0: the level's (PbfSettings::substeps)
  int pbf_iterations = 0;            // 0: the level's (PbfSettings::iterations)
  std::string label;                 // the token: the benchmark's <solver> part
  std::vector<std::string> without;  // of kOptionalParts
};

struct Options {
  long frames = 600;  // timed frames per benchmark
  long warmup = 60;   // frames stepped before them, untimed
  int busy = 0;       // spinning threads of the busy condition; 0: one per CPU
  // The coupling's broad phase; none: the level's own (coupling.broad_phase of playground::scene).
  std::optional<drench::BroadPhaseKind> broad_phase;
  std::vector<SolverRun> solvers = {{drench::PressureSolverKind::DFSPH, 0, 0, "dfsph", {}},
                                    {drench::PressureSolverKind::PCISPH, 0, 0, "pcisph", {}},
                                    {drench::PressureSolverKind::PBF, 0, 0, "pbf", {}}};
};

/// Threads that spin until destroyed, one per CPU of the condition "beside busy threads": each keeps a core
/// busy as a game's own thread does, so that drench's threads must share the cores with them.
class BusyThreads {
 public:
  explicit BusyThreads(int n) {
    for (int i = 0; i < n; ++i)
      m_threads.emplace_back([this] {
        while (!m_stop.load(std::memory_order_relaxed)) {
        }
      });
  }
  ~BusyThreads() {
    m_stop.store(true);
    for (std::thread& t : m_threads)
      t.join();
  }
  BusyThreads(const BusyThreads&) = delete;
  BusyThreads& operator=(const BusyThreads&) = delete;

 private:
  std::atomic<bool> m_stop{false};
  std::vector<std::thread> m_threads;
};

/// Bins of the frames by the particles at their end: bin k holds counts in (k, k + 1] x kBinParticles (an
/// empty level in bin 0), up to kParticleBins x kBinParticles, the 5,000; more are not binned.
constexpr std::size_t kBinParticles = 500;
constexpr std::size_t kParticleBins = 10;
std::size_t particle_bin(std::size_t particles) {
  return particles == 0 ? 0 : (particles - 1) / kBinParticles;
}

/// The q-quantile of `values` by the nearest rank (q = 0.5: the median), as demos/bullet_playground.cpp
/// reports its frames.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  const std::size_t at = std::min(values.size(), std::max<std::size_t>(rank, 1)) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<long>(at), values.end());
  return values[at];
}

/// Steps the level `warmup` frames, then one frame per benchmark iteration, with `solver`, drench on
/// `threads` threads and `busy` spinning threads beside it. Counters (ms per frame, median and p99 over the
/// timed frames): <stage>_ms_median, <stage>_ms_p99 for the stages of CoupledStepReport::seconds (emit,
/// fluid, cloth, rigid, coupling, other = total less the named ones, total); leaks over the whole run
/// (warm-up included; the target is 0), of which jump_leaks between steps (audit_face_jumps), and the
/// particles the impact zones squeezed out over the whole run (squeezed_out); the fastest particle and node
/// at the end of any step of the run (unit: m/s); particles at the end and at most; the fluid's CFL sub-steps
/// per frame and mean density error over the timed frames; the continuous handling's CCD rounds, impacts,
/// fail-safe particles and sub-step obstacle stops per frame, and the shares of frames that reached its
/// fail-safe and its impact zones; per frame, what the last resorts gave particles (N s), the momentum impact
/// zones' node moves gave the cloth (N s) and how far they moved nodes whose engine ignores it (m)
/// (CouplingStepStats); the time of a blow-up (0: none), after which nothing more is stepped; per bin of 500
/// particles at a frame's end, up to 5,000, its timed frames (frames_upto_<n>) and their median total
/// (total_ms_median_upto_<n>, 0 without frames).
void game_frame(benchmark::State& state, const std::string& name, const SolverRun& solver, int threads,
                int busy, long warmup, std::optional<drench::BroadPhaseKind> broad_phase) {
  drench::set_thread_count(threads);
  const auto frames = static_cast<long>(state.max_iterations);
  playground::World game;
  drench::SceneConfig scene =
      playground::scene(static_cast<double>(warmup + frames) * playground::kDt, solver.kind);
  if (solver.pbf_substeps > 0) scene.fluid.pbf.substeps = solver.pbf_substeps;
  if (solver.pbf_iterations > 0) scene.fluid.pbf.iterations = solver.pbf_iterations;
  for (const std::string& part : solver.without) {
    if (part == "substep_obstacle") {
      scene.coupling.substep_obstacle = false;
    } else {
      scene.effects.erase(std::remove(scene.effects.begin(), scene.effects.end(), part), scene.effects.end());
    }
  }
  const bool audited = scene.has_effect("leak_audit");
  if (broad_phase) scene.coupling.broad_phase = *broad_phase;
  drench::bullet::CoupledWorld coupled(game.world, game.cloths(), scene);
  const BusyThreads spinning(busy);

  std::uint64_t leaks = 0, jump_leaks = 0, squeezed_out = 0, failed_frames = 0;
  // The continuous handling's work over the timed frames: how often a frame needs its last resorts tells
  // whether its rounds (coupling.max_ccd_iterations) suffice for the level.
  struct {
    std::uint64_t rounds = 0, impacts = 0, failsafe_particles = 0, failsafe_frames = 0, zone_frames = 0,
                  obstacle_stops = 0;
    double last_resort_impulse = 0.0, zone_cloth_momentum = 0.0, zone_ignored_shift = 0.0;
  } ccd;
  bool timing = false;
  const auto checked_step = [&]() {
    drench::bullet::CoupledStepReport report = coupled.step();
    leaks += report.leak_stats.leaks;
    jump_leaks += report.leak_stats.jump_leaks;
    squeezed_out += report.coupling_stats.squeezed_out;
    if (report.failed()) ++failed_frames;
    if (timing) {
      const drench::CouplingStepStats& c = report.coupling_stats;
      ccd.rounds += c.ccd_iterations;
      ccd.impacts += c.ccd_impacts;
      ccd.failsafe_particles += c.failsafe_activations;
      ccd.obstacle_stops += c.obstacle_stops;
      ccd.last_resort_impulse += c.last_resort_impulse;
      ccd.zone_cloth_momentum += c.zone_cloth_momentum;
      ccd.zone_ignored_shift += c.zone_ignored_shift;
      if (report.coupling & drench::COUPLING_FAILSAFE_USED) ++ccd.failsafe_frames;
      if (report.coupling & drench::COUPLING_ZONES_STOPPED) ++ccd.zone_frames;
    }
    return report;
  };
  // A blow-up stops the stepping: the iterations left pass without a step, with time 0, so that the
  // counters keep how far it got and what its frames cost until then (Google Benchmark drops an errored
  // run's counters). blew_up_at_s > 0 marks it; the mean time per iteration is then not a frame's.
  double blew_up_at = 0.0;
  const auto blow_up = [&](const drench::bullet::CoupledStepReport& report) {
    blew_up_at = coupled.time();
    std::fprintf(stderr, "%s: the fluid or a cloth blew up at t = %.4f s: %s\n", name.c_str(), blew_up_at,
                 report.fluid.describe().c_str());
  };
  for (long n = 0; n < warmup && blew_up_at == 0.0; ++n) {
    const drench::bullet::CoupledStepReport report = checked_step();
    if (!report.ok()) blow_up(report);
  }

  const drench::FluidStatistics fluid_before = coupled.simulation().fluid().statistics();
  drench::detail::reset_pool_stats();
  std::vector<std::vector<double>> stages(7);
  // The whole frame's time by the particles in the level at its end, in bins of kBinParticles: the level's
  // count rises and falls (the jets, then the water squeezed out or run off), and the median over all frames
  // hides what a frame costs at a given count, which is what a game budgets by.
  std::vector<std::vector<double>> total_by_particles(kParticleBins);
  std::size_t particles_max = 0;
  timing = true;
  for (auto _ : state) {
    if (blew_up_at > 0.0) {
      state.SetIterationTime(0.0);
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    const drench::bullet::CoupledStepReport report = checked_step();
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    const auto& s = report.seconds;
    const double other = s.total - (s.emit + s.fluid + s.cloth + s.rigid + s.coupling);
    const double values[] = {s.emit, s.fluid, s.cloth, s.rigid, s.coupling, other, s.total};
    for (std::size_t k = 0; k < stages.size(); ++k)
      stages[k].push_back(values[k]);
    particles_max = std::max(particles_max, coupled.particles().size());
    if (const std::size_t bin = particle_bin(coupled.particles().size()); bin < kParticleBins)
      total_by_particles[bin].push_back(s.total);
    if (!report.ok()) blow_up(report);
  }

  // The pool's loops over the timed frames, per frame (a DRENCH_POOL_STATS build only): how many parallel
  // and serial loops a frame runs, and how long the callers waited at their ends for a late worker.
  const drench::detail::PoolStats pool = drench::detail::pool_stats();
  if (pool.counted) {
    const double per_frame = 1.0 / static_cast<double>(std::max<std::size_t>(1, stages[0].size()));
    const auto share = [](std::uint64_t part, std::uint64_t whole) {
      return whole == 0 ? 0.0 : static_cast<double>(part) / static_cast<double>(whole);
    };
    state.counters["pool_loops"] = per_frame * static_cast<double>(pool.parallel_loops);
    state.counters["pool_serial_loops"] = per_frame * static_cast<double>(pool.serial_loops);
    state.counters["pool_loop_ms"] = 1e3 * per_frame * pool.loop_seconds;
    state.counters["pool_wait_ms"] = 1e3 * per_frame * pool.wait_seconds;
    state.counters["pool_serial_ms"] = 1e3 * per_frame * pool.serial_seconds;
    state.counters["pool_waits"] = per_frame * static_cast<double>(pool.waits);
    state.counters["pool_blocked_waits"] = per_frame * static_cast<double>(pool.blocked_waits);
    state.counters["pool_long_waits"] = per_frame * static_cast<double>(pool.long_waits);
    state.counters["pool_max_wait_ms"] = 1e3 * pool.max_wait_seconds;
    state.counters["pool_solo_stretches"] = per_frame * static_cast<double>(pool.solo_stretches);
    state.counters["pool_light_loops"] = per_frame * static_cast<double>(pool.light_loops);
    state.counters["pool_light_ms"] = 1e3 * per_frame * pool.light_seconds;
    state.counters["pool_caller_chunk_share"] = share(pool.caller_chunks, pool.chunks);
    state.counters["pool_caller_alone_share"] = share(pool.caller_alone_loops, pool.parallel_loops);
  }

  const char* names[] = {"emit", "fluid", "cloth", "rigid", "coupling", "other", "total"};
  for (std::size_t k = 0; k < stages.size(); ++k) {
    state.counters[std::string(names[k]) + "_ms_median"] = 1e3 * quantile(stages[k], 0.5);
    state.counters[std::string(names[k]) + "_ms_p99"] = 1e3 * quantile(stages[k], 0.99);
  }
  const drench::Simulation& sim = coupled.simulation();
  const drench::FluidStatistics& fluid = sim.fluid().statistics();
  const auto substeps = static_cast<double>(fluid.substeps - fluid_before.substeps);
  state.counters["frames"] = static_cast<double>(stages[0].size());
  state.counters["warmup_frames"] = static_cast<double>(warmup);
  state.counters["drench_threads"] = drench::thread_count();
  state.counters["busy_threads"] = busy;
  // Without the audit nothing counts leaks: 0 then means not counted (leak_audit 0), not none.
  state.counters["leak_audit"] = audited ? 1.0 : 0.0;
  state.counters["leaks"] = static_cast<double>(leaks);
  state.counters["jump_leaks"] = static_cast<double>(jump_leaks);
  state.counters["squeezed_out"] = static_cast<double>(squeezed_out);
  state.counters["failed_frames"] = static_cast<double>(failed_frames);
  state.counters["blew_up_at_s"] = blew_up_at;
  state.counters["fastest_particle_mps"] = sim.max_particle_speed();
  state.counters["fastest_node_mps"] = sim.max_node_speed();
  state.counters["particles"] = static_cast<double>(coupled.particles().size());
  state.counters["particles_max"] = static_cast<double>(particles_max);
  state.counters["fluid_substeps_per_frame"] =
      substeps / static_cast<double>(std::max<std::size_t>(1, stages[0].size()));
  const double frames_done = static_cast<double>(std::max<std::size_t>(1, stages[0].size()));
  state.counters["ccd_rounds_per_frame"] = static_cast<double>(ccd.rounds) / frames_done;
  state.counters["ccd_impacts_per_frame"] = static_cast<double>(ccd.impacts) / frames_done;
  state.counters["failsafe_particles_per_frame"] = static_cast<double>(ccd.failsafe_particles) / frames_done;
  state.counters["failsafe_frame_share"] = static_cast<double>(ccd.failsafe_frames) / frames_done;
  state.counters["zone_frame_share"] = static_cast<double>(ccd.zone_frames) / frames_done;
  state.counters["obstacle_stops_per_frame"] = static_cast<double>(ccd.obstacle_stops) / frames_done;
  state.counters["last_resort_impulse_per_frame"] = ccd.last_resort_impulse / frames_done;
  state.counters["zone_cloth_momentum_per_frame"] = ccd.zone_cloth_momentum / frames_done;
  state.counters["zone_ignored_shift_per_frame"] = ccd.zone_ignored_shift / frames_done;
  state.counters["density_error_mean"] =
      substeps > 0 ? (fluid.density_error_sum - fluid_before.density_error_sum) / substeps : 0.0;
  for (std::size_t bin = 0; bin < kParticleBins; ++bin) {
    const std::string upto = std::to_string((bin + 1) * kBinParticles);
    state.counters["frames_upto_" + upto] = static_cast<double>(total_by_particles[bin].size());
    state.counters["total_ms_median_upto_" + upto] = 1e3 * quantile(total_by_particles[bin], 0.5);
  }
}

[[noreturn]] void usage(const char* program, const std::string& problem) {
  std::string known;
  for (drench::PressureSolverKind kind : kKnownSolvers)
    known += std::string(known.empty() ? "" : ", ") + drench::pressure_solver_name(kind);
  std::fprintf(
      stderr,
      "%s: %s\nusage: %s [--frames N (600)] [--warmup N (60)] [--solvers NAME,... (dfsph,pcisph,pbf; "
      "known: %s; pbf:<substeps>x<iterations> for PBF at another setting; -<part> leaves out viscosity, "
      "leak_audit, wetting or substep_obstacle, e.g. pbf:2x3-leak_audit)] [--busy N (one per CPU)] "
      "[Google Benchmark flags]\n",
      program, problem.c_str(), program, known.c_str());
  std::exit(1);
}

long count_option(const char* program, const char* flag, const char* text, long least) {
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (*text == '\0' || *end != '\0' || value < least || value > 1000000)
    usage(program, std::string(flag) + " must be an integer in [" + std::to_string(least) +
                       ", 1000000], got '" + text + "'");
  return value;
}

Options parse(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) usage(argv[0], "unknown argument or missing value: '" + flag + "'");
    const char* value = argv[++i];
    if (flag == "--frames") {
      options.frames = count_option(argv[0], "--frames", value, 1);
    } else if (flag == "--warmup") {
      options.warmup = count_option(argv[0], "--warmup", value, 0);
    } else if (flag == "--busy") {
      options.busy = static_cast<int>(count_option(argv[0], "--busy", value, 1));
    } else if (flag == "--broad-phase") {
      const std::string name = value;
      if (name == "grid") {
        options.broad_phase = drench::BroadPhaseKind::GRID;
      } else if (name == "fcl") {
        options.broad_phase = drench::BroadPhaseKind::FCL;
      } else {
        usage(argv[0], "--broad-phase: unknown broad phase '" + name + "' (known: grid, fcl)");
      }
    } else if (flag == "--solvers") {
      options.solvers.clear();
      std::string list = value;
      for (std::size_t from = 0; from <= list.size();) {
        const std::size_t to = std::min(list.find(',', from), list.size());
        const std::string token = list.substr(from, to - from);
        from = to + 1;
        // <solver>[-<part>...]: the level without those parts (kOptionalParts).
        std::vector<std::string> without;
        std::size_t dash = token.find('-');
        const std::string solver_name = token.substr(0, dash);
        while (dash != std::string::npos) {
          const std::size_t next = token.find('-', dash + 1);
          const std::string part = token.substr(dash + 1, next == std::string::npos ? next : next - dash - 1);
          const auto* known = std::find(std::begin(kOptionalParts), std::end(kOptionalParts), part);
          if (known == std::end(kOptionalParts))
            usage(argv[0], "--solvers: '" + token + "': unknown part '" + part +
                               "' (known: viscosity, leak_audit, wetting, substep_obstacle)");
          without.push_back(part);
          dash = next;
        }
        // pbf:<substeps>x<iterations>: PBF at a setting other than the level's.
        int substeps = 0, iterations = 0;
        if (solver_name.rfind("pbf:", 0) == 0) {
          const std::string setting = solver_name.substr(4);
          const std::size_t x = setting.find('x');
          if (x == std::string::npos)
            usage(argv[0], "--solvers: '" + token + "' must read pbf:<substeps>x<iterations>, e.g. pbf:2x3");
          substeps = static_cast<int>(
              count_option(argv[0], "--solvers pbf:<substeps>", setting.substr(0, x).c_str(), 1));
          iterations = static_cast<int>(
              count_option(argv[0], "--solvers pbf:...x<iterations>", setting.substr(x + 1).c_str(), 1));
          options.solvers.push_back({drench::PressureSolverKind::PBF, substeps, iterations, token, without});
          continue;
        }
        const auto* kind = std::find_if(std::begin(kKnownSolvers), std::end(kKnownSolvers), [&](auto k) {
          return solver_name == drench::pressure_solver_name(k);
        });
        if (kind == std::end(kKnownSolvers)) usage(argv[0], "--solvers: unknown solver '" + token + "'");
        options.solvers.push_back({*kind, 0, 0, token, without});
      }
    } else {
      usage(argv[0], "unknown argument '" + flag + "'");
    }
  }
  return options;
}

}  // namespace

int main(int argc, char** argv) {
  // Before any set_thread_count: the count drench takes by itself (the CPUs, or OMP_NUM_THREADS).
  const int default_threads = drench::thread_count();
  const int cpus = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  benchmark::Initialize(&argc, argv);
  const Options options = parse(argc, argv);

  std::vector<int> thread_counts = {1};
  if (default_threads != 1) thread_counts.push_back(default_threads);
  for (const SolverRun& solver : options.solvers) {
    for (int threads : thread_counts) {
      for (int busy : {0, options.busy > 0 ? options.busy : cpus}) {
        const std::string name = "game_frame/" + solver.label + "/threads:" + std::to_string(threads) +
                                 (busy == 0 ? "/alone" : "/busy:" + std::to_string(busy));
        benchmark::RegisterBenchmark(name.c_str(), game_frame, name, solver, threads, busy, options.warmup,
                                     options.broad_phase)
            ->Iterations(options.frames)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
      }
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
