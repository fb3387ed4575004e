#pragma once
/// A drench run folder's frames and settings as the comparison with a reference reads them
/// (compare/run_comparison.hpp), and the reference run's record (reference.json, `drench reference`).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include <drench/compare/run_comparison.hpp>
#include <drench/scene/scene_config.hpp>

namespace drench {

/// The simulated time at which `drench run` writes frame `n` (unit: s): at the end of the first step whose
/// time reaches n / frame_rate (scene_runner.cpp), k dt with k = ceil(n / (frame_rate dt) - 1e-3); with
/// `time.adaptive`, whose steps are cut to land on every frame, n / frame_rate exactly.
/// Precondition: time.frame_rate > 0.
double frame_time(const TimeSettings& time, std::int64_t n);

/// The frames of the run in `dir`: its `scene.json` (the particle mass, rest_density x spacing^3, and the
/// frames' times) and `frames/fluid_NNNN.ply`, with `frames/cloth_NNNN.ply` when the scene has a cloth,
/// and when it has kill regions the water they removed by each frame (`summary.json`'s
/// `killed_kg_by_frame`).
/// @throws IoError naming the file: no scene.json or an invalid one, no frames/ or no fluid frame, a frame
///         numbering with a gap (the first missing file named), a fluid frame without its cloth frame; with
///         kill regions, a summary.json that is missing, unreadable or has no killed_kg_by_frame entry for
///         a frame.
RunFrames read_run_frames(const std::string& dir);

/// What `drench reference` makes a scene's reference run of: each setting that bounds the error, made finer.
struct ReferenceRefinement {
  double dt_divisor = 8;             ///< time.dt (and with time.adaptive time.dt_min) divided by this, >= 1
  double eta_divisor = 10;           ///< fluid.pcisph.eta and fluid.dfsph.eta divided by this, >= 1
  double cloth_substeps_factor = 4;  ///< cloth.substeps multiplied by this, >= 1 (a whole number)
  bool double_precision = true;      ///< fluid.{pcisph,dfsph,pbf}.precision "double"
};

/// The `--set` assignments that make `scene` (a scene document with the user's overrides applied, valid)
/// its reference: e.g. "time.dt=0.000125", "fluid.pcisph={...}" (a whole object, as an override cannot
/// make a missing key's parent), "cloth.substeps=16".
/// @throws SceneError when a divisor or factor is < 1 or the factor is not a whole number.
std::vector<std::string> reference_overrides(const nlohmann::json& scene,
                                             const ReferenceRefinement& refinement);

}  // namespace drench
