#pragma once
/// Four neighbors at a time: the vector type and the loads shared by the SPH pair loops over PackedPoint
/// arrays (sph/fluid_context.cpp, sph/forces/viscosity.cpp). Internal to those files' DRENCH_SIMD_CLONES
/// functions; everything is in an unnamed namespace and always inlined, so each copy compiles its own.

#include <cmath>
#include <cstdint>
#include <cstring>

#include "sph/fluid_context.hpp"

namespace drench {
namespace {

/// Four doubles as one vector: an AVX2 register, or two SSE2 registers in the baseline copy. GCC's and
/// clang's vector extension, so one source serves every copy of DRENCH_SIMD_CLONES; lane-wise loops over it
/// (sqrt, the kernel) are vectorized by the compiler.
typedef Scalar Lanes __attribute__((vector_size(4 * sizeof(Scalar))));
constexpr std::uint32_t kLanes = 4;

/// x, y, z and w of four packed points as four vectors.
struct FourPoints {
  Lanes x, y, z, w;
};

/// Loads the points js[0..3] and transposes the four records in registers (a 4 x 4 transpose: unpack within
/// 128-bit halves, then exchange halves).
[[gnu::always_inline]] inline void load_four(const PackedPoint* points, const Index* js, FourPoints& out) {
  Lanes a, b, c, d;
  std::memcpy(&a, &points[js[0]], sizeof(Lanes));
  std::memcpy(&b, &points[js[1]], sizeof(Lanes));
  std::memcpy(&c, &points[js[2]], sizeof(Lanes));
  std::memcpy(&d, &points[js[3]], sizeof(Lanes));
  const Lanes ab_xz = __builtin_shufflevector(a, b, 0, 4, 2, 6);  // ax bx az bz
  const Lanes ab_yw = __builtin_shufflevector(a, b, 1, 5, 3, 7);  // ay by aw bw
  const Lanes cd_xz = __builtin_shufflevector(c, d, 0, 4, 2, 6);
  const Lanes cd_yw = __builtin_shufflevector(c, d, 1, 5, 3, 7);
  out.x = __builtin_shufflevector(ab_xz, cd_xz, 0, 1, 4, 5);
  out.z = __builtin_shufflevector(ab_xz, cd_xz, 2, 3, 6, 7);
  out.y = __builtin_shufflevector(ab_yw, cd_yw, 0, 1, 4, 5);
  out.w = __builtin_shufflevector(ab_yw, cd_yw, 2, 3, 6, 7);
}

/// The lanes summed in a fixed order, (a0 + a1) + (a2 + a3), whatever the vector width of the copy.
[[gnu::always_inline]] inline Scalar lane_sum(const Lanes& a) {
  return (a[0] + a[1]) + (a[2] + a[3]);
}

/// w[l] = W(|x_i - x_l|) for the four points of `p` (unit: 1/m^3), lane by lane (the compiler makes one
/// vector square root of it).
[[gnu::always_inline]] inline void kernel_at_four(const CubicSplineKernel& k, const PackedPoint& xi,
                                                  const FourPoints& p, Lanes& w) {
  const Lanes dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
  const Lanes r2 = dx * dx + dy * dy + dz * dz;
  for (std::uint32_t l = 0; l < kLanes; ++l)
    w[l] = k.value(std::sqrt(r2[l]));
}

/// W(|x_i - x_p|) for one packed point (unit: 1/m^3): the loops' tail, in the lanes' arithmetic.
[[gnu::always_inline]] inline Scalar kernel_at(const CubicSplineKernel& k, const PackedPoint& xi,
                                               const PackedPoint& p) {
  const Scalar dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
  return k.value(std::sqrt(dx * dx + dy * dy + dz * dz));
}

}  // namespace
}  // namespace drench
