#pragma once
/// Which particle gave which cloth triangle an impulse that the cloth takes only at its next step
/// (CouplingScheme::CARRIED_WATER). The carried water carries such a particle with that triangle through the
/// cloth's step, so the impulse moves node and particle together, as the inelastic impulse of eq. 2 between
/// them would: on the bare node (4.1e-5 kg in the paper's Fig. 3, a particle 1.25e-4 kg) the same impulse
/// would throw the node several times faster than the particle ever moved.

#include <cstdint>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

struct ImpulseLink {
  std::uint32_t particle_id = 0;  ///< ParticleSet::ids, stable across re-sorting and removal
  Index triangle = 0;             ///< index into ClothMesh::triangles
  Vec3 weights = Vec3::Zero();    ///< barycentric weights of the contact point on the triangle
  double impulse = 0.0;           ///< magnitude of the impulse (unit: N s), > 0; the largest one counts
};

using ImpulseLinks = std::vector<ImpulseLink>;

}  // namespace drench
