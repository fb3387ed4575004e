#include <drench/scene/scene_loader.hpp>

#include <openssl/evp.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include <drench/common/error.hpp>
#include <drench/common/file_text.hpp>
#include <drench/scene/effect_registry.hpp>
#include <drench/scene/json_reader.hpp>
#include <drench/scene/load_sections.hpp>

namespace drench {
namespace {

using loader::join;
using loader::json;
using loader::kMaxJsonDepth;
using loader::kNonNegative;
using loader::kPositive;
using loader::Node;
using loader::ObjectReader;
using loader::show;

/// Largest step or frame count a scene may ask for: 2^53, the last integer a double holds exactly (the
/// counts are computed from doubles and kept as int64).
constexpr double kMaxCount = 9007199254740992.0;

/// Masses (particles, cloth nodes) must lie within [kMassMin, kMassMax] kg: then their inverses and the
/// products of any two of them (impulses, momenta, energies) stay finite doubles, far from underflow.
constexpr double kMassMin = 1e-150;
constexpr double kMassMax = 1e150;

/// A particle spacing must span at least 2^17 units in the last place of the coordinates it is laid at
/// (spacing >= 2^-35 |x|): a step moves a particle by a small fraction of the spacing, which must still
/// change its position, and lattice points one spacing apart must stay apart (at 1e-12 m near 0.3 m the
/// nozzle emitted nothing).
constexpr double kSpacingResolution = 0x1p-35;

/// The smallest surface.cell_size relative to fluid.particle_spacing: 1/16 gives 4096 cells per particle
/// volume already; below it a frame's grid outgrows memory and OpenVDB's int32 coordinates.
constexpr double kMinCellPerSpacing = 1.0 / 16.0;
/// The largest surface.cell_size relative to fluid.particle_spacing: twice the Zhu-Bridson kernel's reach (2
/// spacings). A coarser grid steps over water thinner than a cell: surface.cell_size = 1e300 made 0
/// triangles and `drench reconstruct` ended 0.
constexpr double kMaxCellPerSpacing = 4.0;

/// A derived figure in a message, to 3 digits (a key's own value is shown as written).
std::string approx(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

/// The first of `keys` the scene wrote, else the first (for a message about defaults).
Node written_key(const Node& object, std::initializer_list<const char*> keys) {
  for (const char* key : keys) {
    if (object.child(key).present()) return object.child(key);
  }
  return object.child(*keys.begin());
}

/// Fails `key` with `problem`, with its value when the scene wrote it, else saying it is the default.
[[noreturn]] void fail_key(const Node& key, const std::string& problem) {
  if (key.present()) key.fail(problem);
  key.fail_without_value(problem + " (with its default)");
}

/// `time` (TimeSettings): the step, the duration and the frame rate; the step may not exceed the duration.
TimeSettings read_time(const Node& node) {
  TimeSettings time;
  const ObjectReader r(node, {"dt", "duration", "frame_rate", "adaptive", "dt_min"});
  r.read("dt", time.dt, kPositive);
  r.read("duration", time.duration, kPositive);
  r.read("frame_rate", time.frame_rate, kNonNegative);
  r.read("adaptive", time.adaptive);
  r.read("dt_min", time.dt_min, kPositive);
  r.require_order("dt", time.dt, "duration", time.duration);
  r.require_order("dt_min", time.dt_min, "dt", time.dt);
  // Step and frame counts are int64 and computed through doubles: beyond 2^53 they are no longer exact, and
  // beyond 2^63 llround overflows (1e308 s ran one step and said "ok").
  const double steps = time.duration / (time.adaptive ? time.dt_min : time.dt);
  if (!(steps <= kMaxCount)) {
    fail_key(written_key(node, {"duration", time.adaptive ? "dt_min" : "dt"}),
             "gives " + approx(steps) + " steps (time.duration / time." + (time.adaptive ? "dt_min" : "dt") +
                 "); at most 2^53 = 9.0e15 can be counted");
  }
  const double frames = time.duration * time.frame_rate + 1.0;
  if (!(frames <= kMaxCount)) {
    fail_key(written_key(node, {"frame_rate", "duration"}),
             "gives " + approx(frames) +
                 " frames (time.duration x time.frame_rate + 1); at most 2^53 = 9.0e15 can be counted");
  }
  return time;
}

/// `effects`: names from the effect registry, each at most once. Whether the scene has what they need is
/// checked by check_effects once every section is read.
std::vector<std::string> read_effects(const Node& node) {
  std::vector<std::string> effects;
  if (!node.present()) return effects;
  const std::vector<std::string>& known = known_effects();
  for (std::size_t i = 0; i < node.array().size(); ++i) {
    const Node item = node.element(i);
    const std::string name = item.string();
    if (!find_effect(name)) item.fail("must be one of " + join(known, true));
    const auto previous = std::find(effects.begin(), effects.end(), name);
    if (previous != effects.end())
      item.fail("repeats " + node.path() + "[" + std::to_string(previous - effects.begin()) +
                "]; list each of " + join(known, true) + " at most once");
    effects.push_back(name);
  }
  return effects;
}

/// What each effect needs (its registry entry's `needs`), and no settings section without its effect: an
/// effect that needs something the scene lacks, or settings of an effect the scene does not run, would be
/// silently ignored. The errors name the effect's place in `effects`, or the section.
void check_effects(const SceneConfig& config, const ObjectReader& r, const SuppliedMeshes& supplied) {
  for (const EffectEntry& effect : effect_registry()) {
    const auto listed = std::find(config.effects.begin(), config.effects.end(), effect.name);
    if (listed == config.effects.end()) {
      const EffectSection& section = effect.settings;
      if (section.key && r[section.key].present())
        r[section.key].fail("sets " + std::string(section.what) + ", but effects does not list \"" +
                            effect.name + "\"");
      continue;
    }
    const Node node = r["effects"].element(static_cast<std::size_t>(listed - config.effects.begin()));
    const EffectNeeds& needs = effect.needs;
    if (needs.mesh == EffectMesh::CLOTH_OR_OBSTACLES && !config.cloth && config.obstacles.empty() &&
        !supplied.meshes)
      node.fail("needs a cloth or obstacles; the scene has no \"cloth\" and no \"obstacles\"");
    if (needs.mesh == EffectMesh::CLOTH && !config.cloth && !supplied.cloth)
      node.fail("needs a cloth; the scene has no \"cloth\"");
    if (needs.effect && !config.has_effect(needs.effect))
      node.fail("needs the \"" + std::string(needs.effect) + "\" effect" + needs.why);
  }
}

/// An emitter at or over fluid.max_speed would stop the run at its first particle: said at load time instead,
/// naming the emitter's key.
void check_emitter_speeds(const SceneConfig& config, const ObjectReader& r) {
  if (!config.fluid.max_speed) return;
  for (std::size_t i = 0; i < config.emitters.size(); ++i) {
    const EmitterSettings& e = config.emitters[i];
    const bool nozzle = e.kind == EmitterSettings::Kind::NOZZLE;
    const Scalar speed = nozzle ? e.nozzle.speed : e.box.velocity.norm();
    if (speed >= *config.fluid.max_speed) {
      char limit[32];
      std::snprintf(limit, sizeof limit, "%g", *config.fluid.max_speed);
      const std::string problem = "must be slower than fluid.max_speed (" + std::string(limit) + " m/s)";
      const Node key = r["emitters"].element(i).child(nozzle ? "speed" : "velocity");
      if (key.present()) key.fail(problem);
      key.fail_without_value(problem + ", as its default is");
    }
  }
}

/// The masses the scene's settings give, within [kMassMin, kMassMax]: a particle's, rest_density x
/// spacing^3, and a patch cloth's lightest and heaviest node, area_density x cell area / 6 (a corner in one
/// triangle) and x cell area (six triangles); the error names the key, its value and the derived mass.
/// (An OBJ cloth's nodes are checked when it is built.)
void check_masses(const SceneConfig& config, const ObjectReader& r) {
  const auto outside = [](double mass) { return !(mass >= kMassMin && mass <= kMassMax); };
  const std::string range =
      "; masses must be within [1e-150, 1e150] kg, so that inverse masses and impulses stay finite";
  const double s = config.fluid.particle_spacing;
  const double particle = config.fluid.rest_density * s * s * s;
  if (!config.emitters.empty() && outside(particle)) {
    fail_key(written_key(r["fluid"], {"particle_spacing", "rest_density"}),
             "gives particles of " + approx(particle) +
                 " kg (fluid.rest_density x fluid.particle_spacing^3)" + range);
  }
  if (!config.cloth || config.cloth->mesh != "patch") return;
  const ClothSettings& c = *config.cloth;
  const double cell = c.size_x / (c.nodes_x - 1) * (c.size_z / (c.nodes_z - 1));
  const double lightest = c.area_density * cell / 6.0;
  const double heaviest = c.area_density * cell;
  if (outside(lightest) || outside(heaviest)) {
    const bool light = outside(lightest);
    const double mass = light ? lightest : heaviest;
    fail_key(written_key(r["cloth"], {"area_density", "size", "nodes"}),
             "gives a cloth node of " + approx(mass) + " kg and inverse mass " + approx(1.0 / mass) +
                 " 1/kg (" +
                 (light ? "a corner: cloth.area_density x cell area / 6" : "cloth.area_density x cell area") +
                 ")" + range);
  }
}

/// What each emitter can lay at the scene's spacing: positions one spacing apart that double tells apart
/// at the emitter's coordinates (kSpacingResolution), a nozzle disc whose lattice fits an int and whose
/// layers, spacing / speed apart, double tells apart over the run's times. Else the emitter would emit
/// nothing (or a loop could not progress) while the run reports success.
void check_emitters(const SceneConfig& config, const ObjectReader& r) {
  const double s = config.fluid.particle_spacing;
  const Node spacing_key = r["fluid"].child("particle_spacing");
  for (std::size_t i = 0; i < config.emitters.size(); ++i) {
    const EmitterSettings& e = config.emitters[i];
    const Node node = r["emitters"].element(i);
    const std::string name = "emitters[" + std::to_string(i) + "]";
    const bool nozzle = e.kind == EmitterSettings::Kind::NOZZLE;
    const double reach = nozzle ? e.nozzle.center.cwiseAbs().maxCoeff() + e.nozzle.radius
                                : std::max(e.box.min.cwiseAbs().maxCoeff(), e.box.max.cwiseAbs().maxCoeff());
    // The lattice spans radius / spacing rows either way, counted in int. A radius the scene wrote is
    // named first: at 1e308 it is the radius that is wrong, not the spacing.
    const double rows = nozzle ? e.nozzle.radius / (s * 0.9) : 0.0;
    const Node radius = node.child("radius");
    const std::string too_wide =
        "gives a nozzle disc " + approx(rows) +
        " particle rows across (radius / fluid.particle_spacing); at most 1e8 can be laid";
    if (nozzle && radius.present() && !(rows <= 1e8)) radius.fail(too_wide);
    if (!(s >= kSpacingResolution * reach)) {
      fail_key(spacing_key, "is too fine for " + name + " at coordinates up to " + approx(reach) +
                                " m: a double resolves spacings from " + approx(kSpacingResolution * reach) +
                                " m there (2^-35 of the coordinate), so the emitter would lay nothing");
    }
    if (nozzle && !(rows <= 1e8)) fail_key(spacing_key, too_wide);
    if (nozzle) {
      const double period = s / e.nozzle.speed;
      const double latest = e.nozzle.start_time + config.time.duration;
      if (!(period >= kSpacingResolution * latest)) {
        const Node speed = node.child("speed");
        fail_key(
            speed.present() ? speed : spacing_key,
            "makes " + name + " release a layer every " + approx(period) +
                " s (fluid.particle_spacing / speed), below what a double resolves at t = " + approx(latest) +
                " s (" + approx(kSpacingResolution * latest) + " s): its emit loop could not progress");
      }
    }
  }
}

/// surface.cell_size within [kMinCellPerSpacing, kMaxCellPerSpacing] of the particle spacing.
void check_surface(const SceneConfig& config, const ObjectReader& r) {
  const double cell = config.surface.cell_size;
  if (cell <= 0.0) return;  // 0: half the spacing
  const double least = kMinCellPerSpacing * config.fluid.particle_spacing;
  if (!(cell >= least)) {
    r["surface"]
        .child("cell_size")
        .fail("must be >= fluid.particle_spacing / 16 = " + show(least) +
              " m (finer cells give a frame's grid more cells than memory and OpenVDB's "
              "int32 coordinates hold)");
  }
  const double most = kMaxCellPerSpacing * config.fluid.particle_spacing;
  if (!(cell <= most)) {
    r["surface"]
        .child("cell_size")
        .fail("must be <= 4 x fluid.particle_spacing = " + show(most) +
              " m (a coarser grid steps over water thinner than a cell, and draws it as nothing)");
  }
}

/// coupling.cloth_thickness at most kMaxClothThicknessPerSpacing particle spacings, where a coupling runs.
void check_coupling(const SceneConfig& config, const ObjectReader& r) {
  if (!config.has_effect("coupling")) return;
  const double most = kMaxClothThicknessPerSpacing * config.fluid.particle_spacing;
  if (!(config.coupling.cloth_thickness <= most)) {
    fail_key(r["coupling"].child("cloth_thickness"),
             "must be <= 2 fluid.particle_spacing = " + show(most) +
                 " m (the kernel's support; the pairs within the thickness grow as its square)");
  }
}

/// 1-based line and column of the character at `offset`, as an editor shows them.
std::pair<std::size_t, std::size_t> line_and_column(const std::string& text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  return {line, offset - line_start + 1};
}

/// nlohmann's what() minus its "[json.exception...] parse error at line L, column C: " prefix, which would
/// repeat the position we report ourselves.
std::string parser_message(const json::exception& e) {
  std::string message = e.what();
  const std::size_t column = message.find("column ");
  const std::size_t colon = message.find(": ", column == std::string::npos ? 0 : column);
  if (colon != std::string::npos) return message.substr(colon + 2);
  const std::size_t bracket = message.find("] ");
  return bracket == std::string::npos ? message : message.substr(bracket + 2);
}

/// The scene file's text: a regular file of at most kMaxSceneFileBytes (read_file_text). Too large is the
/// scene's fault (SceneError); anything else is the file system's (IoError).
std::string read_text_file(const std::string& path) {
  try {
    return read_file_text(path, kMaxSceneFileBytes,
                          "16 MiB (" + std::to_string(kMaxSceneFileBytes) + " bytes) a scene file");
  } catch (const FileTextError& e) {
    const std::string message = path + ": cannot read scene file: " + e.reason();
    if (e.kind() == FileTextError::Kind::TOO_LARGE) throw SceneError(message);
    throw IoError(message);
  }
}

/// Calls `visit(value)` on each value of `document` that names a file: `cloth.mesh` unless "patch",
/// `obstacles[i].mesh` unless "v_plane", and only where it is a non-empty string (validation reports the
/// rest).
template <class Visit>
void for_each_file_path(json& document, Visit visit) {
  if (!document.is_object()) return;
  const auto visit_key = [&](json& object, const char* key, const char* builtin) {
    if (!object.is_object()) return;
    const auto it = object.find(key);
    if (it != object.end() && it->is_string() && !it->get<std::string>().empty() &&
        it->get<std::string>() != builtin)
      visit(*it);
  };
  if (const auto cloth = document.find("cloth"); cloth != document.end()) visit_key(*cloth, "mesh", "patch");
  if (const auto obstacles = document.find("obstacles");
      obstacles != document.end() && obstacles->is_array()) {
    for (json& obstacle : *obstacles)
      visit_key(obstacle, "mesh", "v_plane");
  }
}

/// Makes the relative file paths of `document` absolute against `base` (an absolute folder).
void make_paths_absolute(json& document, const std::filesystem::path& base) {
  for_each_file_path(document, [&](json& value) {
    const std::filesystem::path file(value.get<std::string>());
    if (file.is_relative()) value = (base / file).lexically_normal().string();
  });
}

/// The absolute folder of `path`, for the paths its scene names.
std::filesystem::path folder_of(const std::string& path) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  if (error) throw IoError(path + ": cannot find its folder: " + error.message());
  return absolute.parent_path();
}

/// One step of an override path: an object key, or an array index written `[i]`. A key made of digits
/// (`emitters.0`) also indexes an array.
struct PathStep {
  std::string key;
  bool bracket = false;
  std::size_t index = 0;
};

bool is_digits(const std::string& text) {
  return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

std::size_t parse_index(const std::string& digits) {
  // Saturate instead of overflowing: any index this large is past the end anyway.
  return digits.size() > 18 ? std::numeric_limits<std::size_t>::max() : std::stoull(digits);
}

std::vector<PathStep> split_path(const std::string& path, const std::string& assignment) {
  const auto malformed = [&]() {
    return SceneError("--set " + assignment + ": malformed path \"" + path +
                      "\"; expected keys separated by '.' with optional [index], e.g. emitters[0].speed");
  };
  std::vector<PathStep> steps;
  std::size_t i = 0;
  while (true) {
    const std::size_t start = i;
    while (i < path.size() && path[i] != '.' && path[i] != '[' && path[i] != ']')
      ++i;
    if (i == start) throw malformed();
    steps.push_back({path.substr(start, i - start)});
    while (i < path.size() && path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos || !is_digits(path.substr(i + 1, close - i - 1))) throw malformed();
      steps.push_back({"", true, parse_index(path.substr(i + 1, close - i - 1))});
      i = close + 1;
    }
    if (i == path.size()) return steps;
    if (path[i] != '.') throw malformed();
    ++i;
  }
}

/// The override's value: JSON when it parses, else the raw text, so `pressure_solver=wcsph` needs no quotes.
json parse_override_value(const std::string& text, const std::string& assignment, std::size_t path_depth,
                          const std::string& path) {
  // The value and the path it goes to together stay within the document's nesting limit.
  try {
    return loader::parse_json_strict(text, kMaxJsonDepth, path, path_depth);
  } catch (const SceneError& e) {
    throw SceneError("--set " + assignment + ": " + e.what());
  } catch (const json::parse_error&) {
    return json(text);
  } catch (const json::out_of_range& e) {
    // A number too large for a double: keep it as infinity so validation reports "must be finite" with the
    // path, exactly as for any other bad value.
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    const std::size_t consumed = static_cast<std::size_t>(end - text.c_str());
    if (consumed > 0 && text.find_first_not_of(" \t\r\n", consumed) == std::string::npos) return json(value);
    throw SceneError("--set " + assignment + ": " + parser_message(e));
  }
}

}  // namespace

SceneConfig parse_scene(const nlohmann::json& document, const std::string& source,
                        const SuppliedMeshes& supplied) {
  const Node root(&document, "", source);
  const ObjectReader r(
      root, {"gravity", "fluid", "emitters", "boundaries", "kill_regions", "time", "cloth", "obstacles",
             "coupling", "surface", "wetting", "effects", "camera", "surface_tension"});
  SceneConfig config;
  config.source = source;
  r.read("gravity", config.gravity);
  config.fluid = loader::read_fluid(r["fluid"]);
  config.emitters = loader::read_list(r["emitters"], loader::read_emitter);
  config.boundaries = loader::read_list(r["boundaries"], loader::read_boundary);
  config.kill_regions = loader::read_list(r["kill_regions"], loader::read_kill_region);
  config.time = read_time(r["time"]);
  if (r["cloth"].present()) config.cloth = loader::read_cloth(r["cloth"]);
  config.obstacles = loader::read_list(r["obstacles"], loader::read_obstacle);
  config.coupling = loader::read_coupling(r["coupling"]);
  config.surface = loader::read_surface(r["surface"]);
  config.wetting = loader::read_wetting(r["wetting"]);
  config.surface_tension = loader::read_surface_tension(r["surface_tension"]);
  config.effects = read_effects(r["effects"]);
  if (r["camera"].present()) config.camera = loader::read_camera(r["camera"]);
  check_effects(config, r, supplied);
  check_emitter_speeds(config, r);
  check_masses(config, r);
  check_emitters(config, r);
  check_surface(config, r);
  check_coupling(config, r);
  if (!config.has_effect("adhesion")) {
    // The works of adhesion would be ignored without the effect.
    const char* problem = "sets a work of adhesion, but effects does not list \"adhesion\"";
    if (const Node key = r["cloth"].child("adhesion"); key.present()) key.fail(problem);
    for (std::size_t i = 0; i < config.obstacles.size(); ++i)
      if (const Node key = r["obstacles"].element(i).child("adhesion"); key.present()) key.fail(problem);
  }
  if (config.coupling.asks_tangential() && !config.has_effect("friction")) {
    const Node coupling = r["coupling"];
    // The key that asks: slip when it is no-slip, else the friction coefficient.
    const Node key = config.coupling.slip == SlipCondition::NO_SLIP ? coupling.child("slip")
                                                                    : coupling.child("friction_coefficient");
    key.fail("asks for tangential boundary conditions, but effects does not list \"friction\"");
  }
  return config;
}

CameraSettings parse_camera(const nlohmann::json& camera, const std::string& source) {
  return loader::read_camera(Node(&camera, "camera", source));
}

void apply_override(nlohmann::json& document, const std::string& assignment) {
  const auto fail = [&](const std::string& problem) {
    return SceneError("--set " + assignment + ": " + problem);
  };
  const std::size_t equals = assignment.find('=');
  if (equals == std::string::npos || equals == 0) throw fail("expected json.path=value");
  try {
    // Rejecting invalid UTF-8 here keeps dump() (error messages, canonical_scene_text) from throwing later.
    (void)json(assignment).dump();
  } catch (const json::type_error&) {
    throw fail("not valid UTF-8");
  }
  const std::string path = assignment.substr(0, equals);
  const std::vector<PathStep> steps = split_path(path, assignment);
  if (steps.size() >= kMaxJsonDepth)
    throw fail("path of " + std::to_string(steps.size()) + " levels; JSON nested deeper than " +
               std::to_string(kMaxJsonDepth) + " levels of arrays and objects is refused");
  json value = parse_override_value(assignment.substr(equals + 1), assignment, steps.size(), path);

  json* node = &document;
  std::string walked;  // the path so far, written canonically for messages
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const PathStep& step = steps[k];
    const bool last = k + 1 == steps.size();
    const std::string name = walked.empty() ? "the scene" : walked;
    if (node->is_object() && !step.bracket) {
      walked += (walked.empty() ? "" : ".") + step.key;
      if (last) {
        (*node)[step.key] = std::move(value);
        return;
      }
      if (!node->contains(step.key)) {
        // Only objects are created: an index into a missing array can only be a mistake.
        if (steps[k + 1].bracket) throw fail(walked + " is missing; --set creates objects but not arrays");
        (*node)[step.key] = json::object();
      }
      node = &(*node)[step.key];
    } else if (node->is_array() && (step.bracket || is_digits(step.key))) {
      const std::size_t index = step.bracket ? step.index : parse_index(step.key);
      if (index >= node->size()) throw fail(name + " has " + std::to_string(node->size()) + " element(s)");
      walked += "[" + std::to_string(index) + "]";
      if (last) {
        (*node)[index] = std::move(value);
        return;
      }
      node = &(*node)[index];
    } else if (node->is_object()) {
      throw fail(name + " is an object, not an array");
    } else if (node->is_array()) {
      throw fail(name + " is an array; expected an index, e.g. " + name + "[0]");
    } else {
      throw fail(name + " is not an object or array, got " + show(*node));
    }
  }
}

std::string canonical_scene_text(const nlohmann::json& document) {
  return document.dump();
}

nlohmann::json read_scene_document(const std::string& path, const std::vector<std::string>& overrides) {
  const std::string text = read_text_file(path);
  json document;
  try {
    document = loader::parse_json_strict(text, kMaxJsonDepth);
  } catch (const SceneError& e) {
    throw SceneError(path + ": " + e.what());
  } catch (const json::parse_error& e) {
    // e.byte counts the characters read, so the offending one is at e.byte - 1.
    const auto [line, column] = line_and_column(text, e.byte == 0 ? 0 : e.byte - 1);
    throw SceneError(path + ": malformed JSON at line " + std::to_string(line) + ", column " +
                     std::to_string(column) + ": " + parser_message(e));
  } catch (const json::exception& e) {
    throw SceneError(path + ": malformed JSON: " + parser_message(e));
  }
  // A path the file names is relative to the file's folder; one an override names, to the working
  // directory, as any path on a command line. Both are made absolute, so that the document (and the
  // scene.json a run copies it to) means the same wherever it is read from.
  make_paths_absolute(document, folder_of(path));
  for (const std::string& assignment : overrides) {
    try {
      apply_override(document, assignment);
    } catch (const SceneError& e) {
      throw SceneError(std::string(e.what()) + " (" + path + ")");
    }
  }
  if (!overrides.empty()) {
    std::error_code error;
    const std::filesystem::path working = std::filesystem::current_path(error);
    if (error) throw IoError("cannot find the working directory for --set paths: " + error.message());
    make_paths_absolute(document, working);
  }
  return document;
}

std::string scene_source(const std::string& path, const std::vector<std::string>& overrides) {
  std::string source = path;
  if (!overrides.empty()) source += " with";
  for (const std::string& assignment : overrides)
    source += " --set " + assignment;
  return source;
}

SceneConfig load_scene_file(const std::string& path, const std::vector<std::string>& overrides) {
  // read_scene_document has made the file paths absolute (relative ones are the scene file's folder's).
  return parse_scene(read_scene_document(path, overrides), scene_source(path, overrides));
}

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr) != 1)
    throw Error("SHA-256 of " + std::to_string(bytes.size()) + " bytes failed in OpenSSL's EVP_Digest");
  static const char kHex[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * length);
  for (unsigned int i = 0; i < length; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 0xf];
  }
  return hex;
}

}  // namespace drench
