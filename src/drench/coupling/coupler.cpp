#include <drench/coupling/coupler.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/coupler_stages.hpp>

// One coupling step runs the paper's stages in order (Huber et al. 2013 sec. 3; each in its own file,
// declared in coupler_stages.hpp): proximity at the start positions (sec. 3.1) -> Gauss-Seidel sweeps of the
// inelastic (eq. 2) and elastic (eq. 3-4) impulses -> friction (eq. 7-8) on the same contacts -> continuous
// handling (sec. 3.3): CCD (eq. 5-6) on the corrected motion, an inelastic impulse at each particle's
// earliest impact, repeated on the pairs that changed until none collides -> fail-safe: a particle still
// colliding moves with its triangle's contact point, which a triangle cannot cross.

namespace drench {
namespace {

using coupling_detail::adhere;
using coupling_detail::apply_friction;
using coupling_detail::Contact;
using coupling_detail::find_contacts;
using coupling_detail::repulse;
using coupling_detail::resolve_ccd;
using coupling_detail::StepContext;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

Coupler::Coupler(const CouplingSettings& settings, bool with_friction)
    : m_settings(settings), m_with_friction(with_friction) {
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) throw SceneError("coupling." + what);
  };
  require(settings.cloth_thickness > 0.0 && std::isfinite(settings.cloth_thickness),
          "cloth_thickness must be > 0, got " + format_number(settings.cloth_thickness));
  require(settings.repulsion_stiffness >= 0.0 && std::isfinite(settings.repulsion_stiffness),
          "repulsion_stiffness must be >= 0, got " + format_number(settings.repulsion_stiffness));
  require(settings.repulsion_sweeps >= 1,
          "repulsion_sweeps must be >= 1, got " + std::to_string(settings.repulsion_sweeps));
  require(settings.max_ccd_iterations >= 1,
          "max_ccd_iterations must be >= 1, got " + std::to_string(settings.max_ccd_iterations));
  require(settings.friction_coefficient >= 0.0 && std::isfinite(settings.friction_coefficient),
          "friction_coefficient must be >= 0, got " + format_number(settings.friction_coefficient));
  m_broad_phase = make_broad_phase(settings.broad_phase);
  m_counter.constructed = 1;
  m_friction_counter.constructed = with_friction ? 1 : 0;
}

Coupler::~Coupler() = default;

void Coupler::set_adhesion(AdhesionSettings settings) {
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) throw SceneError(what);
  };
  for (std::size_t t = 0; t < settings.work.size(); ++t) {
    require(settings.work[t] >= 0.0 && settings.work[t] <= kMaxWorkOfAdhesion,
            "adhesion of triangle " + std::to_string(t) + " must be in [0, " +
                format_number(kMaxWorkOfAdhesion) + "] (N/m), got " + format_number(settings.work[t]));
  }
  require(settings.range > 0.0 && std::isfinite(settings.range),
          "adhesion range must be > 0, got " + format_number(settings.range));
  require(settings.rest_density > 0.0 && std::isfinite(settings.rest_density),
          "adhesion rest density must be > 0, got " + format_number(settings.rest_density));
  m_adhesion = std::move(settings);
  m_adhesion_counter.constructed = 1;
}

std::uint32_t Coupler::step(const FluidView& fluid, ClothMesh& cloth, double dt, CouplingStepStats& stats,
                            const ScalarArray* engine_inverse_masses) {
  m_node_impulses.assign(cloth.node_count(), Vec3::Zero());
  m_squeezed.clear();
  m_node_shifts.assign(cloth.node_count(), Vec3::Zero());
  m_owed_impulses.assign(cloth.node_count(), Vec3::Zero());
  m_impulse_links.clear();
  m_unresolved = {-1, -1};
  // Exact, not a heuristic: every pair a stage acts on comes from the broad phase, asked at x_t0 with margin
  // thickness / 2 (proximity) and over x_t0 to x_t1 with margin 0 (the first CCD round); both particle boxes
  // lie inside particle_box(x_t0, x_t1, thickness) and every triangle's box inside the mesh's, so when no
  // particle box meets the mesh's there is no pair, no impulse, and later CCD rounds only follow a change.
  if (fluid.positions_t0->empty() || cloth.triangles.empty() ||
      !any_particle_box_overlaps(*fluid.positions_t0, *fluid.positions_t1,
                                 std::max(m_settings.cloth_thickness, m_adhesion ? m_adhesion->range : 0.0),
                                 mesh_box(cloth))) {
    ++m_counter.skipped;
    return COUPLING_OK;
  }
  ++m_counter.passes;
  const bool record = fluid.ids != nullptr;
  if (record) m_largest.assign(fluid.positions_t0->size(), ImpulseLink{});
  const std::uint32_t status = correct(fluid, cloth, dt, stats, engine_inverse_masses);
  if (record) {
    for (std::size_t p = 0; p < m_largest.size(); ++p) {
      if (m_largest[p].impulse == 0.0) continue;
      m_impulse_links.push_back(m_largest[p]);
      m_impulse_links.back().particle_id = (*fluid.ids)[p];
    }
  }
  return status;
}

std::uint32_t Coupler::correct(const FluidView& fluid, ClothMesh& cloth, double dt, CouplingStepStats& stats,
                               const ScalarArray* engine_inverse_masses) {
  std::uint32_t status = COUPLING_OK;
  StepContext ctx(fluid, cloth, dt, stats, m_node_impulses, fluid.ids != nullptr ? &m_largest : nullptr,
                  &m_node_shifts, engine_inverse_masses, &m_squeezed, &m_owed_impulses);
  ctx.clear_changes();
  const double thickness = m_settings.cloth_thickness;
  std::vector<std::pair<Index, Index>> pairs;

  const auto repulsion_start = Clock::now();
  // Candidates for proximity (sec. 3.1: a start position within the thickness of the triangle at the step's
  // start): the particle's start point and the triangle's swept box, each grown by half the thickness,
  // overlap for every such pair. Querying the particle's swept box with both boxes grown by the whole
  // thickness finds the same contacts among several times the pairs, which the 5 mm row of bench_jet_on_cloth
  // pays for in repulsion time (bench_jet_on_cloth table_thickness_5mm, docs/performance.md).
  m_broad_phase->find_pairs(ctx.x0(), ctx.x0(), cloth, 0.5 * thickness, nullptr, pairs);
  std::vector<Contact> contacts = find_contacts(ctx, pairs, thickness);  // sec. 3.1, eq. 1
  // Adhesion first: repulsion then stops the approach it adds (a cotton plate pulled water to 0 mm of its
  // faces, inside the thickness, when it came last).
  if (m_adhesion) {
    adhere(ctx, *m_broad_phase, *m_adhesion, thickness);  // the paper's future work, sec. 6
    ++m_adhesion_counter.passes;
  }
  stats.contacts += contacts.size();
  repulse(ctx, contacts, m_settings);  // sec. 3.2, eq. 2-4
  if (m_with_friction) {
    apply_friction(ctx, contacts, m_settings);  // sec. 3.4, eq. 7-8
    ++m_friction_counter.passes;
  }
  for (const Contact& c : contacts) {
    const Vec3 v = ctx.relative_velocity(c.particle, c.triangle, c.weights);
    stats.slip_sum_mps += (v - v.dot(c.normal) * c.normal).norm();
  }
  stats.seconds_repulsion += seconds_since(repulsion_start);
  if (!m_settings.continuous) return status;

  const auto ccd_start = Clock::now();
  status |= resolve_ccd(ctx, *m_broad_phase, m_settings, &m_unresolved);  // sec. 3.3, eq. 5-6
  stats.seconds_ccd += seconds_since(ccd_start);
  return status;
}

}  // namespace drench
