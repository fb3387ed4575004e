#include <drench/scene/scene_loader.hpp>

#include <openssl/evp.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include <drench/common/error.hpp>
#include <drench/scene/effect_registry.hpp>
#include <drench/scene/json_reader.hpp>
#include <drench/scene/load_sections.hpp>

namespace drench {
namespace {

using loader::join;
using loader::json;
using loader::kNonNegative;
using loader::kPositive;
using loader::Node;
using loader::ObjectReader;
using loader::show;

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
void check_effects(const SceneConfig& config, const ObjectReader& r) {
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
    if (needs.mesh == EffectMesh::CLOTH_OR_OBSTACLES && !config.cloth && config.obstacles.empty())
      node.fail("needs a cloth or obstacles; the scene has no \"cloth\" and no \"obstacles\"");
    if (needs.mesh == EffectMesh::CLOTH && !config.cloth)
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

std::string read_text_file(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw IoError(path + ": cannot read scene file: " + std::strerror(errno));
  std::string text;
  char buffer[65536];
  std::size_t count = 0;
  while ((count = std::fread(buffer, 1, sizeof buffer, file)) > 0)
    text.append(buffer, count);
  const bool failed = std::ferror(file) != 0;
  const int error = errno;  // fclose may overwrite errno
  std::fclose(file);
  if (failed) throw IoError(path + ": cannot read scene file: " + std::strerror(error));
  return text;
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
json parse_override_value(const std::string& text, const std::string& assignment) {
  try {
    return json::parse(text);
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

SceneConfig parse_scene(const nlohmann::json& document, const std::string& source) {
  const Node root(&document, "", source);
  const ObjectReader r(root, {"gravity", "fluid", "emitters", "boundaries", "kill_regions", "time", "cloth",
                              "obstacles", "coupling", "surface", "wetting", "effects", "camera"});
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
  config.effects = read_effects(r["effects"]);
  if (r["camera"].present()) config.camera = loader::read_camera(r["camera"]);
  check_effects(config, r);
  check_emitter_speeds(config, r);
  if (config.coupling.asks_tangential() && !config.has_effect("friction")) {
    const Node coupling = r["coupling"];
    const Node key =
        coupling.child("slip").present() ? coupling.child("slip") : coupling.child("friction_coefficient");
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
  json value = parse_override_value(assignment.substr(equals + 1), assignment);

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
    document = json::parse(text);
  } catch (const json::parse_error& e) {
    // e.byte counts the characters read, so the offending one is at e.byte - 1.
    const auto [line, column] = line_and_column(text, e.byte == 0 ? 0 : e.byte - 1);
    throw SceneError(path + ": malformed JSON at line " + std::to_string(line) + ", column " +
                     std::to_string(column) + ": " + parser_message(e));
  } catch (const json::exception& e) {
    throw SceneError(path + ": malformed JSON: " + parser_message(e));
  }
  for (const std::string& assignment : overrides) {
    try {
      apply_override(document, assignment);
    } catch (const SceneError& e) {
      throw SceneError(std::string(e.what()) + " (" + path + ")");
    }
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
  SceneConfig config = parse_scene(read_scene_document(path, overrides), scene_source(path, overrides));
  // A cloth or obstacle OBJ named relative to the scene file lives next to it, wherever drench is run from.
  if (config.cloth && config.cloth->mesh != "patch" &&
      std::filesystem::path(config.cloth->mesh).is_relative()) {
    config.cloth->mesh = (std::filesystem::path(path).parent_path() / config.cloth->mesh).string();
  }
  for (ObstacleSettings& obstacle : config.obstacles) {
    if (obstacle.mesh != "v_plane" && std::filesystem::path(obstacle.mesh).is_relative())
      obstacle.mesh = (std::filesystem::path(path).parent_path() / obstacle.mesh).string();
  }
  return config;
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
