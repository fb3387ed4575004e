#include <drench/bullet/soft_body_builder.hpp>

#include <BulletSoftBody/btSoftBodyHelpers.h>

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
  if (s.position_iterations < kMinClothPositionIterations || s.position_iterations > kMaxPassesPerStep) {
    bad_setting("position_iterations",
                "in [" + std::to_string(kMinClothPositionIterations) + ", " +
                    std::to_string(kMaxPassesPerStep) + "] (1 blows the 57 x 57 patch up at dt = 1 ms)",
                std::to_string(s.position_iterations));
  }
  if (s.substeps < 1 || s.substeps > kMaxPassesPerStep)
    bad_setting("substeps", "in [1, " + std::to_string(kMaxPassesPerStep) + "]", std::to_string(s.substeps));
  check_range("stretch_stiffness", s.stretch_stiffness, 0.0, true, 1.0, false, "in (0, 1]");
  check_range("bending_stiffness", s.bending_stiffness, 0.0, false, 1.0, false, "in [0, 1]");
  check_range("damping", s.damping, 0.0, false, 1.0, false, "in [0, 1]");
}

TriangleMesh load_cloth_obj_mesh(const std::string& path) {
  TriangleMesh mesh = load_obj_mesh(path, "cloth.mesh");
  if (mesh.positions.size() > static_cast<std::size_t>(INT_MAX / 8)) {
    throw SceneError("cloth.mesh: OBJ file \"" + path + "\" has " + std::to_string(mesh.positions.size()) +
                     " vertices, more than Bullet's " + std::to_string(INT_MAX / 8));
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
    body = create_from_triangles(world_info, load_cloth_obj_mesh(settings.mesh));
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
