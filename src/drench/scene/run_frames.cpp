#include <drench/scene/run_frames.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include <drench/common/error.hpp>
#include <drench/scene/frame_files.hpp>
#include <drench/scene/scene_loader.hpp>

namespace drench {

namespace fs = std::filesystem;

namespace {

/// `path=value` for `--set` where every key of `path` up to the last that `document` has exists: the
/// first missing key gets the rest of the path as nested objects, since an override cannot make a parent.
std::string assignment(const nlohmann::json& document, const std::vector<std::string>& path,
                       const nlohmann::json& value) {
  const nlohmann::json* node = &document;
  std::string key;
  std::size_t i = 0;
  for (; i + 1 < path.size(); ++i) {
    if (!node->is_object() || !node->contains(path[i])) break;
    node = &(*node)[path[i]];
    key += (key.empty() ? "" : ".") + path[i];
  }
  nlohmann::json nested = value;
  for (std::size_t j = path.size() - 1; j > i; --j)
    nested = nlohmann::json{{path[j], nested}};
  key += (key.empty() ? "" : ".") + path[i];
  return key + "=" + nested.dump();
}

}  // namespace

double frame_time(const TimeSettings& time, std::int64_t n) {
  const double exact = static_cast<double>(n) / time.frame_rate;
  if (time.adaptive) return exact;
  return std::ceil(exact / time.dt - 1e-3) * time.dt;
}

RunFrames read_run_frames(const std::string& dir) {
  const fs::path folder = dir;
  const fs::path scene_file = folder / "scene.json";
  if (!fs::is_regular_file(scene_file))
    throw IoError(scene_file.string() + ": missing; " + dir + " is not the --out folder of a drench run");
  SceneConfig config;
  try {
    config = parse_scene(read_scene_document(scene_file.string()), scene_file.string());
  } catch (const SceneError& e) {
    throw IoError(scene_file.string() + ": not a valid scene: " + e.what());
  }
  if (!(config.time.frame_rate > 0))
    throw IoError(scene_file.string() + ": time.frame_rate is 0, so the run saved no frames to compare");
  RunFrames run;
  run.dir = dir;
  run.particle_spacing = config.fluid.particle_spacing;
  run.particle_mass = config.fluid.rest_density * std::pow(config.fluid.particle_spacing, 3);

  const fs::path frames = folder / "frames";
  std::error_code error;
  std::map<std::int64_t, std::string> fluid, cloth;
  for (fs::directory_iterator it(frames, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    std::string digits;
    if (frame_number(name, "fluid_", digits)) fluid[std::stoll(digits)] = it->path().string();
    if (frame_number(name, "cloth_", digits)) cloth[std::stoll(digits)] = it->path().string();
  }
  if (error) throw IoError(frames.string() + ": cannot list the frames: " + error.message());
  if (fluid.empty()) throw IoError(frames.string() + ": no frame (fluid_0000.ply)");
  const bool has_cloth = config.cloth.has_value() || !cloth.empty();
  auto file_name = [&](const char* what, std::int64_t n) {
    char name[40];
    std::snprintf(name, sizeof name, "%s_%04lld.ply", what, static_cast<long long>(n));
    return (frames / name).string();
  };
  const std::int64_t count = fluid.rbegin()->first + 1;
  for (std::int64_t n = 0; n < count; ++n) {
    if (!fluid.count(n)) throw IoError(file_name("fluid", n) + ": missing, though a later frame exists");
    run.fluid_files.push_back(fluid[n]);
    if (has_cloth) {
      if (!cloth.count(n)) throw IoError(file_name("cloth", n) + ": missing beside " + fluid[n]);
      run.cloth_files.push_back(cloth[n]);
    }
    run.times.push_back(frame_time(config.time, n));
  }
  if (!config.kill_regions.empty()) {
    // The water the kill regions removed is in no frame; the run's summary records it per frame.
    const fs::path summary_file = folder / "summary.json";
    nlohmann::json summary;
    try {
      std::ifstream in(summary_file);
      if (!in) throw IoError("missing");
      summary = nlohmann::json::parse(in);
    } catch (const std::exception& e) {
      throw IoError(summary_file.string() + ": cannot read the water the kill regions removed: " + e.what());
    }
    const nlohmann::json killed = summary.value("killed_kg_by_frame", nlohmann::json());
    if (!killed.is_array() || killed.size() < run.fluid_files.size()) {
      throw IoError(summary_file.string() + ": killed_kg_by_frame " +
                    (killed.is_array()
                         ? "has " + std::to_string(killed.size()) + " entries for " +
                               std::to_string(run.fluid_files.size()) + " frames"
                         : std::string("is missing (a drench before issue 42's kill counts?)")) +
                    ": the water the kill regions removed is unknown");
    }
    for (std::size_t n = 0; n < run.fluid_files.size(); ++n)
      run.killed_kg.push_back(killed[n].is_number() ? killed[n].get<double>() : NAN);
  }
  return run;
}

std::vector<std::string> reference_overrides(const nlohmann::json& scene,
                                             const ReferenceRefinement& refinement) {
  for (const auto& [name, value] :
       {std::pair{"dt divisor", refinement.dt_divisor}, std::pair{"eta divisor", refinement.eta_divisor},
        std::pair{"cloth sub-step factor", refinement.cloth_substeps_factor}}) {
    if (!(value >= 1))
      throw SceneError(std::string("reference: the ") + name + " must be >= 1, got " + format_number(value));
  }
  if (refinement.cloth_substeps_factor != std::floor(refinement.cloth_substeps_factor))
    throw SceneError("reference: the cloth sub-step factor must be a whole number, got " +
                     format_number(refinement.cloth_substeps_factor));
  // The effective values, defaults included, are what is refined.
  const SceneConfig config = parse_scene(scene, "the reference's scene");
  std::vector<std::string> result;
  // Each assignment against the document with the earlier ones applied: the second key of an object that
  // the first one made must not replace it.
  nlohmann::json document = scene;
  auto add = [&](const std::vector<std::string>& path, const nlohmann::json& value) {
    result.push_back(assignment(document, path, value));
    apply_override(document, result.back());
  };
  add({"time", "dt"}, config.time.dt / refinement.dt_divisor);
  if (config.time.adaptive) add({"time", "dt_min"}, config.time.dt_min / refinement.dt_divisor);
  add({"fluid", "pcisph", "eta"}, config.fluid.pcisph.eta / refinement.eta_divisor);
  add({"fluid", "dfsph", "eta"}, config.fluid.dfsph.eta / refinement.eta_divisor);
  if (refinement.double_precision) {
    add({"fluid", "pcisph", "precision"}, "double");
    add({"fluid", "dfsph", "precision"}, "double");
    add({"fluid", "pbf", "precision"}, "double");
  }
  if (config.cloth)
    add({"cloth", "substeps"}, static_cast<int>(config.cloth->substeps * refinement.cloth_substeps_factor));
  return result;
}

}  // namespace drench
