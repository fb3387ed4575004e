#include "io/ply_writer.hpp"

#include <cstdint>
#include <cstring>

#include "io/atomic_file.hpp"

namespace drench {

namespace {

static_assert(sizeof(float) == 4, "PLY float is 32-bit");

template <class T>
void append_le(std::string& out, T value) {
  // x86-64 and aarch64 are little-endian, as PLY's binary_little_endian asks.
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

}  // namespace

std::string particles_to_ply(const ParticleSet& particles) {
  const std::size_t n = particles.size();
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment drench " DRENCH_VERSION
                    " fluid particles, SI units\n"
                    "element vertex " +
                    std::to_string(n) +
                    "\nproperty float x\nproperty float y\nproperty float z\n"
                    "property float vx\nproperty float vy\nproperty float vz\n"
                    "property float density\nproperty float pressure\nproperty uint id\nend_header\n";
  out.reserve(out.size() + n * 36);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(particles.positions[i][a]));
    for (int a = 0; a < 3; ++a)
      append_le(out, static_cast<float>(particles.velocities[i][a]));
    append_le(out, static_cast<float>(particles.densities[i]));
    append_le(out, static_cast<float>(particles.pressures[i]));
    append_le(out, static_cast<std::uint32_t>(particles.ids[i]));
  }
  return out;
}

void write_particles_ply(const std::string& path, const ParticleSet& particles) {
  write_file_atomic(path, particles_to_ply(particles));
}

}  // namespace drench
