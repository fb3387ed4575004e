#include <drench/sph/pressure/pressure_dfsph.hpp>

#include <algorithm>
#include <cassert>
#include <limits>

#include <drench/common/parallel.hpp>
#include <drench/sph/float_lanes.hpp>

namespace drench {

namespace {
/// A particle with fewer neighbors (fluid and boundary) is left out of the divergence solve, as SPlisHSPlasH
/// does in 3D: at a free surface or in a spray its density deficit makes any divergence meaningless.
constexpr std::size_t kMinDivergenceNeighbors = 20;
}  // namespace

DRENCH_SIMD_CLONES void dfsph_denominators(const FluidContext& ctx, const PackedPointArray& x_mass,
                                           std::size_t begin, std::size_t end, Scalar* out) {
  const NeighborList& fn = ctx.fluid_neighbors;
  const NeighborList& bn = ctx.boundary_neighbors;
  const float* ff = ctx.fluid_gradient_factors.data();
  const float* bf = ctx.boundary_gradient_factors.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PackedPoint& xi = x_mass[i];
    Scalar gx = 0.0, gy = 0.0, gz = 0.0, squares = 0.0;
    for (std::uint32_t n = fn.offsets[i]; n < fn.offsets[i + 1]; ++n) {
      const PackedPoint& xj = x_mass[fn.indices[n]];
      const Scalar s = xj.w * Scalar{ff[n]};
      const Scalar dx = s * (xi.x - xj.x), dy = s * (xi.y - xj.y), dz = s * (xi.z - xj.z);
      gx += dx;
      gy += dy;
      gz += dz;
      squares += dx * dx + dy * dy + dz * dz;
    }
    for (std::uint32_t n = bn.offsets[i]; n < bn.offsets[i + 1]; ++n) {
      const PackedPoint& b = ctx.boundary[bn.indices[n]];
      const Scalar s = b.w * Scalar{bf[n]};
      gx += s * (xi.x - b.x);
      gy += s * (xi.y - b.y);
      gz += s * (xi.z - b.z);
    }
    out[i - begin] = gx * gx + gy * gy + gz * gz + squares;
  }
}

DRENCH_SIMD_CLONES void density_change(const FluidContext& ctx, const PackedPointArray& x_mass,
                                       const PackedPointArray& velocities, std::size_t begin, std::size_t end,
                                       Scalar* out) {
  const NeighborList& fn = ctx.fluid_neighbors;
  const NeighborList& bn = ctx.boundary_neighbors;
  const float* ff = ctx.fluid_gradient_factors.data();
  const float* bf = ctx.boundary_gradient_factors.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PackedPoint& xi = x_mass[i];
    const PackedPoint& vi = velocities[i];
    Scalar sum = 0.0;
    for (std::uint32_t n = fn.offsets[i]; n < fn.offsets[i + 1]; ++n) {
      const Index j = fn.indices[n];
      const PackedPoint& xj = x_mass[j];
      const PackedPoint& vj = velocities[j];
      sum += xj.w * Scalar{ff[n]} *
             ((vi.x - vj.x) * (xi.x - xj.x) + (vi.y - vj.y) * (xi.y - xj.y) + (vi.z - vj.z) * (xi.z - xj.z));
    }
    for (std::uint32_t n = bn.offsets[i]; n < bn.offsets[i + 1]; ++n) {
      const PackedPoint& b = ctx.boundary[bn.indices[n]];
      sum += b.w * Scalar{bf[n]} * (vi.x * (xi.x - b.x) + vi.y * (xi.y - b.y) + vi.z * (xi.z - b.z));
    }
    out[i - begin] = sum;
  }
}

DRENCH_SIMD_CLONES void density_change_float(const FluidContext& ctx, const PackedPointFArray& x_mass,
                                             const PackedPointFArray& velocities,
                                             const PackedPointFArray& boundary, std::size_t begin,
                                             std::size_t end, Scalar* out) {
  assert(ctx.uniform_mass > 0.0);
  const PackedPointF* xs = x_mass.data();
  const PackedPointF* vs = velocities.data();
  const PackedPointF* bs = boundary.data();
  with_group_of_copy<FloatHalvesGroup, FloatWideGroup>([&](auto lanes) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPointF& xi = xs[i];
      const PackedPointF& vi = vs[i];
      const float fluid = float_density_change_sum<Group, false>(xi, vi, xs, vs, ctx.fluid_neighbors, i,
                                                                 ctx.fluid_gradient_factors.data());
      const float walls = float_density_change_sum<Group, true>(xi, vi, bs, nullptr, ctx.boundary_neighbors,
                                                                i, ctx.boundary_gradient_factors.data());
      out[i - begin] = ctx.uniform_mass * Scalar{fluid} + Scalar{walls};
    }
  });
}

PressureDfsph::PressureDfsph(const FluidSettings& settings) : m_settings(settings.dfsph) {
  const Scalar s = settings.particle_spacing;
  const Scalar mass = settings.rest_density * s * s * s;
  const CubicSplineKernel kernel(s);
  Scalar squares = 0.0;
  for (int k = -2; k <= 2; ++k) {
    for (int j = -2; j <= 2; ++j) {
      for (int i = -2; i <= 2; ++i)
        squares += (mass * kernel.gradient(-s * Vec3(i, j, k))).squaredNorm();
    }
  }
  // A filled lattice's gradient sum is zero by symmetry; its squares are the denominator. A particle under a
  // tenth of it has lost most of its neighbours or sits where their gradients cancel (inside a moving body's
  // boundary shell): dividing by that tenth keeps its Jacobi step bounded, where a near-zero denominator
  // threw particles out of bench_game_frame's level
  // (CaughtParticle.DoesNotThrowItsNeighbour).
  m_min_denominator = 0.1 * squares;
}

void PressureDfsph::follow_particles(const ParticleSet& particles) {
  if (particles.ids == m_ids) return;
  const std::size_t n = particles.size();
  std::uint32_t max_id = 0;
  for (const std::uint32_t id : m_ids)
    max_id = std::max(max_id, id);
  m_by_id.assign(m_ids.empty() ? 0 : 2 * (std::size_t{max_id} + 1), 0.0);
  for (std::size_t k = 0; k < m_ids.size(); ++k) {
    m_by_id[2 * std::size_t{m_ids[k]}] = m_warm[k];
    m_by_id[2 * std::size_t{m_ids[k]} + 1] = m_warm_divergence[k];
  }
  m_warm.assign(n, 0.0);
  m_warm_divergence.assign(n, 0.0);
  // Particles new since the last sub-step have ids above every earlier one (ids are never reused) and start
  // without a warm start.
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t id = particles.ids[i];
    if (m_ids.empty() || id > max_id) continue;
    m_warm[i] = m_by_id[2 * id];
    m_warm_divergence[i] = m_by_id[2 * id + 1];
  }
  m_ids = particles.ids;
}

void PressureDfsph::compute_factors(const FluidContext& ctx) {
  const ParticleSet& particles = ctx.particles;
  const std::size_t n = particles.size();
  Vec3 origin;
  m_single = single_precision_origin(ctx, m_settings.precision, origin);
  m_points.resize(n);
  m_kappa_points.resize(m_single ? 0 : n);
  m_points_float.resize(m_single ? n : 0);
  m_kappa_points_float.resize(m_single ? n : 0);
  m_velocities_float.resize(m_single ? n : 0);
  m_boundary_float.resize(m_single ? ctx.boundary.size() : 0);
  m_inv_denominator.resize(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      m_points[i] = packed(particles.positions[i], particles.masses[i]);
      if (m_single) {
        m_points_float[i] = packed_float(particles.positions[i] - origin, particles.masses[i]);
        m_kappa_points_float[i] = packed_float(particles.positions[i] - origin, 0.0);
      } else {
        m_kappa_points[i] = packed(particles.positions[i], 0.0);
      }
    }
  });
  if (m_single) {
    parallel_for(ctx.boundary.size(), kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t b = begin; b < end; ++b) {
        const PackedPoint& p = ctx.boundary[b];
        m_boundary_float[b] = packed_float(Vec3(p.x, p.y, p.z) - origin, p.w);
      }
    });
  }
  for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
    dfsph_denominators(ctx, m_points, begin, end, &m_inv_denominator[begin]);
    for (std::size_t i = begin; i < end; ++i) {
      const Scalar d = m_inv_denominator[i];
      m_inv_denominator[i] = 1.0 / std::max(d, m_min_denominator);
    }
  });
  m_factors_current = true;
}

void PressureDfsph::set_velocities(const Vec3Array& velocities) {
  const std::size_t n = velocities.size();
  m_velocities.resize(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      m_velocities[i] = packed(velocities[i], 0.0);
      if (m_single) m_velocities_float[i] = packed_float(velocities[i], 0.0);
    }
  });
}

void PressureDfsph::update_velocities(const FluidContext& ctx, Scalar dt, Vec3Array* accelerations,
                                      ScalarArray* totals) {
  for_each_chunk(ctx.particles.size(), [&](std::size_t begin, std::size_t end) {
    Vec3 a[kParticleChunk];
    if (m_single) {
      pressure_accelerations_float(ctx, m_kappa_points_float, m_boundary_float, begin, end, a);
    } else {
      pressure_accelerations(ctx, m_kappa_points, begin, end, a);
    }
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3& ai = a[i - begin];
      PackedPoint& v = m_velocities[i];
      v.x += dt * ai.x();
      v.y += dt * ai.y();
      v.z += dt * ai.z();
      if (m_single) m_velocities_float[i] = packed_float(Vec3(v.x, v.y, v.z), 0.0);
      if (accelerations) (*accelerations)[i] += ai;
      if (totals) (*totals)[i] += kappa(i);
    }
  });
}

bool PressureDfsph::apply_warm_start(const ScalarArray& warm, Scalar scale, ScalarArray& totals) {
  const std::size_t n = warm.size();
  const int any = parallel_reduce(
      n, kLightChunk, 0,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
          if (m_error[i] > 0.0 && warm[i] != 0.0) return 1;
        return 0;
      },
      [](int a, int b) { return a | b; });
  if (!any) return false;
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Scalar w = m_error[i] > 0.0 ? scale * warm[i] : 0.0;
      set_kappa(i, w);
      totals[i] += w;
    }
  });
  return true;
}

PressureDfsph::ChunkErrors PressureDfsph::measure(const FluidContext& ctx, Scalar dt, Measure what) {
  const std::size_t n = ctx.particles.size();
  const NeighborList& fn = ctx.fluid_neighbors;
  const NeighborList& bn = ctx.boundary_neighbors;
  const Scalar rho0 = ctx.rest_density;
  const ScalarArray& densities = ctx.particles.densities;
  const bool divergence = what == Measure::DIVERGENCE;
  const Scalar max_relief = m_settings.max_relief_per_substep ? *m_settings.max_relief_per_substep * rho0
                                                              : std::numeric_limits<Scalar>::infinity();
  // Density solve: kappa_i / rho_i = max(rho*_i - target_i, 0) / (dt^2 denominator_i) (eq. 11 with Algorithm
  // 3's source); divergence solve: max(D rho_i / Dt, 0) / (dt denominator_i) (Algorithm 2).
  const Scalar scale = divergence ? 1.0 / dt : 1.0 / (dt * dt);
  m_chunk_errors.resize((n + kParticleChunk - 1) / kParticleChunk);
  for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
    Scalar change[kParticleChunk];
    if (m_single) {
      density_change_float(ctx, m_points_float, m_velocities_float, m_boundary_float, begin, end, change);
    } else {
      density_change(ctx, m_points, m_velocities, begin, end, change);
    }
    ChunkErrors errors;
    for (std::size_t i = begin; i < end; ++i) {
      Scalar error, to_target;
      if (divergence) {
        error = fn.count(i) + bn.count(i) < kMinDivergenceNeighbors ? 0.0 : std::max(change[i - begin], 0.0);
        to_target = error;
      } else {
        const Scalar predicted = densities[i] + dt * change[i - begin];
        // Fixed at the first prediction (no pressure yet): what the motion of this sub-step would add is
        // undone in full, what the particle entered it with only down to (density - max_relief).
        if (what == Measure::FIRST_DENSITY)
          m_target[i] = std::max(rho0, std::min(predicted, densities[i] - max_relief));
        error = std::max(predicted - rho0, 0.0);
        to_target = std::max(predicted - m_target[i], 0.0);
      }
      m_error[i] = to_target;
      set_kappa(i, to_target * scale * m_inv_denominator[i]);
      errors.sum += error;
      errors.max = std::max(errors.max, error);
      errors.sum_to_target += to_target;
    }
    m_chunk_errors[begin / kParticleChunk] = errors;
  });
  ChunkErrors total;
  for (const ChunkErrors& errors : m_chunk_errors) {
    total.sum += errors.sum;
    total.max = std::max(total.max, errors.max);
    total.sum_to_target += errors.sum_to_target;
  }
  return total;
}

DivergenceStats PressureDfsph::correct_divergence(const FluidContext& ctx, Scalar dt) {
  ParticleSet& particles = ctx.particles;
  const std::size_t n = particles.size();
  DivergenceStats stats;
  follow_particles(particles);
  compute_factors(ctx);
  m_kappa_divergence.assign(n, 0.0);
  if (n == 0) return stats;
  set_velocities(particles.velocities);
  m_error.resize(n);
  const Scalar scale = 1.0 / (static_cast<Scalar>(n) * ctx.rest_density);
  ChunkErrors errors = measure(ctx, dt, Measure::DIVERGENCE);
  if (m_settings.warm_start && apply_warm_start(m_warm_divergence, 0.5, m_kappa_divergence)) {
    update_velocities(ctx, dt, nullptr, nullptr);
    errors = measure(ctx, dt, Measure::DIVERGENCE);
  }
  // No minimum: a field already below the target is left as it is (SPlisHSPlasH runs one iteration, whose
  // update is then below the target too).
  while (true) {
    const bool below = errors.sum * scale <= m_settings.eta_divergence;
    if (below || stats.iterations >= m_settings.max_divergence_iterations) {
      stats.converged = below;
      break;
    }
    update_velocities(ctx, dt, nullptr, &m_kappa_divergence);
    ++stats.iterations;
    errors = measure(ctx, dt, Measure::DIVERGENCE);
  }
  stats.average_divergence_error = errors.sum * scale;
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPoint& v = m_velocities[i];
      particles.velocities[i] = Vec3(v.x, v.y, v.z);
      m_warm_divergence[i] = m_kappa_divergence[i];
    }
  });
  return stats;
}

PressureStats PressureDfsph::solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                                   Vec3Array& accelerations) {
  ParticleSet& particles = ctx.particles;
  const std::size_t n = particles.size();
  PressureStats stats;
  follow_particles(particles);
  if (!m_factors_current || m_inv_denominator.size() != n) compute_factors(ctx);
  if (m_kappa_divergence.size() != n) m_kappa_divergence.assign(n, 0.0);
  m_factors_current = false;
  accelerations.assign(n, Vec3::Zero());
  m_kappa.assign(n, 0.0);
  if (n == 0) return stats;
  set_velocities(velocities_adv);
  m_error.resize(n);
  m_target.resize(n);
  const Scalar rho0 = ctx.rest_density;
  const Scalar scale = 1.0 / (static_cast<Scalar>(n) * rho0);
  ChunkErrors errors = measure(ctx, dt, Measure::FIRST_DENSITY);
  const Scalar first_error = errors.sum_to_target;
  if (m_settings.warm_start && apply_warm_start(m_warm, 0.5, m_kappa)) {
    update_velocities(ctx, dt, &accelerations, nullptr);
    errors = measure(ctx, dt, Measure::DENSITY);
  }
  while (true) {
    // Measured against each particle's target (the rest density unless max_relief_per_substep is set); the
    // reported errors are against the rest density.
    const bool below = errors.sum_to_target * scale <= m_settings.eta;
    if ((below && stats.iterations >= m_settings.min_iterations) ||
        stats.iterations >= m_settings.max_iterations) {
      stats.converged = below;
      stats.diverged = !below && errors.sum_to_target > first_error;
      break;
    }
    update_velocities(ctx, dt, &accelerations, &m_kappa);
    ++stats.iterations;
    errors = measure(ctx, dt, Measure::DENSITY);
  }
  stats.average_density_error = errors.sum * scale;
  stats.max_density_error = errors.max / rho0;
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Scalar rho = particles.densities[i];
      particles.pressures[i] = rho * rho * (m_kappa[i] + m_kappa_divergence[i]);
      m_warm[i] = m_kappa[i];
    }
  });
  return stats;
}

void PressureDfsph::boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const {
  out.resize(particles.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = m_kappa[i] + m_kappa_divergence[i];
}

}  // namespace drench
