#include <drench/scene/scene_runner.hpp>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>
#include <drench/common/stopwatch.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/scene/effect_registry.hpp>
#include <drench/scene/frame_files.hpp>

namespace drench {

namespace {

std::string frame_name(const char* what, std::int64_t frame) {
  char name[48];
  std::snprintf(name, sizeof name, "%s_%04lld.ply", what, static_cast<long long>(frame));
  return name;
}

/// A single self-overwriting line on a terminal, at most five times a second; silent elsewhere.
class ProgressLine {
 public:
  explicit ProgressLine(bool wanted) : m_enabled(wanted && ::isatty(STDERR_FILENO)) {}
  void update(const Simulation& sim, std::int64_t last_step, double wall) {
    if (!m_enabled || wall - m_last < 0.2) return;
    m_last = wall;
    const double rate = sim.steps_done() / std::max(wall, 1e-9);
    const double eta = (last_step - sim.steps_done()) / std::max(rate, 1e-9);
    const TimeSettings& t = sim.config().time;
    // With adaptive steps the count is a bound: the time simulated measures progress.
    const double end = t.adaptive ? t.duration : last_step * t.dt;
    const double left = t.adaptive ? (end - sim.time()) / std::max(sim.time(), 1e-9) * wall : eta;
    std::fprintf(stderr, "\r  t = %.3f / %.3f s   %.1f steps/s   %zu particles   ETA %.0f s   ", sim.time(),
                 end, rate, sim.particles().size(), left);
    std::fflush(stderr);
  }
  ~ProgressLine() {
    if (m_enabled && m_last > 0) std::fprintf(stderr, "\n");
  }

 private:
  bool m_enabled;
  double m_last = 0;
};

/// Replaces every non-finite number under `value` by null and records it in `notes` under its path ("a.b",
/// "a[2]"): JSON has no NaN or infinity, and a bare null would not say which it was.
void mark_non_finite(nlohmann::json& value, const std::string& path, nlohmann::json& notes) {
  if (value.is_object()) {
    for (auto it = value.begin(); it != value.end(); ++it)
      mark_non_finite(it.value(), path.empty() ? it.key() : path + "." + it.key(), notes);
  } else if (value.is_array()) {
    for (std::size_t i = 0; i < value.size(); ++i)
      mark_non_finite(value[i], path + "[" + std::to_string(i) + "]", notes);
  } else if (value.is_number_float() && !std::isfinite(value.get<double>())) {
    const double number = value.get<double>();
    notes[path] = std::isnan(number) ? "nan" : number > 0 ? "inf" : "-inf";
    value = nullptr;
  }
}

}  // namespace

void apply_non_finite_rule(nlohmann::json& summary) {
  nlohmann::json notes = summary.value("non_finite", nlohmann::json::object());
  summary.erase("non_finite");
  mark_non_finite(summary, "", notes);
  if (!notes.empty()) summary["non_finite"] = notes;
}

nlohmann::json make_summary(const Simulation& sim, double wall_seconds, const std::string& scene_sha256,
                            const StepStatus& status, const EffectCounter& surface) {
  const FluidStatistics& f = sim.fluid().statistics();
  const double substeps = std::max<std::int64_t>(f.substeps, 1);
  const auto& t = f.timings_s;
  nlohmann::json s;
  s["steps"] = sim.steps_done();
  s["sim_time_s"] = sim.time();
  s["particles"] = sim.particles().size();
  s["created"] = sim.created();
  s["removed"] = sim.removed();
  s["density_error"] = {{"mean", f.density_error_sum / substeps},
                        {"max", f.density_error_max},
                        {"particle_max", f.particle_density_error_max}};
  s["pressure_iterations"] = {{"mean", f.pressure_iterations / substeps}, {"max", f.max_pressure_iterations}};
  if (sim.config().fluid.pressure_solver == PressureSolverKind::DFSPH) {
    s["divergence_iterations"] = {{"mean", f.divergence_iterations / substeps},
                                  {"max", f.max_divergence_iterations}};
  }
  s["fluid_substeps"] = {
      {"total", f.substeps}, {"max_per_step", f.max_substeps_per_step}, {"halved", f.substeps_halved}};
  if (sim.steps_done() > 0) {
    s["dt_s"] = {{"min", sim.min_dt()}, {"mean", sim.sum_dt() / sim.steps_done()}, {"max", sim.max_dt()}};
  }
  s["boundary_guards"] = f.boundary_guards;
  s["timings_s"] = {{"fluid", t.total},          {"neighbors", t.neighbors}, {"density", t.density},
                    {"forces", t.forces},        {"pressure", t.pressure},   {"integrate", t.integrate},
                    {"emit", sim.emit_seconds()}};
  s["wall_s"] = wall_seconds;
  s["threads"] = thread_count();
  s["version"] = DRENCH_VERSION;
  s["scene_sha256"] = scene_sha256;
  s["effects"] = sim.effects();
  EffectCounters counters = sim.effect_counters();
  counters.surface = surface;
  s["effect_passes"] = nlohmann::json::object();
  s["effects_ran"] = nlohmann::json::array();
  for (const EffectEntry& effect : effect_registry()) {
    const EffectCounter& c = counters.*effect.counter;
    if (c.constructed == 0) continue;
    s["effect_passes"][effect.name] = c.passes;
    if (c.passes > 0) s["effects_ran"].push_back(effect.name);
  }
  if (counters.coupling.constructed > 0) s["coupling_skipped_steps"] = counters.coupling.skipped;
  if (counters.substep_obstacle.constructed > 0)
    s["obstacle_skipped_substeps"] = counters.substep_obstacle.skipped;
  if (counters.leak_audit.constructed > 0) s["leak_audit_skipped_steps"] = counters.leak_audit.skipped;
  s["pressure_solver"] = pressure_solver_name(sim.config().fluid.pressure_solver);
  s["speed_of_sound_mps"] = sim.speed_of_sound();
  s["status"] = status.describe().empty() ? "ok" : status.describe();
  s["max_speed_mps"] = {{"particle", sim.max_particle_speed()}};
  if (sim.cloth()) {
    s["max_speed_mps"]["node"] = sim.max_node_speed();
    s["max_cloth_strain"] = sim.max_cloth_strain();
  }
  if (sim.closed()) {
    const double initial = sim.initial_fluid_energy(), final = sim.fluid_energy();
    s["fluid_energy_J"] = {{"initial", initial}, {"final", final}};
    // Relative to the energy the fluid started with; null for a fluid that started with none to lose.
    s["energy_drift"] = initial > 0.0 ? nlohmann::json((final - initial) / initial) : nlohmann::json();
  }
  if (sim.contact_mesh()) {
    const CouplingStepStats& c = sim.coupling_stats();
    if (const ClothEngine* cloth = sim.cloth()) {
      s["cloth_faces"] = cloth->mesh().triangle_count();
      s["cloth_mass_kg"] = cloth->total_mass();
    }
    if (!sim.obstacles().empty()) {
      std::size_t faces = 0;
      for (const TriangleMesh& obstacle : sim.obstacles())
        faces += obstacle.triangles.size();
      s["obstacle_faces"] = faces;
      if (sim.cloth()) {
        const CouplingStepStats held = sim.cloth_obstacle_stats();
        s["cloth_obstacle_contacts"] = held.contacts;
        s["cloth_obstacle_impacts"] = held.ccd_impacts;
      }
    }
    s["contacts"] = c.contacts;
    s["ccd_impacts"] = c.ccd_impacts;
    s["ccd_iterations"] = c.ccd_iterations;
    s["failsafe_activations"] = c.failsafe_activations;
    s["stopped_particles"] = c.stopped_particles;
    s["stopped_nodes"] = c.stopped_nodes;
    s["carried_by_zones"] = c.carried_by_zones;
    s["squeezed_out"] = c.squeezed_out;
    s["squeezed_out_kg"] = c.squeezed_out_mass;
    s["obstacle_stops"] = c.obstacle_stops;
    s["mean_contact_slip_mps"] = c.contacts > 0 ? c.slip_sum_mps / static_cast<double>(c.contacts) : 0.0;
    s["coupling_status"] = sim.coupling_status();
    s["timings_s"]["cloth"] = sim.cloth_seconds();
    s["timings_s"]["coupling"] = sim.coupling_seconds();
    s["timings_s"]["repulsion"] = c.seconds_repulsion;
    s["timings_s"]["ccd"] = c.seconds_ccd;
    if (sim.config().has_effect("leak_audit")) {
      s["leaks"] = sim.leak_stats().leaks;
      s["jump_leaks"] = sim.leak_stats().jump_leaks;
      s["timings_s"]["leak_audit"] = sim.leak_stats().seconds;
    }
    if (const ClothWetting* wetting = sim.wetting()) {
      // Every kilogram accounted for: what entered (initial particles, nozzles) is in the fluid, in the
      // cloth, or was removed by a kill region.
      double fluid = 0.0;
      for (const Scalar m : sim.particles().masses)
        fluid += m;
      const WettingStepStats& w = sim.wetting_stats();
      s["mass_kg"] = {{"fluid", fluid},
                      {"held_by_cloth", wetting->held()},
                      {"absorbed", w.absorbed_kg},
                      {"dripped", w.dripped_kg},
                      {"killed", sim.killed_mass()},
                      {"squeezed_out", sim.coupling_stats().squeezed_out_mass},
                      {"initial_total", sim.emitted_mass()},
                      {"final_total",
                       fluid + wetting->held() + sim.killed_mass() + sim.coupling_stats().squeezed_out_mass}};
      s["particles_absorbed"] = w.particles_absorbed;
      s["particles_dripped"] = w.particles_dripped;
      s["wet_area_fraction"] = wetting->wet_area_fraction();
      s["timings_s"]["wetting"] = w.seconds;
    }
  }
  apply_non_finite_rule(s);
  return s;
}

RunResult run_scene(Simulation& sim, const RunOptions& options) {
  namespace fs = std::filesystem;
  const fs::path out(options.out_dir);
  const fs::path frames = out / "frames";
  std::error_code ec;
  fs::create_directories(frames, ec);
  if (ec) throw IoError("cannot create " + frames.string() + ": " + ec.message());
  // First, so that even a run stopped early leaves what `drench reconstruct` needs beside its frames.
  if (!options.scene_document.is_null())
    write_file_atomic((out / "scene.json").string(), options.scene_document.dump(2) + "\n");

  const auto start = std::chrono::steady_clock::now();
  auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  const std::int64_t last_step =
      options.max_steps ? std::min(*options.max_steps, sim.total_steps()) : sim.total_steps();
  const double frame_rate = sim.config().time.frame_rate;
  double output_seconds = 0, surface_seconds = 0, surface_audit_seconds = 0;
  std::uint64_t surface_intersections = 0;
  const bool surface = sim.config().has_effect("surface");
  EffectCounter surface_counter;
  surface_counter.constructed = surface ? 1 : 0;
  // The surface is made from the positions as the frames save them (float32): then `drench reconstruct`
  // on the saved files gives the same surface files byte for byte (from the doubles, a third to two thirds
  // of the vertices differ by a float ulp). Obstacles are static: rounded once.
  std::vector<Vec3Array> saved_obstacles;
  if (surface) {
    for (const TriangleMesh& obstacle : sim.obstacles())
      saved_obstacles.push_back(positions_as_saved(obstacle.positions));
  }
  std::int64_t frame = 0;
  // The water kill regions had removed when each frame was written: it is in no frame, and a comparison
  // with a reference (compare/run_comparison.hpp) must still count it.
  nlohmann::json killed_by_frame = nlohmann::json::array();
  auto write_due_frames = [&] {
    if (frame_rate <= 0) return;
    // A frame is due when the simulated time has reached its time, up to a thousandth of a step.
    while (frame / frame_rate <= sim.time() + 1e-3 * sim.config().time.dt) {
      ScopedTimer timer(output_seconds);
      write_particles_ply((frames / frame_name("fluid", frame)).string(), sim.particles());
      killed_by_frame.push_back(sim.killed_mass());
      if (const ClothEngine* cloth = sim.cloth()) {
        // Between steps positions_t1 is where the cloth is now (end_step wrote it back to the engine).
        if (const ClothWetting* wetting = sim.wetting()) {
          write_cloth_ply((frames / frame_name("cloth", frame)).string(), cloth->mesh(), wetting->wetness());
        } else {
          write_cloth_ply((frames / frame_name("cloth", frame)).string(), cloth->mesh());
        }
      }
      if (surface) {
        std::vector<SurfaceObstacle> obstacles;
        Vec3Array cloth_positions;
        if (const ClothEngine* cloth = sim.cloth()) {
          cloth_positions = positions_as_saved(cloth->mesh().positions_t1);
          obstacles.push_back({&cloth_positions, &cloth->mesh().triangles});
        }
        for (std::size_t k = 0; k < saved_obstacles.size(); ++k)
          obstacles.push_back({&saved_obstacles[k], &sim.obstacles()[k].triangles});
        const Vec3Array particles = positions_as_saved(sim.particles().positions);
        SurfaceStats stats;
        const SurfaceMesh mesh = reconstruct_surface(particles, sim.config().fluid.particle_spacing,
                                                     sim.config().surface, obstacles, &stats);
        surface_seconds += stats.seconds;
        ++surface_counter.passes;
        {
          // The claim of sec. 4, measured on every frame by a count that does not trust the reconstruction.
          ScopedTimer audit(surface_audit_seconds);
          surface_intersections += count_surface_intersections(mesh, obstacles);
        }
        write_surface_ply((frames / frame_name("surface", frame)).string(), mesh);
      }
      ++frame;
    }
  };

  // Static: written once, beside the frames.
  if (!sim.obstacles().empty()) write_obstacles_ply((out / "obstacles.ply").string(), sim.obstacles());

  RunResult result;
  ProgressLine progress(options.progress);
  write_due_frames();
  auto stop_asked = [&] { return options.stop && options.stop->load(std::memory_order_relaxed); };
  while (sim.steps_done() < last_step && !sim.finished()) {
    // Between steps only: the state and the frames on disk then agree with summary.json.
    if (stop_asked()) {
      result.interrupted = true;
      break;
    }
    result.status |= sim.step();
    if (!result.status.ok()) break;
    write_due_frames();
    progress.update(sim, last_step, wall());
  }
  result.summary = make_summary(sim, wall(), options.scene_sha256, result.status, surface_counter);
  if (result.interrupted) {
    // What went wrong before the signal stays said: a leak does not become a clean interruption.
    const std::string flags = result.summary["status"];
    result.summary["status"] = flags == "ok" ? std::string("interrupted") : "interrupted; " + flags;
  }
  result.effects = sim.effect_counters();
  result.effects.surface = surface_counter;
  result.summary["frames"] = frame;
  if (!sim.config().kill_regions.empty()) result.summary["killed_kg_by_frame"] = killed_by_frame;
  // Reconstruction and its audit are their own lines, not output.
  result.summary["timings_s"]["output"] = output_seconds - surface_seconds - surface_audit_seconds;
  if (surface) {
    result.summary["timings_s"]["surface"] = surface_seconds;
    result.summary["timings_s"]["surface_audit"] = surface_audit_seconds;
    result.summary["surface_intersections"] = surface_intersections;
  }
  apply_non_finite_rule(result.summary);
  write_file_atomic((out / "summary.json").string(), result.summary.dump(2) + "\n");
  return result;
}

}  // namespace drench
