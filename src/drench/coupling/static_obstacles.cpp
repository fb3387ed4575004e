#include <drench/coupling/static_obstacles.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include <drench/common/error.hpp>
#include <drench/common/stopwatch.hpp>
#include <drench/coupling/swept_water.hpp>

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
  // Counted in double first: size / triangle_size can be far beyond an int (1e300 / 0.005).
  const double rows_along = std::ceil(s.size / s.triangle_size - 1e-9);
  const double rows_across = std::ceil(s.width / s.triangle_size - 1e-9);
  if (!((2.0 * rows_along + 1.0) * (rows_across + 1.0) <= kMaxVPlaneNodes)) {
    throw SceneError(key + ".triangle_size " + format_number(s.triangle_size) + " makes " +
                     format_number((2.0 * rows_along + 1.0) * (rows_across + 1.0)) + " nodes of " + key +
                     ".size " + format_number(s.size) + " x " + key + ".width " + format_number(s.width) +
                     "; at most 10 million");
  }
  const int along = static_cast<int>(rows_along);
  const int across = static_cast<int>(rows_across);
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
                                       double clearance, RigidBodySource* bodies)
    : m_cloth(cloth), m_obstacles(std::move(obstacles)), m_bodies(bodies) {
  if (m_obstacles.empty() && !m_bodies) throw Error("ClothWithObstacles needs an obstacle or rigid bodies");
  for (std::size_t i = 0; i < m_obstacles.size(); ++i)
    validate_triangle_mesh(m_obstacles[i], "obstacles[" + std::to_string(i) + "]");
  if (m_cloth) {
    CouplingSettings settings;  // free slip: the cloth slides on the obstacles as Bullet's would
    settings.cloth_thickness = clearance;
    m_holder = std::make_unique<Coupler>(settings, false);
  }
  pull();
}

ClothWithObstacles::~ClothWithObstacles() = default;

void ClothWithObstacles::hold_cloth_off_obstacles(double dt) {
  const std::size_t m = cloth_nodes();
  if (m_rigid.triangles.empty()) return;
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

void ClothWithObstacles::rebuild() {
  const std::size_t nodes = cloth_nodes();
  m_mesh = ClothMesh();
  if (m_cloth) {
    m_mesh.triangles = m_cloth->mesh().triangles;
    m_mesh.positions_t0.resize(nodes);
    m_mesh.positions_t1.resize(nodes);
    m_mesh.inverse_masses.resize(nodes);
  }
  append_obstacles(m_obstacles, m_mesh);
  m_rigid = ClothMesh();
  append_obstacles(m_obstacles, m_rigid);
  m_surface_first.clear();
  m_rigid_first.clear();
  const auto append = [](const RigidSurface& s, ClothMesh& mesh) {
    const auto first = static_cast<Index>(mesh.positions_t0.size());
    for (const Triangle& t : s.triangles)
      mesh.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
    const std::size_t size = mesh.positions_t0.size() + s.positions_t0.size();
    mesh.positions_t0.resize(size);
    mesh.positions_t1.resize(size);
    mesh.inverse_masses.resize(size, 0.0);
    return static_cast<std::size_t>(first);
  };
  for (const RigidSurface& s : m_surfaces) {
    m_surface_first.push_back(append(s, m_mesh));
    // Static bodies hold the cloth as the static obstacles do; moving ones meet it in the engine's step.
    m_rigid_first.push_back(m_holder && s.motion == RigidMotion::STATIC ? append(s, m_rigid) : SIZE_MAX);
  }
  m_built = true;
}

void ClothWithObstacles::pull() {
  std::vector<std::uint64_t> layout = {cloth_nodes(), m_cloth ? m_cloth->mesh().triangle_count() : 0};
  for (const RigidSurface& s : m_surfaces) {
    // The instance too: a body re-meshed (a ground plane under water that moved) or replaced by another of
    // the same counts has other triangles.
    layout.insert(layout.end(), {s.key, s.instance, static_cast<std::uint64_t>(s.motion),
                                 s.positions_t0.size(), s.triangles.size()});
  }
  if (!m_built || layout != m_layout) {
    rebuild();
    m_layout = std::move(layout);
  }
  if (m_cloth) {
    const ClothMesh& cloth = m_cloth->mesh();
    std::copy(cloth.positions_t0.begin(), cloth.positions_t0.end(), m_mesh.positions_t0.begin());
    std::copy(cloth.positions_t1.begin(), cloth.positions_t1.end(), m_mesh.positions_t1.begin());
    std::copy(cloth.inverse_masses.begin(), cloth.inverse_masses.end(), m_mesh.inverse_masses.begin());
  }
  for (std::size_t i = 0; i < m_surfaces.size(); ++i) {
    const RigidSurface& s = m_surfaces[i];
    const auto at = static_cast<long>(m_surface_first[i]);
    std::copy(s.positions_t0.begin(), s.positions_t0.end(), m_mesh.positions_t0.begin() + at);
    std::copy(s.positions_t1.begin(), s.positions_t1.end(), m_mesh.positions_t1.begin() + at);
    if (m_rigid_first[i] == SIZE_MAX) continue;
    const auto rigid_at = static_cast<long>(m_rigid_first[i]);
    std::copy(s.positions_t0.begin(), s.positions_t0.end(), m_rigid.positions_t0.begin() + rigid_at);
    std::copy(s.positions_t1.begin(), s.positions_t1.end(), m_rigid.positions_t1.begin() + rigid_at);
  }
}

void ClothWithObstacles::begin_step() {
  if (m_cloth) m_cloth->begin_step();
  if (m_bodies) {
    ScopedTimer timer(m_body_seconds);
    m_bodies->begin_step(m_surfaces);
  }
  pull();
}

void ClothWithObstacles::give_bodies(const Vec3Array& impulses) {
  ScopedTimer timer(m_body_seconds);
  for (std::size_t i = 0; i < m_surfaces.size(); ++i) {
    if (m_surfaces[i].motion != RigidMotion::DYNAMIC) continue;
    const Vec3* first = impulses.data() + m_surface_first[i];
    const std::size_t n = m_surfaces[i].positions_t0.size();
    if (std::any_of(first, first + n, [](const Vec3& j) { return j.squaredNorm() > 0.0; }))
      m_bodies->apply_impulses(i, m_surfaces[i], first);
  }
}

void ClothWithObstacles::apply_impulses(const Vec3Array& impulses) {
  if (impulses.size() != m_mesh.node_count()) {
    throw std::invalid_argument("apply_impulses: " + std::to_string(impulses.size()) + " impulses for " +
                                std::to_string(m_mesh.node_count()) + " nodes");
  }
  if (m_cloth) {
    m_cloth->apply_impulses(Vec3Array(impulses.begin(), impulses.begin() + static_cast<long>(cloth_nodes())));
  }
  give_bodies(impulses);
}

void ClothWithObstacles::apply_body_impulses(const Vec3Array& node_impulses) {
  if (node_impulses.size() != m_mesh.node_count()) {
    throw std::invalid_argument("apply_body_impulses: " + std::to_string(node_impulses.size()) +
                                " impulses for " + std::to_string(m_mesh.node_count()) + " nodes");
  }
  give_bodies(node_impulses);
}

std::size_t ClothWithObstacles::meet_swept_water(double dt, double rest_density, const Vec3Array& positions,
                                                 const ScalarArray& masses, Vec3Array& velocities) {
  Vec3Array impulses;
  const std::size_t swept = drench::meet_swept_water(m_surfaces, m_surface_first, m_mesh.node_count(), dt,
                                                     rest_density, positions, masses, velocities, impulses);
  if (!impulses.empty()) give_bodies(impulses);
  return swept;
}

void ClothWithObstacles::set_carried_masses(const ScalarArray& carried) {
  if (carried.size() != m_mesh.node_count()) {
    throw std::invalid_argument("set_carried_masses: " + std::to_string(carried.size()) + " masses for " +
                                std::to_string(m_mesh.node_count()) + " nodes");
  }
  if (!m_cloth) return;
  m_cloth->set_carried_masses(
      ScalarArray(carried.begin(), carried.begin() + static_cast<long>(cloth_nodes())));
}

void ClothWithObstacles::step(double dt) {
  if (m_cloth) {
    m_cloth->step(dt);
  } else if (m_bodies) {
    m_bodies->step(dt);
  }
  if (m_bodies) {
    ScopedTimer timer(m_body_seconds);
    m_bodies->end_positions(m_surfaces);
    for (std::size_t i = 0; i < m_surfaces.size(); ++i) {
      const Vec3Array& t1 = m_surfaces[i].positions_t1;
      std::copy(t1.begin(), t1.end(), m_mesh.positions_t1.begin() + static_cast<long>(m_surface_first[i]));
      if (m_rigid_first[i] != SIZE_MAX)
        std::copy(t1.begin(), t1.end(), m_rigid.positions_t1.begin() + static_cast<long>(m_rigid_first[i]));
    }
  }
  if (!m_cloth) return;
  const Vec3Array& t1 = m_cloth->mesh().positions_t1;
  std::copy(t1.begin(), t1.end(), m_mesh.positions_t1.begin());
  // A non-finite cloth is not corrected: the step reports it and nothing couples it.
  if (std::all_of(t1.begin(), t1.end(), [](const Vec3& x) { return x.allFinite(); }))
    hold_cloth_off_obstacles(dt);
}

void ClothWithObstacles::end_step(double dt) {
  if (m_cloth) {
    Vec3Array& t1 = m_cloth->mesh().positions_t1;
    std::copy(m_mesh.positions_t1.begin(), m_mesh.positions_t1.begin() + static_cast<long>(cloth_nodes()),
              t1.begin());
    m_cloth->end_step(dt);
    // What the engine holds now (rounded, for a single-precision engine), for the leak audit.
    std::copy(t1.begin(), t1.end(), m_mesh.positions_t1.begin());
  }
}

std::vector<ClothPiece> ClothWithObstacles::pieces() const {
  return m_cloth ? m_cloth->pieces() : std::vector<ClothPiece>{};
}

Vec3Array ClothWithObstacles::velocities() const {
  Vec3Array v = m_cloth ? m_cloth->velocities() : Vec3Array();
  v.resize(m_mesh.node_count(), Vec3::Zero());
  for (std::size_t i = 0; i < m_surfaces.size(); ++i) {
    const Vec3Array& vs = m_surfaces[i].velocities_t0;
    if (vs.size() == m_surfaces[i].positions_t0.size())
      std::copy(vs.begin(), vs.end(), v.begin() + static_cast<long>(m_surface_first[i]));
  }
  return v;
}

double ClothWithObstacles::total_mass() const {
  return m_cloth ? m_cloth->total_mass() : 0.0;
}

}  // namespace drench
