#include <drench/sph/forces/surface_tension.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <Eigen/LU>

#include <drench/common/parallel.hpp>

namespace drench {

namespace {
constexpr Scalar kPi = 3.14159265358979323846;
using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
}  // namespace

Scalar SurfaceTensionAkinci::cohesion_kernel(Scalar r) const {
  const Scalar h = m_support;
  if (!(r > 0.0) || r > h) return 0.0;
  const Scalar f = (h - r) * (h - r) * (h - r) * r * r * r;
  return 2.0 * r > h ? m_cohesion_scale * f : m_cohesion_scale * (2.0 * f - m_cohesion_offset);
}

SurfaceTensionAkinci::SurfaceTensionAkinci(Scalar sigma, Scalar particle_spacing, Scalar rest_density,
                                           Terms terms)
    : m_terms(terms),
      m_gamma(0.0),
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
  add_pair_accelerations(ctx, nullptr, accelerations);
}

void SurfaceTensionAkinci::add_pair_accelerations(const FluidContext& ctx, const std::vector<char>* mask,
                                                  Vec3Array& accelerations) const {
  const ParticleSet& p = ctx.particles;
  const std::size_t n = p.size();
  const NeighborList& nb = ctx.fluid_neighbors;
  const bool curvature_term = m_terms == Terms::COHESION_AND_CURVATURE;
  m_normals.assign(n, Vec3::Zero());
  m_virial_pressures.resize(n);
  if (curvature_term)
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
      if (mask && !(*mask)[i]) {
        m_virial_pressures[i] = 0.0;
        continue;
      }
      Vec3 a = Vec3::Zero();
      Scalar virial = 0.0;
      for (const Index* j = nb.begin(i); j != nb.end(i); ++j) {
        const Vec3 x_ij = p.positions[i] - p.positions[*j];
        const Scalar r = x_ij.norm();
        if (!(r > 0.0) || r > m_support) continue;
        const Scalar correction = 2.0 * rho0 / (p.densities[i] + p.densities[*j]);
        const Vec3 cohesion = (-m_gamma * p.masses[*j] * cohesion_kernel(r) / r) * x_ij;
        const Vec3 a_ij = curvature_term
                              ? Vec3(correction * (cohesion - m_gamma * (m_normals[i] - m_normals[*j])))
                              : Vec3(correction * cohesion);
        a += a_ij;
        virial += x_ij.dot(a_ij);
      }
      accelerations[i] += a;
      m_virial_pressures[i] = p.densities[i] * virial / 6.0;
    }
  });
}

namespace {
/// |g| spacing above which a particle may be on the surface (Morris 2000's reliable normals); a flat face's
/// layer has 0.51, the layer below it 0.
constexpr Scalar kSurfaceThreshold = 0.1;
/// |g smoothed| spacing above which it is: a flat face's layers have 0.26, 0.11, 0.01. Disorder makes |g|
/// spacing up to 0.37 inside a collapsing cube, where the smoothed one stays below 0.08 at first; with |g|
/// alone, those particles took forces that grew the disorder into a void (sphericity 0.99 -> 0.3).
constexpr Scalar kSmoothedThreshold = 0.16;
/// Smoothing passes of g before its direction is taken as the normal.
constexpr int kNormalSmoothingPasses = 2;
}  // namespace

SurfaceTensionCsf::SurfaceTensionCsf(Scalar sigma, Scalar particle_spacing, Scalar rest_density,
                                     Scalar cohesion_share)
    : m_sigma((1.0 - cohesion_share) * sigma),
      m_spacing(particle_spacing),
      m_delta_normalisation(0.0),
      m_cohesion(cohesion_share * sigma, particle_spacing, rest_density,
                 SurfaceTensionAkinci::Terms::COHESION),
      m_small_droplets((1.0 - cohesion_share) * sigma, particle_spacing, rest_density),
      m_min_resolved_particles(
          static_cast<std::size_t>(std::ceil(4.0 / 3.0 * kPi * std::pow(kMinResolvedRadius, 3)))) {
  // D: the face z = 0 of the lattice filling z <= 0; every layer whose support reaches past the face counts.
  const CubicSplineKernel kernel(particle_spacing);
  const Scalar s = particle_spacing;
  const Scalar volume = s * s * s;
  for (int layer = 0; layer >= -2; --layer) {
    Vec3 g = Vec3::Zero();
    for (int a = -2; a <= 2; ++a)
      for (int b = -2; b <= 2; ++b)
        for (int c = layer - 2; c <= 0; ++c)
          if (a != 0 || b != 0 || c != layer) g += volume * kernel.gradient(s * Vec3(-a, -b, layer - c));
    m_delta_normalisation += s * g.norm();
  }
}

void SurfaceTensionCsf::add_accelerations(const FluidContext& ctx, Scalar dt,
                                          Vec3Array& accelerations) const {
  const ParticleSet& p = ctx.particles;
  const std::size_t n = p.size();
  const NeighborList& nb = ctx.fluid_neighbors;
  const CubicSplineKernel& kernel = ctx.kernel;
  const Scalar self_weight = kernel.value(0.0);
  m_colour_gradients.resize(n);
  m_smoothed.resize(n);
  m_scratch.resize(n);
  m_on_surface.resize(n);
  m_raw_curvatures.assign(n, 0.0);
  m_curvatures.assign(n, 0.0);
  mark_unresolved_droplets(ctx);
  // Rest volumes m / rho0: SPH's density of a surface particle is low by the kernel's truncation, not by
  // expansion, and D is calibrated with the lattice's volumes (m / rho_j read kappa 18-36% high on droplets).
  const Scalar rest_density = ctx.rest_density;
  const auto volume = [&](Index j) { return p.masses[j] / rest_density; };
  parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Vec3 g = Vec3::Zero();
      for (std::uint32_t e = nb.offsets[i]; e < nb.offsets[i + 1]; ++e) {
        const Index j = nb.indices[e];
        g += (volume(j) * static_cast<Scalar>(ctx.fluid_gradient_factors[e])) *
             (p.positions[i] - p.positions[j]);
      }
      m_colour_gradients[i] = g;
      m_on_surface[i] = g.norm() * m_spacing > kSurfaceThreshold;
    }
  });
  m_smoothed = m_colour_gradients;
  for (int pass = 0; pass < kNormalSmoothingPasses; ++pass) {
    parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        Vec3 sum = (volume(static_cast<Index>(i)) * self_weight) * m_smoothed[i];
        for (const Index* j = nb.begin(i); j != nb.end(i); ++j)
          sum += (volume(*j) * kernel.value((p.positions[i] - p.positions[*j]).norm())) * m_smoothed[*j];
        m_scratch[i] = sum;
      }
    });
    m_smoothed.swap(m_scratch);
  }
  parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Scalar norm = m_smoothed[i].norm();
      m_on_surface[i] = m_on_surface[i] && norm * m_spacing > kSmoothedThreshold;
      m_smoothed[i] = m_on_surface[i] && norm > 0.0 ? Vec3(-m_smoothed[i] / norm) : Vec3::Zero();
    }
  });
  const Vec3Array& normals = m_smoothed;
  const Scalar max_curvature = 2.0 / m_spacing;
  parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (!m_on_surface[i]) continue;
      const Vec3& m_i = normals[i];
      const Mat3 tangent = Mat3::Identity() - m_i * m_i.transpose();
      Mat3 moments = m_i * m_i.transpose();
      Mat3 derivatives = Mat3::Zero();
      for (std::uint32_t e = nb.offsets[i]; e < nb.offsets[i + 1]; ++e) {
        const Index j = nb.indices[e];
        if (!m_on_surface[j]) continue;
        const Vec3 x_ji = p.positions[j] - p.positions[i];
        const Vec3 w = tangent * ((-volume(j) * static_cast<Scalar>(ctx.fluid_gradient_factors[e])) * x_ji);
        moments += w * (tangent * x_ji).transpose();
        derivatives += w * (normals[j] - m_i).transpose();
      }
      const Scalar det = moments.determinant();
      if (!(det > 0.01)) continue;
      m_raw_curvatures[i] =
          std::clamp((moments.inverse() * derivatives).trace(), -max_curvature, max_curvature);
    }
  });
  parallel_for(n, kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (!m_on_surface[i] || m_unresolved[i]) continue;
      Scalar weights = volume(static_cast<Index>(i)) * self_weight;
      Scalar sum = weights * m_raw_curvatures[i];
      for (const Index* j = nb.begin(i); j != nb.end(i); ++j) {
        if (!m_on_surface[*j]) continue;
        const Scalar w = volume(*j) * kernel.value((p.positions[i] - p.positions[*j]).norm());
        weights += w;
        sum += w * m_raw_curvatures[*j];
      }
      // The surface that bounds the particles' volumes lies half a spacing outside the outer layer's centres:
      // each principal curvature k there is k / (1 + k spacing / 2), with k = kappa / 2 (a sphere's).
      const Scalar kappa = sum / weights;
      m_curvatures[i] = kappa / (1.0 + 0.25 * kappa * m_spacing);
      accelerations[i] +=
          (m_sigma * m_curvatures[i] / (m_delta_normalisation * rest_density)) * m_colour_gradients[i];
    }
  });
  m_cohesion.add_accelerations(ctx, dt, accelerations);
  m_virial_pressures = m_cohesion.virial_pressures();
  if (m_unresolved_count == 0) return;
  m_small_droplets.add_pair_accelerations(ctx, &m_unresolved, accelerations);
  for (std::size_t i = 0; i < n; ++i)
    m_virial_pressures[i] += m_small_droplets.virial_pressures()[i];
}

void SurfaceTensionCsf::mark_unresolved_droplets(const FluidContext& ctx) const {
  // Union-find over the pairs within the support: sequential, so the same sets for any thread count.
  const ParticleSet& p = ctx.particles;
  const std::size_t n = p.size();
  const NeighborList& nb = ctx.fluid_neighbors;
  const Scalar support_sq = ctx.kernel.support_radius() * ctx.kernel.support_radius();
  m_droplet.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    m_droplet[i] = static_cast<Index>(i);
  const auto root = [&](Index i) {
    while (m_droplet[i] != i) {
      m_droplet[i] = m_droplet[m_droplet[i]];
      i = m_droplet[i];
    }
    return i;
  };
  for (std::size_t i = 0; i < n; ++i)
    for (const Index* j = nb.begin(i); j != nb.end(i); ++j) {
      if ((p.positions[i] - p.positions[*j]).squaredNorm() >= support_sq) continue;
      const Index a = root(static_cast<Index>(i));
      const Index b = root(*j);
      if (a != b) m_droplet[std::max(a, b)] = std::min(a, b);
    }
  m_droplet_sizes.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    ++m_droplet_sizes[root(static_cast<Index>(i))];
  m_unresolved.resize(n);
  m_unresolved_count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    m_unresolved[i] = m_droplet_sizes[root(static_cast<Index>(i))] < m_min_resolved_particles;
    m_unresolved_count += m_unresolved[i] ? 1 : 0;
  }
}

std::unique_ptr<SurfaceTension> make_surface_tension(const SurfaceTensionSettings& settings,
                                                     Scalar particle_spacing, Scalar rest_density) {
  if (settings.model == SurfaceTensionModel::AKINCI)
    return std::make_unique<SurfaceTensionAkinci>(settings.sigma, particle_spacing, rest_density);
  return std::make_unique<SurfaceTensionCsf>(settings.sigma, particle_spacing, rest_density);
}

}  // namespace drench
