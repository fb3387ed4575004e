#pragma once
/// Private to src/coupling, not part of drench's API: the stages of one coupling step (Huber et al. 2013
/// sec. 3) and the state they share. Coupler::step (coupler.cpp) calls them in the paper's order; each stage
/// has its own file: proximity.cpp (sec. 3.1), repulsion.cpp (sec. 3.2), continuous_handling.cpp (sec. 3.3),
/// friction.cpp (sec. 3.4). Only those files include this header; nothing in it is stable.
///
/// Impulses, not forces (sec. 3, after Bridson, Fedkiw, Anderson 2002): every correction is an impulse J on a
/// particle and -w_i J on the nodes of a triangle, w the barycentric weights of the contact point. With
/// velocities v = (x_t1 - x_t0) / dt on both sides, J changes the particle's end position by J / m dt and
/// node i's by -w_i J im_i dt. The impulse that changes the relative velocity at the contact point by dv
/// along a unit direction is dv / (1 / m + sum w_i^2 im_i): mass-weighted on both sides, so sum of m dv is
/// zero and linear momentum is conserved exactly; a pinned node (im = 0) takes its share without moving.
///
/// Determinism: contacts and impacts are processed in particle order, then triangle order, on one thread;
/// only the pure parts (broad phase, narrow-phase CCD queries) run in parallel and write to per-pair slots.
/// Results are bit-identical for any thread count.

#include <cstdint>
#include <utility>
#include <vector>

#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/types.hpp>
#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/cloth_mesh.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/coupling_settings.hpp>
#include <drench/coupling/impulse_link.hpp>

namespace drench {
namespace coupling_detail {

/// A particle within the cloth thickness of a triangle at the start of the step (sec. 3.1).
struct Contact {
  Index particle = 0;
  Index triangle = 0;
  Vec3 weights = Vec3::Zero();         // barycentric weights of the closest point at t0
  Vec3 normal = Vec3::Zero();          // unit, from the triangle towards the particle's side at t0
  double overlap = 0.0;                // d of eq. 3: thickness - distance at t0 (unit: m), > 0
  double inverse_mass = 0.0;           // 1 / m_p + sum w_i^2 im_i (unit: 1/kg)
  double normal_impulse = 0.0;         // sum of the normal impulses given (unit: N s)
  Vec3 tangential_pre = Vec3::Zero();  // relative tangential velocity before coupling (unit: m/s)
};

/// State shared by the stages of one step: the particles' and nodes' start and end positions, and what the
/// impulses changed. Call clear_changes() before the first apply() or place(). The small accessors stay
/// inline here: the stages call them per contact and per impact.
class StepContext {
 public:
  /// @param node_shifts  M entries, or null: where move_node() adds how far it moved each node of inverse
  ///        mass 0 (unit: m)
  /// @param engine_inverse_masses  M inverse masses as the nodes' engines hold them (unit: 1/kg), or null
  ///        for cloth.inverse_masses: a node of 0 is fixed (see fixed())
  /// @param squeezed  where squeeze_out() flags the particles it removes, or null (nothing can be removed)
  /// @param owed  M entries, or null: where place(..., owe = true) adds the impulses it books on nodes of
  ///        inverse mass > 0 without moving them (unit: N s)
  StepContext(const FluidView& fluid, ClothMesh& cloth, double dt, CouplingStepStats& stats,
              Vec3Array& node_impulses, ImpulseLinks* largest, Vec3Array* node_shifts = nullptr,
              const ScalarArray* engine_inverse_masses = nullptr,
              std::vector<std::uint8_t>* squeezed = nullptr, Vec3Array* owed = nullptr)
      : m_x0(*fluid.positions_t0),
        m_x1(*fluid.positions_t1),
        m_v(*fluid.velocities),
        m_mass(*fluid.masses),
        m_cloth(cloth),
        m_dt(dt),
        m_stats(stats),
        m_node_impulses(node_impulses),
        m_largest(largest),
        m_node_shifts(node_shifts),
        m_engine_inverse_masses(engine_inverse_masses ? *engine_inverse_masses : cloth.inverse_masses),
        m_squeezed(squeezed),
        m_owed(owed) {}

  const Triangle& triangle(Index t) const { return m_cloth.triangles[t]; }
  Vec3 particle_velocity(Index p) const { return (m_x1[p] - m_x0[p]) / m_dt; }
  Vec3 point_velocity(Index t, const Vec3& w) const {
    const Triangle& tri = triangle(t);
    Vec3 v = Vec3::Zero();
    for (int i = 0; i < 3; ++i)
      v += w[i] * (m_cloth.positions_t1[tri[i]] - m_cloth.positions_t0[tri[i]]);
    return v / m_dt;
  }
  Vec3 relative_velocity(Index p, Index t, const Vec3& w) const {
    return particle_velocity(p) - point_velocity(t, w);
  }
  double inverse_mass(Index p, Index t, const Vec3& w) const {
    const Triangle& tri = triangle(t);
    double k = 1.0 / m_mass[p];
    for (int i = 0; i < 3; ++i)
      k += w[i] * w[i] * m_cloth.inverse_masses[tri[i]];
    return k;
  }

  /// Impulse J (unit: N s) on particle p, -w_i J on the nodes of triangle t.
  void apply(Index p, Index t, const Vec3& w, const Vec3& impulse) {
    const Vec3 dv = impulse / m_mass[p];
    m_x1[p] += dv * m_dt;
    m_v[p] += dv;
    const Triangle& tri = triangle(t);
    for (int i = 0; i < 3; ++i) {
      const double im = m_cloth.inverse_masses[tri[i]];
      m_node_impulses[tri[i]] -= w[i] * impulse;
      if (im > 0.0) {
        m_cloth.positions_t1[tri[i]] -= (w[i] * im * m_dt) * impulse;
        m_node_changed[tri[i]] = 1;
        m_nodes_changed = true;
      }
    }
    m_particle_changed[p] = 1;
    m_stats.vertical_impulse_on_cloth -= impulse.y();
    if (m_largest != nullptr) {
      ImpulseLink& link = (*m_largest)[p];
      const double size = impulse.norm();
      if (size > link.impulse) link = {0, t, w, size};
    }
  }

  /// Moves particle p's end position (fail-safe), keeping velocity = displacement / dt. The momentum this
  /// gives the particle is booked against the nodes of triangle t by the weights w, as apply() books an
  /// impulse, without moving them: a rigid body or a carried-water cloth takes it from node_impulses, so the
  /// exchange stays conservative even here. With `owe`, a node of inverse mass > 0, which no one else pays,
  /// also has it added to `owed` (the fail-safe: moving the triangle would let it cross the particle it was
  /// to carry; an impact zone's move of its nodes pays for its own particles).
  void place(Index p, const Vec3& x_t1, Index t, const Vec3& w, bool owe = false) {
    const Vec3 dv = (x_t1 - m_x1[p]) / m_dt;
    m_v[p] += dv;
    m_x1[p] = x_t1;
    m_particle_changed[p] = 1;
    const Vec3 impulse = m_mass[p] * dv;
    const Triangle& tri = triangle(t);
    for (int i = 0; i < 3; ++i) {
      m_node_impulses[tri[i]] -= w[i] * impulse;
      if (owe && m_owed != nullptr && m_cloth.inverse_masses[tri[i]] > 0.0)
        (*m_owed)[tri[i]] -= w[i] * impulse;
    }
    m_stats.vertical_impulse_on_cloth -= impulse.y();
    m_stats.last_resort_impulse += impulse.norm();
  }

  /// Sets node i's end position (an impact zone's move), marked as a change like apply()'s. A node of
  /// inverse mass 0 takes no impulse for it: the move is added to node_shifts for the caller to settle.
  void move_node(Index i, const Vec3& x_t1) {
    if (m_node_shifts != nullptr && !(m_cloth.inverse_masses[i] > 0.0))
      (*m_node_shifts)[i] += x_t1 - m_cloth.positions_t1[i];
    m_cloth.positions_t1[i] = x_t1;
    m_node_changed[i] = 1;
    m_nodes_changed = true;
  }

  /// True when node i's engine ignores a move (a rigid body's, an obstacle's, a pinned cloth node): the
  /// impact zones leave it where it was given.
  bool fixed(Index i) const { return !(m_engine_inverse_masses[i] > 0.0); }

  /// Removes particle p from the rest of the step (the impact zones' last resort, where no motion keeps it
  /// out of every face): flagged in `squeezed` for the caller to remove, its mass and momentum m v booked
  /// in the stats (squeezed_out, squeezed_out_mass, squeezed_out_momentum); later CCD rounds skip it.
  /// Precondition: constructed with `squeezed`.
  void squeeze_out(Index p) {
    if (m_squeezed->empty()) m_squeezed->assign(m_x0.size(), 0);
    (*m_squeezed)[p] = 1;
    ++m_stats.squeezed_out;
    m_stats.squeezed_out_mass += m_mass[p];
    m_stats.squeezed_out_momentum += m_mass[p] * m_v[p];
  }
  bool squeezed_out(Index p) const {
    return m_squeezed != nullptr && !m_squeezed->empty() && (*m_squeezed)[p];
  }

  ccd::VertexFaceQuery query(Index p, Index t) const {
    const Triangle& tri = triangle(t);
    const Vec3Array& c0 = m_cloth.positions_t0;
    const Vec3Array& c1 = m_cloth.positions_t1;
    return {m_x0[p], c0[tri[0]], c0[tri[1]], c0[tri[2]], m_x1[p], c1[tri[0]], c1[tri[1]], c1[tri[2]]};
  }

  void clear_changes() {
    m_particle_changed.assign(m_x0.size(), 0);
    m_node_changed.assign(m_cloth.node_count(), 0);
    m_nodes_changed = false;
  }
  /// Marks in `only` (N entries) every particle that can be in a changed pair (pair_changed) whose boxes
  /// overlap: the changed particles, and those whose box over the step (margin 0, as the CCD rounds' query)
  /// overlaps the box of all changed triangles. A particle left unmarked has only unchanged pairs, or pairs
  /// the broad phase would not report, so a query restricted to the marked ones finds every changed pair.
  /// Defined in continuous_handling.cpp, its only user.
  void mark_changed_candidates(std::vector<std::uint8_t>& only) const;

  /// True when a node was marked as changed since the last clear_changes().
  bool nodes_changed() const { return m_nodes_changed; }

  bool pair_changed(Index p, Index t) const {
    const Triangle& tri = triangle(t);
    return m_particle_changed[p] || m_node_changed[tri[0]] || m_node_changed[tri[1]] ||
           m_node_changed[tri[2]];
  }

  const Vec3Array& x0() const { return m_x0; }
  const Vec3Array& x1() const { return m_x1; }
  ClothMesh& cloth() { return m_cloth; }
  const ClothMesh& cloth() const { return m_cloth; }
  double dt() const { return m_dt; }
  double mass(Index p) const { return m_mass[p]; }
  CouplingStepStats& stats() { return m_stats; }

 private:
  const Vec3Array& m_x0;
  Vec3Array& m_x1;
  Vec3Array& m_v;
  const ScalarArray& m_mass;
  ClothMesh& m_cloth;
  double m_dt;
  CouplingStepStats& m_stats;
  std::vector<std::uint8_t> m_particle_changed;
  std::vector<std::uint8_t> m_node_changed;
  // Some m_node_changed is set: a flag, where a search of the M flags was asked for twice a round.
  bool m_nodes_changed = false;
  Vec3Array& m_node_impulses;  // what every node received, inverse mass 0 or not (unit: N s)
  ImpulseLinks* m_largest;     // N, each particle's largest impulse so far (impulse 0: none), or null
  Vec3Array* m_node_shifts;    // M, what move_node moved each node of inverse mass 0 by (m), or null
  const ScalarArray& m_engine_inverse_masses;  // M, as the engines hold them (unit: 1/kg)
  std::vector<std::uint8_t>* m_squeezed;
  Vec3Array* m_owed;  // N flags of the particles squeezed out (empty: none), or null
};

/// Proximity (sec. 3.1, proximity.cpp): eq. 1's plane distance and barycentric inside test, extended to edges
/// and vertices by taking the closest point of the closed triangle; all at the start positions, which also
/// decide the side (sec. 3.2). An edge or vertex contact counts only in that feature's Voronoi region: it is
/// dropped when a triangle holding the feature lies closer to the particle (the particle is over that face,
/// whose normal is the paper's). A particle whose closest points on several triangles coincide (a shared edge
/// or vertex) keeps one contact, the triangle of lowest index, so it is pushed once.
/// @param ctx  the step; read only: the start positions, and the relative velocity (end minus start over dt)
///        for each contact's tangential_pre and the side of a particle lying exactly on a triangle
/// @param pairs  candidate (particle, triangle) pairs sorted by particle, then triangle, each once (as
///        TriangleBroadPhase::find_pairs returns them)
/// @param thickness  the cloth thickness h (unit: m), > 0
/// @return the contacts, in the order of `pairs`: those with distance < thickness at t0
std::vector<Contact> find_contacts(const StepContext& ctx, const std::vector<std::pair<Index, Index>>& pairs,
                                   double thickness);

/// Repulsion (sec. 3.2, repulsion.cpp) in settings.repulsion_sweeps Gauss-Seidel sweeps over `contacts`, in
/// their order: the inelastic impulse of eq. 2 stops an approach; the elastic impulse of eq. 3-4, k d dt,
/// pushes out of the cloth thickness, capped as in Bridson et al. 2002 (never faster than 0.1 d / dt) and
/// given in the first sweep only, so it is one spring impulse per step.
/// @param contacts  from find_contacts; each contact's normal_impulse accumulates what it was given (N s)
/// @param settings  validated (Coupler's constructor): repulsion_stiffness k (N/m), repulsion_sweeps >= 1
void repulse(StepContext& ctx, std::vector<Contact>& contacts, const CouplingSettings& settings);

/// Tangential boundary conditions (sec. 3.4, friction.cpp) on the contacts after repulse(): eq. 8, v_t =
/// max(1 - mu dv_N / |v_t_pre|, 0) v_t_pre with dv_N the normal velocity change the repulsion gave the
/// contact; no-slip (eq. 7) sets v_t = 0. mu = 0 is free slip: nothing to do.
/// @param contacts  from find_contacts, with normal_impulse filled by repulse()
/// @param settings  slip and friction_coefficient mu (>= 0, dimensionless)
void apply_friction(StepContext& ctx, std::vector<Contact>& contacts, const CouplingSettings& settings);

/// Adhesion of water to the faces (adhesion.cpp; the paper's future work, sec. 6), before repulsion, so that
/// the inelastic impulse of eq. 2 stops what the pull adds to an approach and the water stays out of the
/// cloth thickness. Every particle whose start position lies within `settings.range` of a face is pulled
/// towards its closest face by a = 6 W / (rho0 (r - h)^2) min(1, (r - d) / (r - h)), d its distance, r the
/// range, h the thickness, W the face's work of adhesion: the work to pull water filling d >= h off the face
/// is then W per unit area (the integral of rho0 a (d' - h) over d' in [h, r]). An impulse -m a dt n on the
/// particle and its opposite on the face's nodes by the barycentric weights (apply), so the cloth takes what
/// the water gets; static faces (inverse mass 0) book it in node_impulses only.
/// @param broad_phase  the coupler's, queried at x_t0 with margin range / 2
/// @param settings  work (N/m, one per triangle of ctx's mesh, missing ones 0), range (m) > 0, rest density
/// @param thickness  the cloth thickness h (unit: m), > 0; where it exceeds half the range, half the range
///        stands for it
void adhere(StepContext& ctx, TriangleBroadPhase& broad_phase, const AdhesionSettings& settings,
            double thickness);

/// Brings `all`, every pair of the motion as it was at the last clear_changes(), to the current motion:
/// the broad phase is asked only for the particles mark_changed_candidates marks, whose pairs (`fresh`)
/// replace theirs; an unmarked particle keeps its pairs with unchanged triangles and has none with a
/// changed one (its box misses all of theirs). So `all` is exactly what a query of every particle would
/// give, in the same order, at the cost of a query of the few marked ones: the fail-safe's and the impact
/// zones' rounds asked for every particle again, four queries of the whole fluid per step in issue 41's
/// level.
/// @param all  every pair of the motion at the last clear_changes() (a query of every particle with margin 0,
///        sorted by particle, then triangle), brought to the current motion
/// @param fresh  output, replaced: the pairs of the marked particles (mark_changed_candidates)
/// @param only, merged  scratch
void update_pairs(StepContext& ctx, TriangleBroadPhase& broad_phase, std::vector<std::uint8_t>& only,
                  std::vector<std::pair<Index, Index>>& fresh, std::vector<std::pair<Index, Index>>& all,
                  std::vector<std::pair<Index, Index>>& merged);

/// Continuous intersection handling (sec. 3.3, continuous_handling.cpp) on the motion the earlier stages
/// corrected: rounds of point-triangle CCD (eq. 5-6) and an inelastic impulse at each particle's earliest
/// impact, the first round over every pair, later ones over the pairs whose motion the previous round
/// changed, until no pair collides (the fail-safe's check and the impact zones' rounds below need every
/// pair's answer: an unchanged pair keeps the one it had). After settings.max_ccd_iterations rounds the
/// fail-safe moves each particle still colliding with its triangle's contact point, which that triangle
/// cannot cross; and where that is not enough (folds), the colliding particles and nodes join impact zones
/// that each move by one motion for the step (rigid impact zones), taking the fixed nodes'
/// (StepContext::fixed) as given, until no pair collides; a zone between fixed nodes that move differently
/// has its particles squeezed out (StepContext::squeeze_out).
/// Adds to the stats' ccd_iterations, ccd_impacts, failsafe_activations, stopped_particles, stopped_nodes,
/// squeezed_out.
/// @param broad_phase  the coupler's, queried with margin 0 for swept boxes
/// @param settings  cloth_thickness (unit: m) > 0, max_ccd_iterations >= 1
/// @param unresolved  optional output: (particle index, triangle) of a collision left, else (-1, -1)
/// @return COUPLING_FAILSAFE_USED, COUPLING_ZONES_STOPPED and COUPLING_UNRESOLVED flags, or COUPLING_OK
std::uint32_t resolve_ccd(StepContext& ctx, TriangleBroadPhase& broad_phase, const CouplingSettings& settings,
                          std::pair<std::int64_t, std::int64_t>* unresolved = nullptr);

}  // namespace coupling_detail
}  // namespace drench
