#pragma once
/// Runs a Simulation to its end while writing frames, a progress line and summary.json: what `drench run`
/// does, available to tests and embedding programs.

#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include <drench/scene/simulation.hpp>

namespace drench {

/// What run_scene does and where. run_scene writes into `out_dir` whatever it holds; `drench run` first makes
/// the folder its own (output_folder.hpp: refused when it holds other files, `--overwrite`, the manifest).
struct RunOptions {
  std::string out_dir;                    ///< receives frames/ and summary.json; created if missing
  std::optional<std::int64_t> max_steps;  ///< stop after this many steps (the `--steps` flag)
  std::string scene_sha256;               ///< reported as `scene_sha256`
  bool progress = true;                   ///< print a progress line when stderr is a terminal
  /// The effective scene (the file after `--set`), written as `scene.json` before the first frame so that
  /// `drench reconstruct` can redo the surface later; not written when null.
  nlohmann::json scene_document;
  /// Checked between steps: once it is true the run ends after the step under way (and its frame, if due),
  /// with summary.json's `status` "interrupted". `drench run` sets it from SIGINT and SIGTERM; null: never.
  const std::atomic<bool>* stop = nullptr;
};

struct RunResult {
  nlohmann::json summary;    ///< what summary.json holds
  StepStatus status;         ///< all flags raised during the run
  bool interrupted = false;  ///< RunOptions::stop ended the run before its end
  /// The simulation's effect counts with the surface's (constructed 1 with the `surface` effect, a pass per
  /// frame reconstructed).
  EffectCounters effects;
};

/// Steps `simulation` until it finishes (or max_steps), writing `scene.json` first (when options has a
/// scene_document), then `frames/fluid_NNNN.ply` at the scene's frame rate (frame 0 is the initial state)
/// and `summary.json` at the end, each through a temporary name. The `surface` effect reconstructs each
/// frame from the positions as the frame files hold them (frame_files.hpp, positions_as_saved). A step with
/// a non-finite state ends the run early; the summary is still written and says so in `status`, as does a
/// run that `options.stop` ended ("interrupted").
/// @throws IoError when out_dir or a file cannot be written.
RunResult run_scene(Simulation& simulation, const RunOptions& options);

/// The summary of a run so far; keys are documented in docs/output.md. A figure that is not finite (NaN,
/// +-inf) is null, as JSON has no such numbers, and `non_finite` maps its path (e.g. "energy_drift") to
/// "nan", "inf" or "-inf", so that a reader can tell why it is null.
/// @param surface  the `surface` effect's counts, which the run loop keeps (zero: no surface)
nlohmann::json make_summary(const Simulation& simulation, double wall_seconds,
                            const std::string& scene_sha256, const StepStatus& status,
                            const EffectCounter& surface = {});

/// summary.json's rule for figures that are not finite: each becomes null (JSON has no NaN or infinity)
/// and `summary["non_finite"]` maps its path ("energy_drift", "density_error.max", "a[2]") to "nan", "inf"
/// or "-inf"; notes already there are kept. make_summary applies it; so does run_scene after adding its keys.
void apply_non_finite_rule(nlohmann::json& summary);

}  // namespace drench
