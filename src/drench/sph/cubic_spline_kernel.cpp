#include <drench/sph/cubic_spline_kernel.hpp>

#include <cassert>
#include <cmath>

namespace drench {

CubicSplineKernel::CubicSplineKernel(Scalar smoothing_length)
    : m_h(smoothing_length),
      m_inv_h(1.0 / smoothing_length),
      m_sigma(1.0 / (M_PI * std::pow(m_h, 3))),
      m_quarter_sigma(0.25 * m_sigma) {
  assert(smoothing_length > 0.0);
}

}  // namespace drench
