// The pair loops over packed points (src/drench/sph/fluid_context.cpp, XSPH in
// src/drench/sph/forces/viscosity.cpp) read eight (densities, XSPH) or four (pressure) neighbors at a time
// and transpose them in registers. They must give the textbook sums: SPH density (Akinci et al. 2012 eq. 6),
// symmetric pressure acceleration (eq. 10) and XSPH (Monaghan 1989), written here pair by pair with Eigen,
// for every neighbor count modulo eight, and with a last group that ends the list (padded with copies, not
// the next particle's entries). The eight-lane loops have two group types (two vectors of four doubles in the
// AVX2 copy, one of eight in the others); the public functions run the one of this CPU's copy, so a last test
// runs both and requires the same bits.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include <drench/sph/float_lanes.hpp>
#include <drench/sph/fluid_context.hpp>
#include <drench/sph/forces/viscosity.hpp>
#include <drench/sph/packed_lanes.hpp>
#include <drench/sph/pressure/pressure_dfsph.hpp>
#include "neighbor_test_helpers.hpp"

namespace drench {
namespace {

using testing::brute_force;
using testing::random_points;

constexpr Scalar kSpacing = 0.01;  // m

NeighborList to_list(const std::vector<IndexArray>& sets) {
  NeighborList list;
  list.offsets.push_back(0);
  for (const IndexArray& set : sets) {
    list.indices.insert(list.indices.end(), set.begin(), set.end());
    list.offsets.push_back(static_cast<std::uint32_t>(list.indices.size()));
  }
  return list;
}

PackedPointArray pack(const Vec3Array& x, const ScalarArray& w) {
  PackedPointArray points(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    points[i] = packed(x[i], w[i]);
  return points;
}

/// out[i] of the particles [0, n) from loop(begin, end, out + begin), called for [0, split) and [split, n),
/// so that a range starting inside the array is covered.
template <class T, class Loop>
std::vector<T> in_two_ranges(std::size_t n, std::size_t split, Loop loop) {
  std::vector<T> out(n);
  loop(std::size_t{0}, split, out.data());
  loop(split, n, out.data() + split);
  return out;
}

/// The gradient factors of the pairs of `list`, stored as the neighbor lists store them (float).
GradientFactorArray factors_of(const CubicSplineKernel& kernel, const NeighborList& list, const Vec3Array& x,
                               const Vec3Array& sources) {
  GradientFactorArray factors;
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (const Index* j = list.begin(i); j != list.end(i); ++j)
      factors.push_back(static_cast<float>(kernel.gradient_factor((x[i] - sources[*j]).squaredNorm())));
  }
  return factors;
}

/// grad W(x_i - x_j) with its factor rounded to float, as the pressure loop is given it.
Vec3 stored_gradient(const CubicSplineKernel& kernel, const Vec3& x_ij) {
  return Scalar{static_cast<float>(kernel.gradient_factor(x_ij.squaredNorm()))} * x_ij;
}

/// Random fluid points (about 60 neighbors inside, fewer at the faces) over a slab of boundary points (none
/// for the fluid above it); masses equal or random, p / rho^2 random and zero for every fifth particle (which
/// skips the boundary term).
struct Scene {
  CubicSplineKernel kernel{kSpacing};
  ParticleSet particles;
  Vec3Array boundary_x = random_points(150, Vec3(0, 0, 0), Vec3(0.06, 0.06, 0.01), 2);
  ScalarArray psi;
  ScalarArray p_over_rho2;
  NeighborList fluid, boundary;
  GradientFactorArray fluid_factors, boundary_factors;
  PackedPointArray boundary_packed;

  explicit Scene(bool uniform_mass) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<Scalar> u(0.5, 1.5);
    const Vec3Array x = random_points(400, Vec3(0, 0, 0), Vec3(0.06, 0.06, 0.06), 1);
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Scalar mass = uniform_mass ? 1e-3 : 1e-3 * u(rng);
      particles.add(x[i], Vec3(u(rng), u(rng), u(rng)) - Vec3::Ones(), mass, static_cast<std::uint32_t>(i));
      particles.densities.back() = 1000.0 * u(rng);
      p_over_rho2.push_back(i % 5 == 0 ? 0.0 : 1e-3 * u(rng));
    }
    for (std::size_t b = 0; b < boundary_x.size(); ++b)
      psi.push_back(1e-3 * u(rng));
    const Scalar radius = kernel.support_radius();
    fluid = to_list(brute_force(x, x, radius, true));
    boundary = to_list(brute_force(x, boundary_x, radius, false));
    fluid_factors = factors_of(kernel, fluid, x, x);
    boundary_factors = factors_of(kernel, boundary, x, boundary_x);
    boundary_packed = pack(boundary_x, psi);
  }

  /// The textbook density of particle i (Akinci et al. 2012 eq. 6), pair by pair in double.
  Scalar expected_density(std::size_t i) const {
    const ParticleSet& p = particles;
    Scalar expected = p.masses[i] * kernel.value(0.0);
    for (const Index* j = fluid.begin(i); j != fluid.end(i); ++j)
      expected += p.masses[*j] * kernel.value((p.positions[i] - p.positions[*j]).norm());
    for (const Index* b = boundary.begin(i); b != boundary.end(i); ++b)
      expected += psi[*b] * kernel.value((p.positions[i] - boundary_x[*b]).norm());
    return expected;
  }

  /// The textbook pressure acceleration of particle i (eq. 10) with the stored gradients, pair by pair in
  /// double; `magnitude` = the sum of the terms' norms, the scale of the rounding.
  Vec3 expected_pressure_acceleration(std::size_t i, Scalar& magnitude) const {
    const ParticleSet& p = particles;
    Vec3 expected = Vec3::Zero();
    magnitude = 0.0;
    for (const Index* j = fluid.begin(i); j != fluid.end(i); ++j) {
      const Vec3 term = p.masses[*j] * (p_over_rho2[i] + p_over_rho2[*j]) *
                        stored_gradient(kernel, p.positions[i] - p.positions[*j]);
      expected -= term;
      magnitude += term.norm();
    }
    for (const Index* b = boundary.begin(i); b != boundary.end(i); ++b) {
      const Vec3 term = psi[*b] * p_over_rho2[i] * stored_gradient(kernel, p.positions[i] - boundary_x[*b]);
      expected -= term;
      magnitude += term.norm();
    }
    return expected;
  }

  FluidContext context() {
    return FluidContext{kernel, particles, fluid,         boundary,         boundary_packed,
                        1000.0, kSpacing,  fluid_factors, boundary_factors, particles.common_mass()};
  }
};

/// The scene covers every length of the loops' last group: each neighbor count modulo `lanes` (8 or 16),
/// and a last group at the very end of the list (the last particle with neighbors has a count not divisible
/// by `lanes`).
void expect_every_tail(const NeighborList& list, std::size_t lanes = 8) {
  std::vector<bool> seen(lanes, false);
  std::size_t last = 0;
  for (std::size_t i = 0; i + 1 < list.offsets.size(); ++i) {
    seen[list.count(i) % lanes] = true;
    if (list.count(i) > 0) last = i;
  }
  ASSERT_TRUE(std::all_of(seen.begin(), seen.end(), [](bool b) { return b; }))
      << "the scene must exercise every tail length modulo " << lanes;
  ASSERT_NE(list.count(last) % lanes, 0u) << "the scene must end the list with a partial group";
}

PackedPointFArray pack_float(const Vec3Array& x, const ScalarArray& w) {
  PackedPointFArray points(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    points[i] = packed_float(x[i], w[i]);
  return points;
}

void check_densities(bool uniform_mass) {
  Scene s(uniform_mass);
  expect_every_tail(s.fluid);
  expect_every_tail(s.boundary);
  const FluidContext ctx = s.context();
  const ParticleSet& p = s.particles;
  const std::size_t n = p.size();
  const PackedPointArray x_mass = pack(p.positions, p.masses);
  const ScalarArray got = in_two_ranges<Scalar>(n, 123, [&](std::size_t begin, std::size_t end, Scalar* out) {
    sph_densities(ctx, x_mass, begin, end, out);
  });
  for (std::size_t i = 0; i < n; ++i) {
    const Scalar expected = s.expected_density(i);
    // Every term is positive: the sums differ only by the order of a few dozen roundings.
    EXPECT_NEAR(got[i], expected, 1e-13 * expected) << "particle " << i;
  }
}

void check_pressure_accelerations(bool uniform_mass) {
  Scene s(uniform_mass);
  const FluidContext ctx = s.context();
  const ParticleSet& p = s.particles;
  const std::size_t n = p.size();
  const PackedPointArray x_p_over_rho2 = pack(p.positions, s.p_over_rho2);
  const Vec3Array got = in_two_ranges<Vec3>(n, 200, [&](std::size_t begin, std::size_t end, Vec3* out) {
    pressure_accelerations(ctx, x_p_over_rho2, begin, end, out);
  });
  for (std::size_t i = 0; i < n; ++i) {
    Scalar magnitude;
    const Vec3 expected = s.expected_pressure_acceleration(i, magnitude);
    EXPECT_LE((got[i] - expected).norm(), 1e-13 * magnitude) << "particle " << i;
  }
}

void check_xsph(bool uniform_mass) {
  Scene s(uniform_mass);
  const FluidContext ctx = s.context();
  const ParticleSet& p = s.particles;
  const Scalar coefficient = 0.01, dt = 1e-3;  // (unit: -, s)
  const Vec3 gravity(0.0, -9.81, 0.0);
  Vec3Array got(p.size(), gravity);
  ViscosityXsph(coefficient).add_accelerations(ctx, dt, got);
  for (std::size_t i = 0; i < p.size(); ++i) {
    Vec3 sum = Vec3::Zero();
    Scalar magnitude = 0.0;
    for (const Index* j = s.fluid.begin(i); j != s.fluid.end(i); ++j) {
      const Vec3 term = (p.masses[*j] / p.densities[*j]) *
                        s.kernel.value((p.positions[i] - p.positions[*j]).norm()) *
                        (p.velocities[*j] - p.velocities[i]);
      sum += term;
      magnitude += term.norm();
    }
    const Vec3 expected = gravity + coefficient / dt * sum;
    EXPECT_LE((got[i] - expected).norm(), 1e-13 * (coefficient / dt * magnitude + gravity.norm()))
        << "particle " << i;
  }
}

/// The single-precision densities against the textbook sum in double. Rounding the positions (within
/// 0.06 m of the origin: 3.6e-9 m, 4e-7 of the spacing) and some 60 float roundings of 6e-8 each bound the
/// relative difference by about 5e-6; 1e-5 is asserted.
void check_float_densities(bool uniform_mass) {
  Scene s(uniform_mass);
  expect_every_tail(s.fluid, 16);
  const FluidContext ctx = s.context();
  const ParticleSet& p = s.particles;
  const std::size_t n = p.size();
  const PackedPointFArray x_mass = pack_float(p.positions, p.masses);
  const PackedPointFArray boundary = pack_float(s.boundary_x, s.psi);
  const ScalarArray got = in_two_ranges<Scalar>(n, 123, [&](std::size_t begin, std::size_t end, Scalar* out) {
    sph_densities_float(ctx, x_mass, boundary, begin, end, out);
  });
  Scalar largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Scalar expected = s.expected_density(i);
    EXPECT_NEAR(got[i], expected, 1e-5 * expected) << "particle " << i;
    largest = std::max(largest, std::abs(got[i] - expected) / expected);
  }
  EXPECT_GT(largest, 0.0) << "single precision must be in use (else this test checks nothing new)";
}

/// The single-precision pressure accelerations against the textbook sum in double (uniform masses, the
/// loop's precondition), relative to the sum of the terms' magnitudes: 1e-5, as for the densities.
TEST(FluidContext, FloatPressureAccelerationsAreTheSymmetricSphSumsWithin1e5) {
  Scene s(true);
  expect_every_tail(s.fluid, 16);
  const FluidContext ctx = s.context();
  const ParticleSet& p = s.particles;
  const std::size_t n = p.size();
  const PackedPointFArray points = pack_float(p.positions, s.p_over_rho2);
  const PackedPointFArray boundary = pack_float(s.boundary_x, s.psi);
  const Vec3Array got = in_two_ranges<Vec3>(n, 200, [&](std::size_t begin, std::size_t end, Vec3* out) {
    pressure_accelerations_float(ctx, points, boundary, begin, end, out);
  });
  std::size_t with_boundary = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Scalar magnitude;
    const Vec3 expected = s.expected_pressure_acceleration(i, magnitude);
    with_boundary += s.boundary.count(i) > 0 && s.p_over_rho2[i] != 0.0;
    EXPECT_LE((got[i] - expected).norm(), 1e-5 * magnitude) << "particle " << i;
  }
  EXPECT_GT(with_boundary, 10u) << "the boundary term must be exercised";
}

/// DFSPH's rate of density change (Bender & Koschier 2017 eq. 9) pair by pair in double with the stored
/// gradient factors, against density_change (the same sums in another order: 1e-13) and density_change_float
/// (1e-5, as the float densities), both relative to the sum of the terms' magnitudes.
TEST(FluidContext, DensityChangeIsTheSphSumInDoubleAndWithin1e5InFloat) {
  Scene s(true);
  expect_every_tail(s.fluid, 16);
  const FluidContext ctx = s.context();
  const ParticleSet& p = s.particles;
  const std::size_t n = p.size();
  const ScalarArray zeros(n, 0.0);
  const PackedPointArray x_mass = pack(p.positions, p.masses);
  const PackedPointArray v = pack(p.velocities, zeros);
  const PackedPointFArray x_mass_float = pack_float(p.positions, p.masses);
  const PackedPointFArray v_float = pack_float(p.velocities, zeros);
  const PackedPointFArray boundary = pack_float(s.boundary_x, s.psi);
  const ScalarArray in_double =
      in_two_ranges<Scalar>(n, 123, [&](std::size_t begin, std::size_t end, Scalar* out) {
        density_change(ctx, x_mass, v, begin, end, out);
      });
  const ScalarArray in_float =
      in_two_ranges<Scalar>(n, 123, [&](std::size_t begin, std::size_t end, Scalar* out) {
        density_change_float(ctx, x_mass_float, v_float, boundary, begin, end, out);
      });
  Scalar largest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    Scalar expected = 0.0, magnitude = 0.0;
    for (const Index* j = s.fluid.begin(i); j != s.fluid.end(i); ++j) {
      const Vec3 x_ij = p.positions[i] - p.positions[*j];
      const Scalar term =
          p.masses[*j] * (p.velocities[i] - p.velocities[*j]).dot(stored_gradient(s.kernel, x_ij));
      expected += term;
      magnitude += std::abs(term);
    }
    for (const Index* b = s.boundary.begin(i); b != s.boundary.end(i); ++b) {
      const Vec3 x_ib = p.positions[i] - s.boundary_x[*b];
      const Scalar term = s.psi[*b] * p.velocities[i].dot(stored_gradient(s.kernel, x_ib));
      expected += term;
      magnitude += std::abs(term);
    }
    EXPECT_LE(std::abs(in_double[i] - expected), 1e-13 * magnitude) << "particle " << i;
    EXPECT_LE(std::abs(in_float[i] - expected), 1e-5 * magnitude) << "particle " << i;
    if (magnitude > 0.0) largest = std::max(largest, std::abs(in_float[i] - expected) / magnitude);
  }
  EXPECT_GT(largest, 0.0) << "single precision must be in use (else this test checks nothing new)";
}

TEST(FluidContext, FloatDensitiesAreTheSphSumsWithin1e5) {
  check_float_densities(true);
  check_float_densities(false);
}

TEST(FluidContext, DensitiesAreTheSphSumsOverFluidAndBoundaryNeighbors) {
  check_densities(true);
  check_densities(false);
}

TEST(FluidContext, PressureAccelerationsAreTheSymmetricSphSums) {
  check_pressure_accelerations(true);
  check_pressure_accelerations(false);
}

TEST(ViscosityXsph, AddsTheXsphSumsToTheAccelerations) {
  check_xsph(true);
  check_xsph(false);
}

/// The kernel sums (densities) and XSPH sums of both eight-lane group types, bit for bit, over every tail
/// length of the fluid and the boundary lists: which type runs depends on the CPU, the results must not.
TEST(PackedLanes, WideAndHalvesGroupsGiveTheSameBits) {
  Scene s(false);
  expect_every_tail(s.fluid);
  expect_every_tail(s.boundary);
  const ParticleSet& p = s.particles;
  const PackedPointArray x_mass = pack(p.positions, p.masses);
  ScalarArray volumes(p.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    volumes[i] = p.masses[i] / p.densities[i];
  const PackedPointArray x_volume = pack(p.positions, volumes);
  const PackedPointArray velocities = pack(p.velocities, ScalarArray(p.size(), 0.0));
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < x_mass.size(); ++i) {
    using Sources = std::pair<const NeighborList*, const PackedPoint*>;
    for (const auto& [list, sources] :
         {Sources{&s.fluid, x_mass.data()}, Sources{&s.boundary, s.boundary_packed.data()}}) {
      const Scalar wide = kernel_sum<WideGroup>(s.kernel, *list, i, x_mass[i], sources);
      const Scalar halves = kernel_sum<HalvesGroup>(s.kernel, *list, i, x_mass[i], sources);
      EXPECT_EQ(wide, halves) << "density sum, particle " << i;
      nonzero += wide != 0.0;
    }
    const Vec3 wide = xsph_sum<WideGroup>(s.kernel, s.fluid, i, x_volume.data(), velocities.data());
    const Vec3 halves = xsph_sum<HalvesGroup>(s.kernel, s.fluid, i, x_volume.data(), velocities.data());
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(wide[c], halves[c]) << "XSPH sum, particle " << i << ", component " << c;
    nonzero += wide.squaredNorm() != 0.0;
  }
  EXPECT_GT(nonzero, x_mass.size()) << "the sums must not be trivially zero";
}

/// The single-precision kernel sums (densities), gradient sums (pressure) and density changes (DFSPH) of both
/// sixteen-lane group types, bit for bit, over every tail length modulo sixteen of the fluid list and over
/// the boundary list.
TEST(FloatLanes, WideAndHalvesGroupsGiveTheSameBits) {
  Scene s(true);
  expect_every_tail(s.fluid, 16);
  const ParticleSet& p = s.particles;
  const PackedPointFArray x_mass = pack_float(p.positions, p.masses);
  const PackedPointFArray x_pressure = pack_float(p.positions, s.p_over_rho2);
  const PackedPointFArray v = pack_float(p.velocities, ScalarArray(p.size(), 0.0));
  const PackedPointFArray boundary = pack_float(s.boundary_x, s.psi);
  const FloatKernel kernel(s.kernel);
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < x_mass.size(); ++i) {
    using Sources = std::pair<const NeighborList*, const PackedPointF*>;
    for (const auto& [list, sources] :
         {Sources{&s.fluid, x_mass.data()}, Sources{&s.boundary, boundary.data()}}) {
      const float wide = kernel_sum<FloatWideGroup>(kernel, *list, i, x_mass[i], sources);
      const float halves = kernel_sum<FloatHalvesGroup>(kernel, *list, i, x_mass[i], sources);
      EXPECT_EQ(wide, halves) << "density sum, particle " << i;
      nonzero += wide != 0.0f;
    }
    using Pass = std::tuple<const NeighborList*, const PackedPointF*, const float*, float, float>;
    const float w = x_pressure[i].w;
    for (const auto& [list, points, factors, alpha, a] :
         {Pass{&s.fluid, x_pressure.data(), s.fluid_factors.data(), w, 1e-3f},
          Pass{&s.boundary, boundary.data(), s.boundary_factors.data(), 0.0f, w}}) {
      float wide[3] = {}, halves[3] = {};
      float_subtract_gradient_sum<FloatWideGroup>(x_pressure[i], alpha, a, points, *list, i, factors, wide[0],
                                                  wide[1], wide[2]);
      float_subtract_gradient_sum<FloatHalvesGroup>(x_pressure[i], alpha, a, points, *list, i, factors,
                                                    halves[0], halves[1], halves[2]);
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(wide[c], halves[c]) << "pressure sum, particle " << i << ", component " << c;
      nonzero += wide[0] != 0.0f;
    }
    const PackedPointF& xi = x_mass[i];
    const PackedPointF& vi = v[i];
    const float* ff = s.fluid_factors.data();
    const float* bf = s.boundary_factors.data();
    const float fluid_wide =
        float_density_change_sum<FloatWideGroup, false>(xi, vi, x_mass.data(), v.data(), s.fluid, i, ff);
    const float fluid_halves =
        float_density_change_sum<FloatHalvesGroup, false>(xi, vi, x_mass.data(), v.data(), s.fluid, i, ff);
    const float walls_wide =
        float_density_change_sum<FloatWideGroup, true>(xi, vi, boundary.data(), nullptr, s.boundary, i, bf);
    const float walls_halves =
        float_density_change_sum<FloatHalvesGroup, true>(xi, vi, boundary.data(), nullptr, s.boundary, i, bf);
    EXPECT_EQ(fluid_wide, fluid_halves) << "density change, particle " << i;
    EXPECT_EQ(walls_wide, walls_halves) << "density change at the boundary, particle " << i;
    nonzero += fluid_wide != 0.0f;
  }
  EXPECT_GT(nonzero, 3 * x_mass.size()) << "the sums must not be trivially zero";
}

}  // namespace
}  // namespace drench
