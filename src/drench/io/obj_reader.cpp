#include <drench/io/obj_reader.hpp>

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <sstream>

#include <drench/common/error.hpp>
#include <drench/common/file_text.hpp>

namespace drench {

namespace {

std::string obj_error(const std::string& key, const std::string& path, const std::string& problem) {
  return key + ": OBJ file \"" + path + "\" " + problem;
}

// tinyobjloader's messages end in newlines and may hold several lines.
std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  while (!text.empty() && text.back() == ' ')
    text.pop_back();
  return text;
}

/// The largest positive vertex index of the faces and its line, checked against the vertex count at the end
/// of the file (a face may name a vertex defined after it).
struct ForwardIndex {
  long long index = 0;
  int line = 0;
};

/// One vertex of an `f` line, `v`, `v/vt`, `v//vn` or `v/vt/vn`: each index an integer that fits an int
/// (tinyobjloader wraps larger ones silently: 4294967299 became vertex 3), not 0, and a negative vertex index
/// (counted back from the last vertex so far) within the vertices read so far.
void check_face_token(const std::string& key, const std::string& path, int line, const std::string& token,
                      long long vertices, ForwardIndex& largest) {
  const auto fail = [&](const std::string& problem) {
    throw SceneError(obj_error(key, path, "line " + std::to_string(line) + ": " + problem));
  };
  std::size_t start = 0;
  for (int part = 0; part < 3 && start <= token.size(); ++part) {
    const std::size_t slash = std::min(token.find('/', start), token.size());
    const std::string digits = token.substr(start, slash - start);
    start = slash + 1;
    if (digits.empty()) {
      if (part == 0) fail("face vertex \"" + token + "\" has no vertex index");
      continue;  // `v//vn`: no texture coordinate
    }
    const char* what = part == 0 ? "vertex index" : part == 1 ? "texture index" : "normal index";
    errno = 0;
    char* end = nullptr;
    const long long index = std::strtoll(digits.c_str(), &end, 10);
    if (end != digits.c_str() + digits.size())
      fail(std::string(what) + " \"" + digits + "\" is not an integer");
    if (errno == ERANGE || index > std::numeric_limits<int>::max() ||
        index < -std::numeric_limits<int>::max())
      fail(std::string(what) + " " + digits + " out of range (an OBJ index must fit 32 bits)");
    if (index == 0) fail(std::string(what) + " 0 is invalid (OBJ indices start at 1)");
    if (part != 0) continue;
    if (index < 0 && -index > vertices) {
      fail("vertex index " + digits + " out of range: only " + std::to_string(vertices) +
           " vertices precede it");
    }
    if (index > largest.index) largest = {index, line};
  }
}

/// What tinyobjloader 2.0rc10 lets pass silently, checked on the text first: a coordinate that is not a
/// number ("nan" and "abc" both parse as 0) or not finite, a face of fewer than 3 vertices (dropped with a
/// warning), and a face index that overflows an int or is out of range (wrapped or left to later checks).
void check_obj_text(const std::string& key, const std::string& path, const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  long long vertices = 0;
  ForwardIndex first_forward;
  for (int number = 1; std::getline(lines, line); ++number) {
    std::istringstream tokens(line);
    std::string keyword;
    tokens >> keyword;
    if (keyword == "v") {
      for (int k = 0; k < 3; ++k) {
        std::string token;
        if (!(tokens >> token)) {
          throw SceneError(
              obj_error(key, path, "line " + std::to_string(number) + ": a vertex needs 3 coordinates"));
        }
        char* end = nullptr;
        const double value = std::strtod(token.c_str(), &end);
        if (end != token.c_str() + token.size() || !std::isfinite(value)) {
          throw SceneError(obj_error(key, path,
                                     "line " + std::to_string(number) + ": vertex coordinate \"" + token +
                                         "\" is not a finite number"));
        }
      }
      ++vertices;
    } else if (keyword == "f") {
      int count = 0;
      for (std::string token; tokens >> token;) {
        ++count;
        check_face_token(key, path, number, token, vertices, first_forward);
      }
      if (count < 3) {
        throw SceneError(obj_error(key, path,
                                   "line " + std::to_string(number) +
                                       ": a face needs at least 3 vertices, got " + std::to_string(count)));
      }
    }
  }
  if (first_forward.line > 0 && first_forward.index > vertices) {
    throw SceneError(obj_error(key, path,
                               "line " + std::to_string(first_forward.line) + ": vertex index " +
                                   std::to_string(first_forward.index) + " out of range 1.." +
                                   std::to_string(vertices)));
  }
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace

TriangleMesh load_obj_mesh(const std::string& path, const std::string& key) {
  std::string text;
  try {
    text = read_file_text(path, kMaxObjFileBytes,
                          "1 GiB (" + std::to_string(kMaxObjFileBytes) + " bytes) an OBJ file");
  } catch (const FileTextError& e) {
    throw SceneError(obj_error(key, path, std::string("cannot be read: ") + e.reason()));
  }
  check_obj_text(key, path, text);
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // From the text: materials are not needed (ParseFromString ignores mtllib).
  if (!reader.ParseFromString(text, "", config)) {
    throw SceneError(obj_error(key, path, "cannot be parsed: " + one_line(reader.Error())));
  }
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  const std::size_t vertex_count = attrib.vertices.size() / 3;

  // Faces first, in file order, with the file's vertex indices.
  std::vector<Triangle> triangles;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    std::size_t offset = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
      const std::size_t n = shape.mesh.num_face_vertices[f];
      if (n != 3) {
        throw SceneError(obj_error(key, path,
                                   "has a face with " + std::to_string(n) +
                                       " vertices that could not be triangulated (object \"" + shape.name +
                                       "\", face " + std::to_string(f) + ")"));
      }
      Triangle t;
      for (std::size_t k = 0; k < 3; ++k) {
        const int v = shape.mesh.indices[offset + k].vertex_index;
        if (v < 0 || static_cast<std::size_t>(v) >= vertex_count) {
          throw SceneError(obj_error(key, path,
                                     "has a face with vertex index " + std::to_string(v + 1) +
                                         " out of range 1.." + std::to_string(vertex_count)));
        }
        t[k] = static_cast<Index>(v);
      }
      offset += n;
      triangles.push_back(t);
    }
  }
  if (triangles.empty()) throw SceneError(obj_error(key, path, "has no faces"));

  // Keep the vertices some face uses, in their order.
  constexpr Index unused = ~Index{0};
  std::vector<Index> new_index(vertex_count, unused);
  for (const Triangle& t : triangles) {
    for (Index v : t)
      new_index[v] = 0;
  }
  TriangleMesh mesh;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (new_index[v] == unused) continue;
    const Vec3 x(attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]);
    if (!x.allFinite()) {
      throw SceneError(
          obj_error(key, path, "has a non-finite vertex " + std::to_string(v + 1) + " " + format_vec3(x)));
    }
    new_index[v] = static_cast<Index>(mesh.positions.size());
    mesh.positions.push_back(x);
  }
  mesh.triangles.reserve(triangles.size());
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      throw SceneError(obj_error(key, path,
                                 "has face " + std::to_string(f + 1) + " that repeats a vertex (" +
                                     std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
                                     std::to_string(t[2] + 1) + ")"));
    }
    const Triangle mapped{new_index[t[0]], new_index[t[1]], new_index[t[2]]};
    if (!(triangle_area(mesh.positions[mapped[0]], mesh.positions[mapped[1]], mesh.positions[mapped[2]]) >
          0.0)) {
      throw SceneError(obj_error(key, path, "has face " + std::to_string(f + 1) + " of zero area"));
    }
    mesh.triangles.push_back(mapped);
  }
  return mesh;
}

}  // namespace drench
