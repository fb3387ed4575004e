#pragma once

#include <drench/sph/pressure/pressure_solver.hpp>

namespace drench {

/// Position Based Fluids, Macklin & Mueller 2013: Jacobi iterations of the density constraint
/// C_i = max(rho_i / rho0 - 1, 0) on predicted positions. Each iteration computes at the current prediction
/// rho_i, lambda_i = -C_i / (sum_k |grad_k C_i|^2 + epsilon) (their eq. 9-11) and moves every particle by
/// dp_i = sum_j (m_j / rho0) (lambda_i + lambda_j + s_corr_ij) grad W_ij + lambda_i sum_b (Psi_b / rho0)
/// grad W_ib (their eq. 12-14, with Akinci et al. 2012's boundary particles as neighbors of zero inverse
/// mass, as SPlisHSPlasH's PBF). Only compression is a violation, as SPlisHSPlasH's: a free-surface particle
/// lacks neighbours, and pulling it in clusters the surface. FluidSolver drives it with project() from
/// positions already predicted and neighbor lists searched there (their Algorithm 1); PbfSettings has the
/// sources of the defaults. PbfSettings::precision chooses the precision of the iterations' pair sums.
class PressurePbf final : public PressureSolver {
 public:
  explicit PressurePbf(const FluidSettings& settings);

  /// Moves ctx.particles.positions, the predicted positions x* (unit: m), by settings.pbf.iterations Jacobi
  /// iterations; ctx.particles.densities end as the densities of the last iteration's positions before its
  /// move (unit: kg/m^3), and the stats report their error, as PCISPH's.
  /// @param dt  the sub-step (unit: s), > 0: scales boundary_pressure_factors, and the artificial pressure's
  ///        move below PbfSettings::scorr_substep
  /// @param first_moving  the first of ctx.boundary's points that belong to moving bodies (those at and past
  ///        it get boundary_pushes()); ctx.boundary.size() or more: none
  /// Preconditions: ctx's neighbor lists were searched at the predicted positions.
  PressureStats project(const FluidContext& ctx, Scalar dt, std::size_t first_moving);

  /// The PressureSolver contract: predicts x + dt v_adv, projects it, and returns the acceleration that
  /// lands there, (x* - x - dt v_adv) / dt^2; ctx.particles.positions are unchanged. ctx's neighbor lists
  /// must hold every pair within the support at the predicted positions (a skin of dt max|v_adv| or more).
  PressureStats solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                      Vec3Array& accelerations) override;

  /// -sum over the last projection's iterations of lambda_i / (rho0 dt^2): its boundary move as Akinci's
  /// -w_i sum_b Psi_b grad W_ib over dt^2, were every iteration's gradient that of one position. FluidSolver
  /// takes a moving body's reaction from boundary_pushes() instead, which has each iteration's.
  void boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const override;

  /// What a moving boundary point pushed a particle by in the last projection: m_i / dt times the sum over
  /// its iterations of the move it gave the particle, w_i Psi_b f_ib (x_i - x_b) at that iteration's
  /// positions and lambda (eq. 12's boundary term; unit: N s). The particle's momentum changed by minus this,
  /// so the body takes it, and momentum is exchanged exactly: with the gradients of the prediction alone, two
  /// boxes thrown into water lost 3.5% of the momentum at 1 ms steps
  /// (RigidBodies.WaterAndBodiesKeepTheirMomentumInCollisionsWithPbf).
  struct BoundaryPush {
    Index particle;  ///< i
    Index entry;     ///< the entry of ctx.boundary_neighbors.indices that names the point
    Vec3 push;       ///< (unit: N s)
  };
  /// Every pair of a particle and a moving boundary point in its list, in particle then list order.
  const std::vector<BoundaryPush>& boundary_pushes() const { return m_boundary_pushes; }

 private:
  PbfSettings m_settings;
  Scalar m_rest_density;      // rho0 (unit: kg/m^3)
  Scalar m_epsilon;           // relaxation times the lattice's sum_k |grad_k C|^2 (unit: 1/m^2)
  Scalar m_min_denominator;   // a tenth of that sum: the least denominator of lambda (unit: 1/m^2)
  Scalar m_scorr_scale;       // k / (the lattice's sum_k |grad_k C|^2): s_corr in lambda's unit (unit: m^2)
  Scalar m_inv_w_dq;          // 1 / W(dq) (unit: m^3)
  Scalar m_last_dt = 0;       // the sub-step of the last projection (unit: s)
  PackedPointArray m_points;  // N: the current prediction (unit: m), w = mass (unit: kg)
  PackedPointArray m_lambda_points;  // N: the same positions, w = -lambda_i / rho0 (unit: m^5/kg)
  ScalarArray m_denominator;         // N: sum_k |grad_k C_i|^2 + epsilon, floored, this iteration (1/m^2)
  Vec3Array m_scorr_moves;           // N: the artificial pressure's move per iteration (unit: m)
  ScalarArray m_lambda_sum;          // N: lambda_i summed over the projection's iterations (unit: m^2)
  Vec3Array m_moves;                 // N: this iteration's dp_i without s_corr (unit: m)
  ScalarArray m_fluid_factors;       // per fluid list entry: grad W = f (x_i - x_j) this iteration (1/m^5)
  ScalarArray m_boundary_factors;    // per boundary list entry: the same with the boundary point (1/m^5)
  // For IterationPrecision::SINGLE, in float, every point relative to the centre of the fluid's bounding box
  // at the projection's start (single_precision_origin, unit: m); m_points stays the double prediction the
  // moves are added to, and these are rounded from it after every move. Empty in double precision.
  PackedPointFArray m_points_float;             // N: w = mass (unit: kg)
  PackedPointFArray m_lambda_points_float;      // N: w = -lambda_i / rho0 (unit: m^5/kg)
  PackedPointFArray m_boundary_float;           // ctx.boundary, w = Psi_b (unit: kg); made at each projection
  std::vector<float> m_fluid_factors_float;     // as m_fluid_factors, in float (unit: 1/m^5)
  std::vector<float> m_boundary_factors_float;  // as m_boundary_factors, in float (unit: 1/m^5)
  // N, single precision only: the blocks of each particle's fluid neighbors (pbf_constraint_float).
  std::vector<std::uint32_t> m_neighbor_blocks;
  // Per chunk of the constraint pass: the sum and largest of the violations, and the blocks of 2^k particles
  // (k: project's block_shift) that hold a particle with w != 0 (pbf_moves_float).
  struct ChunkErrors {
    Scalar sum = 0.0, max = 0.0;
    std::uint32_t moving_blocks = 0;
  };
  std::vector<ChunkErrors> m_chunk_errors;
  std::vector<BoundaryPush> m_boundary_pushes;
};

}  // namespace drench
