#include "scene/scene_loader.hpp"

#include <openssl/evp.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include "common/error.hpp"

namespace drench {
namespace {

using nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Shows a value in a message as JSON, shortened so that a misplaced object does not flood the terminal.
std::string show(const json& value) {
  // dump() would print non-finite numbers (only possible in documents built in code, or --set 1e999) as null.
  if (value.is_number_float() && !std::isfinite(value.get<double>()))
    return format_number(value.get<double>());
  std::string text = value.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() > 80) text = text.substr(0, 77) + "...";
  return text;
}

/// A limit computed from another key, shortest form (5, not 5.0: it may be an iteration count).
std::string show(double v) {
  std::string text = show(json(v));
  if (text.size() > 2 && text.compare(text.size() - 2, 2, ".0") == 0) text.resize(text.size() - 2);
  return text;
}

std::string show(const Vec3& v) {
  return show(json::array({v.x(), v.y(), v.z()}));
}

std::string join(const std::vector<std::string>& items, bool quoted) {
  std::string text;
  for (const std::string& item : items) {
    if (!text.empty()) text += ", ";
    text += quoted ? "\"" + item + "\"" : item;
  }
  return text;
}

/// Allowed interval of a number; an infinite end means unbounded on that side.
struct Range {
  double lo = -kInf;
  bool lo_open = false;
  double hi = kInf;
  bool hi_open = false;

  bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }
  std::string describe() const {
    if (std::isinf(hi)) return std::string(lo_open ? "> " : ">= ") + format_number(lo);
    if (std::isinf(lo)) return std::string(hi_open ? "< " : "<= ") + format_number(hi);
    return std::string("in ") + (lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) +
           (hi_open ? ")" : "]");
  }
};

const Range kAny{};
const Range kPositive{0.0, true, kInf, false};
const Range kNonNegative{0.0, false, kInf, false};
const Range kAtLeastOne{1.0, false, kInf, false};

template <class Enum>
using Choices = std::vector<std::pair<std::string, Enum>>;

/// A value (possibly absent) at a JSON path of the scene named `source`: all an error message needs, so each
/// check is one call instead of hand-assembled text per key.
class Node {
 public:
  Node(const json* value, std::string path, const std::string& source)
      : m_value(value), m_path(std::move(path)), m_source(&source) {}

  bool present() const { return m_value != nullptr; }
  const json& value() const { return *m_value; }
  const std::string& path() const { return m_path; }
  const std::string& source() const { return *m_source; }
  std::string name() const { return m_path.empty() ? "the scene" : m_path; }

  /// Throws `<path> <problem>, got <value> (<source>)`.
  [[noreturn]] void fail(const std::string& problem) const {
    throw SceneError(name() + " " + problem + ", got " + show(*m_value) + " (" + *m_source + ")");
  }
  /// Throws `<path> <problem> (<source>)<suffix>` for problems without a value (missing or unknown keys).
  [[noreturn]] void fail_without_value(const std::string& problem, const std::string& suffix = "") const {
    throw SceneError(name() + " " + problem + " (" + *m_source + ")" + suffix);
  }

  Node child(const std::string& key) const {
    const json* found = nullptr;
    if (present() && m_value->is_object()) {
      const auto it = m_value->find(key);
      if (it != m_value->end()) found = &*it;
    }
    return Node(found, m_path.empty() ? key : m_path + "." + key, *m_source);
  }
  Node element(std::size_t index) const {
    return Node(&m_value->at(index), m_path + "[" + std::to_string(index) + "]", *m_source);
  }

  const json& array() const {
    if (!m_value->is_array()) fail("must be an array");
    return *m_value;
  }
  double number(const Range& range = kAny) const {
    if (!m_value->is_number()) fail("must be a number");
    const double v = m_value->get<double>();
    if (!std::isfinite(v)) fail("must be finite");
    if (!range.contains(v)) fail("must be " + range.describe());
    return v;
  }
  /// Only JSON integers are accepted: 1.0 for a count more likely hides a mistake than saves typing.
  template <class Int>
  Int integer(const Range& range) const {
    if (!m_value->is_number_integer()) fail("must be an integer");
    const double approx = m_value->get<double>();
    // Every range here excludes negatives, so only the upper end of Int can be exceeded.
    constexpr Int max = std::numeric_limits<Int>::max();
    const bool fits = m_value->is_number_unsigned()
                          ? m_value->get<std::uint64_t>() <= static_cast<std::uint64_t>(max)
                          : m_value->get<std::int64_t>() <= max;
    if (!fits || !range.contains(approx))
      fail("must be " + (fits ? range.describe() : "<= " + std::to_string(max)));
    return static_cast<Int>(m_value->get<std::int64_t>());
  }
  bool boolean() const {
    if (!m_value->is_boolean()) fail("must be true or false");
    return m_value->get<bool>();
  }
  std::string string() const {
    if (!m_value->is_string()) fail("must be a string");
    return m_value->get<std::string>();
  }
  Vec3 vec3() const {
    if (!m_value->is_array() || m_value->size() != 3) fail("must be an array of 3 numbers");
    return Vec3(element(0).number(), element(1).number(), element(2).number());
  }
  /// A non-zero vector, normalised: directions and normals are stored as unit vectors.
  Vec3 unit_vec3() const {
    const Vec3 v = vec3();
    const double length = v.stableNorm();
    if (!(length > 0.0)) fail("must be non-zero");
    return v / length;
  }
  template <class Enum>
  Enum choice(const Choices<Enum>& choices) const {
    std::vector<std::string> names;
    for (const auto& [name, value] : choices) {
      if (m_value->is_string() && m_value->get<std::string>() == name) return value;
      names.push_back(name);
    }
    fail("must be one of " + join(names, true));
  }

 private:
  const json* m_value;
  std::string m_path;
  const std::string* m_source;
};

/// An object whose keys are checked against `known` up front, so a misspelt key is reported instead of being
/// silently replaced by its default. An absent object reads nothing and leaves every default in place.
class ObjectReader {
 public:
  ObjectReader(const Node& node, const std::vector<std::string>& known) : m_node(node) {
    if (!node.present()) return;
    if (!node.value().is_object()) node.fail("must be an object");
    for (const auto& item : node.value().items()) {
      if (std::find(known.begin(), known.end(), item.key()) == known.end())
        node.child(item.key()).fail_without_value("is not a known key", "; known: " + join(known, false));
    }
  }

  Node operator[](const std::string& key) const { return m_node.child(key); }

  void read(const std::string& key, Scalar& out, const Range& range = kAny) const {
    if (const Node n = m_node.child(key); n.present()) out = n.number(range);
  }
  void read(const std::string& key, int& out, const Range& range) const {
    if (const Node n = m_node.child(key); n.present()) out = n.integer<int>(range);
  }
  void read(const std::string& key, std::int64_t& out, const Range& range) const {
    if (const Node n = m_node.child(key); n.present()) out = n.integer<std::int64_t>(range);
  }
  void read(const std::string& key, bool& out) const {
    if (const Node n = m_node.child(key); n.present()) out = n.boolean();
  }
  void read(const std::string& key, Vec3& out) const {
    if (const Node n = m_node.child(key); n.present()) out = n.vec3();
  }
  void read_unit(const std::string& key, Vec3& out) const {
    if (const Node n = m_node.child(key); n.present()) out = n.unit_vec3();
  }
  template <class Enum>
  void read_choice(const std::string& key, Enum& out, const Choices<Enum>& choices) const {
    if (const Node n = m_node.child(key); n.present()) out = n.choice(choices);
  }

  /// Reports `lo_key` > `hi_key` on the key the user actually wrote (the other may be a default).
  void require_order(const std::string& lo_key, double lo, const std::string& hi_key, double hi) const {
    if (lo <= hi) return;
    if (const Node n = m_node.child(hi_key); n.present())
      n.fail("must be >= " + m_node.child(lo_key).path() + " = " + show(lo));
    m_node.child(lo_key).fail("must be <= " + m_node.child(hi_key).path() + " = " + show(hi));
  }
  void require_box(const Vec3& min, const Vec3& max) const {
    if ((max.array() > min.array()).all()) return;
    if (const Node n = m_node.child("max"); n.present())
      n.fail("must be > " + m_node.child("min").path() + " = " + show(min) + " on every axis");
    m_node.child("min").fail("must be < " + m_node.child("max").path() + " = " + show(max) +
                             " on every axis");
  }

 private:
  Node m_node;
};

/// The required `type` of a list element; checked before the keys, since the type decides which are known.
template <class Enum>
Enum read_type(const Node& node, const Choices<Enum>& choices) {
  if (!node.value().is_object()) node.fail("must be an object");
  const Node type = node.child("type");
  if (!type.present()) {
    std::vector<std::string> names;
    for (const auto& choice : choices)
      names.push_back(choice.first);
    type.fail_without_value("is missing; must be one of " + join(names, true));
  }
  return type.choice(choices);
}

template <class T>
std::vector<T> read_list(const Node& node, T (*read_one)(const Node&)) {
  std::vector<T> items;
  if (!node.present()) return items;
  for (std::size_t i = 0; i < node.array().size(); ++i)
    items.push_back(read_one(node.element(i)));
  return items;
}

FluidSettings read_fluid(const Node& node) {
  FluidSettings fluid;
  const ObjectReader r(node, {"rest_density", "particle_spacing", "pressure_solver", "wcsph", "pcisph",
                              "viscosity", "cfl", "sort_interval"});
  r.read("rest_density", fluid.rest_density, kPositive);
  r.read("particle_spacing", fluid.particle_spacing, kPositive);
  r.read_choice("pressure_solver", fluid.pressure_solver,
                Choices<PressureSolverKind>{{"pcisph", PressureSolverKind::PCISPH},
                                            {"wcsph", PressureSolverKind::WCSPH}});
  r.read("cfl", fluid.cfl, Range{0.0, true, 1.0, false});
  r.read("sort_interval", fluid.sort_interval, kAtLeastOne);

  const ObjectReader wcsph(r["wcsph"], {"speed_of_sound", "exponent"});
  // null is accepted as "auto" so that --set fluid.wcsph.speed_of_sound=null can undo a file's value.
  if (const Node c = wcsph["speed_of_sound"]; c.present() && !c.value().is_null())
    fluid.wcsph.speed_of_sound = c.number(kPositive);
  wcsph.read("exponent", fluid.wcsph.exponent, kAtLeastOne);

  const ObjectReader pcisph(r["pcisph"],
                            {"eta", "min_iterations", "max_iterations", "max_compression_per_iteration",
                             "max_relief_per_substep", "precision"});
  pcisph.read("eta", fluid.pcisph.eta, Range{0.0, true, 1.0, true});
  pcisph.read("min_iterations", fluid.pcisph.min_iterations, kAtLeastOne);
  pcisph.read("max_iterations", fluid.pcisph.max_iterations, kAtLeastOne);
  pcisph.read_choice("precision", fluid.pcisph.precision,
                     Choices<IterationPrecision>{{"single", IterationPrecision::SINGLE},
                                                 {"double", IterationPrecision::DOUBLE}});
  pcisph.require_order("min_iterations", fluid.pcisph.min_iterations, "max_iterations",
                       fluid.pcisph.max_iterations);
  // null is "no limit" (the published PCISPH), so that --set can undo the default.
  for (auto [key, limit] :
       {std::pair{"max_compression_per_iteration", &fluid.pcisph.max_compression_per_iteration},
        std::pair{"max_relief_per_substep", &fluid.pcisph.max_relief_per_substep}}) {
    if (const Node c = pcisph[key]; c.present()) {
      if (c.value().is_null()) {
        limit->reset();
      } else {
        *limit = c.number(kPositive);
      }
    }
  }

  const ObjectReader viscosity(r["viscosity"], {"method", "coefficient"});
  viscosity.read_choice(
      "method", fluid.viscosity.method,
      Choices<ViscosityKind>{{"xsph", ViscosityKind::XSPH}, {"artificial", ViscosityKind::ARTIFICIAL}});
  viscosity.read("coefficient", fluid.viscosity.coefficient, kNonNegative);
  return fluid;
}

EmitterSettings read_emitter(const Node& node) {
  using Kind = EmitterSettings::Kind;
  EmitterSettings emitter;
  emitter.kind = read_type(node, Choices<Kind>{{"nozzle", Kind::NOZZLE}, {"box", Kind::BOX}});
  if (emitter.kind == Kind::NOZZLE) {
    NozzleEmitterSettings& nozzle = emitter.nozzle;
    const ObjectReader r(node,
                         {"type", "center", "direction", "radius", "speed", "start_time", "max_particles"});
    r.read("center", nozzle.center);
    r.read_unit("direction", nozzle.direction);
    r.read("radius", nozzle.radius, kPositive);
    r.read("speed", nozzle.speed, kPositive);
    r.read("start_time", nozzle.start_time, kNonNegative);
    r.read("max_particles", nozzle.max_particles, kNonNegative);
  } else {
    BoxEmitterSettings& box = emitter.box;
    const ObjectReader r(node, {"type", "min", "max", "velocity"});
    r.read("min", box.min);
    r.read("max", box.max);
    r.read("velocity", box.velocity);
    r.require_box(box.min, box.max);
  }
  return emitter;
}

BoundarySettings read_boundary(const Node& node) {
  using Kind = BoundarySettings::Kind;
  BoundarySettings boundary;
  boundary.kind = read_type(node, Choices<Kind>{{"box", Kind::BOX}, {"plane", Kind::PLANE}});
  if (boundary.kind == Kind::BOX) {
    const ObjectReader r(node, {"type", "min", "max", "open_top", "layers"});
    r.read("min", boundary.min);
    r.read("max", boundary.max);
    r.read("open_top", boundary.open_top);
    r.read("layers", boundary.layers, kAtLeastOne);
    r.require_box(boundary.min, boundary.max);
  } else {
    const ObjectReader r(node, {"type", "point", "normal", "size", "layers"});
    r.read("point", boundary.point);
    r.read_unit("normal", boundary.normal);
    if (const Node size = r["size"]; size.present()) {
      if (!size.value().is_array() || size.value().size() != 2) size.fail("must be an array of 2 numbers");
      for (std::size_t i = 0; i < 2; ++i)
        boundary.size[i] = size.element(i).number(kPositive);
    }
    r.read("layers", boundary.layers, kAtLeastOne);
  }
  return boundary;
}

KillRegionSettings read_kill_region(const Node& node) {
  using Kind = KillRegionSettings::Kind;
  KillRegionSettings region;
  region.kind = read_type(node, Choices<Kind>{{"plane", Kind::PLANE}, {"box", Kind::BOX}});
  if (region.kind == Kind::PLANE) {
    const ObjectReader r(node, {"type", "point", "normal"});
    r.read("point", region.point);
    r.read_unit("normal", region.normal);
  } else {
    const ObjectReader r(node, {"type", "min", "max"});
    r.read("min", region.min);
    r.read("max", region.max);
    r.require_box(region.min, region.max);
  }
  return region;
}

TimeSettings read_time(const Node& node) {
  TimeSettings time;
  const ObjectReader r(node, {"dt", "duration", "frame_rate"});
  r.read("dt", time.dt, kPositive);
  r.read("duration", time.duration, kPositive);
  r.read("frame_rate", time.frame_rate, kNonNegative);
  r.require_order("dt", time.dt, "duration", time.duration);
  return time;
}

ClothSettings read_cloth(const Node& node) {
  ClothSettings cloth;
  const ObjectReader r(
      node, {"mesh", "center", "size", "nodes", "area_density", "pinned", "position_iterations", "substeps",
             "stretch_stiffness", "bending_stiffness", "damping"});
  if (const Node mesh = r["mesh"]; mesh.present()) {
    cloth.mesh = mesh.string();
    if (cloth.mesh.empty()) mesh.fail("must be \"patch\" or the path of an OBJ file");
  }
  r.read("center", cloth.center);
  if (const Node size = r["size"]; size.present()) {
    if (!size.value().is_array() || size.value().size() != 2)
      size.fail("must be an array of 2 numbers [x, z]");
    cloth.size_x = size.element(0).number(kPositive);
    cloth.size_z = size.element(1).number(kPositive);
  }
  if (const Node nodes = r["nodes"]; nodes.present()) {
    if (!nodes.value().is_array() || nodes.value().size() != 2)
      nodes.fail("must be an array of 2 integers [x, z]");
    cloth.nodes_x = nodes.element(0).integer<int>(Range{2.0, false, 4096.0, false});
    cloth.nodes_z = nodes.element(1).integer<int>(Range{2.0, false, 4096.0, false});
  }
  r.read("area_density", cloth.area_density, kPositive);
  if (const Node pinned = r["pinned"]; pinned.present()) {
    cloth.pinned = pinned.string();
    if (cloth.pinned != "corners" && cloth.pinned != "corner" && cloth.pinned != "none")
      pinned.fail("must be one of \"corners\", \"corner\", \"none\"");
  }
  r.read("position_iterations", cloth.position_iterations, Range{1.0, false, 1000.0, false});
  r.read("substeps", cloth.substeps, Range{1.0, false, 1000.0, false});
  r.read("stretch_stiffness", cloth.stretch_stiffness, Range{0.0, true, 1.0, false});
  r.read("bending_stiffness", cloth.bending_stiffness, Range{0.0, false, 1.0, false});
  r.read("damping", cloth.damping, Range{0.0, false, 1.0, false});
  return cloth;
}

CouplingSettings read_coupling(const Node& node) {
  CouplingSettings coupling;
  const ObjectReader r(
      node, {"cloth_thickness", "repulsion_stiffness", "repulsion_sweeps", "continuous", "substep_obstacle",
             "scheme", "max_ccd_iterations", "slip", "friction_coefficient", "broad_phase"});
  r.read("cloth_thickness", coupling.cloth_thickness, kPositive);
  r.read("repulsion_stiffness", coupling.repulsion_stiffness, kNonNegative);
  r.read("repulsion_sweeps", coupling.repulsion_sweeps, kAtLeastOne);
  r.read("continuous", coupling.continuous);
  r.read("substep_obstacle", coupling.substep_obstacle);
  r.read_choice("scheme", coupling.scheme,
                Choices<CouplingScheme>{{"carried_water", CouplingScheme::CARRIED_WATER},
                                        {"impulses", CouplingScheme::IMPULSES}});
  r.read("max_ccd_iterations", coupling.max_ccd_iterations, kAtLeastOne);
  r.read_choice(
      "slip", coupling.slip,
      Choices<SlipCondition>{{"friction", SlipCondition::FRICTION}, {"no_slip", SlipCondition::NO_SLIP}});
  r.read("friction_coefficient", coupling.friction_coefficient, kNonNegative);
  r.read_choice("broad_phase", coupling.broad_phase,
                Choices<BroadPhaseKind>{{"grid", BroadPhaseKind::GRID}, {"fcl", BroadPhaseKind::FCL}});
  return coupling;
}

std::vector<std::string> read_effects(const Node& node) {
  std::vector<std::string> effects;
  if (!node.present()) return effects;
  const std::vector<std::string>& known = known_effects();
  for (std::size_t i = 0; i < node.array().size(); ++i) {
    const Node item = node.element(i);
    const std::string name = item.string();
    if (std::find(known.begin(), known.end(), name) == known.end())
      item.fail("must be one of " + join(known, true));
    const auto previous = std::find(effects.begin(), effects.end(), name);
    if (previous != effects.end())
      item.fail("repeats " + node.path() + "[" + std::to_string(previous - effects.begin()) +
                "]; list each of " + join(known, true) + " at most once");
    effects.push_back(name);
  }
  return effects;
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
                              "coupling", "effects"});
  SceneConfig config;
  config.source = source;
  r.read("gravity", config.gravity);
  config.fluid = read_fluid(r["fluid"]);
  config.emitters = read_list(r["emitters"], read_emitter);
  config.boundaries = read_list(r["boundaries"], read_boundary);
  config.kill_regions = read_list(r["kill_regions"], read_kill_region);
  config.time = read_time(r["time"]);
  if (r["cloth"].present()) config.cloth = read_cloth(r["cloth"]);
  config.coupling = read_coupling(r["coupling"]);
  config.effects = read_effects(r["effects"]);
  // An effect that needs something the scene lacks, or settings of an effect the scene does not run, would be
  // silently ignored: both are errors.
  const auto effect_node = [&](const std::string& name) {
    const auto it = std::find(config.effects.begin(), config.effects.end(), name);
    return r["effects"].element(static_cast<std::size_t>(it - config.effects.begin()));
  };
  for (const char* needs_cloth : {"coupling", "leak_audit"}) {
    if (config.has_effect(needs_cloth) && !config.cloth)
      effect_node(needs_cloth).fail("needs a cloth; the scene has no \"cloth\"");
  }
  if (config.has_effect("friction") && !config.has_effect("coupling"))
    effect_node("friction").fail("needs the \"coupling\" effect");
  const bool tangential =
      config.coupling.slip == SlipCondition::NO_SLIP || config.coupling.friction_coefficient > 0;
  if (tangential && !config.has_effect("friction")) {
    const Node coupling = r["coupling"];
    const Node key =
        coupling.child("slip").present() ? coupling.child("slip") : coupling.child("friction_coefficient");
    key.fail("asks for tangential boundary conditions, but effects does not list \"friction\"");
  }
  return config;
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
  // A cloth OBJ named relative to the scene file lives next to it, wherever drench is run from.
  if (config.cloth && config.cloth->mesh != "patch" &&
      std::filesystem::path(config.cloth->mesh).is_relative()) {
    config.cloth->mesh = (std::filesystem::path(path).parent_path() / config.cloth->mesh).string();
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
