#include <drench/sph/particle_set.hpp>

#include <algorithm>
#include <cassert>

namespace drench {

void ParticleSet::add(const Vec3& position, const Vec3& velocity, Scalar mass, std::uint32_t id) {
  positions.push_back(position);
  positions_t0.push_back(position);
  velocities.push_back(velocity);
  densities.push_back(0.0);
  pressures.push_back(0.0);
  masses.push_back(mass);
  ids.push_back(id);
}

namespace {

template <class T>
void permute_array(std::vector<T>& values, const IndexArray& order) {
  std::vector<T> sorted(values.size());
#pragma omp parallel for schedule(static)
  for (std::size_t k = 0; k < order.size(); ++k)
    sorted[k] = values[order[k]];
  values.swap(sorted);
}

template <class T>
void compact_array(std::vector<T>& values, const std::vector<std::uint8_t>& remove) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!remove[i]) values[kept++] = values[i];
  }
  values.resize(kept);
}

}  // namespace

void ParticleSet::permute(const IndexArray& order) {
  assert(order.size() == size());
  permute_array(positions, order);
  permute_array(velocities, order);
  permute_array(densities, order);
  permute_array(pressures, order);
  permute_array(masses, order);
  permute_array(ids, order);
  permute_array(positions_t0, order);
}

std::size_t ParticleSet::remove_flagged(const std::vector<std::uint8_t>& remove) {
  assert(remove.size() == size());
  const std::size_t before = size();
  compact_array(positions, remove);
  compact_array(velocities, remove);
  compact_array(densities, remove);
  compact_array(pressures, remove);
  compact_array(masses, remove);
  compact_array(ids, remove);
  compact_array(positions_t0, remove);
  return before - size();
}

void ParticleSet::reserve(std::size_t n) {
  positions.reserve(n);
  velocities.reserve(n);
  densities.reserve(n);
  pressures.reserve(n);
  masses.reserve(n);
  ids.reserve(n);
  positions_t0.reserve(n);
}

Scalar ParticleSet::common_mass() const {
  if (masses.empty()) return 0.0;
  Scalar lo = masses[0];
  Scalar hi = masses[0];
#pragma omp parallel for schedule(static) reduction(min : lo) reduction(max : hi)
  for (std::size_t i = 0; i < masses.size(); ++i) {
    lo = std::min(lo, masses[i]);
    hi = std::max(hi, masses[i]);
  }
  return lo == hi ? lo : 0.0;
}

}  // namespace drench
