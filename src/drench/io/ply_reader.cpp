#include <drench/io/ply_reader.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>

#include <drench/common/error.hpp>
#include <drench/common/file_text.hpp>

namespace drench {

namespace {

enum class PlyType { INT8, UINT8, INT16, UINT16, INT32, UINT32, FLOAT32, FLOAT64 };

struct PlyProperty {
  std::string name;
  bool list = false;
  PlyType count_type = PlyType::UINT8;  ///< lists only
  PlyType type = PlyType::FLOAT32;      ///< the value's type, or a list item's
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  int line = 0;  ///< header line of its `element` line, for messages
};

/// Every name PLY's specification gives each type: the original ones and the sized aliases.
bool parse_type(const std::string& word, PlyType& type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::INT8},      {"int8", PlyType::INT8},       {"uchar", PlyType::UINT8},
      {"uint8", PlyType::UINT8},    {"short", PlyType::INT16},     {"int16", PlyType::INT16},
      {"ushort", PlyType::UINT16},  {"uint16", PlyType::UINT16},   {"int", PlyType::INT32},
      {"int32", PlyType::INT32},    {"uint", PlyType::UINT32},     {"uint32", PlyType::UINT32},
      {"float", PlyType::FLOAT32},  {"float32", PlyType::FLOAT32}, {"double", PlyType::FLOAT64},
      {"float64", PlyType::FLOAT64}};
  for (const auto& [name, value] : kNames) {
    if (word == name) {
      type = value;
      return true;
    }
  }
  return false;
}

std::size_t type_size(PlyType type) {
  switch (type) {
    case PlyType::INT8:
    case PlyType::UINT8:
      return 1;
    case PlyType::INT16:
    case PlyType::UINT16:
      return 2;
    case PlyType::INT32:
    case PlyType::UINT32:
    case PlyType::FLOAT32:
      return 4;
    case PlyType::FLOAT64:
      return 8;
  }
  return 0;
}

bool is_real(PlyType type) {
  return type == PlyType::FLOAT32 || type == PlyType::FLOAT64;
}

template <class T>
T load_le(const char* p) {
  // x86-64 and aarch64 are little-endian, as the files are (the writer's assumption too).
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

double load_real(PlyType type, const char* p) {
  return type == PlyType::FLOAT32 ? static_cast<double>(load_le<float>(p)) : load_le<double>(p);
}

std::int64_t load_integer(PlyType type, const char* p) {
  switch (type) {
    case PlyType::INT8:
      return load_le<std::int8_t>(p);
    case PlyType::UINT8:
      return load_le<std::uint8_t>(p);
    case PlyType::INT16:
      return load_le<std::int16_t>(p);
    case PlyType::UINT16:
      return load_le<std::uint16_t>(p);
    case PlyType::INT32:
      return load_le<std::int32_t>(p);
    case PlyType::UINT32:
      return load_le<std::uint32_t>(p);
    default:
      return 0;  // real types are rejected where an integer is required
  }
}

std::vector<std::string> split_words(const std::string& line) {
  std::istringstream stream(line);
  std::vector<std::string> words;
  std::string word;
  while (stream >> word)
    words.push_back(word);
  return words;
}

/// The header, up to and including `end_header`; `body` is the offset of the first data byte.
struct PlyHeader {
  std::vector<PlyElement> elements;
  std::size_t body = 0;
};

PlyHeader parse_header(const std::string& bytes, const std::string& name) {
  const auto fail = [&](const std::string& problem) { return IoError(name + ": " + problem); };
  if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0)
    throw fail("not a PLY file (it does not start with a \"ply\" line)");

  PlyHeader header;
  bool format_seen = false;
  std::size_t start = 0;
  for (int line_number = 1;; ++line_number) {
    const std::size_t newline = bytes.find('\n', start);
    if (newline == std::string::npos) throw fail("truncated header: no end_header line");
    std::string line = bytes.substr(start, newline - start);
    start = newline + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto line_fail = [&](const std::string& problem) {
      return fail("header line " + std::to_string(line_number) + " (\"" + line + "\"): " + problem);
    };
    if (line_number == 1) continue;  // "ply", checked above
    const std::vector<std::string> words = split_words(line);
    if (words.empty()) continue;
    const std::string& keyword = words[0];
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      if (!format_seen) throw line_fail("end of header without a format line");
      header.body = start;
      return header;
    }
    if (keyword == "format") {
      if (words.size() != 3) throw line_fail("expected format <type> 1.0");
      if (words[1] == "ascii" || words[1] == "binary_big_endian")
        throw line_fail(words[1] + " PLY is not supported; drench reads binary_little_endian");
      if (words[1] != "binary_little_endian") throw line_fail("unknown format " + words[1]);
      format_seen = true;
    } else if (keyword == "element") {
      if (words.size() != 3) throw line_fail("expected element <name> <count>");
      const std::string& count = words[2];
      // At most 18 digits: any count that large is far beyond the file anyway, and it cannot overflow.
      if (count.empty() || count.size() > 18 || count.find_first_not_of("0123456789") != std::string::npos)
        throw line_fail("the element count must be a non-negative integer");
      PlyElement element;
      element.name = words[1];
      element.count = std::stoull(count);
      element.line = line_number;
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty()) throw line_fail("a property before any element");
      PlyProperty property;
      if (words.size() == 5 && words[1] == "list") {
        property.list = true;
        if (!parse_type(words[2], property.count_type) || !parse_type(words[3], property.type))
          throw line_fail("unknown type");
        if (is_real(property.count_type)) throw line_fail("a list's count must have an integer type");
        property.name = words[4];
      } else if (words.size() == 3) {
        if (!parse_type(words[1], property.type)) throw line_fail("unknown type " + words[1]);
        property.name = words[2];
      } else {
        throw line_fail("expected property <type> <name> or property list <count type> <type> <name>");
      }
      header.elements.back().properties.push_back(property);
    } else {
      throw line_fail("unknown keyword " + keyword);
    }
  }
}

/// Index of the property called `name` in `element`, or -1.
int find_property(const PlyElement& element, const char* property_name) {
  for (std::size_t k = 0; k < element.properties.size(); ++k) {
    if (element.properties[k].name == property_name) return static_cast<int>(k);
  }
  return -1;
}

/// What a property means to the reader.
enum class Role { SKIP, X, Y, Z, VX, VY, VZ, INDICES };

}  // namespace

PlyData parse_ply(const std::string& bytes, const std::string& name) {
  const auto fail = [&](const std::string& problem) { return IoError(name + ": " + problem); };
  const PlyHeader header = parse_header(bytes, name);

  // Which element holds the vertices and the faces, and which of their properties matter.
  int vertex_element = -1, face_element = -1;
  bool has_velocities = false;
  std::vector<std::vector<Role>> roles(header.elements.size());
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    roles[e].assign(element.properties.size(), Role::SKIP);
    if (element.name == "vertex") {
      if (vertex_element >= 0)
        throw fail("two vertex elements (header line " + std::to_string(element.line) + ")");
      vertex_element = static_cast<int>(e);
      const char* axes[] = {"x", "y", "z"};
      for (int a = 0; a < 3; ++a) {
        const int k = find_property(element, axes[a]);
        if (k < 0) throw fail("element vertex has no property " + std::string(axes[a]));
        const PlyProperty& property = element.properties[k];
        if (property.list || !is_real(property.type))
          throw fail("vertex property " + property.name +
                     " must be a float or double, not a list or integer");
        roles[e][k] = static_cast<Role>(static_cast<int>(Role::X) + a);
      }
      // Velocities only as a complete real triple: a file with some other `vx` keeps it skipped.
      const char* velocity[] = {"vx", "vy", "vz"};
      int velocity_k[3];
      bool all_real = true;
      for (int a = 0; a < 3; ++a) {
        velocity_k[a] = find_property(element, velocity[a]);
        all_real = all_real && velocity_k[a] >= 0 && !element.properties[velocity_k[a]].list &&
                   is_real(element.properties[velocity_k[a]].type);
      }
      if (all_real) {
        has_velocities = true;
        for (int a = 0; a < 3; ++a)
          roles[e][velocity_k[a]] = static_cast<Role>(static_cast<int>(Role::VX) + a);
      }
    } else if (element.name == "face") {
      if (face_element >= 0)
        throw fail("two face elements (header line " + std::to_string(element.line) + ")");
      face_element = static_cast<int>(e);
      int k = find_property(element, "vertex_indices");
      if (k < 0) k = find_property(element, "vertex_index");
      if (k < 0) throw fail("element face has no list property vertex_indices");
      const PlyProperty& property = element.properties[k];
      if (!property.list || is_real(property.type))
        throw fail("face property " + property.name + " must be a list of integers");
      roles[e][k] = Role::INDICES;
    }
  }
  if (vertex_element < 0) throw fail("no vertex element");

  PlyData data;
  data.has_faces = face_element >= 0;
  const char* const begin = bytes.data();
  std::size_t at = header.body;
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    const PlyElement& element = header.elements[e];
    if (element.properties.empty()) continue;  // items of no bytes: nothing to read, however many
    // The smallest an item can be (lists empty): enough to refuse a count the file cannot hold before
    // allocating anything for it.
    std::size_t min_item = 0;
    for (const PlyProperty& property : element.properties)
      min_item += type_size(property.list ? property.count_type : property.type);
    const std::size_t remaining = bytes.size() - at;
    if (element.count > remaining / min_item) {
      throw fail("truncated: element " + element.name + " needs at least " + std::to_string(element.count) +
                 " x " + std::to_string(min_item) + " bytes, " + std::to_string(remaining) +
                 " remain after the header and the elements before it");
    }
    if (static_cast<int>(e) == vertex_element) {
      data.positions.reserve(element.count);
      if (has_velocities) data.velocities.reserve(element.count);
    }
    if (static_cast<int>(e) == face_element) data.triangles.reserve(element.count);

    for (std::uint64_t i = 0; i < element.count; ++i) {
      Vec3 x = Vec3::Zero(), velocity = Vec3::Zero();
      for (std::size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        const auto cut_off = [&]() {
          return fail("truncated: " + element.name + " " + std::to_string(i) + " of " +
                      std::to_string(element.count) + " is cut off at its property " + property.name);
        };
        if (!property.list) {
          const std::size_t size = type_size(property.type);
          if (bytes.size() - at < size) throw cut_off();
          const Role role = roles[e][k];
          if (role == Role::X || role == Role::Y || role == Role::Z)
            x[static_cast<int>(role) - static_cast<int>(Role::X)] = load_real(property.type, begin + at);
          else if (role == Role::VX || role == Role::VY || role == Role::VZ)
            velocity[static_cast<int>(role) - static_cast<int>(Role::VX)] =
                load_real(property.type, begin + at);
          at += size;
          continue;
        }
        const std::size_t count_size = type_size(property.count_type);
        if (bytes.size() - at < count_size) throw cut_off();
        const std::int64_t count = load_integer(property.count_type, begin + at);
        at += count_size;
        if (count < 0) {
          throw fail(element.name + " " + std::to_string(i) + ": list " + property.name +
                     " has a negative length " + std::to_string(count));
        }
        const std::size_t item_size = type_size(property.type);
        if (static_cast<std::uint64_t>(count) > (bytes.size() - at) / item_size) throw cut_off();
        if (roles[e][k] == Role::INDICES) {
          if (count != 3) {
            throw fail("face " + std::to_string(i) + " has " + std::to_string(count) +
                       " vertices; drench reads triangles only");
          }
          Triangle t;
          for (int c = 0; c < 3; ++c) {
            const std::int64_t v = load_integer(property.type, begin + at + c * item_size);
            if (v < 0 || v > std::numeric_limits<Index>::max()) {
              throw fail("face " + std::to_string(i) + " names vertex " + std::to_string(v) +
                         ", which is out of range");
            }
            t[c] = static_cast<Index>(v);
          }
          data.triangles.push_back(t);
        }
        at += static_cast<std::size_t>(count) * item_size;
      }
      if (static_cast<int>(e) == vertex_element) {
        if (!x.allFinite()) {
          throw fail("vertex " + std::to_string(i) + " has a non-finite coordinate (" + format_number(x.x()) +
                     ", " + format_number(x.y()) + ", " + format_number(x.z()) + ")");
        }
        data.positions.push_back(x);
        if (has_velocities) {
          if (!velocity.allFinite()) {
            throw fail("vertex " + std::to_string(i) + " has a non-finite velocity (" +
                       format_number(velocity.x()) + ", " + format_number(velocity.y()) + ", " +
                       format_number(velocity.z()) + ")");
          }
          data.velocities.push_back(velocity);
        }
      }
    }
  }
  if (at != bytes.size()) {
    throw fail(std::to_string(bytes.size() - at) +
               " bytes after the last element, which the header does not describe");
  }
  for (std::size_t f = 0; f < data.triangles.size(); ++f) {
    for (Index v : data.triangles[f]) {
      if (v >= data.positions.size()) {
        throw fail("face " + std::to_string(f) + " names vertex " + std::to_string(v) + ", but there are " +
                   std::to_string(data.positions.size()) + " vertices");
      }
    }
  }
  return data;
}

PlyData read_ply(const std::string& path) {
  std::string bytes;
  try {
    bytes = read_file_text(path, kMaxPlyFileBytes,
                           "4 GiB (" + std::to_string(kMaxPlyFileBytes) + " bytes) a PLY file");
  } catch (const FileTextError& e) {
    throw IoError(path + ": cannot read: " + e.reason());
  }
  return parse_ply(bytes, path);
}

}  // namespace drench
