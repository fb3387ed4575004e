#include <drench/sph/pressure/pressure_wcsph.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include <drench/common/parallel.hpp>

namespace drench {

PressureWcsph::PressureWcsph(const FluidSettings& settings, Scalar speed_of_sound)
    : m_speed_of_sound(speed_of_sound),
      m_exponent(settings.wcsph.exponent),
      m_stiffness(settings.rest_density * speed_of_sound * speed_of_sound / settings.wcsph.exponent),
      m_max_ratio(settings.wcsph.max_compression ? 1.0 + *settings.wcsph.max_compression
                                                 : std::numeric_limits<Scalar>::infinity()) {}

PressureStats PressureWcsph::solve(const FluidContext& ctx, const Vec3Array& /*velocities_adv*/,
                                   Scalar /*dt*/, Vec3Array& accelerations) {
  auto& particles = ctx.particles;
  const std::size_t n = particles.size();
  m_pressure_points.resize(n);
  accelerations.resize(n);
  const Scalar rho0 = ctx.rest_density;
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Scalar rho = particles.densities[i];
      const Scalar p =
          std::max(0.0, m_stiffness * (std::pow(std::min(rho / rho0, m_max_ratio), m_exponent) - 1.0));
      particles.pressures[i] = p;
      m_pressure_points[i] = packed(particles.positions[i], p / (rho * rho));
    }
  });
  for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
    pressure_accelerations(ctx, m_pressure_points, begin, end, &accelerations[begin]);
  });

  PressureStats stats;
  stats.iterations = 1;
  density_error_stats(particles.densities, rho0, stats);
  return stats;
}

void PressureWcsph::boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const {
  out.resize(particles.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = m_pressure_points[i].w;
}

}  // namespace drench
