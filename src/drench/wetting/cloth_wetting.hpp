#pragma once
/// Water inside the cloth (Huber et al. 2013 sec. 5, Fig. 9; the absorption and diffusion model of Huber,
/// Pabst & Straßer 2011): every cloth node holds a mass of water up to a capacity proportional to its dry
/// mass; particles touching the cloth give it their mass (absorption), the water spreads from wetter to
/// drier nodes along the mesh's edges (diffusion) and runs down along falling edges (gravity drainage), and
/// a node holding more than its capacity lets go of whole particles on the cloth's lower side (dripping).
/// The cloth's engine then weighs each node with its water (ClothEngine::set_water_masses), so a wet cloth
/// sags more. Every transfer moves mass from one holder to another: particle mass + water held + particles
/// dripped stays what it was, up to rounding.

#include <cstdint>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/coupling/cloth_layout.hpp>
#include <drench/wetting/wetting_settings.hpp>

namespace drench {

/// One particle touching one cloth triangle, as the coupling found it (Coupler::impulse_links).
struct WettingContact {
  std::size_t particle = 0;     ///< index into the particle arrays
  Index triangle = 0;           ///< cloth triangle, < F
  Vec3 weights = Vec3::Zero();  ///< barycentric weights of the contact point, >= 0, summing to 1
};

/// A particle a node lets go of: new fluid at the cloth's lower side.
struct WettingDrop {
  Vec3 position = Vec3::Zero();  ///< (unit: m)
  Vec3 velocity = Vec3::Zero();  ///< the node's (unit: m/s)
  Index node = 0;                ///< the node it came from
};

/// What one step of wetting did; summed into the run's summary.json.
struct WettingStepStats {
  double absorbed_kg = 0.0;              ///< mass the cloth took from particles
  double dripped_kg = 0.0;               ///< mass the cloth gave back as new particles
  std::uint64_t particles_absorbed = 0;  ///< particles that gave all their mass and went
  std::uint64_t particles_dripped = 0;   ///< particles made by dripping
  std::uint64_t spread_substeps = 0;     ///< explicit sub-steps of diffusion and drainage
  double seconds = 0.0;                  ///< wall time (unit: s)
};

/// The water held by one cloth of M nodes and F triangles. Not thread-safe.
class ClothWetting {
 public:
  /// @param settings  within their ranges (check_wetting_settings, WettingSettings)
  /// @param triangles  F cloth triangles, node indices < M
  /// @param rest_positions  M node positions (unit: m) whose edge lengths the diffusion keeps as its rest
  ///        lengths (the cloth at the start of the scene)
  /// @param dry_masses  M node masses of the dry cloth (unit: kg), > 0, pinned nodes included (they hold
  ///        water too); the capacity of node i is max_saturation * dry_masses[i]
  /// @throws SceneError naming the setting out of range (check_wetting_settings), before anything else;
  ///         drench::Error naming the node or triangle at fault: sizes that differ, an index out of range,
  ///         a non-positive or non-finite mass, an edge of zero length
  ClothWetting(const WettingSettings& settings, const std::vector<Triangle>& triangles,
               const Vec3Array& rest_positions, const ScalarArray& dry_masses);

  /// Absorption: each contact (in the order given) takes from its particle the fraction absorption_rate dt
  /// (at most 1) of its mass times (1 - S), S the saturation of the triangle's nodes at the contact point
  /// (barycentric), and gives it to those nodes by weight, never beyond a node's capacity. A particle left
  /// lighter than `min_mass` gives the rest too (to its heaviest-weighted node) and is flagged in `remove`.
  /// @param masses  N particle masses (unit: kg), > 0; reduced in place
  /// @param remove  N flags; set to 1 for particles absorbed whole (the caller removes them)
  /// @param min_mass  (unit: kg), >= 0
  /// @param dt  (unit: s), > 0
  void absorb(const std::vector<WettingContact>& contacts, ScalarArray& masses,
              std::vector<std::uint8_t>& remove, double min_mass, double dt, WettingStepStats& stats);

  /// Diffusion and gravity drainage over dt (unit: s, > 0), explicit in sub-steps each within the
  /// scheme's limit dt_sub (sum_j k_ij / C_i + u sum_j slope_ij / l_ij) <= 1/2 for every node (k_ij the
  /// edge's conductance, u the drainage speed, l_ij the rest length), so no node ever
  /// goes negative and, by the maximum principle of the diffusion, none rises above the largest saturation
  /// it started with unless water runs down into it.
  /// @param positions  M current node positions (unit: m), finite: the slopes of the drainage
  /// @param gravity  (unit: m/s^2); zero turns the drainage off
  void spread(const Vec3Array& positions, const Vec3& gravity, double dt, WettingStepStats& stats);

  /// Dripping: every node holding at least `particle_mass` more than its capacity lets go of one particle
  /// of that mass, at `offset` (unit: m, > 0) from the node along its normal turned to the side gravity
  /// pulls to, moving with the node; none is made closer than `clearance` (unit: m) to a particle or to a
  /// drop made before it (it stays in the cloth until there is room).
  /// @param positions, velocities  M node positions (m) and velocities (m/s)
  /// @param particles  the fluid's N positions (unit: m)
  /// @return the drops, in node order; their mass is already taken from the nodes
  std::vector<WettingDrop> drip(const Vec3Array& positions, const Vec3Array& velocities, const Vec3& gravity,
                                double particle_mass, double offset, const Vec3Array& particles,
                                double clearance, WettingStepStats& stats);

  /// Follows the cloth torn, cut or refined between two steps (ClothEngine::pieces): each node keeps its
  /// water at its new index and a node the tear added holds none, so the water held is what it was; every
  /// node can hold max_saturation times its dry mass now (a tear moves mass between nodes; water over a
  /// capacity drips at the next drip()). The faces become `triangles`; an edge keeps its rest length when it
  /// was an edge before, a new one takes its length now, and a face with a new node its area now (its nodes'
  /// rest places are unknown). An edge of zero length is left out of the diffusion.
  /// @param change  from the layout of the last call (or construction) to now; this cloth is its pieces
  /// @param triangles  F' faces, node indices < M'
  /// @param positions  M' node positions now (unit: m)
  /// @param dry_masses  M' dry node masses now (unit: kg), > 0 and finite
  /// @throws drench::Error on sizes that do not match the change, a node index out of range or a mass that
  ///         is not > 0 and finite, before anything changes
  void follow(const ClothLayoutChange& change, const std::vector<Triangle>& triangles,
              const Vec3Array& positions, const ScalarArray& dry_masses);
  /// Water held per node (unit: kg), M entries, >= 0.
  const ScalarArray& water() const { return m_water; }
  /// Capacity per node (unit: kg), M entries.
  const ScalarArray& capacities() const { return m_capacity; }
  /// Water over capacity per node, clamped to [0, 1]: the `wetness` of the cloth frames.
  ScalarArray wetness() const;
  /// Total water held (unit: kg).
  double held() const;
  /// Fraction of the cloth's rest area (a third of each triangle to each node) whose node holds more than 1%
  /// of its capacity.
  double wet_area_fraction() const;
  /// Sets the water of every node (unit: kg), M entries, >= 0 (tests, restarts).
  /// @throws drench::Error on a wrong size or a negative or non-finite entry
  void set_water(const ScalarArray& water);

 private:
  struct Edge {
    Index a = 0, b = 0;
    double conductance = 0.0;  // k_ab = diffusion (C_a + C_b) / 2 / rest_length^2 (unit: kg/s)
    double rest_length = 0.0;  // (unit: m)
  };

  /// The edge between nodes a and b of that rest length (m), its conductance of m_capacity's.
  Edge edge(Index a, Index b, double rest_length) const;

  WettingSettings m_settings;
  std::vector<Triangle> m_triangles;
  std::vector<Edge> m_edges;
  ScalarArray m_capacity;
  ScalarArray m_water;
  ScalarArray m_node_area;
  Vec3Array m_rest_positions;  // M, the rest places the node areas and the edges' rest lengths are of
  ScalarArray m_flow;          // M, scratch of spread()
};

}  // namespace drench
