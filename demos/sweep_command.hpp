#pragma once
/// `drench sweep`: a scene run over a grid of settings, or each setting varied alone, one `drench run`
/// process per run, into DIR/sweep.csv, DIR/report.md and DIR/pareto.png (issue 28).
#include <string>
#include <vector>

#include <drench/scene/sweep.hpp>

namespace drench {

struct SweepOptions {
  std::string program;                 ///< the drench executable the runs start (this one)
  std::string scene_path;              ///< the scene file
  std::string out_dir;                 ///< DIR: runs/NNN/, sweep.csv, report.md, pareto.png
  std::vector<std::string> overrides;  ///< `--set`s applied to every run, before its own settings
  std::vector<SweepAxis> axes;         ///< `--vary`s
  std::vector<SweepCase> cases;        ///< `--case`s
  bool one_at_a_time = false;          ///< each axis varied alone around the scene, not the grid
  int repeats = 1;                     ///< runs per setting, >= 1
  int jobs = 1;                        ///< runs side by side, >= 1
  int threads = 0;                     ///< threads per run; 0: thread_count() shared among the jobs
  double timeout_s = 0;  ///< a run's wall time limit (unit: s), after which it is killed; 0: none
  /// The scene's speed bound (unit: m/s), >= 0; 0: none. A run whose fastest particle or cloth node went
  /// faster (summary.json's max_speed_mps) ended "ok" yet threw water no flow of the scene makes: it is drawn
  /// apart and never on the Pareto front, as a run that leaked or stopped (issue 42). Its row is unchanged.
  double speed_bound_mps = 0;
  /// The column the Pareto plot uses: of sweep_columns(), or with a reference of reference_columns(); empty:
  /// `cloth_rms_m` with a reference that has a cloth, `front_m` with one without, else `density_error_mean`.
  std::string error_key;
  /// A `drench reference` folder (reference.json, scene.json, frames/): every run is compared with it and
  /// its row gains reference_columns(). Empty: none.
  std::string reference_dir;
  ComparisonSettings comparison;  ///< how the runs are compared with the reference
  std::string command_line;       ///< as the user typed it, for the report
  bool quiet = false;             ///< no line per finished run
  bool overwrite = false;  ///< replace an earlier sweep in out_dir (output_folder.hpp); else it must be empty
};

/// Runs the sweep and writes its files; sweep.csv is rewritten (atomically) after every finished run, so an
/// interrupted sweep keeps the rows it has. A run that fails or blows up is a row with its status. The runs
/// go into runs/NNN/ with their output in runs/NNN.log. SIGINT or SIGTERM (stop_signal.hpp) is passed on
/// once to the runs under way, which end as "interrupted"; no further run starts (their rows say so), and the
/// report is written for what ran.
/// With a reference, a run that cannot be compared with it (compare_runs' errors: a missing frame, other
/// frame times) is a row whose status says why, not "ok".
/// @return the number of runs whose status is not "ok"
/// @throws SceneError when the scene, an override or a setting is invalid (before anything is written),
///         `error_key` is not a column, the reference is of another scene (its scene_sha256 differs from the
///         sweep's scene with its `--set`s), or a setting's frames would not be at the reference's times;
///         IoError when the reference folder has no readable reference.json or frames (read_run_frames'
///         errors), when DIR cannot be written, is not empty (without `overwrite`) or holds files an earlier
///         sweep did not write, or a run cannot be started.
int run_sweep(const SweepOptions& options);

}  // namespace drench
