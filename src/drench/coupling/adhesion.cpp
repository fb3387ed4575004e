// Adhesion of water to the cloth and the obstacles (the paper's future work, sec. 6). Declared and documented
// in coupler_stages.hpp.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <drench/common/parallel.hpp>
#include <drench/common/triangle_geometry.hpp>
#include <drench/coupling/coupler_stages.hpp>

namespace drench {
namespace coupling_detail {

void adhere(StepContext& ctx, TriangleBroadPhase& broad_phase, const AdhesionSettings& settings,
            double thickness) {
  const ClothMesh& cloth = ctx.cloth();
  const double range = settings.range;
  std::vector<std::pair<Index, Index>> pairs;
  // Both boxes grown by half the range meet for every particle within the range of a face at x_t0.
  broad_phase.find_pairs(ctx.x0(), ctx.x0(), cloth, 0.5 * range, nullptr, pairs);
  // Distance and closest point of every pair, in parallel into per-pair slots; then one face per particle
  // (its closest), so that a particle over the shared edge of two faces is not pulled twice.
  std::vector<double> distance(pairs.size(), std::numeric_limits<double>::infinity());
  std::vector<Vec3> weights(pairs.size());
  parallel_for(pairs.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const auto [p, t] = pairs[k];
      if (t >= settings.work.size() || settings.work[t] == 0.0) continue;
      const Triangle& tri = cloth.triangles[t];
      const Vec3& a = cloth.positions_t0[tri[0]];
      const Vec3& b = cloth.positions_t0[tri[1]];
      const Vec3& c = cloth.positions_t0[tri[2]];
      const Vec3 w = closest_point_barycentric(ctx.x0()[p], a, b, c);
      distance[k] = (ctx.x0()[p] - (w[0] * a + w[1] * b + w[2] * c)).norm();
      weights[k] = w;
    }
  });
  // The water's surface lies at the cloth thickness h, where repulsion holds it, so the pull falls from its
  // peak at h to 0 at the range r: the work to pull water filling d >= h off the face, rho0 int_h^r a(d)
  // (d - h) dd, is then W per unit area for a peak of 6 W / (rho0 (r - h)^2). Measured from d = 0 instead,
  // the pull's work within h went unspent, and a water-repellent plate beaded at 123 degrees against
  // Young-Dupre's 108 (Adhesion.DropletSpreadsOnCottonAndBeadsOnAWaterRepellentPlate).
  const double span = range - std::min(thickness, 0.5 * range);
  const double peak_per_work = 6.0 / (settings.rest_density * span * span);
  const double dt = ctx.dt();
  // Pairs come sorted by particle; one thread, in that order, so any thread count gives the same bits.
  for (std::size_t k = 0; k < pairs.size();) {
    const Index p = pairs[k].first;
    std::size_t best = pairs.size();
    for (; k < pairs.size() && pairs[k].first == p; ++k)
      if (distance[k] < range && (best == pairs.size() || distance[k] < distance[best])) best = k;
    if (best == pairs.size() || !(distance[best] > 1e-12 * range)) continue;  // on the face: no direction
    const Index t = pairs[best].second;
    const Triangle& tri = cloth.triangles[t];
    const Vec3& w = weights[best];
    const Vec3 closest = w[0] * cloth.positions_t0[tri[0]] + w[1] * cloth.positions_t0[tri[1]] +
                         w[2] * cloth.positions_t0[tri[2]];
    const Vec3 towards_face = (closest - ctx.x0()[p]) / distance[best];
    const double pull = peak_per_work * settings.work[t] * std::min(1.0, (range - distance[best]) / span);
    ctx.apply(p, t, w, (ctx.mass(p) * pull * dt) * towards_face);
  }
}

}  // namespace coupling_detail
}  // namespace drench
