#include "sph/emitters.hpp"

#include <algorithm>
#include <cmath>

namespace drench {

std::size_t emit_box(const BoxEmitterSettings& box, Scalar spacing, Scalar mass, ParticleSet& particles,
                     std::uint32_t& next_id) {
  Vec3i count;
  for (int a = 0; a < 3; ++a) {
    count[a] = std::max(1, static_cast<int>(std::floor((box.max[a] - box.min[a]) / spacing + 1e-9)));
  }
  particles.reserve(particles.size() + static_cast<std::size_t>(count.prod()));
  for (int k = 0; k < count.z(); ++k) {
    for (int j = 0; j < count.y(); ++j) {
      for (int i = 0; i < count.x(); ++i) {
        particles.add(box.min + spacing * Vec3(i + 0.5, j + 0.5, k + 0.5), box.velocity, mass, next_id++);
      }
    }
  }
  return static_cast<std::size_t>(count.prod());
}

NozzleEmitter::NozzleEmitter(const NozzleEmitterSettings& settings, Scalar spacing)
    : m_settings(settings), m_spacing(spacing) {
  const Vec3& d = m_settings.direction;
  int least = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(d[a]) < std::abs(d[least])) least = a;
  }
  const Vec3 first = d.cross(Vec3::Unit(least)).normalized();
  const Vec3 second = d.cross(first);
  const int n = static_cast<int>(std::floor(settings.radius / spacing));
  const Scalar r2 = settings.radius * settings.radius;
  for (int j = -n; j <= n; ++j) {
    for (int i = -n; i <= n; ++i) {
      const Vec3 offset = spacing * (i * first + j * second);
      if (offset.squaredNorm() <= r2) m_disc.push_back(offset);
    }
  }
}

std::size_t NozzleEmitter::emit(Scalar t, Scalar dt, Scalar mass, ParticleSet& particles,
                                std::uint32_t& next_id) {
  const Scalar t_end = t + dt;
  const Scalar layer_period = m_spacing / m_settings.speed;
  const Vec3 velocity = m_settings.speed * m_settings.direction;
  std::size_t added = 0;
  while (m_emitted < m_settings.max_particles) {
    const Scalar release = m_settings.start_time + m_layers * layer_period;
    if (release > t_end) break;
    // Placed where it would be at the start of the step had it left the nozzle at `release`, i.e. still
    // upstream inside the nozzle when release > t: the fluid step that follows carries it to its place at
    // t + dt, so layers end one spacing apart whatever dt is.
    const Vec3 centre = m_settings.center + (t - release) * velocity;
    for (const Vec3& offset : m_disc) {
      if (m_emitted >= m_settings.max_particles) break;
      particles.add(centre + offset, velocity, mass, next_id++);
      ++m_emitted;
      ++added;
    }
    ++m_layers;
  }
  return added;
}

}  // namespace drench
