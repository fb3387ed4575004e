#include <drench/sph/fluid_solver.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>
#include <drench/common/stopwatch.hpp>
#include <drench/sph/boundary_sampling.hpp>

namespace drench {

namespace {
/// Skin of a neighbor search whose lists are reused over sub-steps, as a fraction of the kernel support. 0.2:
/// (1.2)^3 = 1.73 times the candidates of an exact search, kept while no particle moves 0.1 support.
constexpr Scalar kSkinOfSupport = 0.2;

const FluidSettings& checked(const FluidSettings& settings) {
  check_fluid_settings(settings);
  return settings;
}
}  // namespace

void check_fluid_settings(const FluidSettings& f) {
  constexpr Scalar kInf = std::numeric_limits<Scalar>::infinity();
  const auto require = [](bool ok, const std::string& key, const std::string& range, double value) {
    require_setting(ok, "fluid." + key, range, value);
  };
  const auto positive = [&](const std::string& key, double v) {
    require(v > 0.0 && v < kInf, key, "> 0", v);
  };
  const auto non_negative = [&](const std::string& key, double v) {
    require(v >= 0.0 && v < kInf, key, ">= 0", v);
  };
  const auto fraction = [&](const std::string& key, double v) {
    require(v > 0.0 && v < 1.0, key, "in (0, 1)", v);
  };
  const auto passes = [&](const std::string& key, int v) {
    require(v >= 1 && v <= kMaxPassesPerStep, key, "in [1, " + std::to_string(kMaxPassesPerStep) + "]", v);
  };
  const auto limit = [&](const std::string& key, const std::optional<Scalar>& v) {
    if (v) positive(key, *v);
  };
  // PCISPH's and DFSPH's iteration counts: each a count of passes, the most no fewer than the least.
  const auto iterations = [&](const std::string& solver, int least, int most) {
    passes(solver + ".min_iterations", least);
    passes(solver + ".max_iterations", most);
    require(most >= least, solver + ".max_iterations",
            ">= fluid." + solver + ".min_iterations = " + std::to_string(least), most);
  };
  positive("rest_density", f.rest_density);
  positive("particle_spacing", f.particle_spacing);
  require(f.cfl > 0.0 && f.cfl <= 1.0, "cfl", "in (0, 1]", f.cfl);
  limit("max_speed", f.max_speed);
  require(f.substep_halvings >= 0 && f.substep_halvings <= kMaxSubstepHalvings, "substep_halvings",
          "in [0, " + std::to_string(kMaxSubstepHalvings) + "]", f.substep_halvings);
  require(f.sort_interval >= 1, "sort_interval", ">= 1", f.sort_interval);
  if (f.wcsph.speed_of_sound) {
    const Scalar c = *f.wcsph.speed_of_sound;
    require(c > 0.0 && c <= kMaxSpeedOfSound, "wcsph.speed_of_sound",
            "in (0, " + format_number(kMaxSpeedOfSound) + "]", c);
  }
  require(f.wcsph.exponent >= 1.0 && f.wcsph.exponent < kInf, "wcsph.exponent", ">= 1", f.wcsph.exponent);
  limit("wcsph.max_compression", f.wcsph.max_compression);
  fraction("pcisph.eta", f.pcisph.eta);
  iterations("pcisph", f.pcisph.min_iterations, f.pcisph.max_iterations);
  limit("pcisph.max_compression_per_iteration", f.pcisph.max_compression_per_iteration);
  limit("pcisph.max_relief_per_substep", f.pcisph.max_relief_per_substep);
  fraction("dfsph.eta", f.dfsph.eta);
  positive("dfsph.eta_divergence", f.dfsph.eta_divergence);
  iterations("dfsph", f.dfsph.min_iterations, f.dfsph.max_iterations);
  passes("dfsph.max_divergence_iterations", f.dfsph.max_divergence_iterations);
  limit("dfsph.max_relief_per_substep", f.dfsph.max_relief_per_substep);
  passes("pbf.substeps", f.pbf.substeps);
  passes("pbf.iterations", f.pbf.iterations);
  non_negative("pbf.relaxation", f.pbf.relaxation);
  non_negative("pbf.scorr_k", f.pbf.scorr_k);
  require(f.pbf.scorr_n >= 1 && f.pbf.scorr_n <= kMaxScorrExponent, "pbf.scorr_n",
          "in [1, " + std::to_string(kMaxScorrExponent) + "]", f.pbf.scorr_n);
  fraction("pbf.scorr_dq", f.pbf.scorr_dq);
  limit("pbf.scorr_substep", f.pbf.scorr_substep);
  limit("pbf.max_compression_per_iteration", f.pbf.max_compression_per_iteration);
  non_negative("viscosity.coefficient", f.viscosity.coefficient);
}

StepStatus& StepStatus::operator|=(const StepStatus& other) {
  flags |= other.flags;
  if (non_finite_particle < 0) non_finite_particle = other.non_finite_particle;
  if (non_finite_node < 0) non_finite_node = other.non_finite_node;
  if (runaway_particle < 0) {
    runaway_particle = other.runaway_particle;
    runaway_speed = other.runaway_speed;
  }
  if (leaked_particle < 0) {
    leaked_particle = other.leaked_particle;
    leaked_triangle = other.leaked_triangle;
  }
  if (runaway_node < 0) {
    runaway_node = other.runaway_node;
    runaway_node_speed = other.runaway_node_speed;
  }
  if (overstretched_edge[0] < 0) {
    overstretched_edge[0] = other.overstretched_edge[0];
    overstretched_edge[1] = other.overstretched_edge[1];
    edge_strain = other.edge_strain;
  }
  if (collapsed_particles < 0) {
    collapsed_particles = other.collapsed_particles;
    particle_count = other.particle_count;
  }
  return *this;
}

std::string StepStatus::describe() const {
  std::string text;
  if (flags & NON_FINITE_STATE) {
    text += "NON_FINITE_STATE: particle id " + std::to_string(non_finite_particle) +
            " has a NaN or infinite position or velocity (lower time.dt or fluid.cfl)";
  }
  if (flags & PRESSURE_NOT_CONVERGED) {
    if (!text.empty()) text += "; ";
    text +=
        "PRESSURE_NOT_CONVERGED: the pressure solver reached its max_iterations (fluid.pcisph or "
        "fluid.dfsph) above eta";
  }
  if (flags & FLUID_COLLAPSED) {
    if (!text.empty()) text += "; ";
    text +=
        "FLUID_COLLAPSED: " + std::to_string(collapsed_particles) + " of " + std::to_string(particle_count) +
        " particles packed past twice the rest density in a sub-step (lower time.dt or fluid.cfl, or raise "
        "fluid.pbf.substeps)";
  }
  if (flags & NON_FINITE_CLOTH) {
    if (!text.empty()) text += "; ";
    text += "NON_FINITE_CLOTH: cloth node " + std::to_string(non_finite_node) +
            " has a NaN or infinite position (lower time.dt, raise cloth.position_iterations)";
  }
  if (flags & RUNAWAY_PARTICLE) {
    if (!text.empty()) text += "; ";
    char speed[32];
    std::snprintf(speed, sizeof speed, "%.4g", runaway_speed);
    text += "RUNAWAY_PARTICLE: particle id " + std::to_string(runaway_particle) + " moved at " + speed +
            " m/s, over fluid.max_speed (lower time.dt or fluid.cfl)";
  }
  if (flags & LEAKED) {
    if (!text.empty()) text += "; ";
    text += "LEAKED: particle id " + std::to_string(leaked_particle) + " crossed face " +
            std::to_string(leaked_triangle) +
            " of the cloth or an obstacle (turn coupling.continuous on, lower time.dt)";
  }
  if (flags & RUNAWAY_NODE) {
    if (!text.empty()) text += "; ";
    char speed[32];
    std::snprintf(speed, sizeof speed, "%.4g", runaway_node_speed);
    text += "RUNAWAY_NODE: cloth node " + std::to_string(runaway_node) + " moved at " + speed +
            " m/s, over cloth.max_speed (lower time.dt, raise cloth.substeps)";
  }
  if (flags & CLOTH_OVERSTRETCHED) {
    if (!text.empty()) text += "; ";
    char strain[32];
    std::snprintf(strain, sizeof strain, "%.4g", edge_strain);
    text += "CLOTH_OVERSTRETCHED: the cloth edge between nodes " + std::to_string(overstretched_edge[0]) +
            " and " + std::to_string(overstretched_edge[1]) + " is stretched by a strain of " + strain +
            ", over cloth.max_strain (lower time.dt, raise cloth.substeps or cloth.position_iterations)";
  }
  return text;
}

FluidSolver::FluidSolver(const FluidSettings& settings, const Vec3& gravity, BoundaryParticles boundary,
                         std::vector<BoundarySettings> guards, bool with_viscosity, Scalar speed_of_sound,
                         const SurfaceTensionSettings* surface_tension)
    : m_settings(checked(settings)),
      m_gravity(gravity),
      m_kernel(settings.particle_spacing),
      m_guards(std::move(guards)),
      m_neighbors(m_kernel, kSkinOfSupport * m_kernel.support_radius(), std::move(boundary.positions)),
      m_pressure(make_pressure_solver(settings, speed_of_sound)) {
  if (settings.pressure_solver == PressureSolverKind::PBF)
    m_pbf = static_cast<PressurePbf*>(m_pressure.get());
  const Vec3Array& points = m_neighbors.boundary_points();
  m_boundary_packed.resize(points.size());
  for (std::size_t b = 0; b < points.size(); ++b)
    m_boundary_packed[b] = packed(points[b], settings.rest_density * boundary.volumes[b]);
  m_static_boundary = points.size();
  if (with_viscosity) {
    m_viscosity = make_viscosity(settings.viscosity, speed_of_sound);
    ++m_viscosity_counter.constructed;
  }
  // PBF takes the kernel's gradients at its iterations' positions; of its forces, only surface tension reads
  // the lists' fluid gradient factors.
  if (m_pbf && !surface_tension) m_neighbors.set_fluid_gradient_factors(false);
  if (surface_tension) {
    if (!(surface_tension->sigma >= 0.0 && std::isfinite(surface_tension->sigma))) {
      throw std::invalid_argument("surface_tension.sigma must be >= 0 and finite (N/m), got " +
                                  std::to_string(surface_tension->sigma));
    }
    m_surface_tension =
        make_surface_tension(*surface_tension, settings.particle_spacing, settings.rest_density);
    ++m_surface_tension_counter.constructed;
  }
}

void FluidSolver::set_moving_boundary(const Vec3Array& positions, const ScalarArray& volumes,
                                      const Vec3Array& normals) {
  if (positions.size() != volumes.size() || positions.size() != normals.size()) {
    throw std::invalid_argument("set_moving_boundary: " + std::to_string(positions.size()) + " points, " +
                                std::to_string(volumes.size()) + " volumes and " +
                                std::to_string(normals.size()) + " normals");
  }
  m_moving_impulses.assign(positions.size(), Vec3::Zero());
  m_moving_normals = normals;
  if (positions.empty() && m_boundary_packed.size() == m_static_boundary) return;
  // Sized once and written in place: a game's bodies move every step, and growing both arrays a point at a
  // time was most of this function's own cost in issue 41's level (callgrind).
  m_boundary_packed.resize(m_static_boundary + positions.size());
  PackedPoint* moving = m_boundary_packed.data() + m_static_boundary;
  for (std::size_t b = 0; b < positions.size(); ++b)
    moving[b] = packed(positions[b], m_settings.rest_density * volumes[b]);
  m_neighbors.set_boundary_points(m_static_boundary, positions);
}

void FluidSolver::keep_moving_boundary() {
  std::fill(m_moving_impulses.begin(), m_moving_impulses.end(), Vec3::Zero());
  if (m_boundary_packed.size() > m_static_boundary) m_neighbors.search_afresh();
}

void FluidSolver::add_moving_boundary_reactions(Scalar dt, const Vec3Array& positions) {
  m_pressure->boundary_pressure_factors(m_particles, m_boundary_factors);
  const NeighborList& bn = m_neighbors.boundary();
  const Vec3Array& points = m_neighbors.boundary_points();
  const GradientFactorArray& factors = m_neighbors.boundary_gradient_factors();
  // In particle order, one thread: the sums per boundary point are then the same bits for any thread count.
  // Only particles next to a body have moving neighbors; the others cost a scan of their boundary list.
  for (std::size_t i = 0; i < m_particles.size(); ++i) {
    const Scalar w = m_boundary_factors[i];
    if (w == 0.0) continue;
    const Vec3& xi = positions[i];
    const Scalar scale = m_particles.masses[i] * dt * w;
    Vec3 along_faces = Vec3::Zero();
    bool moving = false;
    for (std::uint32_t k = bn.offsets[i]; k < bn.offsets[i + 1]; ++k) {
      const Index b = bn.indices[k];
      if (b < m_static_boundary) continue;
      // The fluid got -dt w_i Psi_b grad W_ib per unit mass (Akinci et al. 2012 eq. 10); the body takes the
      // opposite of its normal part, and the fluid gives back the rest.
      const Vec3 push = (scale * m_boundary_packed[b].w * static_cast<Scalar>(factors[k])) * (xi - points[b]);
      along_faces += book_boundary_push(b, push);
      moving = true;
    }
    if (moving) m_pressure_accelerations[i] += along_faces / (m_particles.masses[i] * dt);
  }
}

void FluidSolver::add_pbf_boundary_reactions(Scalar dt) {
  const NeighborList& bn = m_neighbors.boundary();
  const std::vector<PressurePbf::BoundaryPush>& pushes = m_pbf->boundary_pushes();
  // As add_moving_boundary_reactions, with the pushes the projection summed over its iterations. In particle
  // order, one thread: the same bits for any thread count.
  for (std::size_t k = 0; k < pushes.size();) {
    const Index i = pushes[k].particle;
    Vec3 along_faces = Vec3::Zero();
    for (; k < pushes.size() && pushes[k].particle == i; ++k)
      along_faces += book_boundary_push(bn.indices[pushes[k].entry], pushes[k].push);
    m_pressure_accelerations[i] += along_faces / (m_particles.masses[i] * dt);
  }
}

Vec3 FluidSolver::book_boundary_push(Index b, const Vec3& push) {
  const Vec3& n = m_moving_normals[b - m_static_boundary];
  const Vec3 normal_part = push.dot(n) * n;
  m_moving_impulses[b - m_static_boundary] += normal_part;
  return push - normal_part;
}

StepStatus FluidSolver::speed_check() const {
  return speed_check(max_speed());
}

StepStatus FluidSolver::speed_check(Scalar speed) const {
  StepStatus status;
  // An infinite speed is left to the non-finite check, which names it as such.
  if (m_settings.max_speed && std::isfinite(speed) && speed > *m_settings.max_speed) {
    status.flags |= StepStatus::RUNAWAY_PARTICLE;
    status.runaway_particle = m_particles.ids[fastest_particle()];
    status.runaway_speed = speed;
  }
  return status;
}

Scalar FluidSolver::particle_mass() const {
  const Scalar s = m_settings.particle_spacing;
  return m_settings.rest_density * s * s * s;
}

void FluidSolver::sort_particles() {
  if (m_stats.substeps % m_settings.sort_interval == 0) {
    ScopedTimer timer(m_stats.timings_s.neighbors);
    m_particles.permute(m_neighbors.z_order(m_particles.positions));
  }
}

void FluidSolver::update_neighbors(Scalar max_displacement) {
  ScopedTimer timer(m_stats.timings_s.neighbors);
  // A search with a skin pays for (1 + kSkinOfSupport)^3 more candidates, so it is made only when its lists
  // can serve at least two sub-steps (the fastest particle moving less than a quarter of the skin per
  // sub-step): WCSPH's short sub-steps; PCISPH's long ones search exactly to the support every time.
  const Scalar skin = kSkinOfSupport * m_kernel.support_radius();
  if (m_neighbors.update(m_particles.positions, m_particles.ids, 4.0 * max_displacement <= skin ? skin : 0.0))
    ++m_stats.neighbor_searches;
}

void FluidSolver::compute_densities(const FluidContext& ctx) {
  ScopedTimer timer(m_stats.timings_s.density);
  const std::size_t n = m_particles.size();
  m_positions_mass.resize(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      m_positions_mass[i] = packed(m_particles.positions[i], m_particles.masses[i]);
  });
  for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
    sph_densities(ctx, m_positions_mass, begin, end, &m_particles.densities[begin]);
  });
}

Scalar FluidSolver::max_speed() const {
  const auto& v = m_particles.velocities;
  const Scalar max_speed_sq = parallel_reduce(
      v.size(), kLightChunk, Scalar(0.0),
      [&](std::size_t begin, std::size_t end) {
        Scalar m = 0.0;
        for (std::size_t i = begin; i < end; ++i)
          m = std::max(m, v[i].squaredNorm());
        return m;
      },
      [](Scalar a, Scalar b) { return std::max(a, b); });
  return std::sqrt(max_speed_sq);
}

std::size_t FluidSolver::fastest_particle() const {
  const auto& v = m_particles.velocities;
  std::size_t fastest = 0;
  for (std::size_t i = 1; i < v.size(); ++i)
    if (v[i].squaredNorm() > v[fastest].squaredNorm()) fastest = i;
  return fastest;
}

Scalar FluidSolver::cfl_limit(Scalar max_speed) const {
  if (m_pbf) return std::numeric_limits<Scalar>::infinity();
  // Water at rest has no speed to limit its sub-steps, and PCISPH's and DFSPH's solves at a whole 1/60 s
  // step stir it or blow up (HydrostaticTank*.SettlesAtTheGamesStep); a sub-step under its surface waves'
  // CFL holds it. Jets faster than the waves keep their limit (bench_game_frame, jet_on_cloth: the same
  // sub-steps).
  const Scalar speed = std::max(max_speed + m_pressure->signal_speed(), gravity_wave_speed());
  if (!(speed > 0.0)) return std::numeric_limits<Scalar>::infinity();
  return m_settings.cfl * m_settings.particle_spacing / speed;
}

Scalar FluidSolver::gravity_wave_speed() const {
  const Scalar g = m_gravity.norm();
  if (!(g > 0.0) || m_particles.empty()) return 0.0;
  const Vec3 up = -m_gravity / g;
  const auto& x = m_particles.positions;
  struct Range {
    Scalar lo, hi;
  };
  const Scalar inf = std::numeric_limits<Scalar>::infinity();
  const Range range = parallel_reduce(
      x.size(), kLightChunk, Range{inf, -inf},
      [&](std::size_t begin, std::size_t end) {
        Range r{inf, -inf};
        for (std::size_t i = begin; i < end; ++i) {
          const Scalar h = x[i].dot(up);
          r.lo = std::min(r.lo, h);
          r.hi = std::max(r.hi, h);
        }
        return r;
      },
      [](const Range& a, const Range& b) {
        return Range{std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
      });
  // h is std::min's and std::max's second argument, so a NaN position is never chosen; the step's
  // non-finite check names it.
  const Scalar depth = range.hi - range.lo;
  return depth > 0.0 ? std::sqrt(g * depth) : 0.0;
}

StepStatus FluidSolver::step(Scalar dt, SubstepConstraint* constraint) {
  ScopedTimer timer(m_stats.timings_s.total);
  std::fill(m_moving_impulses.begin(), m_moving_impulses.end(), Vec3::Zero());
  StepStatus status;
  ++m_stats.steps;
  m_particles.positions_t0 = m_particles.positions;
  if (m_particles.empty()) return status;
  Scalar remaining = dt;
  int count = 0;
  // No sub-step is halved below this; a solve that diverges there is kept with PRESSURE_NOT_CONVERGED.
  const Scalar shortest = std::ldexp(dt, -m_settings.substep_halvings) * (1.0 + 1e-9);
  bool redone = false;
  while (true) {
    const Scalar speed = max_speed();
    // Past fluid.max_speed the CFL limit would cut the step into up to a million sub-steps: a blown-up run
    // would crawl for hours instead of saying so (the WCSPH rows of bench/accuracy_sweep.py's stability
    // sweep).
    status |= speed_check(speed);
    if (status.flags & StepStatus::RUNAWAY_PARTICLE) break;
    if (m_pbf) {
      // A fixed count of equal sub-steps: a game's frame costs the same every frame (PbfSettings).
      const int left = m_settings.pbf.substeps - count;
      const Scalar sub = left == 1 ? remaining : remaining / left;
      status |= substep_pbf(sub, speed, constraint);
      ++count;
      if (left == 1 || !status.ok()) break;
      remaining -= sub;
      continue;
    }
    const Scalar cfl = cfl_limit(speed);
    // A NaN limit means a NaN velocity: take one sub-step so that the check below names the particle. No
    // sub-step is shorter than dt / 2^kMaxSubstepHalvings, the shortest the halvings reach (so a redo still
    // ends): a cap on the count of what remains would let each sub-step take a fixed fraction of the rest,
    // and the step would shrink geometrically (FluidSolver.AStepTakesAtMost2To20Substeps).
    const Scalar limit =
        std::isnan(cfl) ? cfl : std::max(std::min(cfl, m_substep_cap), std::ldexp(dt, -kMaxSubstepHalvings));
    const Scalar wanted = std::isfinite(limit) ? std::ceil(remaining / limit) : 1.0;
    const int n = static_cast<int>(std::clamp(wanted, 1.0, std::ldexp(1.0, kMaxSubstepHalvings)));
    const Scalar sub = n == 1 ? remaining : remaining / n;
    const bool may_redo = sub > shortest;
    bool redo = false;
    status |= substep(sub, speed, constraint, may_redo, redo);
    if (redo) {
      m_substep_cap = 0.5 * sub;
      redone = true;
      ++m_stats.substeps_halved;
      continue;
    }
    ++count;
    if (n == 1 || !status.ok()) break;
    remaining -= sub;
  }
  // Back toward the CFL limit, a little per step, so that a passing hard moment does not slow the rest of the
  // run, and a lasting one costs a redone solve only now and then.
  if (!redone && std::isfinite(m_substep_cap)) {
    m_substep_cap *= 1.25;
    if (m_substep_cap >= dt) m_substep_cap = std::numeric_limits<Scalar>::infinity();
  }
  m_stats.max_substeps_per_step = std::max(m_stats.max_substeps_per_step, count);
  return status;
}

FluidContext FluidSolver::context() {
  return FluidContext{m_kernel,
                      m_particles,
                      m_neighbors.fluid(),
                      m_neighbors.boundary(),
                      m_boundary_packed,
                      m_settings.rest_density,
                      m_settings.particle_spacing,
                      m_neighbors.fluid_gradient_factors(),
                      m_neighbors.boundary_gradient_factors(),
                      m_particles.common_mass()};
}

StepStatus FluidSolver::substep(Scalar dt, Scalar max_speed, SubstepConstraint* constraint, bool may_redo,
                                bool& redo) {
  sort_particles();
  update_neighbors(max_speed * dt);
  ++m_stats.substeps;
  const std::size_t n = m_particles.size();
  const FluidContext ctx = context();
  compute_densities(ctx);
  // DFSPH's divergence solve changes the velocities in place: a redone sub-step must start from these.
  const bool keep_velocities = may_redo && m_settings.pressure_solver == PressureSolverKind::DFSPH;
  if (keep_velocities) m_velocities_start = m_particles.velocities;
  DivergenceStats divergence;
  {
    ScopedTimer timer(m_stats.timings_s.pressure);
    divergence = m_pressure->correct_divergence(ctx, dt);
  }
  m_stats.divergence_iterations += divergence.iterations;
  m_stats.max_divergence_iterations = std::max(m_stats.max_divergence_iterations, divergence.iterations);
  {
    ScopedTimer timer(m_stats.timings_s.forces);
    m_accelerations.assign(n, m_gravity);
    if (m_viscosity) {
      m_viscosity->add_accelerations(ctx, dt, m_accelerations);
      ++m_viscosity_counter.passes;
    }
    if (m_surface_tension) {
      m_surface_tension->add_accelerations(ctx, dt, m_accelerations);
      ++m_surface_tension_counter.passes;
    }
    m_velocities_adv.resize(n);
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        m_velocities_adv[i] = m_particles.velocities[i] + dt * m_accelerations[i];
    });
  }
  PressureStats pressure;
  {
    ScopedTimer timer(m_stats.timings_s.pressure);
    pressure = m_pressure->solve(ctx, m_velocities_adv, dt, m_pressure_accelerations);
  }
  if (may_redo && pressure.diverged) {
    // Its iterations were spent and count; its errors are those of a state that is thrown away.
    m_stats.pressure_iterations += pressure.iterations;
    m_stats.max_pressure_iterations = std::max(m_stats.max_pressure_iterations, pressure.iterations);
    --m_stats.substeps;
    if (keep_velocities) m_particles.velocities.swap(m_velocities_start);
    redo = true;
    return {};
  }
  record(pressure);

  // At the positions the pressure was solved at, before they move.
  if (m_boundary_packed.size() > m_static_boundary) add_moving_boundary_reactions(dt, m_particles.positions);
  StepStatus status;
  if (!pressure.converged || !divergence.converged) status.flags |= StepStatus::PRESSURE_NOT_CONVERGED;
  ScopedTimer timer(m_stats.timings_s.integrate);
  if (constraint) m_positions_before = m_particles.positions;
  status |= finish_substep(dt, constraint, true);
  return status;
}

StepStatus FluidSolver::substep_pbf(Scalar dt, Scalar max_speed, SubstepConstraint* constraint) {
  sort_particles();
  ++m_stats.substeps;
  const std::size_t n = m_particles.size();
  {
    // Macklin & Mueller's prediction: external forces only; the viscosity acts after the solve.
    ScopedTimer timer(m_stats.timings_s.integrate);
    m_positions_before = m_particles.positions;
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        m_particles.velocities[i] += dt * m_gravity;
        m_particles.positions[i] += dt * m_particles.velocities[i];
      }
    });
  }
  // Searched at the prediction, as theirs, so that a fast jet needs no skin of its own displacement; the
  // iterations' moves are small beside the support.
  update_neighbors(max_speed * dt);
  const FluidContext ctx = context();
  if (m_surface_tension) {
    // Macklin & Mueller's prediction takes every external force; surface tension needs the neighbors, so it
    // is taken at the predicted positions and added to the prediction before the projection (v += dt a,
    // x += dt^2 a), not after it as the viscosity: the projection then sees the pull it has to balance.
    compute_densities(ctx);
    ScopedTimer timer(m_stats.timings_s.forces);
    m_accelerations.assign(n, Vec3::Zero());
    m_surface_tension->add_accelerations(ctx, dt, m_accelerations);
    ++m_surface_tension_counter.passes;
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        m_particles.velocities[i] += dt * m_accelerations[i];
        m_particles.positions[i] += (dt * dt) * m_accelerations[i];
      }
    });
  }
  PressureStats pressure;
  {
    ScopedTimer timer(m_stats.timings_s.pressure);
    pressure = m_pbf->project(ctx, dt, m_static_boundary);
  }
  record(pressure);
  {
    ScopedTimer timer(m_stats.timings_s.integrate);
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        m_particles.velocities[i] = (m_particles.positions[i] - m_positions_before[i]) / dt;
    });
  }
  if (m_viscosity || m_boundary_packed.size() > m_static_boundary) {
    ScopedTimer timer(m_stats.timings_s.forces);
    m_accelerations.assign(n, Vec3::Zero());
    if (m_viscosity) {
      m_viscosity->add_accelerations(ctx, dt, m_accelerations);
      ++m_viscosity_counter.passes;
    }
    m_pressure_accelerations.assign(n, Vec3::Zero());
    if (m_boundary_packed.size() > m_static_boundary) add_pbf_boundary_reactions(dt);
    // The viscosity changes velocities only (their Algorithm 1, line 22); what a moving body gives back
    // along its faces moves the particle as a pressure acceleration would.
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        m_particles.velocities[i] += dt * (m_accelerations[i] + m_pressure_accelerations[i]);
        m_particles.positions[i] += (dt * dt) * m_pressure_accelerations[i];
      }
    });
  }
  ScopedTimer timer(m_stats.timings_s.integrate);
  return finish_substep(dt, constraint, false);
}

void FluidSolver::record(const PressureStats& pressure) {
  m_stats.pressure_iterations += pressure.iterations;
  m_stats.max_pressure_iterations = std::max(m_stats.max_pressure_iterations, pressure.iterations);
  m_stats.density_error_sum += pressure.average_density_error;
  m_stats.density_error_max = std::max(m_stats.density_error_max, pressure.average_density_error);
  m_stats.particle_density_error_max =
      std::max(m_stats.particle_density_error_max, pressure.max_density_error);
}

StepStatus FluidSolver::finish_substep(Scalar dt, SubstepConstraint* constraint, bool integrate) {
  const std::size_t n = m_particles.size();
  // The first non-finite particle, the particles the guards moved and those packed past kCollapsedDensity
  // rest densities (by the densities the pressure solve left): a min and integer sums, so any deal. A NaN
  // density is not counted as packed: it comes with a NaN position, named here as non-finite.
  struct Tally {
    std::size_t first_bad;
    std::int64_t guarded = 0, packed = 0;
  };
  const Scalar packed_density = kCollapsedDensity * m_settings.rest_density;
  const auto [first_bad, guarded, packed] = parallel_reduce(
      n, kLightChunk, Tally{n},
      [&](std::size_t begin, std::size_t end) {
        Tally t{n};
        for (std::size_t i = begin; i < end; ++i) {
          Vec3& v = m_particles.velocities[i];
          Vec3& x = m_particles.positions[i];
          Vec3 x_t0;
          if (integrate) {
            v = m_velocities_adv[i] + dt * m_pressure_accelerations[i];
            x_t0 = x;
            x += dt * v;
          } else {
            x_t0 = m_positions_before[i];
          }
          for (const BoundarySettings& guard : m_guards)
            t.guarded += enforce_boundary(guard, x_t0, x, v) ? 1 : 0;
          if (!v.allFinite() || !x.allFinite()) t.first_bad = std::min(t.first_bad, i);
          t.packed += m_particles.densities[i] > packed_density ? 1 : 0;
        }
        return t;
      },
      [](const Tally& a, const Tally& b) {
        return Tally{std::min(a.first_bad, b.first_bad), a.guarded + b.guarded, a.packed + b.packed};
      });
  m_stats.boundary_guards += guarded;
  if (constraint) constraint->apply(m_positions_before, m_particles, dt);
  StepStatus status;
  if (first_bad < n) {
    status.flags |= StepStatus::NON_FINITE_STATE;
    status.non_finite_particle = m_particles.ids[first_bad];
  }
  if (2 * packed > static_cast<std::int64_t>(n)) {
    status.flags |= StepStatus::FLUID_COLLAPSED;
    status.collapsed_particles = packed;
    status.particle_count = static_cast<std::int64_t>(n);
  }
  return status;
}

}  // namespace drench
