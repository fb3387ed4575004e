#include <drench/sph/forces/viscosity.hpp>

#include <cmath>
#include <cstdint>

#include <drench/common/parallel.hpp>
#include <drench/sph/packed_lanes.hpp>

namespace drench {

namespace {

/// a_i += factor sum_j V_j W_ij (v_j - v_i) for the particles [begin, end), with V_j = m_j / rho_j carried in
/// `x_volume` and v_j in `velocities` (w unused). Eight neighbors at a time in a fixed order, as the
/// densities (sph/packed_lanes.hpp).
DRENCH_SIMD_CLONES void add_xsph(const FluidContext& ctx, const PackedPointArray& x_volume,
                                 const PackedPointArray& velocities, Scalar factor, std::size_t begin,
                                 std::size_t end, Vec3* accelerations) {
  const CubicSplineKernel& k = ctx.kernel;
  const PackedPoint* xs = x_volume.data();
  const PackedPoint* vs = velocities.data();
  with_group_of_copy<HalvesGroup, WideGroup>([&](auto lanes) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    for (std::size_t i = begin; i < end; ++i)
      accelerations[i - begin] += factor * xsph_sum<Group>(k, ctx.fluid_neighbors, i, xs, vs);
  });
}

}  // namespace

void ViscosityXsph::add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const {
  const auto& p = ctx.particles;
  const std::size_t n = p.size();
  m_x_volume.resize(n);
  m_velocities.resize(n);
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      m_x_volume[i] = packed(p.positions[i], p.masses[i] / p.densities[i]);
      m_velocities[i] = packed(p.velocities[i], 0.0);
    }
  });
  const Scalar factor = m_coefficient / dt;
  for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
    add_xsph(ctx, m_x_volume, m_velocities, factor, begin, end, &accelerations[begin]);
  });
}

void ViscosityArtificial::add_accelerations(const FluidContext& ctx, Scalar /*dt*/,
                                            Vec3Array& accelerations) const {
  const auto& p = ctx.particles;
  const Scalar h = ctx.kernel.smoothing_length();
  const Scalar eps = 0.01 * h * h;
  const Scalar scale = m_alpha * m_speed_of_sound * h;
  parallel_for(p.size(), kParticleChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
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
  });
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
