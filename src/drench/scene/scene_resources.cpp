#include <drench/scene/scene_resources.hpp>

#include <sys/statvfs.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <drench/common/error.hpp>

namespace drench {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Bytes of output, measured on the files of `drench run` (frames/*.ply, binary little-endian PLY): a fluid
// particle is 9 float32/uint32 properties (position, velocity, density, pressure, id) = 36 bytes; a cloth
// node is its position and normal, 6 float32 = 24 bytes, 28 with wetting's wetness; a triangle is a uchar
// count and 3 int32 = 13 bytes; a header is under 400 bytes.
constexpr double kPlyBytesPerParticle = 36.0;
constexpr double kPlyBytesPerClothNode = 28.0;
constexpr double kPlyBytesPerFace = 13.0;
constexpr double kPlyHeaderBytes = 400.0;
// The surface (effect "surface") at surface.cell_size = spacing / 2, per particle: 159 bytes on the jet
// demo's frame 3 (1,550 particles, a thin jet all surface), 176 on its frame 7; it grows as
// (spacing / cell_size)^2, an area.
constexpr double kSurfaceBytesPerParticleAtHalfSpacing = 200.0;

// Peak resident memory (VmHWM of /usr/bin/time -v), fitted to two runs of each kind (2 steps, no frames):
// the difference of their peaks over the difference of their counts, rounded up.
//   boundary particles: the dam break's 4 x 3 x 1.5 m box without fluid at 2 cm and 1 cm (231,864 and
//   913,664 boundary particles; 78.5 and 183.9 MB): 158 bytes each;
//   fluid particles: the dam break at 5 and 2.5 cm (8,000 and 64,000 particles; 64.2 and 189.5 MB), less
//   the boundary's share: 1,978 bytes each (PCISPH with XSPH; neighbor lists dominate);
//   cloth nodes: the jet scene's patch without fluid at 57 x 57 and 257 x 257 nodes (65.2 and 291.4 MB):
//   3,688 bytes a node (Bullet's nodes, links and faces, the coupling's mesh and broad phase);
//   the program itself (code, Bullet, OpenMP, OpenVDB) is the rest of the first run: 45 MB.
constexpr double kMemoryBytesPerParticle = 2000.0;
constexpr double kMemoryBytesPerClothNode = 3700.0;
constexpr double kMemoryBytesPerBoundaryParticle = 160.0;
constexpr double kMemoryBytesPerLatticePoint = 40.0;  // (distance, offset): 4 doubles, plus the sort's
constexpr double kMemoryBaseBytes = 45e6;
// The surface's grid (OpenVDB, every node within the kernel's reach of a particle) and mesh: the dam break
// at 2.5 cm with and without the surface effect (378.4 and 226.4 MB, 64,000 particles): 2,433 bytes a
// particle at cell_size = spacing / 2. It grows as (spacing / cell_size)^3, a volume.
constexpr double kSurfaceMemoryBytesPerParticleAtHalfSpacing = 2500.0;

/// Adds `value` to `figure`, keeping the key of the largest contribution.
void add(ResourceFigure& figure, double value, const std::string& key, double& largest) {
  figure.value += value;
  if (value > largest || figure.key.empty()) {
    largest = value;
    figure.key = key;
  }
}

/// A figure in a message: 3 digits, or every digit of a count below 10^15 (a count is exact there).
std::string show(double value) {
  char text[32];
  const bool whole = value == std::floor(value) && std::abs(value) < 1e15;
  std::snprintf(text, sizeof text, whole ? "%.0f" : "%.3g", value);
  return text;
}

/// Lattice points along an extent: what emit_box and sample_box_container lay, in double.
double lattice(double extent, double spacing, bool rounded) {
  const double n = rounded ? std::round(extent / spacing) : std::floor(extent / spacing + 1e-9);
  return std::max(1.0, n);
}

double mem_available_bytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string line;
  while (std::getline(meminfo, line)) {
    if (line.rfind("MemAvailable:", 0) == 0) {
      std::istringstream fields(line.substr(13));
      double kilobytes = 0;
      if (fields >> kilobytes) return kilobytes * 1024.0;
    }
  }
  return kInf;  // not Linux, or a kernel before 3.14: no limit we can know
}

double free_disk_bytes(const std::string& out_dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::path folder = fs::absolute(out_dir.empty() ? "." : out_dir, error);
  if (error) return kInf;
  // The folder may not exist yet: its nearest existing parent is on the file system it will be made in.
  while (!fs::exists(folder, error) && folder.has_parent_path() && folder != folder.parent_path())
    folder = folder.parent_path();
  struct statvfs info {};
  if (::statvfs(folder.c_str(), &info) != 0) return kInf;  // the run's own write reports the error
  return static_cast<double>(info.f_bavail) * static_cast<double>(info.f_frsize);
}

}  // namespace

ResourceEstimate estimate_resources(const SceneConfig& config) {
  ResourceEstimate e;
  const double s = config.fluid.particle_spacing;
  const std::string spacing = " with fluid.particle_spacing = " + show(s) + " m";
  const TimeSettings& time = config.time;

  double largest = 0;
  for (std::size_t i = 0; i < config.emitters.size(); ++i) {
    const EmitterSettings& emitter = config.emitters[i];
    const std::string key = "emitters[" + std::to_string(i) + "]";
    if (emitter.kind == EmitterSettings::Kind::BOX) {
      const Vec3 extent = emitter.box.max - emitter.box.min;
      add(e.particles,
          lattice(extent.x(), s, false) * lattice(extent.y(), s, false) * lattice(extent.z(), s, false),
          key + spacing, largest);
    } else {
      const NozzleEmitterSettings& n = emitter.nozzle;
      const double disc = std::max(1.0, std::round(M_PI * n.radius * n.radius / (s * s)));
      const double layers = std::max(0.0, time.duration - n.start_time) * n.speed / s + 1.0;
      add(e.particles, std::min(static_cast<double>(n.max_particles), disc * layers), key + spacing, largest);
      // NozzleEmitter's lattice: (2 rows + 1) x (2 columns + 1) points, rows and columns radius / pitch + 2.
      const double across = 2.0 * (n.radius / (0.93 * s) + 2.0) + 1.0;
      e.nozzle_lattice.value += across * across;
      e.nozzle_lattice.key = key + spacing;
    }
  }
  largest = 0;
  for (std::size_t i = 0; i < config.boundaries.size(); ++i) {
    const BoundarySettings& b = config.boundaries[i];
    const double layers = b.layers;
    double count = 0;
    if (b.kind == BoundarySettings::Kind::BOX) {
      const Vec3 extent = b.max - b.min;
      const double cx = lattice(extent.x(), s, true), cy = lattice(extent.y(), s, true),
                   cz = lattice(extent.z(), s, true);
      count =
          (cx + 2 * layers) * (cy + (b.open_top ? layers : 2 * layers)) * (cz + 2 * layers) - cx * cy * cz;
      // A box beyond the doubles (max 1e200) makes that inf - inf: it is an infinite count, not NaN.
      if (std::isnan(count)) count = kInf;
    } else {
      count = lattice(b.size[0], s, true) * lattice(b.size[1], s, true) * layers;
    }
    add(e.boundary_particles, count, "boundaries[" + std::to_string(i) + "]" + spacing, largest);
  }
  if (config.cloth && config.cloth->mesh == "patch") {
    const double nodes = static_cast<double>(config.cloth->nodes_x) * config.cloth->nodes_z;
    e.cloth_nodes = {nodes, "cloth.nodes"};
    e.cloth_faces = {2.0 * (config.cloth->nodes_x - 1) * (config.cloth->nodes_z - 1), "cloth.nodes"};
  }
  if (time.frame_rate > 0) e.frames = {std::floor(time.duration * time.frame_rate) + 1.0, "time.frame_rate"};

  // Output: every frame holds every particle (an upper bound: nozzles fill up during the run).
  const bool surface = config.has_effect("surface");
  const double cell = config.surface.resolved_cell_size(s);
  const double surface_scale = (0.5 * s / cell) * (0.5 * s / cell);
  double fluid_frame = kPlyHeaderBytes + e.particles.value * kPlyBytesPerParticle;
  if (surface)
    fluid_frame +=
        kPlyHeaderBytes + e.particles.value * kSurfaceBytesPerParticleAtHalfSpacing * surface_scale;
  double cloth_frame = 0;
  if (config.cloth) {
    cloth_frame = kPlyHeaderBytes + e.cloth_nodes.value * kPlyBytesPerClothNode +
                  e.cloth_faces.value * kPlyBytesPerFace;
  }
  e.output_bytes.value = e.frames.value * (fluid_frame + cloth_frame);
  if (e.frames.value > 0) {
    // Name what makes the frames large, or their number when each is small.
    if (fluid_frame >= cloth_frame && e.particles.value * kPlyBytesPerParticle > 1e6) {
      e.output_bytes.key = e.particles.key;
    } else if (cloth_frame > fluid_frame && cloth_frame > 1e6) {
      e.output_bytes.key = "cloth.nodes";
    } else {
      e.output_bytes.key = "time.frame_rate";
    }
  }

  // Memory: name the largest of the particles, the boundary, the cloth and the nozzle lattice.
  const double cube = (0.5 * s / cell) * surface_scale;
  const double fluid_memory =
      e.particles.value *
      (kMemoryBytesPerParticle + (surface ? kSurfaceMemoryBytesPerParticleAtHalfSpacing * cube : 0));
  const double parts[] = {fluid_memory, e.boundary_particles.value * kMemoryBytesPerBoundaryParticle,
                          e.cloth_nodes.value * kMemoryBytesPerClothNode,
                          e.nozzle_lattice.value * kMemoryBytesPerLatticePoint};
  const std::string keys[] = {e.particles.key, e.boundary_particles.key, e.cloth_nodes.key,
                              e.nozzle_lattice.key};
  e.memory_bytes.value = kMemoryBaseBytes;
  double most = -1;
  for (int k = 0; k < 4; ++k) {
    e.memory_bytes.value += parts[k];
    if (parts[k] > most) {
      most = parts[k];
      e.memory_bytes.key = keys[k];
    }
  }
  return e;
}

ResourceLimits machine_limits(const std::string& out_dir, double max_output_bytes) {
  ResourceLimits limits{mem_available_bytes(), kInf, kInf};
  if (!out_dir.empty()) {
    limits.disk_bytes = free_disk_bytes(out_dir);
    limits.output_bytes = max_output_bytes;
  }
  return limits;
}

void check_resources(const SceneConfig& config, const ResourceEstimate& e, const ResourceLimits& limits) {
  const auto what = [&](const ResourceFigure& figure) {
    if (figure.key == e.particles.key) return "about " + show(e.particles.value) + " fluid particles";
    if (figure.key == e.boundary_particles.key)
      return "about " + show(e.boundary_particles.value) + " boundary particles";
    if (figure.key == e.cloth_nodes.key) return show(e.cloth_nodes.value) + " cloth nodes";
    if (figure.key == e.nozzle_lattice.key)
      return "a nozzle lattice of about " + show(e.nozzle_lattice.value) + " points";
    return std::string("each frame's files");
  };
  const std::string source = " (" + config.source + ")";
  // NaN (inf x 0) counts as too much: `!(a <= b)`.
  if (!(e.memory_bytes.value <= limits.memory_bytes)) {
    throw SceneError(e.memory_bytes.key + ": " + what(e.memory_bytes) + " need about " +
                     show(e.memory_bytes.value) + " bytes of memory, more than the " +
                     show(limits.memory_bytes) + " bytes " + limits.memory_of + source);
  }
  const auto output = [&](const std::string& limit) {
    const double frames = std::max(e.frames.value, 1.0);
    return SceneError(e.output_bytes.key + ": " + show(e.frames.value) + " frames of about " +
                      show(e.output_bytes.value / frames) + " bytes (" + what(e.output_bytes) +
                      ") make about " + show(e.output_bytes.value) + " bytes of output, more than " + limit +
                      source);
  };
  if (!(e.output_bytes.value <= limits.output_bytes))
    throw output("--max-output " + show(limits.output_bytes) + " bytes");
  if (!(e.output_bytes.value <= limits.disk_bytes))
    throw output("the " + show(limits.disk_bytes) + " bytes free on the disk of --out");
}

ResourceEstimate check_scene_resources(const SceneConfig& config, const std::string& out_dir,
                                       double max_output_bytes) {
  const ResourceEstimate estimate = estimate_resources(config);
  check_resources(config, estimate, machine_limits(out_dir, max_output_bytes));
  return estimate;
}

}  // namespace drench
