#pragma once
/// `drench reconstruct`: the surface reconstruction of sec. 4 (surface/surface_reconstruction.hpp) redone
/// afterwards from a run's saved frames, with the run's settings or others, as users run splashsurf on saved
/// particles.

#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace drench {

struct ReconstructOptions {
  std::string run_dir;                 ///< a `drench run --out` folder: scene.json, frames/, obstacles.ply
  std::vector<std::string> overrides;  ///< `--set` assignments applied to the saved scene.json, in order
  bool progress = true;                ///< print a progress line when stderr is a terminal
  /// Checked between frames: once true, the new surfaces made so far are discarded and the run folder is
  /// left as it was (`drench reconstruct` sets it from SIGINT and SIGTERM); null: never.
  const std::atomic<bool>* stop = nullptr;
};

struct ReconstructResult {
  nlohmann::json report;  ///< what reconstruct.json holds (docs/output.md)
  std::int64_t frames = 0;
  std::uint64_t surface_triangles = 0;      ///< summed over the frames
  std::uint64_t surface_intersections = 0;  ///< summed over the frames (count_surface_intersections)
  double wall_seconds = 0.0;                ///< the whole command, reading and checking included (unit: s)
  /// `stop` ended it: nothing in the run folder changed, and the counts and `report` are empty.
  bool interrupted = false;
};

/// Reconstructs the surface of every frame a run saved: for each `frames/fluid_NNNN.ply` in frame order,
/// with `frames/cloth_NNNN.ply` (when the run had a cloth) and `obstacles.ply` (when it had obstacles) as
/// the triangles the surface respects, it makes the frame's surface and counts its crossings of those
/// triangles. The surfaces are written into `reconstruct.tmp-PID/` beside `frames/`; only when every frame
/// is done are they moved to `frames/surface_NNNN.ply` (replacing the run's, a rename each), and
/// `reconstruct.json` is written last. So an error or a stop midway leaves the earlier surfaces and
/// reconstruct.json as they were, consistent with each other.
///
/// The settings are the run's `scene.json` with `options.overrides` applied as `drench run --set` applies
/// them; "surface" is added to its `effects` first when missing, so that `surface.*` may be set for a run
/// made without the effect. Given the same settings, the surface files are byte for byte those the run's
/// `surface` effect wrote (it reconstructs from the positions as saved).
///
/// Everything is read and checked before anything is written: the scene, every frame file and the
/// obstacles; bad input writes nothing.
/// @throws IoError naming the file: `scene.json` or the frames are missing, a cloth frame is missing while
///         others exist, a PLY file is malformed (io/ply_reader.hpp), or a file cannot be written.
/// @throws SceneError for a scene or override the loader rejects (naming the key, value and file).
ReconstructResult reconstruct_run(const ReconstructOptions& options);

}  // namespace drench
