#include <drench/scene/reconstruct_run.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <system_error>
#include <utility>

#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>
#include <drench/common/progress_line.hpp>
#include <drench/common/stopwatch.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/io/ply_reader.hpp>
#include <drench/scene/frame_files.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/surface/surface_reconstruction.hpp>

namespace drench {

namespace {

namespace fs = std::filesystem;

/// One saved frame's files; `cloth` is empty when the run had no cloth.
struct FrameFiles {
  std::int64_t number = 0;
  fs::path fluid, cloth, surface;
};

/// The fluid frames in `frames_dir` in frame order, each with the names of its cloth and surface files.
std::vector<FrameFiles> list_frames(const fs::path& frames_dir) {
  std::error_code ec;
  if (!fs::is_directory(frames_dir, ec)) {
    throw IoError(frames_dir.string() +
                  ": missing; drench reconstruct reads the frames/ folder of a `drench run --out` folder");
  }
  std::vector<FrameFiles> frames;
  bool cloth = false;
  for (const fs::directory_entry& entry : fs::directory_iterator(frames_dir, ec)) {
    const std::string name = entry.path().filename().string();
    std::string digits;
    if (frame_number(name, "cloth_", digits)) cloth = true;
    if (!frame_number(name, "fluid_", digits)) continue;
    FrameFiles frame;
    frame.number = std::stoll(digits);
    frame.fluid = entry.path();
    frame.cloth = frames_dir / ("cloth_" + digits + ".ply");
    frame.surface = frames_dir / ("surface_" + digits + ".ply");
    frames.push_back(std::move(frame));
  }
  if (ec) throw IoError(frames_dir.string() + ": cannot list: " + ec.message());
  if (frames.empty()) throw IoError(frames_dir.string() + ": no fluid_NNNN.ply frames");
  std::sort(frames.begin(), frames.end(), [](const FrameFiles& a, const FrameFiles& b) {
    return a.number != b.number ? a.number < b.number : a.fluid < b.fluid;
  });
  for (FrameFiles& frame : frames) {
    if (!cloth) {
      frame.cloth.clear();
    } else if (!fs::exists(frame.cloth, ec)) {
      // Without its cloth the frame's surface would cross the cloth where the run's did not.
      throw IoError(frame.cloth.string() + ": missing, while the run saved the cloth of other frames");
    }
  }
  return frames;
}

/// A PLY file that must be a triangle mesh (a cloth frame, the obstacles).
PlyData read_mesh_ply(const fs::path& path) {
  PlyData data = read_ply(path.string());
  if (!data.has_faces) throw IoError(path.string() + ": has no face element; expected a triangle mesh");
  return data;
}

/// Adds "surface" to the document's `effects` (creating the list) unless it is there; leaves a document of
/// the wrong shape to parse_scene, which says what is wrong with it.
void add_surface_effect(nlohmann::json& document) {
  if (!document.is_object()) return;
  if (!document.contains("effects")) document["effects"] = nlohmann::json::array();
  nlohmann::json& effects = document["effects"];
  if (!effects.is_array()) return;
  if (std::find(effects.begin(), effects.end(), nlohmann::json("surface")) == effects.end())
    effects.push_back("surface");
}

}  // namespace

ReconstructResult reconstruct_run(const ReconstructOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  const fs::path dir(options.run_dir);

  // The settings: the run's scene with the overrides, validated as `drench run` validates them.
  const fs::path scene_path = dir / "scene.json";
  std::error_code ec;
  if (!fs::exists(scene_path, ec)) {
    throw IoError(scene_path.string() +
                  ": missing; drench reconstruct needs the scene.json that drench run writes into its --out "
                  "folder");
  }
  nlohmann::json document = read_scene_document(scene_path.string());
  add_surface_effect(document);
  for (const std::string& assignment : options.overrides) {
    try {
      apply_override(document, assignment);
    } catch (const SceneError& e) {
      throw SceneError(std::string(e.what()) + " (" + scene_path.string() + ")");
    }
  }
  const SceneConfig config = parse_scene(document, scene_source(scene_path.string(), options.overrides));
  const Scalar spacing = config.fluid.particle_spacing;

  // Every input read and checked once before the first write, so that bad input writes nothing. Reading
  // twice costs little beside the reconstruction, and holding every frame could take more memory than the
  // run did.
  double read_seconds = 0, surface_seconds = 0, audit_seconds = 0, write_seconds = 0;
  const std::vector<FrameFiles> frames = list_frames(dir / "frames");
  PlyData obstacles_ply;
  const fs::path obstacles_path = dir / "obstacles.ply";
  const bool has_obstacles = fs::exists(obstacles_path, ec);
  {
    ScopedTimer timer(read_seconds);
    if (has_obstacles) obstacles_ply = read_mesh_ply(obstacles_path);
    for (const FrameFiles& frame : frames) {
      (void)read_ply(frame.fluid.string());
      if (!frame.cloth.empty()) (void)read_mesh_ply(frame.cloth);
    }
  }

  // The new surfaces go beside the old ones and replace them only once all are made: an interrupted or
  // failed reconstruction must not leave surfaces at two cell sizes under a reconstruct.json of one.
  const fs::path staging = dir / ("reconstruct.tmp-" + std::to_string(::getpid()));
  fs::remove_all(staging, ec);
  fs::create_directory(staging, ec);
  if (ec) throw IoError(staging.string() + ": cannot create: " + ec.message());
  struct RemoveStaging {
    const fs::path& path;
    ~RemoveStaging() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  } remove_staging{staging};

  // Checked before each frame and once after the last, so that a signal during the last frame discards the
  // surfaces too: the surfaces made so far go with the staging folder, and the result counts nothing.
  const auto stop_requested = [&] { return options.stop && options.stop->load(std::memory_order_relaxed); };
  const auto stopped = [&] {
    ReconstructResult interrupted;
    interrupted.interrupted = true;
    interrupted.wall_seconds = wall();
    return interrupted;
  };
  ReconstructResult result;
  ProgressLine progress(options.progress, frames.size());
  for (const FrameFiles& frame : frames) {
    if (stop_requested()) return stopped();
    PlyData fluid, cloth;
    {
      ScopedTimer timer(read_seconds);
      fluid = read_ply(frame.fluid.string());
      if (!frame.cloth.empty()) cloth = read_mesh_ply(frame.cloth);
    }
    // The run's order: the cloth, then the obstacles (all in one mesh here, which changes no result: a node
    // is reset, or a particle occluded, when any triangle says so).
    std::vector<SurfaceObstacle> obstacles;
    if (!frame.cloth.empty()) obstacles.push_back({&cloth.positions, &cloth.triangles});
    if (has_obstacles) obstacles.push_back({&obstacles_ply.positions, &obstacles_ply.triangles});
    SurfaceStats stats;
    const SurfaceMesh mesh = reconstruct_surface(fluid.positions, spacing, config.surface, obstacles, &stats);
    surface_seconds += stats.seconds;
    {
      ScopedTimer timer(audit_seconds);
      result.surface_intersections += count_surface_intersections(mesh, obstacles);
    }
    result.surface_triangles += mesh.triangles.size();
    {
      ScopedTimer timer(write_seconds);
      write_surface_ply((staging / frame.surface.filename()).string(), mesh);
    }
    ++result.frames;
    progress.update(static_cast<std::size_t>(result.frames), wall());
  }

  if (stop_requested()) return stopped();

  // The swap: a rename per file (no signal is checked from here on), then reconstruct.json, last.
  for (const FrameFiles& frame : frames) {
    fs::rename(staging / frame.surface.filename(), frame.surface, ec);
    if (ec)
      throw IoError("cannot move " + (staging / frame.surface.filename()).string() + " to " +
                    frame.surface.string() + ": " + ec.message());
  }

  nlohmann::json& r = result.report;
  r["frames"] = result.frames;
  r["surface_triangles"] = result.surface_triangles;
  r["surface_intersections"] = result.surface_intersections;
  r["cell_size"] = config.surface.resolved_cell_size(spacing);
  r["contact_aware"] = config.surface.contact_aware;
  r["contact_offset"] = config.surface.resolved_contact_offset(spacing);
  r["timings_s"] = {{"surface", surface_seconds},
                    {"surface_audit", audit_seconds},
                    {"read", read_seconds},
                    {"write", write_seconds}};
  r["threads"] = thread_count();
  r["version"] = DRENCH_VERSION;
  r["scene_sha256"] = sha256_hex(canonical_scene_text(document));
  result.wall_seconds = wall();
  r["wall_s"] = result.wall_seconds;
  write_file_atomic((dir / "reconstruct.json").string(), r.dump(2) + "\n");
  return result;
}

}  // namespace drench
