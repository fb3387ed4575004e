// Tangential boundary conditions (Huber et al. 2013 sec. 3.4, eq. 7-8): no-slip or friction on the contacts
// after the repulsion. Declared and documented in coupler_stages.hpp.

#include <algorithm>
#include <vector>

#include <drench/coupling/coupler_stages.hpp>

namespace drench {
namespace coupling_detail {

void apply_friction(StepContext& ctx, std::vector<Contact>& contacts, const CouplingSettings& settings) {
  const bool no_slip = settings.slip == SlipCondition::NO_SLIP;
  for (Contact& c : contacts) {
    if (!no_slip && (settings.friction_coefficient == 0.0 || c.normal_impulse == 0.0)) continue;
    const Vec3 v = ctx.relative_velocity(c.particle, c.triangle, c.weights);
    const Vec3 vt = v - v.dot(c.normal) * c.normal;
    Vec3 target = Vec3::Zero();
    if (!no_slip) {
      const double pre = c.tangential_pre.norm();
      const double dv_n = c.normal_impulse * c.inverse_mass;
      if (pre > 0.0)
        target = std::max(1.0 - settings.friction_coefficient * dv_n / pre, 0.0) * c.tangential_pre;
    }
    const Vec3 change = target - vt;
    if (change.squaredNorm() == 0.0) continue;
    ctx.apply(c.particle, c.triangle, c.weights, change / c.inverse_mass);
  }
}

}  // namespace coupling_detail
}  // namespace drench
