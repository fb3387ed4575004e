// Repulsion (Huber et al. 2013 sec. 3.2, eq. 2-4): inelastic and capped elastic impulses on the contacts.
// Declared and documented in coupler_stages.hpp.

#include <algorithm>
#include <vector>

#include <drench/coupling/coupler_stages.hpp>

namespace drench {
namespace coupling_detail {

void repulse(StepContext& ctx, std::vector<Contact>& contacts, const CouplingSettings& settings) {
  const double dt = ctx.dt();
  for (int sweep = 0; sweep < settings.repulsion_sweeps; ++sweep) {
    for (Contact& c : contacts) {
      const double vn = ctx.relative_velocity(c.particle, c.triangle, c.weights).dot(c.normal);
      double j = vn < 0.0 ? -vn / c.inverse_mass : 0.0;  // eq. 2
      if (sweep == 0) {
        const double vn_after = vn + j * c.inverse_mass;
        const double cap = 0.1 * c.overlap / dt;
        if (vn_after < cap) {
          j += std::min(settings.repulsion_stiffness * c.overlap * dt,
                        (cap - vn_after) / c.inverse_mass);  // eq. 4
        }
      }
      if (j == 0.0) continue;
      ctx.apply(c.particle, c.triangle, c.weights, j * c.normal);
      c.normal_impulse += j;
    }
  }
}

}  // namespace coupling_detail
}  // namespace drench
