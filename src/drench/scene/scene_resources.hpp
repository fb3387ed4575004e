#pragma once
/// What a scene will take (particles, cloth nodes, frames, bytes of output and memory), estimated from its
/// settings alone, and the check of that estimate against the machine's memory and disk and the run's
/// output limit: a scene that cannot fit is refused, naming the key, before anything is allocated or
/// written (1e-9 m spacing took 14.4 GB in 20 s; a frame rate of 1e308 wrote 56 GB).

#include <cstdint>
#include <string>

#include <drench/scene/scene_config.hpp>

namespace drench {

/// The default of `drench run --max-output` (unit: bytes): 10 GiB, fifty times the jet demo's 0.2 GB.
inline constexpr double kDefaultMaxOutputBytes = 10.0 * (1u << 30);

/// One figure of an estimate with the scene key that contributes most to it, for messages.
struct ResourceFigure {
  double value = 0.0;  ///< a count or bytes; may be inf for settings whose product overflows
  std::string key;     ///< e.g. "emitters[1]", "cloth.nodes", "time.frame_rate"; "" when value is 0
};

/// A scene's resources, estimated before it is built. Counts are doubles: a hostile scene's counts do not
/// fit any integer, and the comparison with a limit must still be right.
struct ResourceEstimate {
  ResourceFigure particles;           ///< fluid particles at most: box lattices plus nozzle budgets
  ResourceFigure boundary_particles;  ///< particles sampled on box and plane boundaries
  ResourceFigure nozzle_lattice;      ///< candidate points of the nozzle discs, built once
  ResourceFigure cloth_nodes;         ///< patch nodes (an OBJ cloth's are not counted: its file is not read)
  ResourceFigure cloth_faces;         ///< patch triangles
  ResourceFigure frames;              ///< frames written: floor(duration x frame_rate) + 1, 0 without frames
  ResourceFigure output_bytes;        ///< the frames' PLY files (unit: bytes)
  ResourceFigure memory_bytes;        ///< peak resident memory of the run (unit: bytes)
};

/// What a run may take (unit: bytes); infinity where there is no limit.
struct ResourceLimits {
  double memory_bytes;  ///< the machine's MemAvailable (/proc/meminfo)
  double disk_bytes;    ///< free space where the output goes (statvfs)
  double output_bytes;  ///< `drench run --max-output`
  /// Whose memory memory_bytes is, for a message ("bytes <memory_of>").
  std::string memory_of = "available (MemAvailable)";
};

/// Estimates a validated scene's resources (parse_scene's result). Cheap: arithmetic on the settings only.
ResourceEstimate estimate_resources(const SceneConfig& config);

/// The limits of a run writing into `out_dir` on this machine: MemAvailable, the free space of the file
/// system that holds out_dir (or its nearest existing parent), and `max_output_bytes`.
/// @param out_dir  the run's output folder; "" for a run that writes nothing (the viewer): no disk or
///        output limit
/// @param max_output_bytes  > 0, or infinity; ignored without out_dir
ResourceLimits machine_limits(const std::string& out_dir, double max_output_bytes);

/// Refuses an estimate beyond `limits`.
/// @throws SceneError naming the key that contributes most, the estimate and the limit, e.g.
///         `emitters[0] with fluid.particle_spacing = 1e-09 m: about 1e+27 particles need about 2.3e+29
///         bytes of memory, more than the 2.2e+10 bytes available (MemAvailable) (x.json)`.
void check_resources(const SceneConfig& config, const ResourceEstimate& estimate,
                     const ResourceLimits& limits);

/// estimate_resources, machine_limits and check_resources in one: what `drench run`, `view` and `sweep`
/// call before building the Simulation.
/// @throws SceneError as check_resources; IoError when /proc/meminfo cannot be read
ResourceEstimate check_scene_resources(const SceneConfig& config, const std::string& out_dir,
                                       double max_output_bytes);

}  // namespace drench
