#include <drench/coupling/static_obstacles.hpp>

#include <algorithm>
#include <cmath>

#include <drench/common/error.hpp>

namespace drench {

namespace {

constexpr double kPi = 3.14159265358979323846;

void check_positive(const std::string& key, const char* name, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw SceneError(key + "." + name + " must be > 0 and finite, got " + format_number(value));
  }
}

/// Appends the obstacles' nodes and triangles to `mesh` after its nodes, static (positions_t1 = positions_t0
/// for the new nodes) and of inverse mass 0.
void append_obstacles(const std::vector<TriangleMesh>& obstacles, ClothMesh& mesh) {
  const std::size_t before = mesh.positions_t0.size();
  for (const TriangleMesh& obstacle : obstacles) {
    const auto first = static_cast<Index>(mesh.positions_t0.size());
    mesh.positions_t0.insert(mesh.positions_t0.end(), obstacle.positions.begin(), obstacle.positions.end());
    for (const Triangle& t : obstacle.triangles)
      mesh.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
  }
  mesh.positions_t1.resize(before);
  mesh.positions_t1.insert(mesh.positions_t1.end(), mesh.positions_t0.begin() + static_cast<long>(before),
                           mesh.positions_t0.end());
  mesh.inverse_masses.resize(mesh.positions_t0.size(), 0.0);
}

}  // namespace

TriangleMesh v_plane_mesh(const ObstacleSettings& s, const std::string& key) {
  if (!s.center.allFinite()) throw SceneError(key + ".center must be finite");
  if (!(s.angle_deg > 0.0 && s.angle_deg < 180.0)) {
    throw SceneError(key + ".angle_deg must be in (0, 180), got " + format_number(s.angle_deg));
  }
  check_positive(key, "size", s.size);
  check_positive(key, "width", s.width);
  check_positive(key, "triangle_size", s.triangle_size);
  const int along = static_cast<int>(std::ceil(s.size / s.triangle_size - 1e-9));
  const int across = static_cast<int>(std::ceil(s.width / s.triangle_size - 1e-9));
  if (static_cast<double>(2 * along + 1) * (across + 1) > 1e7) {
    throw SceneError(key + ".triangle_size " + format_number(s.triangle_size) +
                     " makes more than 10 million nodes");
  }
  const double half = 0.5 * s.angle_deg * kPi / 180.0;
  // Row r in [-along, along] lies at distance |r| / along * size from the line where the planes meet, on the
  // plane of x < 0 for r < 0.
  TriangleMesh mesh;
  const int rows = 2 * along + 1;
  const int columns = across + 1;
  for (int r = -along; r <= along; ++r) {
    const double d = s.size * std::abs(r) / along;
    const Vec3 offset((r < 0 ? -1.0 : 1.0) * d * std::sin(half), d * std::cos(half), 0.0);
    for (int c = 0; c < columns; ++c) {
      const double z = -0.5 * s.width + s.width * c / across;
      mesh.positions.push_back(s.center + offset + Vec3(0.0, 0.0, z));
    }
  }
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < columns; ++c) {
      const auto a = static_cast<Index>(r * columns + c);  // (x smaller, z smaller)
      const Index b = a + 1;                               // z larger
      const auto d = static_cast<Index>(a + columns);      // x larger
      const Index e = d + 1;
      // Counter-clockwise seen from inside the V (from above the surface): a -> b -> d has normal
      // (b - a) x (d - a) = z x (outward along the slope), which points into the V.
      mesh.triangles.push_back({a, b, d});
      mesh.triangles.push_back({b, e, d});
    }
  }
  return mesh;
}

void validate_triangle_mesh(const TriangleMesh& mesh, const std::string& what) {
  if (mesh.triangles.empty()) throw Error(what + " has no triangles");
  const std::size_t m = mesh.positions.size();
  for (std::size_t i = 0; i < m; ++i) {
    if (!mesh.positions[i].allFinite())
      throw Error(what + ": vertex " + std::to_string(i) + " is not finite");
  }
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    for (Index v : t) {
      if (v >= m) {
        throw Error(what + ": triangle " + std::to_string(f) + " has vertex index " + std::to_string(v) +
                    ", but the mesh has " + std::to_string(m) + " vertices");
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      throw Error(what + ": triangle " + std::to_string(f) + " repeats a vertex");
    }
    const Vec3& a = mesh.positions[t[0]];
    if (!((mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).squaredNorm() > 0.0)) {
      throw Error(what + ": triangle " + std::to_string(f) + " has zero area");
    }
  }
}

ClothWithObstacles::ClothWithObstacles(ClothEngine* cloth, std::vector<TriangleMesh> obstacles,
                                       double clearance)
    : m_cloth(cloth), m_obstacles(std::move(obstacles)) {
  if (m_obstacles.empty()) throw Error("ClothWithObstacles needs at least one obstacle");
  for (std::size_t i = 0; i < m_obstacles.size(); ++i)
    validate_triangle_mesh(m_obstacles[i], "obstacles[" + std::to_string(i) + "]");
  pull_cloth();
  if (m_cloth) {
    append_obstacles(m_obstacles, m_rigid);
    CouplingSettings settings;  // free slip: the cloth slides on the obstacles as Bullet's would
    settings.cloth_thickness = clearance;
    m_holder = std::make_unique<Coupler>(settings, false);
  }
}

ClothWithObstacles::~ClothWithObstacles() = default;

void ClothWithObstacles::hold_cloth_off_obstacles(double dt) {
  const std::size_t m = m_cloth_nodes;
  const auto first = [m](const Vec3Array& array) {
    return Vec3Array(array.begin(), array.begin() + static_cast<long>(m));
  };
  const Vec3Array x0 = first(m_mesh.positions_t0);
  Vec3Array x1 = first(m_mesh.positions_t1);
  Vec3Array v(m);
  ScalarArray masses(m);
  bool any_moves = false;
  for (std::size_t i = 0; i < m; ++i) {
    v[i] = (x1[i] - x0[i]) / dt;
    const double im = m_mesh.inverse_masses[i];
    masses[i] = im > 0.0 ? 1.0 / im : 1.0;  // the obstacles' nodes take nothing: only the ratio matters
    any_moves = any_moves || im > 0.0;
  }
  if (!any_moves) return;
  m_holder->step(FluidView{&x0, &x1, &v, &masses}, m_rigid, dt, m_hold_stats);
  for (std::size_t i = 0; i < m; ++i) {
    // A pinned node goes where its engine puts it (end_step would ignore the change anyway).
    if (m_mesh.inverse_masses[i] > 0.0) m_mesh.positions_t1[i] = x1[i];
  }
}

void ClothWithObstacles::pull_cloth() {
  const std::size_t nodes = cloth_nodes();
  const std::size_t triangles = m_cloth ? m_cloth->mesh().triangle_count() : 0;
  if (!m_built || nodes != m_cloth_nodes || triangles != m_cloth_triangles) {
    m_mesh = ClothMesh();
    if (m_cloth) {
      m_mesh.triangles = m_cloth->mesh().triangles;
      m_mesh.positions_t0.resize(nodes);
      m_mesh.inverse_masses.resize(nodes);
    }
    append_obstacles(m_obstacles, m_mesh);
    m_cloth_nodes = nodes;
    m_cloth_triangles = triangles;
    m_built = true;
  }
  if (!m_cloth) return;
  const ClothMesh& cloth = m_cloth->mesh();
  std::copy(cloth.positions_t0.begin(), cloth.positions_t0.end(), m_mesh.positions_t0.begin());
  std::copy(cloth.positions_t1.begin(), cloth.positions_t1.end(), m_mesh.positions_t1.begin());
  std::copy(cloth.inverse_masses.begin(), cloth.inverse_masses.end(), m_mesh.inverse_masses.begin());
}

void ClothWithObstacles::begin_step() {
  if (m_cloth) m_cloth->begin_step();
  pull_cloth();
}

void ClothWithObstacles::apply_impulses(const Vec3Array& impulses) {
  if (!m_cloth) return;
  m_cloth->apply_impulses(Vec3Array(impulses.begin(), impulses.begin() + static_cast<long>(m_cloth_nodes)));
}

void ClothWithObstacles::set_carried_masses(const ScalarArray& carried) {
  if (carried.size() != m_mesh.node_count()) {
    throw std::invalid_argument("set_carried_masses: " + std::to_string(carried.size()) + " masses for " +
                                std::to_string(m_mesh.node_count()) + " nodes");
  }
  if (!m_cloth) return;
  m_cloth->set_carried_masses(
      ScalarArray(carried.begin(), carried.begin() + static_cast<long>(m_cloth_nodes)));
}

void ClothWithObstacles::step(double dt) {
  if (!m_cloth) return;
  m_cloth->step(dt);
  const Vec3Array& t1 = m_cloth->mesh().positions_t1;
  std::copy(t1.begin(), t1.end(), m_mesh.positions_t1.begin());
  // A non-finite cloth is not corrected: the step reports it and nothing couples it.
  if (std::all_of(t1.begin(), t1.end(), [](const Vec3& x) { return x.allFinite(); }))
    hold_cloth_off_obstacles(dt);
}

void ClothWithObstacles::end_step(double dt) {
  if (m_cloth) {
    Vec3Array& t1 = m_cloth->mesh().positions_t1;
    std::copy(m_mesh.positions_t1.begin(), m_mesh.positions_t1.begin() + static_cast<long>(m_cloth_nodes),
              t1.begin());
    m_cloth->end_step(dt);
    // What the engine holds now (rounded, for a single-precision engine), for the leak audit.
    std::copy(t1.begin(), t1.end(), m_mesh.positions_t1.begin());
  }
}

Vec3Array ClothWithObstacles::velocities() const {
  Vec3Array v = m_cloth ? m_cloth->velocities() : Vec3Array();
  v.resize(m_mesh.node_count(), Vec3::Zero());
  return v;
}

double ClothWithObstacles::total_mass() const {
  return m_cloth ? m_cloth->total_mass() : 0.0;
}

}  // namespace drench
