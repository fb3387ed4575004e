#pragma once
/// Cubic spline kernel of Monaghan 1992 in 3D, with its gradient.

#include <algorithm>
#include <cmath>

#include <drench/common/types.hpp>

namespace drench {

/// W(r, h) = sigma * { 1 - 3/2 q^2 + 3/4 q^3  (0 <= q < 1);  1/4 (2 - q)^3  (1 <= q < 2);  0 }, q = r / h,
/// sigma = 1 / (pi h^3). Support radius 2h. drench uses h = particle spacing, so the support holds the
/// 27 nearest lattice neighbours, as SPlisHSPlasH's default (support = 4 particle radii).
class CubicSplineKernel {
 public:
  /// @param smoothing_length  h (unit: m), > 0
  explicit CubicSplineKernel(Scalar smoothing_length);

  Scalar smoothing_length() const { return m_h; }
  Scalar support_radius() const { return 2.0 * m_h; }

  /// W at distance r (unit: m, >= 0); unit 1/m^3. Written as sigma/4 ((2 - q)+^3 - 4 (1 - q)+^3), the same
  /// polynomial without a branch: neighbors sit on both sides of q = 1 (the first lattice shell is at q = 1),
  /// so the branch on q < 1 was mispredicted in the pair loops that call this most. NaN stays NaN.
  Scalar value(Scalar r) const {
    const Scalar q = r * m_inv_h;
    const Scalar a = std::max(2.0 - q, 0.0);
    const Scalar b = std::max(1.0 - q, 0.0);
    return m_quarter_sigma * (a * a * a - 4.0 * b * b * b);
  }

  /// grad_i W(x_i - x_j) for r_vec = x_i - x_j (unit: m); unit 1/m^4. Zero at r = 0, where the kernel is
  /// smooth and symmetric.
  Vec3 gradient(const Vec3& r_vec) const { return gradient_factor(r_vec.squaredNorm()) * r_vec; }

  /// The scalar f with grad W = f (x_i - x_j), from r2 = |x_i - x_j|^2 (unit: m^2); unit 1/m^5. Zero at r = 0
  /// and beyond the support. Lets a solver keep one number per neighbor pair instead of a vector.
  Scalar gradient_factor(Scalar r2) const {
    // Branch-free as value(), so that loops over pairs vectorize: r = 0 divides by 1 and is then selected
    // away.
    const bool apart = r2 > 0.0;
    const Scalar r = std::sqrt(apart ? r2 : 1.0);
    const Scalar q = r * m_inv_h;
    const Scalar a = std::max(2.0 - q, 0.0);
    const Scalar b = std::max(1.0 - q, 0.0);
    // dW/dq = sigma/4 (12 (1 - q)+^2 - 3 (2 - q)+^2)
    const Scalar f = 3.0 * m_quarter_sigma * (4.0 * b * b - a * a) * m_inv_h / r;
    return apart ? f : 0.0;
  }

  /// w = value(sqrt(r2)) and f = gradient_factor(r2) for each lane of `r2`, a GCC vector of doubles (four or
  /// eight lanes), the same bits as those two, in vector arithmetic and with one square root: PBF's density
  /// and constraint gradients need both per pair, and a loop over lanes through memory made GCC spill its
  /// sums (pressure/pressure_pbf.cpp).
  template <class V>
  [[gnu::always_inline]] void value_and_gradient_factor_lanes(const V& r2, V& w, V& f) const {
    V r;
    for (unsigned l = 0; l < sizeof(V) / sizeof(Scalar); ++l)
      r[l] = std::sqrt(r2[l]);
    const V q = r * m_inv_h;
    const V a_free = 2.0 - q, b_free = 1.0 - q;
    // std::max(x, 0.0) is (x < 0.0) ? 0.0 : x, lane by lane.
    const V a = a_free < 0.0 ? V{} : a_free;
    const V b = b_free < 0.0 ? V{} : b_free;
    w = m_quarter_sigma * (a * a * a - 4.0 * b * b * b);
    const auto apart = r2 > 0.0;
    const V g = 3.0 * m_quarter_sigma * (4.0 * b * b - a * a) * m_inv_h / (apart ? r : V{} + 1.0);
    f = apart ? g : V{};
  }

 private:
  Scalar m_h;
  Scalar m_inv_h;
  Scalar m_sigma;
  Scalar m_quarter_sigma;  // sigma / 4
};

}  // namespace drench
