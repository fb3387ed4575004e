#include <drench/scene/json_reader.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include <drench/common/error.hpp>

namespace drench::loader {

json parse_json_strict(const std::string& text, std::size_t max_depth, const std::string& path_prefix,
                       std::size_t start_depth) {
  // One frame per open array or object: the keys seen so far (objects) or the elements done (arrays), so a
  // duplicate is named by its JSON path.
  struct Frame {
    bool array = false;
    std::size_t elements = 0;
    std::string key;
    std::set<std::string> keys;  // a set: an object of a million keys stays fast
  };
  std::vector<Frame> stack;
  const auto path = [&]() {
    std::string text_path = path_prefix;
    for (std::size_t k = 0; k + 1 < stack.size(); ++k) {
      const Frame& f = stack[k];
      if (f.array) {
        text_path += "[" + std::to_string(f.elements) + "]";
      } else {
        text_path += (text_path.empty() ? "" : ".") + f.key;
      }
    }
    return text_path;
  };
  const auto value_done = [&]() {
    if (!stack.empty() && stack.back().array) ++stack.back().elements;
  };
  const json::parser_callback_t check = [&](int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        if (start_depth + stack.size() >= max_depth)
          throw SceneError("JSON nested deeper than " + std::to_string(max_depth) +
                           " levels of arrays and objects");
        stack.push_back({event == json::parse_event_t::array_start, 0, "", {}});
        break;
      case json::parse_event_t::key: {
        Frame& frame = stack.back();
        const std::string key = parsed.get<std::string>();
        if (!frame.keys.insert(key).second) {
          frame.key = key;
          stack.push_back({});  // so that path() includes the key itself
          const std::string where = path();
          throw SceneError("duplicate key \"" + key + "\" at " + where + "; each key may appear once");
        }
        frame.key = key;
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        value_done();
        break;
      case json::parse_event_t::value:
        value_done();
        break;
    }
    return true;
  };
  return json::parse(text, check);
}

std::string show(const json& value) {
  // dump() would print non-finite numbers (only possible in documents built in code, or --set 1e999) as null.
  if (value.is_number_float() && !std::isfinite(value.get<double>()))
    return format_number(value.get<double>());
  std::string text = value.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() > 80) text = text.substr(0, 77) + "...";
  return text;
}

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

std::string Range::describe() const {
  if (std::isinf(hi)) return std::string(lo_open ? "> " : ">= ") + format_number(lo);
  if (std::isinf(lo)) return std::string(hi_open ? "< " : "<= ") + format_number(hi);
  return std::string("in ") + (lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) +
         (hi_open ? ")" : "]");
}

void Node::fail(const std::string& problem) const {
  throw SceneError(name() + " " + problem + ", got " + show(*m_value) + " (" + *m_source + ")");
}

void Node::fail_without_value(const std::string& problem, const std::string& suffix) const {
  throw SceneError(name() + " " + problem + " (" + *m_source + ")" + suffix);
}

Node Node::child(const std::string& key) const {
  const json* found = nullptr;
  if (present() && m_value->is_object()) {
    const auto it = m_value->find(key);
    if (it != m_value->end()) found = &*it;
  }
  return Node(found, m_path.empty() ? key : m_path + "." + key, *m_source);
}

Node Node::element(std::size_t index) const {
  return Node(&m_value->at(index), m_path + "[" + std::to_string(index) + "]", *m_source);
}

const json& Node::array() const {
  if (!m_value->is_array()) fail("must be an array");
  return *m_value;
}

double Node::number(const Range& range) const {
  if (!m_value->is_number()) fail("must be a number");
  const double v = m_value->get<double>();
  if (!std::isfinite(v)) fail("must be finite");
  if (!range.contains(v)) fail("must be " + range.describe());
  return v;
}

bool Node::boolean() const {
  if (!m_value->is_boolean()) fail("must be true or false");
  return m_value->get<bool>();
}

std::string Node::string() const {
  if (!m_value->is_string()) fail("must be a string");
  return m_value->get<std::string>();
}

Vec3 Node::vec3(const Range& range) const {
  if (!m_value->is_array() || m_value->size() != 3) fail("must be an array of 3 numbers");
  return Vec3(element(0).number(range), element(1).number(range), element(2).number(range));
}

Vec3 Node::unit_vec3() const {
  const Vec3 v = vec3();
  const double length = v.stableNorm();
  if (!(length > 0.0)) fail("must be non-zero");
  return v / length;
}

ObjectReader::ObjectReader(const Node& node, const std::vector<std::string>& known) : m_node(node) {
  if (!node.present()) return;
  if (!node.value().is_object()) node.fail("must be an object");
  for (const auto& item : node.value().items()) {
    if (std::find(known.begin(), known.end(), item.key()) == known.end())
      node.child(item.key()).fail_without_value("is not a known key", "; known: " + join(known, false));
  }
}

void ObjectReader::read(const std::string& key, Scalar& out, const Range& range) const {
  if (const Node n = m_node.child(key); n.present()) out = n.number(range);
}

void ObjectReader::read(const std::string& key, int& out, const Range& range) const {
  if (const Node n = m_node.child(key); n.present()) out = n.integer<int>(range);
}

void ObjectReader::read(const std::string& key, std::int64_t& out, const Range& range) const {
  if (const Node n = m_node.child(key); n.present()) out = n.integer<std::int64_t>(range);
}

void ObjectReader::read(const std::string& key, bool& out) const {
  if (const Node n = m_node.child(key); n.present()) out = n.boolean();
}

void ObjectReader::read(const std::string& key, Vec3& out, const Range& range) const {
  if (const Node n = m_node.child(key); n.present()) out = n.vec3(range);
}

void ObjectReader::read_unit(const std::string& key, Vec3& out) const {
  if (const Node n = m_node.child(key); n.present()) out = n.unit_vec3();
}

void ObjectReader::require_order(const std::string& lo_key, double lo, const std::string& hi_key,
                                 double hi) const {
  if (lo <= hi) return;
  if (const Node n = m_node.child(hi_key); n.present())
    n.fail("must be >= " + m_node.child(lo_key).path() + " = " + show(lo));
  m_node.child(lo_key).fail("must be <= " + m_node.child(hi_key).path() + " = " + show(hi));
}

void ObjectReader::require_box(const Vec3& min, const Vec3& max) const {
  if ((max.array() > min.array()).all()) return;
  if (const Node n = m_node.child("max"); n.present())
    n.fail("must be > " + m_node.child("min").path() + " = " + show(min) + " on every axis");
  m_node.child("min").fail("must be < " + m_node.child("max").path() + " = " + show(max) + " on every axis");
}

}  // namespace drench::loader
