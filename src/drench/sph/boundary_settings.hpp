#pragma once
/// Settings of the fluid's static boundaries (`boundaries` in docs/scenes.md), kept apart from their
/// sampling (boundary_sampling.hpp).

#include <drench/common/types.hpp>

namespace drench {

/// Static boundaries sampled with boundary particles (Akinci et al. 2012).
struct BoundarySettings {
  enum class Kind {
    BOX,   ///< a container: the fluid lives inside [min, max]; walls are sampled on its six faces
    PLANE  ///< a rectangle of size[0] x size[1] centred at `point`, fluid on the side `normal` points to
  } kind = Kind::BOX;
  Vec3 min = Vec3::Zero();            ///< BOX: inner lower corner (unit: m)
  Vec3 max = Vec3::Ones();            ///< BOX: inner upper corner (unit: m), > min
  bool open_top = false;              ///< BOX: no wall at max.y (the up axis is +y, against default gravity)
  Vec3 point = Vec3::Zero();          ///< PLANE: centre (unit: m)
  Vec3 normal = Vec3(0.0, 1.0, 0.0);  ///< PLANE: normalised on load, non-zero
  Scalar size[2] = {1.0, 1.0};        ///< PLANE: side lengths (unit: m), > 0
  int layers = 2;  ///< layers of boundary particles behind the surface, one spacing apart, >= 1
};

}  // namespace drench
