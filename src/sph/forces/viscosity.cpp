#include "sph/forces/viscosity.hpp"

#include "common/parallel.hpp"

namespace drench {

void ViscosityXsph::add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const {
  const auto& p = ctx.particles;
  const Scalar factor = m_coefficient / dt;
#pragma omp parallel for schedule(static, kParticleChunk)
  for (std::size_t i = 0; i < p.size(); ++i) {
    Vec3 sum = Vec3::Zero();
    for (const Index* j = ctx.fluid_neighbors.begin(i); j != ctx.fluid_neighbors.end(i); ++j) {
      sum += (p.masses[*j] / p.densities[*j]) * ctx.kernel.value((p.positions[i] - p.positions[*j]).norm()) *
             (p.velocities[*j] - p.velocities[i]);
    }
    accelerations[i] += factor * sum;
  }
}

void ViscosityArtificial::add_accelerations(const FluidContext& ctx, Scalar /*dt*/,
                                            Vec3Array& accelerations) const {
  const auto& p = ctx.particles;
  const Scalar h = ctx.kernel.smoothing_length();
  const Scalar eps = 0.01 * h * h;
  const Scalar scale = m_alpha * m_speed_of_sound * h;
#pragma omp parallel for schedule(static, kParticleChunk)
  for (std::size_t i = 0; i < p.size(); ++i) {
    Vec3 a = Vec3::Zero();
    for (const Index* j = ctx.fluid_neighbors.begin(i); j != ctx.fluid_neighbors.end(i); ++j) {
      const Vec3 x_ij = p.positions[i] - p.positions[*j];
      const Scalar vx = (p.velocities[i] - p.velocities[*j]).dot(x_ij);
      if (vx >= 0.0) continue;
      const Scalar mu = vx / (x_ij.squaredNorm() + eps);
      const Scalar pi_ij = -scale * mu / (0.5 * (p.densities[i] + p.densities[*j]));
      a -= p.masses[*j] * pi_ij * ctx.kernel.gradient(x_ij);
    }
    accelerations[i] += a;
  }
}

std::unique_ptr<NonPressureForce> make_viscosity(const ViscositySettings& settings, Scalar speed_of_sound) {
  switch (settings.method) {
    case ViscosityKind::XSPH:
      return std::make_unique<ViscosityXsph>(settings.coefficient);
    case ViscosityKind::ARTIFICIAL:
      return std::make_unique<ViscosityArtificial>(settings.coefficient, speed_of_sound);
  }
  return nullptr;
}

}  // namespace drench
