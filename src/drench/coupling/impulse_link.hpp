#pragma once
/// Which particle gave which cloth triangle an impulse that the cloth takes only at its next step
/// (CouplingScheme::CARRIED_WATER). The carried water carries such a particle with that triangle through the
/// cloth's step, so the impulse moves node and particle together, as the inelastic impulse of eq. 2 between
/// them would: on the bare node (4.1e-5 kg in the paper's Fig. 3, a particle 1.25e-4 kg) the same impulse
/// would throw the node several times faster than the particle ever moved.

#include <cstdint>
#include <vector>

#include <drench/common/key_index_table.hpp>
#include <drench/common/types.hpp>

namespace drench {

struct ImpulseLink {
  std::uint32_t particle_id = 0;  ///< ParticleSet::ids, stable across re-sorting and removal
  Index triangle = 0;             ///< index into ClothMesh::triangles
  Vec3 weights = Vec3::Zero();    ///< barycentric weights of the contact point on the triangle
  double impulse = 0.0;           ///< magnitude of the impulse (unit: N s), > 0; the largest one counts
};

using ImpulseLinks = std::vector<ImpulseLink>;

/// Keeps, per particle, the link of its largest impulse: the carried water carries a particle with that
/// link's triangle, and wetting lets that triangle absorb it. For each link of `links` to a triangle below
/// `triangle_count` whose particle is present (`index_of` finds its id), best[i] becomes that link when it is
/// i's first, its impulse is larger, or it is equal with a lower triangle; of the same impulse to the same
/// triangle twice, the first stays. So the choice does not depend on the order of the links, nor on which
/// list (the coupler's, the sub-step obstacle's) a link came in. Call it once per list.
/// @param index_of  the particles' ids (ParticleSet::ids), N of them, built
/// @param best  N pointers into the lists given, null where a particle has no link yet; kept across calls, so
///        the lists must outlive its use
inline void keep_largest_links(const ImpulseLinks& links, std::size_t triangle_count,
                               const KeyIndexTable& index_of, std::vector<const ImpulseLink*>& best) {
  for (const ImpulseLink& link : links) {
    if (link.triangle >= triangle_count) continue;
    const std::int64_t i = index_of.find(link.particle_id);
    if (i < 0) continue;  // a particle no longer present
    const ImpulseLink*& held = best[static_cast<std::size_t>(i)];
    if (held && !(link.impulse > held->impulse ||
                  (link.impulse == held->impulse && link.triangle < held->triangle))) {
      continue;
    }
    held = &link;
  }
}

}  // namespace drench
