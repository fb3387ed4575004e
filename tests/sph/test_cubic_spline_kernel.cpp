#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <drench/sph/cubic_spline_kernel.hpp>

namespace drench {
namespace {

TEST(CubicSplineKernel, SumOfValueTimesVolumeOverLatticeIsOne) {
  // A particle inside a regular lattice of spacing s sees the kernel integrate to one: sum_j W_ij s^3 = 1.
  for (const Scalar s : {0.005, 0.05, 1.0}) {
    const CubicSplineKernel kernel(s);
    Scalar sum = 0.0;
    for (int k = -3; k <= 3; ++k)
      for (int j = -3; j <= 3; ++j)
        for (int i = -3; i <= 3; ++i)
          sum += kernel.value(s * Vec3(i, j, k).norm()) * s * s * s;
    EXPECT_NEAR(sum, 1.0, 0.005) << "spacing " << s;
  }
}

TEST(CubicSplineKernel, SumOfGradientOverLatticeIsZero) {
  const Scalar s = 0.02;
  const CubicSplineKernel kernel(s);
  Vec3 sum = Vec3::Zero();
  Scalar magnitude = 0.0;
  for (int k = -3; k <= 3; ++k)
    for (int j = -3; j <= 3; ++j)
      for (int i = -3; i <= 3; ++i) {
        const Vec3 g = kernel.gradient(-s * Vec3(i, j, k));
        sum += g;
        magnitude += g.norm();
      }
  EXPECT_LT(sum.norm(), 1e-12 * magnitude);
}

TEST(CubicSplineKernel, IntegratesToOneOverItsSupport) {
  // Radial quadrature of 4 pi r^2 W(r) over [0, 2h].
  const CubicSplineKernel kernel(0.1);
  const int n = 20000;
  const Scalar dr = kernel.support_radius() / n;
  Scalar integral = 0.0;
  for (int i = 0; i < n; ++i) {
    const Scalar r = (i + 0.5) * dr;
    integral += 4.0 * M_PI * r * r * kernel.value(r) * dr;
  }
  EXPECT_NEAR(integral, 1.0, 1e-6);
}

TEST(CubicSplineKernel, GradientMatchesCentralFiniteDifferences) {
  const Scalar h = 0.05;
  const CubicSplineKernel kernel(h);
  std::mt19937 rng(7);
  std::uniform_real_distribution<Scalar> coord(-2.1 * h, 2.1 * h);
  const Scalar eps = 1e-7 * h;
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 r(coord(rng), coord(rng), coord(rng));
    const Scalar dist = r.norm();
    // Skip the neighbourhood of the kink-free but curvature-changing points, where differencing is worst.
    if (dist < 1e-3 * h || std::abs(dist - h) < 1e-4 * h || std::abs(dist - 2 * h) < 1e-4 * h) continue;
    Vec3 fd;
    for (int a = 0; a < 3; ++a) {
      Vec3 plus = r, minus = r;
      plus[a] += eps;
      minus[a] -= eps;
      fd[a] = (kernel.value(plus.norm()) - kernel.value(minus.norm())) / (2 * eps);
    }
    const Vec3 g = kernel.gradient(r);
    // Relative to the kernel's gradient scale 1 / (pi h^4).
    EXPECT_LT((g - fd).norm(), 1e-6 / (M_PI * std::pow(h, 4))) << "r = " << r.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 1500);
}

TEST(CubicSplineKernel, BranchFreeFormEqualsMonaghansPiecewisePolynomial) {
  // value() and gradient_factor() evaluate the spline without a branch on q < 1; they must agree with the
  // published piecewise form (Monaghan 1992) within a few roundings, on both sides of q = 1 and q = 2.
  const Scalar h = 0.025;
  const CubicSplineKernel kernel(h);
  const Scalar sigma = 1.0 / (M_PI * h * h * h);
  for (int k = 0; k <= 2400; ++k) {
    const Scalar q = k / 1000.0;
    const Scalar w = q < 1.0   ? sigma * (1.0 - 1.5 * q * q + 0.75 * q * q * q)
                     : q < 2.0 ? sigma * 0.25 * (2.0 - q) * (2.0 - q) * (2.0 - q)
                               : 0.0;
    EXPECT_NEAR(kernel.value(q * h), w, 1e-14 * sigma) << "q = " << q;
    if (q == 0.0) {
      EXPECT_EQ(kernel.gradient_factor(0.0), 0.0);  // the select, not 0 / 0
      continue;
    }
    const Scalar dw_dq = q < 1.0   ? sigma * (-3.0 * q + 2.25 * q * q)
                         : q < 2.0 ? -sigma * 0.75 * (2.0 - q) * (2.0 - q)
                                   : 0.0;
    const Scalar r = q * h;
    // gradient_factor * r is dW/dr; compare on the gradient's scale sigma / h
    EXPECT_NEAR(kernel.gradient_factor(r * r) * r, dw_dq / h, 1e-13 * sigma / h) << "q = " << q;
  }
}

TEST(CubicSplineKernel, VanishesAtAndBeyondSupportRadius) {
  const CubicSplineKernel kernel(0.01);
  EXPECT_EQ(kernel.value(0.02), 0.0);
  EXPECT_EQ(kernel.value(0.05), 0.0);
  EXPECT_TRUE(kernel.gradient(Vec3(0.02, 0, 0)).isZero());
  EXPECT_GT(kernel.value(0.0199), 0.0);
}

TEST(CubicSplineKernel, VectorLanesGiveTheBitsOfValueAndGradientFactor) {
  // PBF's constraint pass takes W and grad W in vector lanes (value_and_gradient_factor_lanes) and must
  // match the scalar value(sqrt(r2)) and gradient_factor(r2) bit for bit, at r = 0 (coincident particles),
  // on both polynomial pieces, at q = 1 and q = 2 exactly, beyond the support, and for a NaN distance.
  typedef Scalar Four __attribute__((vector_size(4 * sizeof(Scalar))));
  const CubicSplineKernel kernel(0.01);
  const Scalar h = kernel.smoothing_length();
  std::mt19937 rng(5);
  std::uniform_real_distribution<Scalar> q2(0.0, 5.0);
  std::vector<Scalar> cases = {0.0, 1e-300, h * h, 4.0 * h * h, 5.0 * h * h, std::nan("")};
  for (int k = 0; k < 200; ++k)
    cases.push_back(q2(rng) * h * h);
  while (cases.size() % 4 != 0)
    cases.push_back(0.5 * h * h);
  for (std::size_t first = 0; first < cases.size(); first += 4) {
    const Four r2 = {cases[first], cases[first + 1], cases[first + 2], cases[first + 3]};
    Four w, f;
    kernel.value_and_gradient_factor_lanes(r2, w, f);
    for (int l = 0; l < 4; ++l) {
      const Scalar value = kernel.value(std::sqrt(r2[l]));
      const Scalar factor = kernel.gradient_factor(r2[l]);
      if (std::isnan(value)) {
        EXPECT_TRUE(std::isnan(w[l])) << "r2 " << r2[l];
      } else {
        EXPECT_EQ(std::memcmp(&w[l], &value, sizeof(Scalar)), 0) << "W at r2 " << r2[l];
      }
      EXPECT_EQ(std::memcmp(&f[l], &factor, sizeof(Scalar)), 0) << "gradient factor at r2 " << r2[l];
    }
  }
}

}  // namespace
}  // namespace drench
