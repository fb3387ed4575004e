#include <drench/bullet/soft_body_builder.hpp>

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

#include <drench/common/error.hpp>

namespace drench::bullet {

namespace {

[[noreturn]] void bad_setting(const std::string& key, const std::string& range, const std::string& value) {
  throw SceneError("cloth." + key + " must be " + range + ", got " + value);
}

void check_range(const std::string& key, double value, double low, bool low_open, double high, bool high_open,
                 const std::string& range) {
  // Written so that NaN fails every comparison and is rejected.
  const bool above = low_open ? value > low : value >= low;
  const bool below = high_open ? value < high : value <= high;
  if (!(above && below)) bad_setting(key, range, format_number(value));
}

std::string format_vec3(const Vec3& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + ")";
}

std::string obj_error(const std::string& path, const std::string& problem) {
  return "cloth.mesh: OBJ file \"" + path + "\" " + problem;
}

// tinyobjloader's messages end in newlines and may hold several lines.
std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  while (!text.empty() && text.back() == ' ')
    text.pop_back();
  return text;
}

/// What tinyobjloader 2.0rc10 lets pass silently, checked on the text first: a coordinate that is not a
/// number
/// ("nan" and "abc" both parse as 0) or not finite, and a face of fewer than 3 vertices (dropped with a
/// warning).
void check_obj_text(const std::string& path, const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    std::istringstream tokens(line);
    std::string keyword;
    tokens >> keyword;
    if (keyword == "v") {
      for (int k = 0; k < 3; ++k) {
        std::string token;
        if (!(tokens >> token)) {
          throw SceneError(
              obj_error(path, "line " + std::to_string(number) + ": a vertex needs 3 coordinates"));
        }
        char* end = nullptr;
        const double value = std::strtod(token.c_str(), &end);
        if (end != token.c_str() + token.size() || !std::isfinite(value)) {
          throw SceneError(obj_error(path, "line " + std::to_string(number) + ": vertex coordinate \"" +
                                               token + "\" is not a finite number"));
        }
      }
    } else if (keyword == "f") {
      int count = 0;
      for (std::string token; tokens >> token;)
        ++count;
      if (count < 3) {
        throw SceneError(obj_error(path, "line " + std::to_string(number) +
                                             ": a face needs at least 3 vertices, got " +
                                             std::to_string(count)));
      }
    }
  }
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace

void validate_cloth_settings(const ClothSettings& s) {
  constexpr double inf = HUGE_VAL;
  if (s.mesh.empty()) bad_setting("mesh", "\"patch\" or the path of an OBJ file", "\"\"");
  if (!s.center.allFinite()) bad_setting("center", "finite", format_vec3(s.center));
  check_range("size_x", s.size_x, 0.0, true, inf, true, "> 0 and finite");
  check_range("size_z", s.size_z, 0.0, true, inf, true, "> 0 and finite");
  if (s.nodes_x < 2) bad_setting("nodes_x", ">= 2", std::to_string(s.nodes_x));
  if (s.nodes_z < 2) bad_setting("nodes_z", ">= 2", std::to_string(s.nodes_z));
  if (static_cast<long long>(s.nodes_x) * s.nodes_z > INT_MAX / 8) {
    // Bullet counts nodes, links and faces in int.
    bad_setting("nodes_x", "such that nodes_x * nodes_z <= " + std::to_string(INT_MAX / 8),
                std::to_string(s.nodes_x) + " (nodes_z " + std::to_string(s.nodes_z) + ")");
  }
  check_range("area_density", s.area_density, 0.0, true, inf, true, "> 0 and finite");
  if (s.pinned != "corners" && s.pinned != "corner" && s.pinned != "none") {
    bad_setting("pinned", "one of \"corners\", \"corner\", \"none\"", "\"" + s.pinned + "\"");
  }
  if (s.position_iterations < 4) {
    bad_setting("position_iterations", ">= 4 (1 blows the 57 x 57 patch up at dt = 1 ms)",
                std::to_string(s.position_iterations));
  }
  if (s.substeps < 1) bad_setting("substeps", ">= 1", std::to_string(s.substeps));
  check_range("stretch_stiffness", s.stretch_stiffness, 0.0, true, 1.0, false, "in (0, 1]");
  check_range("bending_stiffness", s.bending_stiffness, 0.0, false, 1.0, false, "in [0, 1]");
  check_range("damping", s.damping, 0.0, false, 1.0, false, "in [0, 1]");
}

TriangleMesh load_obj_mesh(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw SceneError(obj_error(path, std::string("cannot be read: ") + std::strerror(errno)));
  const std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  if (file.bad()) throw SceneError(obj_error(path, std::string("cannot be read: ") + std::strerror(errno)));
  check_obj_text(path, text);
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // From the text: materials are not needed (ParseFromString ignores mtllib).
  if (!reader.ParseFromString(text, "", config)) {
    throw SceneError(obj_error(path, "cannot be parsed: " + one_line(reader.Error())));
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
        throw SceneError(obj_error(path, "has a face with " + std::to_string(n) +
                                             " vertices that could not be triangulated (object \"" +
                                             shape.name + "\", face " + std::to_string(f) + ")"));
      }
      Triangle t;
      for (std::size_t k = 0; k < 3; ++k) {
        const int v = shape.mesh.indices[offset + k].vertex_index;
        if (v < 0 || static_cast<std::size_t>(v) >= vertex_count) {
          throw SceneError(obj_error(path, "has a face with vertex index " + std::to_string(v + 1) +
                                               " out of range 1.." + std::to_string(vertex_count)));
        }
        t[k] = static_cast<Index>(v);
      }
      offset += n;
      triangles.push_back(t);
    }
  }
  if (triangles.empty()) throw SceneError(obj_error(path, "has no faces"));

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
          obj_error(path, "has a non-finite vertex " + std::to_string(v + 1) + " " + format_vec3(x)));
    }
    new_index[v] = static_cast<Index>(mesh.positions.size());
    mesh.positions.push_back(x);
  }
  mesh.triangles.reserve(triangles.size());
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      throw SceneError(obj_error(path, "has face " + std::to_string(f + 1) + " that repeats a vertex (" +
                                           std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
                                           std::to_string(t[2] + 1) + ")"));
    }
    const Triangle mapped{new_index[t[0]], new_index[t[1]], new_index[t[2]]};
    if (!(triangle_area(mesh.positions[mapped[0]], mesh.positions[mapped[1]], mesh.positions[mapped[2]]) >
          0.0)) {
      throw SceneError(obj_error(path, "has face " + std::to_string(f + 1) + " of zero area"));
    }
    mesh.triangles.push_back(mapped);
  }
  if (mesh.positions.size() > static_cast<std::size_t>(INT_MAX / 8)) {
    throw SceneError(obj_error(path, "has " + std::to_string(mesh.positions.size()) +
                                         " vertices, more than Bullet's " + std::to_string(INT_MAX / 8)));
  }
  return mesh;
}

std::unique_ptr<btSoftBody> create_from_triangles(btSoftBodyWorldInfo& world_info, const TriangleMesh& mesh) {
  btAlignedObjectArray<btVector3> x;
  x.resize(static_cast<int>(mesh.positions.size()));
  for (int i = 0; i < x.size(); ++i)
    x[i] = to_bt(mesh.positions[i]);
  auto body = std::make_unique<btSoftBody>(&world_info, x.size(), &x[0], nullptr);
  // CreateFromTriMesh's order: per triangle the edges (2, 0), (0, 1), (1, 2), each the first time it is seen
  // in either direction, then the face.
  std::unordered_set<std::uint64_t> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    for (int j = 2, k = 0; k < 3; j = k++) {
      const std::uint64_t key = (std::uint64_t{std::min(t[j], t[k])} << 32) | std::max(t[j], t[k]);
      if (edges.insert(key).second) body->appendLink(static_cast<int>(t[j]), static_cast<int>(t[k]));
    }
    body->appendFace(static_cast<int>(t[0]), static_cast<int>(t[1]), static_cast<int>(t[2]));
  }
  body->randomizeConstraints();  // deterministic (fixed seed), as CreateFromTriMesh does by default
  return body;
}

int append_bending_links(btSoftBody& body, btSoftBody::Material* material) {
  const int n = body.m_nodes.size();
  if (n == 0) return 0;
  std::vector<std::vector<int>> neighbours(n);
  for (int l = 0; l < body.m_links.size(); ++l) {
    const int a = node_index(body, body.m_links[l].m_n[0]);
    const int b = node_index(body, body.m_links[l].m_n[1]);
    if (a == b) continue;
    neighbours[a].push_back(b);
    neighbours[b].push_back(a);
  }
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  // Bullet appends (i, j) for j ascending, then i > j ascending, wherever the graph distance is exactly 2.
  // near[i] == j marks i as within one link of j.
  std::vector<int> near(n, -1);
  std::vector<int> candidates;
  const int links_before = body.m_links.size();
  for (int j = 0; j < n; ++j) {
    near[j] = j;
    for (int k : neighbours[j])
      near[k] = j;
    candidates.clear();
    for (int k : neighbours[j]) {
      for (int i : neighbours[k]) {
        if (i > j && near[i] != j) candidates.push_back(i);
      }
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    for (int i : candidates) {
      body.appendLink(i, j, material);
      // Bullet writes 1 into this signed 1-bit field, which holds it as -1: the same bit, without the
      // overflow warning.
      body.m_links[body.m_links.size() - 1].m_bbending = -1;
    }
  }
  return body.m_links.size() - links_before;
}

ScalarArray node_masses_from_area(const btSoftBody& body, double area_density) {
  ScalarArray area_sum(body.m_nodes.size(), 0.0);
  for (int f = 0; f < body.m_faces.size(); ++f) {
    const btSoftBody::Face& face = body.m_faces[f];
    const double area =
        triangle_area(to_vec3(face.m_n[0]->m_x), to_vec3(face.m_n[1]->m_x), to_vec3(face.m_n[2]->m_x));
    for (int k = 0; k < 3; ++k)
      area_sum[node_index(body, face.m_n[k])] += area;
  }
  ScalarArray masses(area_sum.size());
  for (std::size_t i = 0; i < masses.size(); ++i)
    masses[i] = area_density * area_sum[i] / 3.0;
  return masses;
}

std::vector<int> pinned_nodes(const btSoftBody& body, const std::string& pinned) {
  std::vector<std::array<double, 2>> directions;
  if (pinned == "corner") {
    directions = {{-1.0, -1.0}};
  } else if (pinned == "corners") {
    directions = {{-1.0, -1.0}, {1.0, -1.0}, {-1.0, 1.0}, {1.0, 1.0}};
  } else if (pinned != "none") {
    bad_setting("pinned", "one of \"corners\", \"corner\", \"none\"", "\"" + pinned + "\"");
  }
  std::vector<int> nodes;
  if (body.m_nodes.size() == 0) return nodes;
  for (const auto& d : directions) {
    int best = 0;
    double best_value = -HUGE_VAL;
    for (int i = 0; i < body.m_nodes.size(); ++i) {
      const btVector3& x = body.m_nodes[i].m_x;
      const double value = d[0] * x.x() + d[1] * x.z();
      if (value > best_value) {
        best = i;
        best_value = value;
      }
    }
    nodes.push_back(best);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

std::unique_ptr<btSoftBody> create_cloth_body(btSoftBodyWorldInfo& world_info,
                                              const ClothSettings& settings) {
  validate_cloth_settings(settings);
  std::unique_ptr<btSoftBody> body;
  if (settings.mesh == "patch") {
    const Vec3& c = settings.center;
    const double hx = 0.5 * settings.size_x;
    const double hz = 0.5 * settings.size_z;
    // CreatePatch's "x" runs from corner00 to corner10 and its "y" from corner00 to corner01: here x and z.
    // Pins are set below from the area masses, so none here (fixeds = 0); gendiags adds the shear links.
    body.reset(btSoftBodyHelpers::CreatePatch(
        world_info, btVector3(c.x() - hx, c.y(), c.z() - hz), btVector3(c.x() + hx, c.y(), c.z() - hz),
        btVector3(c.x() - hx, c.y(), c.z() + hz), btVector3(c.x() + hx, c.y(), c.z() + hz), settings.nodes_x,
        settings.nodes_z, 0, true));
  } else {
    body = create_from_triangles(world_info, load_obj_mesh(settings.mesh));
  }

  // Before anything reads the margin back (node tree volumes are refreshed from it on the first step).
  body->getCollisionShape()->setMargin(CLOTH_COLLISION_MARGIN);
  body->m_materials[0]->m_kLST = settings.stretch_stiffness;
  if (settings.bending_stiffness > 0.0) {
    btSoftBody::Material* bending = body->appendMaterial();
    bending->m_kLST = settings.bending_stiffness;
    append_bending_links(*body, bending);
  }
  body->m_cfg.piterations = settings.position_iterations;
  body->m_cfg.kDP = settings.damping;
  body->m_cfg.collisions = btSoftBody::fCollision::SDF_RS;  // rigid-soft only: no self collision
  body->setSelfCollision(false);

  // setMass node by node: setTotalMass(m, true), Bullet's masses from faces, would un-pin every node.
  const ScalarArray masses = node_masses_from_area(*body, settings.area_density);
  for (int i = 0; i < body->m_nodes.size(); ++i)
    body->setMass(i, masses[i]);
  for (int i : pinned_nodes(*body, settings.pinned))
    body->setMass(i, 0.0);
  return body;
}

void set_node_masses(btSoftBody& body, const std::vector<std::pair<int, double>>& masses) {
  for (const auto& [node, mass] : masses) {
    if (node < 0 || node >= body.m_nodes.size()) {
      throw std::invalid_argument("set_node_masses: node " + std::to_string(node) + " out of range [0, " +
                                  std::to_string(body.m_nodes.size()) + ")");
    }
    if (!(mass >= 0.0) || !std::isfinite(mass)) {
      throw std::invalid_argument("set_node_masses: node " + std::to_string(node) +
                                  " mass must be >= 0, got " + format_number(mass));
    }
  }
  for (const auto& [node, mass] : masses) {
    btSoftBody::Node& n = body.m_nodes[node];
    n.m_im = mass > 0.0 ? 1.0 / mass : 0.0;
    // Bullet moves every node by its velocity, pinned or not: a node pinned while moving would drift on.
    if (mass == 0.0) n.m_v.setZero();
  }
  body.updateLinkConstants();
}

}  // namespace drench::bullet
