#pragma once
/// Typed reading of a scene's JSON with the errors docs/scenes.md promises: each names the JSON path, the
/// value and the scene's source, `fluid.particle_spacing must be > 0, got -0.01 (scenes/x.json)`. Internal to
/// the scene loader (scene_loader.cpp and the load_*.cpp files of its sections).

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <drench/common/types.hpp>

namespace drench::loader {

using json = nlohmann::json;

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Deepest nesting of arrays and objects a scene document may have (the whole document, `--set` values
/// included). The deepest scene of docs/scenes.md nests 4 levels; the limit keeps recursive code (dump(),
/// the readers) far from the stack's end.
inline constexpr std::size_t kMaxJsonDepth = 64;

/// Parses JSON text as a scene needs it: at most `max_depth` levels of arrays and objects, and no key twice
/// in one object (nlohmann keeps the last silently, so a duplicate would hide a value the user wrote).
/// @param text  the JSON text
/// @param max_depth  the most levels allowed, counting the outermost array or object as 1
/// @param path_prefix  the JSON path of the text's root in messages (`--set` values), "" for a document
/// @param start_depth  the levels above the text's root (a `--set` value's path), counted against max_depth
/// @throws SceneError `JSON nested deeper than <max_depth> levels` or `duplicate key "<k>" at <path>`
///         (without the file: the caller adds it); json::parse_error and json::out_of_range as json::parse.
json parse_json_strict(const std::string& text, std::size_t max_depth, const std::string& path_prefix = "",
                       std::size_t start_depth = 0);

/// Shows a value in a message as JSON, shortened so that a misplaced object does not flood the terminal.
std::string show(const json& value);
/// A limit computed from another key, shortest form (5, not 5.0: it may be an iteration count).
std::string show(double v);
/// A vector as the JSON array a scene would write for it.
std::string show(const Vec3& v);

/// `items` separated by ", ", each in double quotes when `quoted`.
std::string join(const std::vector<std::string>& items, bool quoted);

/// Allowed interval of a number; an infinite end means unbounded on that side.
struct Range {
  double lo = -kInf;
  bool lo_open = false;
  double hi = kInf;
  bool hi_open = false;

  bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }
  /// The interval as messages state it: `> 0`, `>= 1`, `in (0, 1]`.
  std::string describe() const;
};

inline constexpr Range kAny{};
inline constexpr Range kPositive{0.0, true, kInf, false};
inline constexpr Range kNonNegative{0.0, false, kInf, false};
inline constexpr Range kAtLeastOne{1.0, false, kInf, false};
/// A position in a scene (kMaxCoordinate).
inline constexpr Range kCoordinate{-kMaxCoordinate, false, kMaxCoordinate, false};
/// A length or size in a scene, > 0 (kMaxCoordinate).
inline constexpr Range kLength{0.0, true, kMaxCoordinate, false};
/// A count of passes within one scene step (kMaxPassesPerStep).
inline constexpr Range kPassesPerStep{1.0, false, kMaxPassesPerStep, false};

/// The names a scene may write for an enum, each with its value, in the order error messages list them.
template <class Enum>
using Choices = std::vector<std::pair<std::string, Enum>>;

/// A value (possibly absent) at a JSON path of the scene named `source`: all an error message needs, so each
/// check is one call instead of hand-assembled text per key. The typed readers below require a present value.
/// @throws SceneError (every reader and fail): `<path> must be ..., got <value> (<source>)`.
class Node {
 public:
  /// @param value  the value, or nullptr when the key is absent; must outlive the node
  /// @param path  JSON path of the value, "" for the whole document
  /// @param source  the scene's name in messages (scene_source()); must outlive the node
  Node(const json* value, std::string path, const std::string& source)
      : m_value(value), m_path(std::move(path)), m_source(&source) {}

  bool present() const { return m_value != nullptr; }
  const json& value() const { return *m_value; }
  const std::string& path() const { return m_path; }
  const std::string& source() const { return *m_source; }
  /// The path, or "the scene" for the whole document.
  std::string name() const { return m_path.empty() ? "the scene" : m_path; }

  /// Throws `<path> <problem>, got <value> (<source>)`.
  [[noreturn]] void fail(const std::string& problem) const;
  /// Throws `<path> <problem> (<source>)<suffix>` for problems without a value (missing or unknown keys).
  [[noreturn]] void fail_without_value(const std::string& problem, const std::string& suffix = "") const;

  /// The value at `key`, absent when this node is absent or not an object or has no such key.
  Node child(const std::string& key) const;
  /// Element `index` of an array; the caller checks that it exists.
  Node element(std::size_t index) const;

  const json& array() const;
  /// A finite number within `range`.
  double number(const Range& range = kAny) const;
  /// A JSON integer within `range` and within Int. Only JSON integers are accepted: 1.0 for a count more
  /// likely hides a mistake than saves typing.
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
  bool boolean() const;
  std::string string() const;
  /// An array of 3 finite numbers.
  /// @param range  of each of the three numbers
  Vec3 vec3(const Range& range = kAny) const;
  /// A non-zero vector, normalised: directions and normals are stored as unit vectors.
  Vec3 unit_vec3() const;
  /// The value of the string among `choices`.
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
/// silently replaced by its default. An absent object reads nothing and leaves every default in place; each
/// read() likewise leaves `out` as it is when the key is absent.
/// @throws SceneError when the node is present but not an object, has a key not in `known`, or a value fails
///         its reader.
class ObjectReader {
 public:
  ObjectReader(const Node& node, const std::vector<std::string>& known);

  Node operator[](const std::string& key) const { return m_node.child(key); }

  void read(const std::string& key, Scalar& out, const Range& range = kAny) const;
  void read(const std::string& key, int& out, const Range& range) const;
  void read(const std::string& key, std::int64_t& out, const Range& range) const;
  void read(const std::string& key, bool& out) const;
  void read(const std::string& key, Vec3& out, const Range& range = kAny) const;
  /// A non-zero vector, stored normalised.
  void read_unit(const std::string& key, Vec3& out) const;
  template <class Enum>
  void read_choice(const std::string& key, Enum& out, const Choices<Enum>& choices) const {
    if (const Node n = m_node.child(key); n.present()) out = n.choice(choices);
  }

  /// Reports `lo_key` > `hi_key` on the key the user actually wrote (the other may be a default).
  void require_order(const std::string& lo_key, double lo, const std::string& hi_key, double hi) const;
  /// Requires `max` > `min` on every axis, reported as require_order does.
  void require_box(const Vec3& min, const Vec3& max) const;

 private:
  Node m_node;
};

/// The required `type` of a list element; checked before the keys, since the type decides which are known.
/// @throws SceneError when the element is not an object or its type is missing or not among `choices`.
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

/// Each element of an array read by `read_one`; empty when the node is absent.
/// @throws SceneError when the node is not an array, or as `read_one`.
template <class T>
std::vector<T> read_list(const Node& node, T (*read_one)(const Node&)) {
  std::vector<T> items;
  if (!node.present()) return items;
  for (std::size_t i = 0; i < node.array().size(); ++i)
    items.push_back(read_one(node.element(i)));
  return items;
}

}  // namespace drench::loader
