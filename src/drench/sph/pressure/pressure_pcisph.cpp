#include <drench/sph/pressure/pressure_pcisph.hpp>

#include <algorithm>
#include <limits>

#include <drench/common/parallel.hpp>

namespace drench {

PressurePcisph::PressurePcisph(const FluidSettings& settings) : m_settings(settings.pcisph) {
  const Scalar s = settings.particle_spacing;
  const CubicSplineKernel kernel(s);
  Vec3 sum_gradient = Vec3::Zero();
  Scalar sum_squared = 0.0;
  for (int k = -2; k <= 2; ++k) {
    for (int j = -2; j <= 2; ++j) {
      for (int i = -2; i <= 2; ++i) {
        const Vec3 g = kernel.gradient(-s * Vec3(i, j, k));
        sum_gradient += g;
        sum_squared += g.squaredNorm();
      }
    }
  }
  m_prototype_gradient_term = sum_gradient.squaredNorm() + sum_squared;
}

PressureStats PressurePcisph::solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                                    Vec3Array& accelerations) {
  auto& particles = ctx.particles;
  const std::size_t n = particles.size();
  const Scalar rho0 = ctx.rest_density;
  const Scalar mass = rho0 * ctx.particle_spacing * ctx.particle_spacing * ctx.particle_spacing;
  const Scalar beta = 2.0 * (mass * dt / rho0) * (mass * dt / rho0);
  const Scalar delta = 1.0 / (beta * m_prototype_gradient_term);

  Vec3 origin;
  const bool single = single_precision_origin(ctx, m_settings.precision, origin);
  m_predicted.resize(single ? 0 : n);
  m_pressure_points.resize(single ? 0 : n);
  m_predicted_float.resize(single ? n : 0);
  m_pressure_points_float.resize(single ? n : 0);
  m_boundary_float.resize(single ? ctx.boundary.size() : 0);
  m_density.resize(n);
  m_target.assign(n, rho0);
  accelerations.resize(n);
  PressureStats stats;
  const Scalar inv_rho0_sq = 1.0 / (rho0 * rho0);
  const Scalar max_excess = m_settings.max_compression_per_iteration
                                ? *m_settings.max_compression_per_iteration * rho0
                                : std::numeric_limits<Scalar>::infinity();
  const Scalar max_relief = m_settings.max_relief_per_substep ? *m_settings.max_relief_per_substep * rho0
                                                              : std::numeric_limits<Scalar>::infinity();
  // Every solve starts from zero pressure, as Solenthaler & Pajarola and SPlisHSPlasH do. Warm starts from
  // the last sub-step's pressures (as they were, scaled down or smoothed) were tried and rejected: they cut
  // the iterations by 2-3x, but their leftover over-pressure kept the hydrostatic tank moving or from
  // settling at all (demos/scenes/hydrostatic_tank.json, test_hydrostatic_tank).
  std::fill(particles.pressures.begin(), particles.pressures.end(), 0.0);
  std::fill(accelerations.begin(), accelerations.end(), Vec3::Zero());
  if (n == 0) return stats;
  if (single) {
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        m_pressure_points_float[i] = packed_float(particles.positions[i] - origin, 0.0);
    });
    parallel_for(ctx.boundary.size(), kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t b = begin; b < end; ++b) {
        const PackedPoint& p = ctx.boundary[b];
        m_boundary_float[b] = packed_float(Vec3(p.x, p.y, p.z) - origin, p.w);
      }
    });
  } else {
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        m_pressure_points[i] = packed(particles.positions[i], 0.0);
    });
  }
  // Positions predicted with the current pressure accelerations, for the particles [begin, end).
  const auto predict = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 x = particles.positions[i] + dt * (velocities_adv[i] + dt * accelerations[i]);
      if (single) {
        m_predicted_float[i] = packed_float(x - origin, particles.masses[i]);
      } else {
        m_predicted[i] = packed(x, particles.masses[i]);
      }
    }
  };
  for_each_chunk(n, predict);
  const std::size_t chunks = (n + kParticleChunk - 1) / kParticleChunk;
  m_chunk_errors.resize(chunks);
  Scalar first_error = 0.0;
  while (true) {
    const int iteration = stats.iterations;
    for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
      if (single) {
        sph_densities_float(ctx, m_predicted_float, m_boundary_float, begin, end, &m_density[begin]);
      } else {
        sph_densities(ctx, m_predicted, begin, end, &m_density[begin]);
      }
      // The chunk's density errors are summed here, where the densities are at hand, and the chunks' sums
      // in chunk order below: the same sum for any thread count, and no serial pass over N per iteration.
      ChunkErrors errors;
      for (std::size_t i = begin; i < end; ++i) {
        // Only compression is corrected (as SPlisHSPlasH's PCISPH): a free-surface particle lacks neighbours
        // and its density deficit is no expansion to undo, so pressures only grow within a solve.
        const Scalar rho = std::max(m_density[i], rho0);
        // Fixed at the first prediction (no pressure yet): what the motion of this sub-step would add is
        // undone in full, what the particle entered it with only down to (density - max_relief).
        if (iteration == 0) m_target[i] = std::max(rho0, std::min(rho, particles.densities[i] - max_relief));
        const Scalar to_target = std::max(rho - m_target[i], 0.0);
        particles.pressures[i] += delta * std::min(to_target, max_excess);
        if (single) {
          m_pressure_points_float[i].w = static_cast<float>(particles.pressures[i] * inv_rho0_sq);
        } else {
          m_pressure_points[i].w = particles.pressures[i] * inv_rho0_sq;
        }
        errors.sum += rho - rho0;
        errors.max = std::max(errors.max, rho - rho0);
        errors.sum_to_target += to_target;
      }
      m_chunk_errors[begin / kParticleChunk] = errors;
    });
    // The next iteration's predictions are made per chunk as its accelerations come out, while they are in
    // cache: a pass of their own re-read all of them.
    for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
      if (single) {
        pressure_accelerations_float(ctx, m_pressure_points_float, m_boundary_float, begin, end,
                                     &accelerations[begin]);
      } else {
        pressure_accelerations(ctx, m_pressure_points, begin, end, &accelerations[begin]);
      }
      predict(begin, end);
    });

    ++stats.iterations;
    ChunkErrors total;
    for (const ChunkErrors& errors : m_chunk_errors) {
      total.sum += errors.sum;
      total.max = std::max(total.max, errors.max);
      total.sum_to_target += errors.sum_to_target;
    }
    const Scalar scale = 1.0 / (static_cast<Scalar>(n) * rho0);
    stats.average_density_error = total.sum * scale;
    stats.max_density_error = total.max / rho0;
    // The convergence test measures the error against each particle's target density (the rest density
    // unless max_relief_per_substep is set); the reported errors are against the rest density.
    const Scalar error = (m_settings.max_relief_per_substep ? total.sum_to_target : total.sum) * scale;
    if (iteration == 0) first_error = error;
    const bool below = error <= m_settings.eta;
    if ((below && stats.iterations >= m_settings.min_iterations) ||
        stats.iterations >= m_settings.max_iterations) {
      stats.converged = below;
      stats.diverged = !below && error > first_error;
      break;
    }
  }
  return stats;
}

void PressurePcisph::boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const {
  out.resize(particles.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = m_pressure_points_float.size() == out.size() ? static_cast<Scalar>(m_pressure_points_float[i].w)
                                                          : m_pressure_points[i].w;
}

}  // namespace drench
