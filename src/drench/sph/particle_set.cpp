#include <drench/sph/particle_set.hpp>

#include <algorithm>
#include <cassert>
#include <utility>

#include <drench/common/parallel.hpp>

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
  parallel_for(order.size(), kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      sorted[k] = values[order[k]];
  });
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
  using Range = std::pair<Scalar, Scalar>;
  const Range range = parallel_reduce(
      masses.size(), kLightChunk, Range(masses[0], masses[0]),
      [&](std::size_t begin, std::size_t end) {
        Range r(masses[begin], masses[begin]);
        for (std::size_t i = begin; i < end; ++i) {
          r.first = std::min(r.first, masses[i]);
          r.second = std::max(r.second, masses[i]);
        }
        return r;
      },
      [](const Range& a, const Range& b) {
        return Range(std::min(a.first, b.first), std::max(a.second, b.second));
      });
  return range.first == range.second ? range.first : 0.0;
}

}  // namespace drench
