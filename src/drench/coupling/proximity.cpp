// Proximity (Huber et al. 2013 sec. 3.1, eq. 1): which particles start the step within the cloth thickness of
// a triangle. Declared and documented in coupler_stages.hpp.

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include <drench/common/parallel.hpp>
#include <drench/common/triangle_geometry.hpp>
#include <drench/coupling/coupler_stages.hpp>

namespace drench {
namespace coupling_detail {

std::vector<Contact> find_contacts(const StepContext& ctx, const std::vector<std::pair<Index, Index>>& pairs,
                                   double thickness) {
  std::vector<Contact> candidates(pairs.size());
  std::vector<std::uint8_t> keep(pairs.size(), 0);
  Vec3Array points(pairs.size());  // each kept candidate's closest point at t0, for the duplicate test
  const ClothMesh& cloth = ctx.cloth();
  parallel_for(pairs.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const auto [p, t] = pairs[k];
      const Triangle& tri = cloth.triangles[t];
      const Vec3& a = cloth.positions_t0[tri[0]];
      const Vec3& b = cloth.positions_t0[tri[1]];
      const Vec3& c = cloth.positions_t0[tri[2]];
      const Vec3& x = ctx.x0()[p];
      const Vec3 w = closest_point_barycentric(x, a, b, c);
      const Vec3 closest = w[0] * a + w[1] * b + w[2] * c;
      const Vec3 offset = x - closest;
      const double distance = offset.norm();
      if (!(distance < thickness)) continue;
      Vec3 normal = (b - a).cross(c - a);
      const double area2 = normal.norm();
      if (distance > 1e-9 * thickness) {
        normal = offset / distance;
      } else if (area2 > 0.0) {
        // Exactly on the triangle: the side is unknown, take the side the particle comes from.
        normal /= area2;
        if (normal.dot(ctx.relative_velocity(p, t, w)) > 0.0) normal = -normal;
      } else {
        continue;  // on a zero-area triangle: nothing defines a normal; the neighbours handle it
      }
      Contact& contact = candidates[k];
      contact.particle = p;
      contact.triangle = t;
      contact.weights = w;
      contact.normal = normal;
      contact.overlap = thickness - distance;
      contact.inverse_mass = ctx.inverse_mass(p, t, w);
      const Vec3 v = ctx.relative_velocity(p, t, w);
      contact.tangential_pre = v - v.dot(normal) * normal;
      points[k] = closest;
      keep[k] = 1;
    }
  });
  // A closest point on an edge or a vertex of triangle B counts only when no triangle A holding that edge or
  // vertex lies closer: otherwise the particle sits over A's face, and B's slanted normal pushes it sideways
  // (water landing on a flat plate drifted, Coupler.ADropletLandingOnAStaticPlateGainsNoSidewaysMomentum).
  // As A holds the feature, distance_A <= distance_B, equal only where the closest points coincide: a
  // particle off a convex crease keeps its edge contact.
  const auto holds_feature = [&](const Contact& b, Index t) {
    const Triangle& tri = cloth.triangles[b.triangle];
    const Triangle& other = cloth.triangles[t];
    for (int i = 0; i < 3; ++i) {
      if (b.weights[i] > 0.0 && other[0] != tri[i] && other[1] != tri[i] && other[2] != tri[i]) return false;
    }
    return true;
  };
  std::vector<Contact> contacts;
  contacts.reserve(static_cast<std::size_t>(std::count(keep.begin(), keep.end(), std::uint8_t{1})));
  std::vector<std::size_t> kept;  // per contact, its candidate's index
  kept.reserve(contacts.capacity());
  for (std::size_t first = 0; first < pairs.size();) {
    std::size_t last = first;
    while (last < pairs.size() && pairs[last].first == pairs[first].first)
      ++last;
    for (std::size_t k = first; k < last; ++k) {
      if (!keep[k]) continue;
      const Contact& c = candidates[k];
      bool shadowed = false;
      if (c.weights.minCoeff() <= 0.0) {
        for (std::size_t other = first; other < last && !shadowed; ++other) {
          shadowed = other != k && keep[other] &&
                     thickness - candidates[other].overlap < (thickness - c.overlap) * (1.0 - 1e-9) &&
                     holds_feature(c, candidates[other].triangle);
        }
      }
      if (shadowed) continue;
      // Pairs come sorted by particle: earlier contacts of the same particle are at the back of `contacts`.
      // Their closest points come from the parallel pass (the same sum of the weighted nodes), not
      // recomputed for every two contacts of a particle.
      const Vec3& point = points[k];
      bool duplicate = false;
      for (std::size_t j = contacts.size(); j > 0 && contacts[j - 1].particle == c.particle; --j) {
        if ((point - points[kept[j - 1]]).norm() <= 1e-12 * (1.0 + point.norm())) duplicate = true;
      }
      if (!duplicate) {
        contacts.push_back(c);
        kept.push_back(k);
      }
    }
    first = last;
  }
  return contacts;
}

}  // namespace coupling_detail
}  // namespace drench
