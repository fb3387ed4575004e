#pragma once
/// Settings of the emitters that create fluid particles (`emitters` in docs/scenes.md), kept apart from the
/// emitters they configure (emitters.hpp).

#include <cstdint>

#include <drench/common/types.hpp>

namespace drench {

/// A circular jet: particles leave a disc of `radius` around `center` along `direction` at `speed`, in layers
/// one spacing apart, from `start_time` until `max_particles` have been emitted.
struct NozzleEmitterSettings {
  Vec3 center = Vec3::Zero();             ///< (unit: m)
  Vec3 direction = Vec3(0.0, -1.0, 0.0);  ///< non-zero; normalised on load and by the emitter
  Scalar radius = 0.02;                   ///< (unit: m), > 0
  Scalar speed = 1.0;                     ///< (unit: m/s), > 0
  Scalar start_time = 0.0;                ///< (unit: s), >= 0
  std::int64_t max_particles = 10000;     ///< particle budget of this emitter, >= 0
};

/// A box of fluid at rest spacing, created at time 0 (dam-break columns, tanks).
struct BoxEmitterSettings {
  Vec3 min = Vec3::Zero();       ///< lower corner (unit: m)
  Vec3 max = Vec3::Ones();       ///< upper corner (unit: m), > min on every axis
  Vec3 velocity = Vec3::Zero();  ///< initial velocity (unit: m/s)
};

struct EmitterSettings {
  enum class Kind { NOZZLE, BOX } kind = Kind::BOX;
  NozzleEmitterSettings nozzle;
  BoxEmitterSettings box;
};

}  // namespace drench
