#include <drench/scene/simulation.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include <drench/common/error.hpp>
#include <drench/common/key_index_table.hpp>
#include <drench/common/parallel.hpp>
#include <drench/common/stopwatch.hpp>
#include <drench/common/triangle_geometry.hpp>
#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/cloth_obstacle.hpp>
#include <drench/io/obj_reader.hpp>
#include <drench/scene/scene_document.hpp>
#include <drench/scene/scene_resources.hpp>
#include <drench/sph/boundary_sampling.hpp>

namespace drench {

namespace {

/// Holds a mesh's inverse masses at 0 while it lives (the cloth kinematic for the coupler), then puts them
/// back, also when the coupler throws.
class KinematicCloth {
 public:
  explicit KinematicCloth(ClothMesh& mesh) : m_mesh(mesh) {
    m_own.swap(mesh.inverse_masses);
    mesh.inverse_masses.assign(m_own.size(), 0.0);
  }
  ~KinematicCloth() { m_mesh.inverse_masses.swap(m_own); }
  KinematicCloth(const KinematicCloth&) = delete;
  KinematicCloth& operator=(const KinematicCloth&) = delete;
  const ScalarArray& own_inverse_masses() const { return m_own; }

 private:
  ClothMesh& m_mesh;
  ScalarArray m_own;
};

/// `config` once it passes every check its scene file would: a scene built in code (a game's) meets them
/// here, before anything is built.
const SceneConfig& checked(const SceneConfig& config, const SuppliedMeshes& supplied = {}) {
  check_scene_built_in_code(config, supplied);
  // The memory too, as drench run checks it: a program's scene of a few hundred million particles threw
  // std::bad_alloc from deep in the constructor instead of naming the emitter.
  check_resources(config, estimate_resources(config),
                  machine_limits("", std::numeric_limits<double>::infinity()));
  return config;
}

}  // namespace

Scalar automatic_speed_of_sound(const SceneConfig& config) {
  const Scalar g = config.gravity.norm();
  const Vec3 up = g > 0.0 ? Vec3(-config.gravity / g) : Vec3::UnitY();
  Scalar low = std::numeric_limits<Scalar>::infinity();
  Scalar high = -low;
  auto include = [&](const Vec3& x) {
    low = std::min(low, x.dot(up));
    high = std::max(high, x.dot(up));
  };
  auto include_box = [&](const Vec3& a, const Vec3& b) {
    for (int corner = 0; corner < 8; ++corner) {
      include(Vec3(corner & 1 ? b.x() : a.x(), corner & 2 ? b.y() : a.y(), corner & 4 ? b.z() : a.z()));
    }
  };
  Scalar emit_speed = 0.0;
  for (const auto& e : config.emitters) {
    if (e.kind == EmitterSettings::Kind::BOX) {
      include_box(e.box.min, e.box.max);
      emit_speed = std::max(emit_speed, e.box.velocity.norm());
    } else {
      include(e.nozzle.center);
      emit_speed = std::max(emit_speed, e.nozzle.speed);
    }
  }
  for (const auto& b : config.boundaries) {
    if (b.kind == BoundarySettings::Kind::BOX) {
      include_box(b.min, b.max);
    } else {
      include(b.point);
    }
  }
  // A patch cloth is where a jet lands: its fall from the nozzle counts. An OBJ cloth's extent is known only
  // once the engine has loaded it; scenes with one set the speed of sound or a boundary below.
  if (config.cloth && config.cloth->mesh == "patch") {
    const ClothSettings& cloth = *config.cloth;
    const Vec3 half(0.5 * cloth.size_x, 0.0, 0.5 * cloth.size_z);
    include_box(cloth.center - half, cloth.center + half);
  }
  // A built-in obstacle is where water lands too (an OBJ one, like an OBJ cloth, is not known here).
  for (std::size_t i = 0; i < config.obstacles.size(); ++i) {
    if (config.obstacles[i].mesh != "v_plane") continue;
    for (const Vec3& x : v_plane_mesh(config.obstacles[i], "obstacles[" + std::to_string(i) + "]").positions)
      include(x);
  }
  const Scalar height = high > low ? high - low : 0.0;
  return std::max(1.0, 10.0 * (std::sqrt(2.0 * g * height) + emit_speed));
}

namespace {

std::string show_vec3(const Vec3& v) {
  return "[" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + "]";
}

/// Refuses, before a frame is written, a point a frame could not hold: beyond kMaxCoordinate (frames store
/// float32; a cloth OBJ at 1e300 m was written as inf), and with the "surface" effect beyond its grid's int32
/// cells (kMaxSurfaceGridCells), where the first frame's surface failed after the run had begun.
/// @param mesh  the coupling's mesh: its first `cloth_nodes` nodes the cloth's, then obstacles and bodies
void check_frame_range(const SceneConfig& config, const ClothMesh* mesh, std::size_t cloth_nodes,
                       const Vec3Array& particles) {
  const bool surface = config.has_effect("surface");
  const double cell = config.surface.resolved_cell_size(config.fluid.particle_spacing);
  const double reach = surface ? std::min(kMaxCoordinate, kMaxSurfaceGridCells * cell) : kMaxCoordinate;
  const auto check = [&](const Vec3& x, const std::string& what) {
    if (x.cwiseAbs().maxCoeff() <= reach) return;
    const std::string limit = reach < kMaxCoordinate
                                  ? "the surface grid's int32 cells reach " + format_number(reach) +
                                        " m at surface.cell_size " + format_number(cell) +
                                        " m; choose a larger cell"
                                  : "a scene reaches " + format_number(kMaxCoordinate) + " m from the origin";
    throw SceneError(what + " at " + show_vec3(x) + " m is beyond what frames hold: " + limit + " (" +
                     config.source + ")");
  };
  if (mesh) {
    for (std::size_t i = 0; i < mesh->positions_t0.size(); ++i) {
      check(mesh->positions_t0[i], i < cloth_nodes ? "cloth node " + std::to_string(i)
                                                   : "obstacle node " + std::to_string(i - cloth_nodes));
    }
  }
  for (std::size_t i = 0; i < particles.size(); ++i)
    check(particles[i], "particle " + std::to_string(i));
  for (std::size_t i = 0; i < config.emitters.size(); ++i) {
    const EmitterSettings& e = config.emitters[i];
    if (e.kind == EmitterSettings::Kind::NOZZLE)
      check(e.nozzle.center, "emitters[" + std::to_string(i) + "].center");
  }
}

BoundaryParticles sample_boundaries(const SceneConfig& config) {
  const Scalar s = config.fluid.particle_spacing;
  BoundaryParticles all;
  for (const auto& b : config.boundaries) {
    all.append(b.kind == BoundarySettings::Kind::BOX
                   ? sample_box_container(b.min, b.max, s, b.layers, b.open_top)
                   : sample_plane(b.point, b.normal, b.size, s, b.layers));
  }
  return all;
}

std::unique_ptr<ClothEngine> build_cloth(const SceneConfig& config, const ClothEngineFactory& factory) {
  if (!config.cloth) return nullptr;
  if (!factory) {
    throw SceneError(
        "cloth: this program has no cloth engine; run the scene with the drench command, which "
        "links the Bullet adapter (" +
        config.source + ")");
  }
  return factory(*config.cloth, config.gravity);
}

}  // namespace

std::vector<TriangleMesh> build_obstacles(const SceneConfig& config) {
  std::vector<TriangleMesh> meshes;
  for (std::size_t i = 0; i < config.obstacles.size(); ++i) {
    const ObstacleSettings& o = config.obstacles[i];
    const std::string key = "obstacles[" + std::to_string(i) + "]";
    // Every refusal names the scene too: the loader's ranges cannot see what an OBJ file and a scale make.
    try {
      if (o.mesh == "v_plane") {
        meshes.push_back(v_plane_mesh(o, key));
        validate_triangle_mesh(meshes.back(), key);
        continue;
      }
      if (!(o.scale > 0.0) || !std::isfinite(o.scale))
        throw SceneError(key + ".scale must be > 0 and finite, got " + format_number(o.scale));
      if (!o.center.allFinite()) throw SceneError(key + ".center must be finite");
      TriangleMesh mesh = load_obj_mesh(o.mesh, key + ".mesh");
      for (Vec3& x : mesh.positions)
        x = o.center + o.scale * x;
      // A scale of 1e-300 or 1e300 turns the file's triangles to points or infinities.
      validate_triangle_mesh(mesh, key + ".mesh \"" + o.mesh + "\" at " + key + ".scale " +
                                       format_number(o.scale) + " and center " + show_vec3(o.center));
      meshes.push_back(std::move(mesh));
    } catch (const Error& e) {
      throw SceneError(std::string(e.what()) + " (" + config.source + ")");
    }
  }
  return meshes;
}

Simulation::Simulation(const SceneConfig& config, const ClothEngineFactory& cloth_factory)
    : Simulation(config, build_cloth(checked(config), cloth_factory)) {}

Simulation::Simulation(const SceneConfig& config, std::unique_ptr<ClothEngine> cloth,
                       std::vector<TriangleMesh> more_obstacles, RigidBodySource* bodies)
    : m_config(checked(config, {cloth && !config.cloth, cloth || !more_obstacles.empty() || bodies})),
      m_speed_of_sound(config.fluid.wcsph.speed_of_sound.value_or(automatic_speed_of_sound(config))),
      m_cloth(std::move(cloth)),
      m_bodies(bodies) {
  std::vector<TriangleMesh> obstacles = build_obstacles(m_config);
  for (TriangleMesh& mesh : more_obstacles)
    obstacles.push_back(std::move(mesh));
  // Without obstacles the engine is the cloth itself: the obstacles cost nothing when a scene has none.
  if (!obstacles.empty() || bodies)
    m_with_obstacles = std::make_unique<ClothWithObstacles>(m_cloth.get(), std::move(obstacles),
                                                            m_config.coupling.cloth_thickness, bodies);
  m_engine = m_with_obstacles ? static_cast<ClothEngine*>(m_with_obstacles.get()) : m_cloth.get();
  if (bodies && m_config.has_effect("coupling"))
    m_rigid_boundary = std::make_unique<RigidBoundary>(m_config.fluid.particle_spacing);
  if (m_engine) m_engine->mesh().validate();
  if (m_config.coupling.asks_tangential() && !m_config.has_effect("friction")) {
    // The coupler is built without friction then: the settings would be silently ignored.
    throw SceneError(
        "coupling asks for tangential boundary conditions (slip or friction_coefficient), but "
        "effects does not list \"friction\" (" +
        m_config.source + ")");
  }
  // Before the fluid, which builds the viscosity force itself when the effects say so.
  m_effects =
      build_effects({m_config, m_engine ? &m_engine->mesh() : nullptr, m_cloth ? &m_cloth->mesh() : nullptr,
                     m_cloth.get(), m_with_obstacles ? &m_with_obstacles->obstacles() : nullptr});
  m_fluid = std::make_unique<FluidSolver>(m_config.fluid, m_config.gravity, sample_boundaries(m_config),
                                          m_config.boundaries, m_effects.viscosity, m_speed_of_sound,
                                          m_effects.surface_tension ? &m_config.surface_tension : nullptr);
  m_total_steps = std::max<std::int64_t>(1, std::llround(m_config.time.duration / m_config.time.dt));
  if (m_config.time.adaptive) {
    const TimeSettings& t = m_config.time;
    const Scalar frames = std::ceil(t.duration * t.frame_rate);
    m_total_steps = static_cast<std::int64_t>(std::ceil(t.duration / t.dt_min) + frames) + 1;
  }
  const Scalar mass = m_fluid->particle_mass();
  for (const auto& e : m_config.emitters) {
    if (e.kind == EmitterSettings::Kind::BOX) {
      emit_box(e.box, m_config.fluid.particle_spacing, mass, m_fluid->particles(), m_next_id);
    } else {
      m_nozzles.emplace_back(e.nozzle, m_config.fluid.particle_spacing);
    }
  }
  for (const Scalar m : m_fluid->particles().masses)
    m_emitted_mass += m;
  m_last_particle_speed = m_fluid->max_speed();
  for (const auto& e : m_config.emitters)
    if (e.kind == EmitterSettings::Kind::NOZZLE) m_nozzle_speed = std::max(m_nozzle_speed, e.nozzle.speed);
  check_frame_range(m_config, m_engine ? &m_engine->mesh() : nullptr,
                    m_cloth ? m_cloth->mesh().node_count() : 0, m_fluid->particles().positions);
  const ParticleSet& initial = m_fluid->particles();
  if (!initial.empty()) {
    m_energy_floor = std::numeric_limits<double>::infinity();
    for (const Vec3& x : initial.positions)
      m_energy_floor = std::min(m_energy_floor, -m_config.gravity.dot(x));
  }
  m_initial_energy = fluid_energy();
  if (m_engine) m_pending_cloth_impulses.assign(m_engine->mesh().node_count(), Vec3::Zero());
  m_pending_cloth_nodes = m_cloth ? m_cloth->mesh().node_count() : 0;
  if (m_cloth) {
    // The cloth's edges and their lengths now, the rest lengths cloth.max_strain is measured against.
    const ClothMesh& mesh = m_cloth->mesh();
    m_cloth_edges = unique_edges(mesh.triangles);
    const Vec3Array& x =
        mesh.positions_t1.size() == mesh.node_count() ? mesh.positions_t1 : mesh.positions_t0;
    m_rest_lengths.reserve(m_cloth_edges.size());
    for (const auto& [a, b] : m_cloth_edges)
      m_rest_lengths.push_back((x[a] - x[b]).norm());
    m_cloth_pieces = m_cloth->pieces();
  }
}

void Simulation::follow_cloth_layout() {
  std::vector<ClothPiece> pieces = m_cloth->pieces();
  if (pieces == m_cloth_pieces) return;
  const ClothLayoutChange change(m_cloth_pieces, pieces);
  const ClothMesh& cloth = m_cloth->mesh();
  // The wetting first: the only part that can refuse (a new node without a mass), before anything moved.
  if (m_effects.wetting) {
    m_effects.wetting->follow(change, cloth.triangles, cloth.positions_t0,
                              cloth_dry_masses(m_config, m_cloth.get(), cloth));
  }
  m_cloth_pieces = std::move(pieces);
  // What the last step owes the cloth: each node's at its new index (bodies' nodes, after the cloths', owe
  // nothing). The links name faces: a torn cloth's are dropped (ClothLayoutChange::triangle), the impulses
  // they carried stay owed to the nodes.
  if (m_pending_cloth_impulses.size() >= change.cloth_nodes_before()) {
    m_pending_cloth_impulses = change.nodes_moved(m_pending_cloth_impulses, Vec3(Vec3::Zero()));
    m_pending_cloth_nodes = change.cloth_nodes_after();
  }
  ImpulseLinks links;
  for (ImpulseLink link : m_pending_links) {
    const std::size_t t = change.triangle(link.triangle);
    if (t == ClothLayoutChange::kGone) continue;
    link.triangle = static_cast<Index>(t);
    links.push_back(link);
  }
  m_pending_links = std::move(links);
  // The strain limit's edges: an edge that was one keeps its rest length, a new one (around a new node, or
  // one a refinement drew) starts at its length now.
  std::vector<std::pair<Index, Index>> edges = unique_edges(cloth.triangles);
  m_rest_lengths = change.rest_lengths(m_cloth_edges, m_rest_lengths, edges, cloth.positions_t0);
  m_cloth_edges = std::move(edges);
  // The jump audit's end of the last step: each node's at its new index, a new node's where it starts (it
  // was made on its cloth's faces, crossing nothing); the cloths' faces are their new ones, the others'
  // their old ones renumbered.
  if (!m_audited_end.empty() && m_audited_end.size() >= change.cloth_nodes_before()) {
    Vec3Array end = change.nodes_moved(m_audited_end, Vec3(Vec3::Zero()));
    for (std::size_t i = 0; i < change.cloth_nodes_after(); ++i) {
      if (change.is_new_node(i)) end[i] = cloth.positions_t0[i];
    }
    std::vector<Triangle> faces = cloth.triangles;
    for (std::size_t t = change.cloth_triangles_before(); t < m_audited_triangles.size(); ++t) {
      const Triangle& old = m_audited_triangles[t];
      faces.push_back({static_cast<Index>(change.node(old[0])), static_cast<Index>(change.node(old[1])),
                       static_cast<Index>(change.node(old[2]))});
    }
    m_audited_end = std::move(end);
    m_audited_triangles = std::move(faces);
  }
  // The adhesion's work per face (the cloths' faces, then the obstacles'): a cloth's new faces are of its
  // fabric.
  if (m_effects.coupler && m_effects.coupler->adhesion()) {
    AdhesionSettings adhesion = *m_effects.coupler->adhesion();
    const double fabric = (m_config.cloth ? *m_config.cloth : ClothSettings{}).adhesion;
    const std::size_t size =
        adhesion.work.size() + change.cloth_triangles_after() - change.cloth_triangles_before();
    ScalarArray work(std::max(size, change.cloth_triangles_after()), fabric);
    for (std::size_t t = 0; t < adhesion.work.size(); ++t) {
      const std::size_t now = change.triangle(t);
      if (now != ClothLayoutChange::kGone && now < work.size()) work[now] = adhesion.work[t];
    }
    adhesion.work = std::move(work);
    m_effects.coupler->set_adhesion(std::move(adhesion));
  }
}

void Simulation::check_cloth(StepStatus& status) {
  static const ClothSettings kDefaults;  // a cloth built by the caller (CoupledWorld) has no scene settings
  const ClothSettings& limits = m_config.cloth ? *m_config.cloth : kDefaults;
  const Vec3Array velocities = m_cloth->velocities();
  std::int64_t fastest = -1;
  Scalar fastest_speed = 0.0;
  for (std::size_t i = 0; i < velocities.size(); ++i) {
    const Scalar node_speed = velocities[i].norm();
    // `!(a <= b)` rather than std::max, so that a NaN speed stays NaN in the summary.
    if (!(node_speed <= m_max_node_speed)) m_max_node_speed = node_speed;
    if (!(node_speed <= fastest_speed)) {
      fastest = static_cast<std::int64_t>(i);
      fastest_speed = node_speed;
    }
  }
  m_last_node_speed = fastest_speed;
  if (limits.max_speed && fastest >= 0 && !(fastest_speed <= *limits.max_speed)) {
    status.flags |= StepStatus::RUNAWAY_NODE;
    status.runaway_node = fastest;
    status.runaway_node_speed = fastest_speed;
  }
  // Between steps positions_t1 is where the cloth is (end_step wrote it back to the engine).
  const Vec3Array& x = m_cloth->mesh().positions_t1;
  std::size_t most = m_cloth_edges.size();
  Scalar most_strain = 0.0;
  for (std::size_t e = 0; e < m_cloth_edges.size(); ++e) {
    if (!(m_rest_lengths[e] > 0.0)) continue;  // an edge of zero length has no strain to speak of
    const auto& [a, b] = m_cloth_edges[e];
    const Scalar strain = (x[a] - x[b]).norm() / m_rest_lengths[e] - 1.0;
    if (!(strain <= most_strain)) {
      most = e;
      most_strain = strain;
    }
  }
  if (!(most_strain <= m_max_strain)) m_max_strain = most_strain;
  if (limits.max_strain && most < m_cloth_edges.size() && !(most_strain <= *limits.max_strain)) {
    status.flags |= StepStatus::CLOTH_OVERSTRETCHED;
    status.overstretched_edge[0] = m_cloth_edges[most].first;
    status.overstretched_edge[1] = m_cloth_edges[most].second;
    status.edge_strain = most_strain;
  }
}

EffectCounters Simulation::effect_counters() const {
  EffectCounters c;
  c.viscosity = m_fluid->viscosity_counter();
  c.surface_tension = m_fluid->surface_tension_counter();
  if (m_effects.coupler) {
    c.coupling = m_effects.coupler->counter();
    c.friction = m_effects.coupler->friction_counter();
    c.adhesion = m_effects.coupler->adhesion_counter();
  }
  if (m_effects.obstacle) c.substep_obstacle = m_effects.obstacle->counter();
  c.leak_audit = m_effects.leak_counter;
  c.wetting = m_effects.wetting_counter;
  return c;
}

const std::vector<TriangleMesh>& Simulation::obstacles() const {
  static const std::vector<TriangleMesh> none;
  return m_with_obstacles ? m_with_obstacles->obstacles() : none;
}

double Simulation::fluid_energy() const {
  const ParticleSet& p = m_fluid->particles();
  double energy = 0.0;
  // In order, not reduced over threads: the figure is the same whatever the thread count.
  for (std::size_t i = 0; i < p.size(); ++i) {
    energy += p.masses[i] *
              (0.5 * p.velocities[i].squaredNorm() - m_config.gravity.dot(p.positions[i]) - m_energy_floor);
  }
  return energy;
}

bool Simulation::closed() const {
  return m_nozzles.empty() && m_config.kill_regions.empty() && !m_effects.wetting;
}

bool Simulation::finished() const {
  if (m_config.time.adaptive) return m_time >= m_config.time.duration - 1e-3 * m_config.time.dt_min;
  return m_steps >= m_total_steps;
}

Scalar Simulation::next_dt() const {
  const TimeSettings& t = m_config.time;
  if (!t.adaptive) return t.dt;
  // A NaN CFL step (a NaN velocity) takes the largest step, so that the fluid names the particle.
  const Scalar cfl = m_fluid->cfl_step();
  const Scalar longest = std::isnan(cfl) ? t.dt : std::clamp(cfl, t.dt_min, t.dt);
  // Frames and the end land on a step: the time up to the next one is cut into equal steps no longer than
  // `longest`. Cutting only the step that would pass it left slivers (65 us after 2 ms steps), in which
  // DFSPH relieved a compression within the sliver: the dam break's particles reached 32-108 m/s and its
  // energy rose by 11% or more.
  Scalar stop = t.duration;
  if (t.frame_rate > 0) {
    const Scalar next_frame = (std::floor(m_time * t.frame_rate + 1e-9) + 1.0) / t.frame_rate;
    stop = std::min(stop, next_frame);
  }
  const Scalar left = stop - m_time;
  const Scalar steps = std::max(1.0, std::ceil(left / longest - 1e-9));
  return steps == 1.0 ? left : left / steps;
}

StepStatus Simulation::step(Scalar dt) {
  m_last_coupled = false;
  {
    ScopedTimer timer(m_emit_seconds);
    const std::size_t before = m_fluid->particles().size();
    for (auto& nozzle : m_nozzles) {
      nozzle.emit(time(), dt, m_fluid->particle_mass(), m_fluid->particles(), m_next_id);
    }
    m_emitted_mass += static_cast<double>(m_fluid->particles().size() - before) * m_fluid->particle_mass();
  }
  if (m_bodies) tell_bodies_the_points(dt);
  if (m_engine) m_engine->begin_step();
  if (m_cloth) follow_cloth_layout();
  if (m_bodies) {
    ParticleSet& p = m_fluid->particles();
    // The cloth where it starts the step, the side of it the coupling first keeps the water on.
    RigidBodySource::CrossingTest crosses_cloth;
    if (m_cloth) {
      crosses_cloth = [cloth = &m_cloth->mesh()](const Vec3Array& from, const Vec3Array& to,
                                                 std::vector<std::uint8_t>& crosses) {
        moves_crossing_cloth(*cloth, from, to, crosses);
      };
    }
    m_coupling_stats.released_from_bodies += m_bodies->release_trapped(
        p.positions, p.velocities, 0.5 * m_config.fluid.particle_spacing, crosses_cloth, m_displaced);
    if (!m_displaced.empty()) {
      for (std::size_t i = 0; i < p.size(); ++i) {
        if (!m_displaced[i]) continue;
        ++m_coupling_stats.displaced_by_bodies;
        m_coupling_stats.displaced_mass += p.masses[i];
        m_coupling_stats.displaced_momentum += p.masses[i] * p.velocities[i];
      }
      m_removed += static_cast<std::int64_t>(p.remove_flagged(m_displaced));
    }
  }
  if (m_with_obstacles && m_effects.coupler) {
    // The dynamic bodies and the water they would sweep meet before either moves (swept_water.hpp), a part
    // of the "coupling" effect: without it the water passes through the bodies.
    const double bodies_before = body_seconds();
    ScopedTimer timer(m_rigid_seconds);
    ParticleSet& p = m_fluid->particles();
    m_with_obstacles->meet_swept_water(dt, m_config.fluid.rest_density, p.positions, p.masses, p.velocities);
    m_rigid_seconds -= body_seconds() - bodies_before;  // apply_impulses times itself (body_seconds)
  }
  StepStatus jump_status;
  if (m_engine) audit_face_jumps_since_last_step(jump_status);
  // The cloth at its start positions is an obstacle inside the fluid's sub-steps
  // (coupling/cloth_obstacle.hpp).
  if (m_effects.obstacle) m_effects.obstacle->begin_step(m_engine->mesh(), m_engine->velocities());
  if (m_rigid_boundary) place_rigid_boundary();
  StepStatus status = m_fluid->step(dt, m_effects.obstacle.get());
  if ((jump_status.flags & StepStatus::LEAKED) && !(status.flags & StepStatus::LEAKED)) {
    status.flags |= StepStatus::LEAKED;
    status.leaked_particle = jump_status.leaked_particle;
    status.leaked_triangle = jump_status.leaked_triangle;
  }
  if (m_rigid_boundary) push_rigid_bodies();
  if (m_engine) step_cloth_and_couple(dt, status);
  // `!(a <= b)` rather than std::max, so that a NaN speed stays NaN in the summary.
  const Scalar particle_speed = m_fluid->max_speed();
  if (!(particle_speed <= m_max_particle_speed)) m_max_particle_speed = particle_speed;
  m_last_particle_speed = particle_speed;
  if (m_cloth) check_cloth(status);
  ++m_steps;
  m_time += dt;
  m_min_dt = std::min(m_min_dt, dt);
  m_sum_dt += dt;
  m_max_dt = std::max(m_max_dt, dt);
  if (!m_config.kill_regions.empty()) {
    ScopedTimer timer(m_emit_seconds);
    remove_killed();
  }
  // The coupling and the bodies changed velocities after the fluid's own check: a particle they threw past
  // fluid.max_speed ends this step, as the next would end it before moving it (the particles the kill
  // regions removed are gone from both).
  if (!(status.flags & StepStatus::RUNAWAY_PARTICLE)) {
    status |= m_config.kill_regions.empty() ? m_fluid->speed_check(particle_speed) : m_fluid->speed_check();
  }
  return status;
}

void Simulation::tell_bodies_the_points(Scalar dt) {
  // Gravity's pull over the step on top of the fastest speed at the end of the last one, or of a nozzle's new
  // particles: no pass over the particles of its own.
  const Scalar speed = std::max({m_last_particle_speed, m_last_node_speed, m_nozzle_speed});
  // And the coupling's range: a point within the cloth thickness of a face is pushed off it (eq. 1-4), and
  // a particle spacing more for the pressure and impulses the step adds.
  const Scalar reach = (speed + m_config.gravity.norm() * dt) * dt + m_config.coupling.cloth_thickness +
                       m_config.fluid.particle_spacing;
  if (!std::isfinite(reach)) return;  // the step reports the state that is not finite
  std::vector<const Vec3Array*> points = {&m_fluid->particles().positions};
  if (m_cloth) {
    const ClothMesh& mesh = m_cloth->mesh();
    points.push_back(mesh.positions_t1.size() == mesh.node_count() ? &mesh.positions_t1 : &mesh.positions_t0);
  }
  m_bodies->expect_points(points, reach);
}

double Simulation::body_seconds() const {
  return m_with_obstacles ? m_with_obstacles->body_seconds() : 0.0;
}

double Simulation::rigid_seconds() const {
  return m_rigid_seconds + body_seconds();
}

void Simulation::place_rigid_boundary() {
  ScopedTimer timer(m_rigid_seconds);
  // Only the dynamic bodies have boundary particles (static ones hold the water by the coupling alone). When
  // none of them moved, came or went, the fluid keeps its points and their grid, which it would rebuild to
  // the same bits: a level whose bodies rest pays for placing them only when they move.
  RigidBoundary& boundary = *m_rigid_boundary;
  if (boundary.place(m_with_obstacles->rigid_surfaces())) {
    m_fluid->set_moving_boundary(boundary.positions(), boundary.volumes(), boundary.normals());
  } else {
    m_fluid->keep_moving_boundary();
  }
}

void Simulation::push_rigid_bodies() {
  const Vec3Array& on_boundary = m_fluid->moving_boundary_impulses();
  if (on_boundary.empty()) return;
  Vec3Array nodes;
  {
    ScopedTimer timer(m_rigid_seconds);  // apply_body_impulses times itself (body_seconds)
    nodes.assign(m_engine->mesh().node_count(), Vec3::Zero());
    m_rigid_boundary->spread(m_with_obstacles->rigid_surfaces(), on_boundary,
                             m_with_obstacles->rigid_surface_first_nodes(), nodes);
  }
  // Before the bodies' step: the water's pressure moves them in it.
  m_with_obstacles->apply_body_impulses(nodes);
}

std::vector<std::pair<std::uint64_t, std::uint64_t>> Simulation::rigid_body_instances() const {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> bodies;
  if (m_with_obstacles) {
    for (const RigidSurface& s : m_with_obstacles->rigid_surfaces())
      bodies.emplace_back(s.key, s.instance);
  }
  return bodies;
}

void Simulation::audit_face_jumps_since_last_step(StepStatus& status) {
  const ClothMesh& mesh = m_engine->mesh();
  if (!m_effects.leak_audit || m_audited_end.empty()) return;  // the first step: no end to compare with
  const bool same_layout = m_audited_end.size() == mesh.node_count() &&
                           same_triangles(m_audited_triangles, mesh.triangles) &&
                           rigid_body_instances() == m_audited_bodies;
  const std::vector<Triangle>* faces = &mesh.triangles;
  const Vec3Array* end = &m_audited_end;
  const Vec3Array* start = &mesh.positions_t0;
  std::vector<Triangle> cloth_faces;
  Vec3Array cloth_end, cloth_start;
  if (!same_layout) {
    // A body came, went or was re-meshed: its faces have no end to compare with (one replaced by another
    // is no jump of its faces). The cloth's, first in the mesh, still have theirs (test
    // RigidBodies.AClothJumpingThroughTheWaterIsALeakEvenWhenABodyCameMeanwhile).
    const std::size_t nodes = m_cloth ? m_cloth->mesh().node_count() : 0;
    const std::size_t triangles = m_cloth ? m_cloth->mesh().triangle_count() : 0;
    if (triangles == 0 || m_audited_end.size() < nodes || m_audited_triangles.size() < triangles ||
        mesh.triangles.size() < triangles ||
        !std::equal(mesh.triangles.begin(), mesh.triangles.begin() + static_cast<long>(triangles),
                    m_audited_triangles.begin())) {
      return;
    }
    cloth_faces.assign(mesh.triangles.begin(), mesh.triangles.begin() + static_cast<long>(triangles));
    cloth_end.assign(m_audited_end.begin(), m_audited_end.begin() + static_cast<long>(nodes));
    cloth_start.assign(mesh.positions_t0.begin(), mesh.positions_t0.begin() + static_cast<long>(nodes));
    faces = &cloth_faces;
    end = &cloth_end;
    start = &cloth_start;
  }
  ParticleSet& p = m_fluid->particles();
  if (audit_face_jumps(p.positions, *faces, *end, *start, m_leak_stats) > 0) {
    status.flags |= StepStatus::LEAKED;
    status.leaked_particle = p.ids[static_cast<std::size_t>(m_leak_stats.leak_particle)];
    status.leaked_triangle = m_leak_stats.leak_triangle;
  }
}

void Simulation::step_cloth_and_couple(Scalar dt, StepStatus& status) {
  ParticleSet& p = m_fluid->particles();
  ClothMesh& mesh = m_engine->mesh();
  // CouplingScheme::CARRIED_WATER: the water near the cloth weighs on its nodes through the engine's step.
  const bool carry = m_effects.carried && status.ok();
  Vec3Array before_impulses;
  if (carry) {
    ScopedTimer timer(m_coupling_seconds);
    // The particles whose impulses the cloth takes in this step (coupling/carried_water.hpp).
    ImpulseLinks links = m_pending_links;
    if (m_effects.obstacle) {
      const ImpulseLinks& stops = m_effects.obstacle->impulse_links();
      links.insert(links.end(), stops.begin(), stops.end());
    }
    m_effects.carried->attach(mesh, p.masses, p.ids, links);
    m_engine->set_carried_masses(m_effects.carried->carried_masses());
    before_impulses = m_engine->velocities();
  }
  // Before the cloth steps, so that its solver spreads the load over the cloth's links in this step: what
  // the previous step owes the cloth, and what the particles gave it inside the fluid's sub-steps.
  // Only the cloth's nodes are owed anything; they come first in the mesh, so a rigid body added or removed
  // since loses the cloth nothing. (A cloth whose node count changed has lost what it was owed.)
  Vec3Array impulses(mesh.node_count(), Vec3::Zero());
  const std::size_t cloth_nodes = m_cloth ? m_cloth->mesh().node_count() : 0;
  if (m_pending_cloth_impulses.size() == impulses.size()) {
    impulses.swap(m_pending_cloth_impulses);
  } else if (m_pending_cloth_nodes == cloth_nodes) {
    const std::size_t n = std::min({cloth_nodes, impulses.size(), m_pending_cloth_impulses.size()});
    std::copy(m_pending_cloth_impulses.begin(), m_pending_cloth_impulses.begin() + static_cast<long>(n),
              impulses.begin());
  }
  m_pending_cloth_nodes = cloth_nodes;
  m_pending_cloth_impulses.assign(mesh.node_count(), Vec3::Zero());
  m_pending_links.clear();
  if (m_effects.obstacle) {
    const Vec3Array& stopped = m_effects.obstacle->impulses();
    for (std::size_t i = 0; i < impulses.size(); ++i)
      impulses[i] += stopped[i];
    m_coupling_stats.obstacle_stops += m_effects.obstacle->stops();
    m_coupling_stats.vertical_impulse_on_cloth += m_effects.obstacle->vertical_impulse();
  }
  if (carry) {
    // The engine applies gravity to the carried mass too, but the water fell in the fluid's step already.
    const ScalarArray& carried = m_effects.carried->carried_masses();
    for (std::size_t i = 0; i < impulses.size(); ++i)
      impulses[i] -= (carried[i] * dt) * m_config.gravity;
  }
  m_engine->apply_impulses(impulses);
  const double bodies_before = body_seconds();
  {
    ScopedTimer timer(m_cloth_seconds);
    m_engine->step(dt);
  }
  // The engine's step also reads where it put the bodies: that share is the rigid stage's.
  m_cloth_seconds -= body_seconds() - bodies_before;
  m_non_finite_node = -1;
  for (std::size_t i = 0; i < mesh.node_count(); ++i) {
    if (!mesh.positions_t1[i].allFinite()) {
      m_non_finite_node = static_cast<std::int64_t>(i);
      status.flags |= StepStatus::NON_FINITE_CLOTH;
      status.non_finite_node = m_non_finite_node;
      break;
    }
  }
  if (carry && m_non_finite_node < 0) {
    ScopedTimer timer(m_coupling_seconds);
    const Vec3 given = m_effects.carried->hand_back(before_impulses, m_engine->velocities(), mesh, dt,
                                                    p.positions, p.velocities, p.masses);
    m_coupling_stats.vertical_impulse_on_cloth -= given.y();
  }
  // A cloth or fluid that went non-finite is not coupled: its state means nothing any more.
  const bool coupled = m_effects.coupler && m_non_finite_node < 0 && status.ok();
  m_last_coupled = coupled;
  m_last_coupling_status = 0;
  if (coupled) {
    ScopedTimer timer(m_coupling_seconds);
    const FluidView view{&p.positions_t0, &p.positions, &p.velocities, &p.masses,
                         m_effects.carried || m_effects.wetting ? &p.ids : nullptr};
    if (m_effects.carried) {
      // The particles are corrected against the cloth where its engine put it; the cloth's share of every
      // impulse reaches it at its next step (moving a light node with heavy water here is what the links
      // would snap back).
      const KinematicCloth kinematic(mesh);
      m_last_coupling_status =
          m_effects.coupler->step(view, mesh, dt, m_coupling_stats, &kinematic.own_inverse_masses());
      const Vec3Array& given = m_effects.coupler->node_impulses();
      for (std::size_t i = 0; i < given.size(); ++i) {
        if (kinematic.own_inverse_masses()[i] > 0.0) m_pending_cloth_impulses[i] += given[i];
      }
      // What the impact zones' moves of its nodes give the cloth at end_step is owed back at its next step
      // (carried_water.hpp), as the water's impulses are.
      owe_zone_shifts(m_effects.coupler->node_shifts(), kinematic.own_inverse_masses(), dt,
                      m_pending_cloth_impulses, m_coupling_stats);
      m_pending_links = m_effects.coupler->impulse_links();
    } else {
      m_last_coupling_status = m_effects.coupler->step(view, mesh, dt, m_coupling_stats);
      // The fail-safe's share of the nodes it did not move reaches the cloth at its next step.
      const Vec3Array& owed = m_effects.coupler->owed_impulses();
      for (std::size_t i = 0; i < owed.size(); ++i)
        m_pending_cloth_impulses[i] += owed[i];
    }
    m_coupling_status |= m_last_coupling_status;
    if (m_last_coupling_status & COUPLING_UNRESOLVED) {
      // A collision the coupler could not resolve: a crossing may remain, audited or not.
      const auto [particle, triangle] = m_effects.coupler->unresolved();
      status.flags |= StepStatus::LEAKED;
      status.leaked_particle = p.ids[static_cast<std::size_t>(particle)];
      status.leaked_triangle = triangle;
    }
    // The water the impact zones squeezed out between faces that move differently: its mass and momentum
    // are booked in the coupling's stats.
    const std::vector<std::uint8_t>& squeezed = m_effects.coupler->squeezed_out();
    if (!squeezed.empty()) m_removed += static_cast<std::int64_t>(p.remove_flagged(squeezed));
  }
  // A dynamic body takes what the water gave its nodes now: its engine has already stepped it. Outside the
  // coupling's timer: handing the bodies their impulses is the rigid stage's (body_seconds).
  if (coupled && m_with_obstacles) m_with_obstacles->apply_body_impulses(m_effects.coupler->node_impulses());
  {
    ScopedTimer timer(m_cloth_seconds);
    m_engine->end_step(dt);
  }
  // After end_step, which leaves in the mesh the positions the engine holds (rounded, for a single-precision
  // engine), so that the audit checks the cloth the next step starts from.
  if (m_effects.leak_audit && m_non_finite_node < 0 && status.ok()) {
    // The audit pairs a particle with a triangle only where their bare boxes over the step meet, so a
    // particle whose box misses the mesh's cannot leak: the one test decides, exactly.
    bool near = false;
    {
      ScopedTimer timer(m_leak_stats.seconds);
      near = any_particle_box_overlaps(p.positions_t0, p.positions, 0.0, mesh_box(mesh));
    }
    if (near) {
      if (m_leak_audit.audit(p.positions_t0, p.positions, mesh, m_leak_stats) > 0 &&
          !(status.flags & StepStatus::LEAKED)) {
        status.flags |= StepStatus::LEAKED;
        status.leaked_particle = p.ids[static_cast<std::size_t>(m_leak_stats.leak_particle)];
        status.leaked_triangle = m_leak_stats.leak_triangle;
      }
      ++m_effects.leak_counter.passes;
    } else {
      ++m_effects.leak_counter.skipped;
    }
  }
  // Where the next step's audit_face_jumps_since_last_step compares the faces' start with: the faces as
  // the coupler left them, which the water was held against.
  if (m_effects.leak_audit) {
    if (m_non_finite_node < 0) {
      m_audited_end = mesh.positions_t1;
      if (!same_triangles(m_audited_triangles, mesh.triangles)) m_audited_triangles = mesh.triangles;
      m_audited_bodies = rigid_body_instances();
    } else {
      m_audited_end.clear();
    }
  }
  if (m_effects.wetting && coupled) wet_cloth(dt);
}

void Simulation::wet_cloth(Scalar dt) {
  ScopedTimer timer(m_wetting_stats.seconds);
  ++m_effects.wetting_counter.passes;
  ParticleSet& p = m_fluid->particles();
  const ClothMesh& cloth = m_cloth->mesh();
  // The particles the coupling touched in this step: the coupler's and, inside the fluid's sub-steps, the
  // obstacle's; a particle's largest impulse names its triangle. Obstacle triangles (after the cloth's)
  // absorb nothing.
  // Each link's particle is found by its id in a hashed table of the particles' ids: a node-based map of
  // the touched ids, filled and searched per particle, cost more than all of the wetting's own work
  // (callgrind of bench_game_frame). A link to a particle no longer present is passed over.
  KeyIndexTable index_of;
  index_of.build(std::vector<std::uint64_t>(p.ids.begin(), p.ids.end()));
  std::vector<const ImpulseLink*> touched(p.size(), nullptr);
  keep_largest_links(m_effects.coupler->impulse_links(), cloth.triangle_count(), index_of, touched);
  if (m_effects.obstacle)
    keep_largest_links(m_effects.obstacle->impulse_links(), cloth.triangle_count(), index_of, touched);
  std::vector<WettingContact> contacts;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (touched[i]) contacts.push_back({i, touched[i]->triangle, touched[i]->weights});
  }
  std::vector<std::uint8_t> remove(p.size(), 0);
  const Scalar particle_mass = m_fluid->particle_mass();
  m_effects.wetting->absorb(contacts, p.masses, remove, 0.01 * particle_mass, dt, m_wetting_stats);
  if (std::find(remove.begin(), remove.end(), std::uint8_t{1}) != remove.end()) p.remove_flagged(remove);
  m_effects.wetting->spread(cloth.positions_t1, m_config.gravity, dt, m_wetting_stats);
  // A drop starts clear of the cloth's thickness and of the other particles, on the cloth's lower side.
  const Scalar spacing = m_config.fluid.particle_spacing;
  const double offset = std::max(2.0 * m_config.coupling.cloth_thickness, 0.5 * spacing);
  for (const WettingDrop& drop :
       m_effects.wetting->drip(cloth.positions_t1, m_cloth->velocities(), m_config.gravity, particle_mass,
                               offset, p.positions, 0.75 * spacing, m_wetting_stats)) {
    p.add(drop.position, drop.velocity, particle_mass, m_next_id++);
  }
  m_cloth->set_water_masses(m_effects.wetting->water());
}

void Simulation::remove_killed() {
  ParticleSet& particles = m_fluid->particles();
  const std::size_t n = particles.size();
  std::vector<std::uint8_t> remove(n, 0);
  const std::size_t flagged = parallel_reduce(
      n, kLightChunk, std::size_t{0},
      [&](std::size_t begin, std::size_t end) {
        std::size_t count = 0;
        for (std::size_t i = begin; i < end; ++i) {
          const Vec3& x = particles.positions[i];
          for (const auto& region : m_config.kill_regions) {
            const bool out =
                region.kind == KillRegionSettings::Kind::PLANE
                    ? (x - region.point).dot(region.normal) < 0.0
                    : ((x.array() < region.min.array()) || (x.array() > region.max.array())).any();
            if (out) {
              remove[i] = 1;
              ++count;
              break;
            }
          }
        }
        return count;
      },
      std::plus<std::size_t>());
  if (flagged == 0) return;
  for (std::size_t i = 0; i < n; ++i)  // in order, so that the sum is the same whatever the threads
    if (remove[i]) m_killed_mass += particles.masses[i];
  m_removed += static_cast<std::int64_t>(particles.remove_flagged(remove));
}

}  // namespace drench
