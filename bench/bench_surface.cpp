// The surface reconstruction of sec. 4 (issue 25), timed side by side with OpenVDB's own particle surfacer:
//  - dam_break/<size>/{plain,openvdb}: a dam break's state of about 15K, 125K and 1M particles reconstructed
//  by
//    reconstruct_surface without obstacles, and by OpenVDB's ParticlesToLevelSet + volumeToMesh on a grid of
//    the same voxel size (the outside reference);
//  - jet_on_cloth/{plain,contact_aware}: five frames of demos/scenes/jet_on_cloth.json (t = 0.1 ... 0.5 s,
//  the
//    jet landing on and pooling in the cloth) with the cloth as obstacle, contact_aware false and true.
// Cell size: the default, half the particle spacing, for every path.
//
//   OMP_NUM_THREADS=2 build/bench/bench_surface --benchmark_repetitions=3
//       --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true
//       --benchmark_out=bench/results/<machine>/surface.csv --benchmark_out_format=csv
// (bench/bench_surface.py runs this and notes the CPU model and load above the CSV.)
// Thread count: OMP_NUM_THREADS; TBB, which OpenVDB's dilation, rasterization and meshing run on in both
// paths, is held to the same count by a tbb::global_control in main().

#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/common/parallel.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/simulation.hpp>
#include <drench/surface/surface_reconstruction.hpp>

namespace {

using drench::Vec3;
using drench::Vec3Array;

/// A deterministic number in [-0.5, 0.5) from an integer (splitmix64's finaliser), for the lattice's jitter.
double hash_unit(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  x ^= x >> 31;
  return static_cast<double>(x >> 11) / static_cast<double>(1ull << 53) - 0.5;
}

/// The dam break's water at t = 0.2 s as Ritter's (1892) shallow-water solution gives it: a 1 m cube of water
/// released at x = 0 over a dry bed spreads as h(x) = (2 c0 - x / t)^2 / (9 g) for -c0 t < x < 2 c0 t
/// (c0 = sqrt(g h0)), a sloped surface thinning to a tongue, 1 m deep behind the rarefaction. Filled with a
/// cubic lattice of `spacing` (unit: m), each particle jittered by up to 10% of a spacing per axis, about
/// 1 / spacing^3 particles (the volume is conserved). A state, not a simulation: stepping the 1M block that
/// far takes the solver tens of minutes (bench_dam_break's pcisph_1m: 100 steps), and the same analytic shape
/// at every size makes the rates comparable across sizes.
Vec3Array ritter_dam_break(double spacing) {
  const double g = 9.81, h0 = 1.0, t = 0.2, c0 = std::sqrt(g * h0);
  const auto height = [&](double x) {
    if (x <= -c0 * t) return h0;
    if (x >= 2.0 * c0 * t) return 0.0;
    const double u = 2.0 * c0 - x / t;
    return u * u / (9.0 * g);
  };
  const int nx = static_cast<int>(std::ceil((1.0 + 2.0 * c0 * t) / spacing));
  const int ny = static_cast<int>(std::ceil(h0 / spacing));
  const int nz = static_cast<int>(std::round(1.0 / spacing));
  Vec3Array particles;
  std::uint64_t id = 0;
  for (int i = 0; i < nx; ++i) {
    const double x = -1.0 + (i + 0.5) * spacing;
    const double h = height(x);
    for (int j = 0; j < ny && (j + 0.5) * spacing < h; ++j) {
      for (int k = 0; k < nz; ++k, ++id) {
        const Vec3 jitter(hash_unit(3 * id), hash_unit(3 * id + 1), hash_unit(3 * id + 2));
        particles.push_back(Vec3(x, (j + 0.5) * spacing, (k + 0.5) * spacing) + 0.2 * spacing * jitter);
      }
    }
  }
  return particles;
}

/// Spacings of the three sizes: 0.04 m (15.6K), 0.02 m (125K), 0.01 m (1.0M), bench_dam_break's 1M spacing.
double size_spacing(int size) {
  return size == 0 ? 0.04 : size == 1 ? 0.02 : 0.01;
}

/// The dam break's state of size 0, 1 or 2, built once.
const Vec3Array& dam_break_state(int size) {
  static std::map<int, Vec3Array> states;
  auto it = states.find(size);
  if (it == states.end()) it = states.emplace(size, ritter_dam_break(size_spacing(size))).first;
  return it->second;
}

/// One frame of the jet on the cloth: the particles and the cloth as the scene runner hands them to the
/// reconstruction (positions_t1 between steps).
struct JetFrame {
  Vec3Array particles;
  Vec3Array cloth_positions;
  std::vector<drench::Triangle> cloth_triangles;
};

/// Frames at t = 0.1, 0.2, ..., 0.5 s of demos/scenes/jet_on_cloth.json, stepped once (about 12 s on 2
/// threads).
const std::vector<JetFrame>& jet_frames() {
  static const std::vector<JetFrame> frames = [] {
    const drench::SceneConfig config = drench::load_scene_file(
        std::string(DRENCH_SOURCE_DIR) + "/demos/scenes/jet_on_cloth.json", {"time.frame_rate=0"});
    drench::Simulation sim(config, drench::bullet::cloth_engine_factory());
    std::vector<JetFrame> out;
    const std::int64_t every = static_cast<std::int64_t>(std::lround(0.1 / config.time.dt));
    while (!sim.finished()) {
      if (!sim.step().ok()) throw std::runtime_error("jet_on_cloth: non-finite state");
      if (sim.steps_done() % every == 0) {
        out.push_back(
            {sim.particles().positions, sim.cloth()->mesh().positions_t1, sim.cloth()->mesh().triangles});
      }
    }
    return out;
  }();
  return frames;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// reconstruct_surface's stage times summed over calls (unit: s).
struct StageSeconds {
  double grid = 0.0, densities = 0.0, field = 0.0, mesh = 0.0;
  void add(const drench::SurfaceStats& s) {
    grid += s.seconds_grid;
    densities += s.seconds_densities;
    field += s.seconds_field;
    mesh += s.seconds_mesh;
  }
  /// Counters `<stage>_s`: seconds per iteration.
  void report(benchmark::State& state) const {
    const double n = static_cast<double>(state.iterations());
    state.counters["grid_s"] = grid / n;
    state.counters["densities_s"] = densities / n;
    state.counters["field_s"] = field / n;
    state.counters["mesh_s"] = mesh / n;
  }
};

/// The particles as OpenVDB's ParticlesToLevelSet reads them: every sphere of the same radius.
struct VdbParticleList {
  using PosType = openvdb::Vec3R;
  const Vec3Array* positions;
  double radius;  // unit: m
  std::size_t size() const { return positions->size(); }
  void getPos(std::size_t n, openvdb::Vec3R& xyz) const {
    const Vec3& p = (*positions)[n];
    xyz = openvdb::Vec3R(p.x(), p.y(), p.z());
  }
  void getPosRad(std::size_t n, openvdb::Vec3R& xyz, openvdb::Real& r) const {
    getPos(n, xyz);
    r = radius;
  }
};

/// OpenVDB's particle surface: spheres of one particle spacing rasterized into a narrow-band level set (half
/// width 3 voxels, the default) of voxel `cell`, meshed by volumeToMesh at level 0 as drench's grid is.
/// The radius is a spacing, not the Zhu-Bridson field's half spacing: spheres of half a spacing leave a void
/// at the centre of every lattice cube (0.87 spacings from its corners), which the mesher would surface; a
/// spacing closes them and stays above ParticlesToLevelSet's minimum of 1.5 voxels (below it the particle is
/// dropped). Returns the triangle count (quads count as two); adds the rasterization's and the meshing's wall
/// times to `field` and `mesh` (unit: s).
std::size_t openvdb_surface(const Vec3Array& particles, double spacing, double cell, double& field,
                            double& mesh) {
  const auto start = std::chrono::steady_clock::now();
  openvdb::FloatGrid::Ptr grid = openvdb::createLevelSet<openvdb::FloatGrid>(cell);
  openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*grid);
  raster.rasterizeSpheres(VdbParticleList{&particles, spacing});
  raster.finalize();
  field += seconds_since(start);
  const auto meshing = std::chrono::steady_clock::now();
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, 0.0);
  mesh += seconds_since(meshing);
  return triangles.size() + 2 * quads.size();
}

/// Reports what every row shares: particles and triangles per iteration, particles per second of wall time;
/// zeros for the counters the row's path has not (Google Benchmark's CSV wants the same columns in every
/// row).
void report(benchmark::State& state, double particles, double triangles, double wall) {
  for (const char* name : {"nodes", "frames", "occluded_pairs", "reset_nodes"})
    state.counters[name] = 0.0;
  state.counters["threads"] = drench::thread_count();
  state.counters["particles"] = particles;
  state.counters["triangles"] = triangles;
  state.counters["particles_per_s"] = particles * static_cast<double>(state.iterations()) / wall;
}

/// reconstruct_surface without obstacles on the dam break of `size` (0, 1, 2).
void dam_break_plain(benchmark::State& state, int size) {
  const Vec3Array& particles = dam_break_state(size);
  drench::SurfaceSettings settings;
  settings.contact_aware = false;
  drench::SurfaceStats stats;
  StageSeconds stages;
  std::size_t triangles = 0;
  double wall = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const drench::SurfaceMesh mesh =
        drench::reconstruct_surface(particles, size_spacing(size), settings, {}, &stats);
    const double seconds = seconds_since(start);
    state.SetIterationTime(seconds);
    wall += seconds;
    triangles = mesh.triangles.size();
    stages.add(stats);
  }
  report(state, particles.size(), triangles, wall);
  stages.report(state);
  state.counters["nodes"] = stats.nodes;
}

/// OpenVDB's ParticlesToLevelSet + volumeToMesh on the same state, voxel = drench's default cell.
void dam_break_openvdb(benchmark::State& state, int size) {
  const Vec3Array& particles = dam_break_state(size);
  const double spacing = size_spacing(size);
  const double cell = drench::SurfaceSettings().resolved_cell_size(spacing);
  std::size_t triangles = 0;
  double wall = 0.0;
  StageSeconds stages;  // field: ParticlesToLevelSet; mesh: volumeToMesh
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    triangles = openvdb_surface(particles, spacing, cell, stages.field, stages.mesh);
    const double seconds = seconds_since(start);
    state.SetIterationTime(seconds);
    wall += seconds;
  }
  report(state, particles.size(), triangles, wall);
  stages.report(state);
}

/// All jet frames reconstructed per iteration, the cloth passed as obstacle; `aware` sets contact_aware.
void jet_on_cloth(benchmark::State& state, bool aware) {
  const std::vector<JetFrame>& frames = jet_frames();
  const double spacing = 0.005;  // the scene's fluid.particle_spacing
  drench::SurfaceSettings settings;
  settings.contact_aware = aware;
  double particles = 0.0, triangles = 0.0, occluded = 0.0, reset = 0.0, wall = 0.0;
  StageSeconds stages;
  for (auto _ : state) {
    particles = triangles = occluded = reset = 0.0;
    const auto start = std::chrono::steady_clock::now();
    for (const JetFrame& f : frames) {
      drench::SurfaceStats stats;
      const drench::SurfaceMesh mesh = drench::reconstruct_surface(
          f.particles, spacing, settings, {{&f.cloth_positions, &f.cloth_triangles}}, &stats);
      particles += f.particles.size();
      triangles += mesh.triangles.size();
      occluded += stats.occluded;
      reset += stats.reset_nodes;
      stages.add(stats);
    }
    const double seconds = seconds_since(start);
    state.SetIterationTime(seconds);
    wall += seconds;
  }
  report(state, particles, triangles, wall);
  stages.report(state);
  state.counters["frames"] = frames.size();
  state.counters["occluded_pairs"] = occluded;
  state.counters["reset_nodes"] = reset;
}

}  // namespace

BENCHMARK_CAPTURE(dam_break_plain, 15k, 0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(dam_break_openvdb, 15k, 0)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(dam_break_plain, 125k, 1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(dam_break_openvdb, 125k, 1)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(dam_break_plain, 1m, 2)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(dam_break_openvdb, 1m, 2)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(jet_on_cloth, plain, false)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(jet_on_cloth, contact_aware, true)->UseManualTime()->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  // OpenVDB runs on TBB, which would otherwise take every core; both paths get drench's thread count.
  const tbb::global_control tbb_threads(tbb::global_control::max_allowed_parallelism,
                                        static_cast<std::size_t>(drench::thread_count()));
  openvdb::initialize();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
