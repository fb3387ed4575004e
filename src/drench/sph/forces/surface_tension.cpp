#include <drench/sph/forces/surface_tension.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <drench/common/parallel.hpp>

namespace drench {

namespace {
constexpr Scalar kPi = 3.14159265358979323846;
}  // namespace

Scalar SurfaceTensionAkinci::cohesion_kernel(Scalar r) const {
  const Scalar h = m_support;
  if (!(r > 0.0) || r > h) return 0.0;
  const Scalar f = (h - r) * (h - r) * (h - r) * r * r * r;
  return 2.0 * r > h ? m_cohesion_scale * f : m_cohesion_scale * (2.0 * f - m_cohesion_offset);
}

SurfaceTensionAkinci::SurfaceTensionAkinci(Scalar sigma, Scalar particle_spacing, Scalar rest_density)
    : m_gamma(0.0),
      m_support(2.0 * particle_spacing),
      m_rest_density(rest_density),
      m_cohesion_scale(32.0 / (kPi * std::pow(m_support, 9))),
      m_cohesion_offset(std::pow(m_support, 6) / 64.0) {
  // S: pairs (i above the plane z = s/2, j below) of the cubic lattice, per column of i, of int_r^H C.
  const Scalar s = particle_spacing;
  const auto binding = [&](Scalar r) {  // int_r^H C(r') dr', Simpson's rule
    const int steps = 400;
    const Scalar step = (m_support - r) / steps;
    Scalar sum = cohesion_kernel(r) + cohesion_kernel(m_support);
    for (int k = 1; k < steps; ++k)
      sum += (k % 2 ? 4.0 : 2.0) * cohesion_kernel(r + k * step);
    return sum * step / 3.0;
  };
  Scalar pairs = 0.0;
  for (int zi = 1; zi <= 2; ++zi)
    for (int a = -2; a <= 2; ++a)
      for (int b = -2; b <= 2; ++b)
        for (int zj = 0; zj >= -2; --zj) {
          const Scalar r = s * Vec3(a, b, zi - zj).norm();
          if (r < m_support) pairs += binding(r);
        }
  const Scalar m = rest_density * s * s * s;
  m_gamma = 2.0 * sigma * s * s / (m * m * pairs);
}

void SurfaceTensionAkinci::add_accelerations(const FluidContext& ctx, Scalar /*dt*/,
                                             Vec3Array& accelerations) const {
  const ParticleSet& p = ctx.particles;
  const std::size_t n = p.size();
  const NeighborList& nb = ctx.fluid_neighbors;
  m_normals.resize(n);
  m_virial_pressures.resize(n);
  parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Vec3 g = Vec3::Zero();
      // The lists' gradient factors hold at the current positions (FluidContext), for PBF's prediction too.
      for (std::uint32_t e = nb.offsets[i]; e < nb.offsets[i + 1]; ++e) {
        const Index j = nb.indices[e];
        g += (p.masses[j] / p.densities[j] * static_cast<Scalar>(ctx.fluid_gradient_factors[e])) *
             (p.positions[i] - p.positions[j]);
      }
      m_normals[i] = m_support * g;
    }
  });
  const Scalar rho0 = m_rest_density;
  parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Vec3 a = Vec3::Zero();
      Scalar virial = 0.0;
      for (const Index* j = nb.begin(i); j != nb.end(i); ++j) {
        const Vec3 x_ij = p.positions[i] - p.positions[*j];
        const Scalar r = x_ij.norm();
        if (!(r > 0.0) || r > m_support) continue;
        const Scalar correction = 2.0 * rho0 / (p.densities[i] + p.densities[*j]);
        const Vec3 cohesion = (-m_gamma * p.masses[*j] * cohesion_kernel(r) / r) * x_ij;
        const Vec3 curvature = -m_gamma * (m_normals[i] - m_normals[*j]);
        const Vec3 a_ij = correction * (cohesion + curvature);
        a += a_ij;
        virial += x_ij.dot(a_ij);
      }
      accelerations[i] += a;
      m_virial_pressures[i] = p.densities[i] * virial / 6.0;
    }
  });
}

std::unique_ptr<SurfaceTensionAkinci> make_surface_tension(const SurfaceTensionSettings& settings,
                                                           Scalar particle_spacing, Scalar rest_density) {
  return std::make_unique<SurfaceTensionAkinci>(settings.sigma, particle_spacing, rest_density);
}

}  // namespace drench
