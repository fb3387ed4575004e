#pragma once
/// The output folder of `drench run` and `drench sweep`: a folder of its own, never one that holds another
/// program's files or an earlier run's frames to be mixed with this run's. The first file written is a
/// manifest, `drench_run.json`, which lists (as patterns) every file drench writes there; `--overwrite`
/// removes exactly what an earlier manifest lists, and nothing when the folder holds anything else.

#include <string>
#include <vector>

namespace drench {

/// The manifest's name inside an output folder.
inline constexpr const char* kOutputManifest = "drench_run.json";

/// What `drench run` writes into its --out folder, and what `drench reconstruct` and `drench render` add
/// there later, as patterns relative to the folder ('/'-separated; `*` matches any characters within one
/// name). The manifest itself is the first.
const std::vector<std::string>& run_output_patterns();

/// What `drench sweep` writes into its --out folder: its own files, each run's log and, under
/// `runs/*/`, each run's files (run_output_patterns()).
const std::vector<std::string>& sweep_output_patterns();

/// What `drench render --out DIR2` writes into DIR2: its manifest, `frame_*.png` and `video.mp4`.
const std::vector<std::string>& render_output_patterns();

/// Checks, writing nothing, that every entry in `dir` (when it exists) is a file `patterns` cover: the folder
/// drench writes into inside an output folder it owns, such as DIR/render, must not hold another program's
/// files, which it would overwrite or mix with its own.
/// @param command  what is to write there, for the message, e.g. "render"
/// @throws IoError naming the first entry (in name order) that no pattern covers.
void check_folder_holds_only(const std::string& dir, const std::string& command,
                             const std::vector<std::string>& patterns);

/// Whether `relative` (a path inside an output folder, '/'-separated, e.g. "frames/fluid_0001.ply") is a
/// file `pattern` covers: it matches the pattern, or it is a temporary of such a file (`NAME.tmp-PID`, what
/// io/atomic_file.hpp leaves when killed mid-write).
bool output_pattern_covers(const std::string& pattern, const std::string& relative);

/// Refuses an output path that cannot be a folder, before anything is read or written: an empty path (which
/// would put the files into the working directory) or an existing file that is not a folder.
/// @param flag  the option that named it, for the message, e.g. "--out"
/// @throws IoError naming the flag and the value.
void check_output_path(const std::string& dir, const std::string& flag);

/// Checks, writing nothing, that `dir` can take a new output of `command`: it is missing or empty, or, with
/// `overwrite`, it holds an earlier output of the same command (its manifest says so) and every entry in it
/// is covered both by that manifest and by `patterns`. The manifest alone is not trusted: a run's
/// --overwrite would have deleted a sweep's folder, and a forged manifest listing "*" any file.
/// @param command  what is to write the folder, e.g. "run" or "sweep"
/// @param patterns  what that command writes (run_output_patterns(), sweep_output_patterns())
/// @throws IoError naming the flag, the folder and one file found: without `overwrite` the first entry (in
///         name order) of a non-empty folder; with it, the first entry not covered, or the manifest when it
///         is missing, unreadable or another command's. check_output_path's errors too.
void check_output_folder(const std::string& dir, const std::string& flag, const std::string& command,
                         const std::vector<std::string>& patterns, bool overwrite);

/// Makes `dir` ready for a new output: check_output_folder; then, with `overwrite`, removes every file it
/// found covered (and the folders they leave empty); then creates `dir` and writes the new
/// manifest: `{"drench_version": ..., "command": command, "files": patterns}`. A refusal deletes nothing.
/// @param command  what writes the folder, e.g. "run" or "sweep"
/// @param patterns  what it writes (run_output_patterns(), sweep_output_patterns())
/// @throws IoError as check_output_folder, or when a file cannot be removed or written.
void prepare_output_folder(const std::string& dir, const std::string& flag, const std::string& command,
                           const std::vector<std::string>& patterns, bool overwrite);

}  // namespace drench
