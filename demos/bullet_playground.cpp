// bullet_playground: water in a game's world. The world is the game's, built with plain Bullet calls
// (demos/bullet_playground_world.hpp): a ground plane, a table, a hammock pinned all round, a
// curtain pinned along its top, a 3 kg ball and a lighter one dropped into the hammock, a light crate on the
// table. drench adds two jets and wetting through one CoupledWorld for both cloths, and the game steps it at
// its fixed 1/60 s instead of world.stepSimulation.
//
//   build/demos/bullet_playground --out out/playground       4 s; frames every 2 steps (30 per second)
//   build/demos/drench render out/playground                 their PNGs, in out/playground/render/
//   build/demos/bullet_playground --threads 1 --no-rigid     without the balls and the crate; no files
//
// Prints a line per frame (step) and, at the end, the wall time per frame of each stage (median and 99th
// percentile, CoupledStepReport::seconds), the leaks (the target is 0) and the fastest particle and node.
// Exit status 0; 1 for bad arguments or an output folder that is not new or empty; 2 when a step failed or a
// particle leaked through a cloth or a body.
//
// The --out folder holds what `drench run` writes (docs/output.md), through the core's frame writers, so that
// `drench render` draws it: drench_run.json (the manifest), scene.json (the fluid part of the scene with a
// camera: the cloths, the bodies and the coupling are the Bullet world's, not a scene file's),
// frames/fluid_NNNN.ply, frames/cloth_NNNN.ply (both cloths in one mesh, hammock first, with their wetness),
// obstacles.ply (the world's static objects: the ground's square and the table), frames/bodies_NNNN.ply (the
// moving bodies where they are in that frame) and summary.json (the figures printed at the end).

#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include <drench/bullet/bullet_conversions.hpp>
#include <drench/bullet/coupled_world.hpp>
#include <drench/bullet/shape_mesh.hpp>
#include <drench/common/parallel.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/scene/frame_files.hpp>
#include <drench/scene/output_folder.hpp>
#include <drench/scene/scene_loader.hpp>
#include "bullet_playground_world.hpp"
#include "cli_checks.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Options {
  std::string out;  // empty: no files
  double seconds = 4.0;
  int threads = 0;  // 0: drench's default
  bool no_rigid = false;
  int frames_every = 2;
};

/// `mesh` with its vertices split where faces meet at more than 30 degrees, so that the frame files' vertex
/// normals (area-weighted over a vertex's faces) keep a box's faces flat and a sphere's smooth.
drench::TriangleMesh with_sharp_edges(const drench::TriangleMesh& mesh) {
  const double cos_crease = std::sqrt(3.0) / 2.0;  // cos 30 degrees
  drench::TriangleMesh out;
  // Per vertex of `mesh`, its copies in `out`: the normal of the face that made the copy, and its index.
  std::vector<std::vector<std::pair<drench::Vec3, drench::Index>>> copies(mesh.positions.size());
  for (const drench::Triangle& t : mesh.triangles) {
    const drench::Vec3& a = mesh.positions[t[0]];
    const drench::Vec3 normal = (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).normalized();
    drench::Triangle split;
    for (int k = 0; k < 3; ++k) {
      auto& list = copies[t[k]];
      const auto same = std::find_if(list.begin(), list.end(),
                                     [&](const auto& copy) { return copy.first.dot(normal) > cos_crease; });
      if (same != list.end()) {
        split[k] = same->second;
      } else {
        split[k] = static_cast<drench::Index>(out.positions.size());
        out.positions.push_back(mesh.positions[t[k]]);
        list.emplace_back(normal, split[k]);
      }
    }
    out.triangles.push_back(split);
  }
  return out;
}

/// The world's rigid objects as one triangle mesh each, where they are now: the static ones (ground, table)
/// or the moving ones (balls, crate). The same triangles the water meets (shape_mesh), for the frame files.
std::vector<drench::TriangleMesh> rigid_meshes(const btCollisionWorld& world, bool moving) {
  std::vector<drench::TriangleMesh> meshes;
  const btCollisionObjectArray& objects = world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btCollisionObject& object = *objects[i];
    if (object.getInternalType() != btCollisionObject::CO_RIGID_BODY) continue;  // the cloths
    if (object.isStaticObject() == moving) continue;
    drench::TriangleMesh mesh = drench::bullet::shape_mesh(*object.getCollisionShape());
    for (drench::Vec3& x : mesh.positions)
      x = drench::bullet::to_vec3(object.getWorldTransform() * drench::bullet::to_bt(x));
    meshes.push_back(with_sharp_edges(mesh));
  }
  return meshes;
}

std::string frame_file(const fs::path& out, const char* what, long long frame) {
  char name[48];
  std::snprintf(name, sizeof name, "%s_%04lld.ply", what, frame);
  return (out / "frames" / name).string();
}

/// What `drench render` reads of scene.json: the particle size, the frame rate and the camera; with the
/// jets and the kill region, so that it also says where the water comes from and goes. Parsed back before it
/// is written, so that render cannot refuse it.
json render_scene(const drench::SceneConfig& scene, int frames_every) {
  const auto vec = [](const drench::Vec3& v) { return json::array({v.x(), v.y(), v.z()}); };
  json emitters = json::array();
  for (const drench::EmitterSettings& e : scene.emitters) {
    emitters.push_back({{"type", "nozzle"},
                        {"center", vec(e.nozzle.center)},
                        {"direction", vec(e.nozzle.direction)},
                        {"radius", e.nozzle.radius},
                        {"speed", e.nozzle.speed},
                        {"max_particles", e.nozzle.max_particles}});
  }
  json kill = json::array();
  for (const drench::KillRegionSettings& k : scene.kill_regions) {
    if (k.kind == drench::KillRegionSettings::Kind::BOX) {
      kill.push_back({{"type", "box"}, {"min", vec(k.min)}, {"max", vec(k.max)}});
    } else {
      kill.push_back({{"type", "plane"}, {"point", vec(k.point)}, {"normal", vec(k.normal)}});
    }
  }
  json document = {
      {"gravity", vec(scene.gravity)},
      {"fluid",
       {{"rest_density", scene.fluid.rest_density}, {"particle_spacing", scene.fluid.particle_spacing}}},
      {"emitters", emitters},
      {"kill_regions", kill},
      {"time",
       {{"dt", scene.time.dt},
        {"duration", scene.time.duration},
        {"frame_rate", 1.0 / (frames_every * scene.time.dt)}}},
      {"camera", {{"position", {-0.05, 1.15, 1.6}}, {"target", {-0.05, 0.5, 0.0}}, {"fov_deg", 45}}},
  };
  drench::parse_scene(document, "bullet_playground's scene.json");
  return document;
}

/// Writes the frame files of frame `frame` (docs/output.md), as `drench run` does.
void write_frame(const fs::path& out, long long frame, drench::bullet::CoupledWorld& coupled) {
  drench::write_particles_ply(frame_file(out, "fluid", frame), coupled.particles());
  const drench::ClothWetting* wetting = coupled.simulation().wetting();
  if (wetting) {
    drench::write_cloth_ply(frame_file(out, "cloth", frame), coupled.cloth_mesh(), wetting->wetness());
  } else {
    drench::write_cloth_ply(frame_file(out, "cloth", frame), coupled.cloth_mesh());
  }
  const std::vector<drench::TriangleMesh> bodies = rigid_meshes(coupled.world(), true);
  if (!bodies.empty()) drench::write_obstacles_ply(frame_file(out, "bodies", frame), bodies);
}

/// Wall time per frame of one stage (unit: s), one entry per step.
struct Stage {
  const char* name;
  std::vector<double> seconds;
};

/// The q-quantile of `values` by the nearest rank (q = 0.5: the median).
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  const std::size_t at = std::min(values.size(), std::max<std::size_t>(rank, 1)) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<long>(at), values.end());
  return values[at];
}

int run(const Options& options) {
  if (options.threads > 0) drench::bullet::CoupledWorld::set_thread_count(options.threads);
  const bool files = !options.out.empty();
  const fs::path out(options.out);
  if (files) {
    std::vector<std::string> patterns = drench::run_output_patterns();
    patterns.push_back("frames/bodies_*.ply");
    drench::prepare_output_folder(options.out, "--out", "bullet_playground", patterns, false);
    fs::create_directories(out / "frames");
  }

  // ---- The game's world, and drench's CoupledWorld around it --------------------------------------------
  playground::World game(!options.no_rigid);
  const drench::SceneConfig scene = playground::scene(options.seconds);
  drench::bullet::CoupledWorld coupled(game.world, game.cloths(), scene);

  if (files) {
    drench::write_file_atomic((out / "scene.json").string(),
                              render_scene(scene, options.frames_every).dump(2) + "\n");
    drench::write_obstacles_ply((out / "obstacles.ply").string(), rigid_meshes(game.world, false));
    write_frame(out, 0, coupled);
  }
  std::printf("bullet_playground: %s, %d thread(s), %.2f s in steps of 1/60 s\n",
              options.no_rigid ? "without rigid bodies" : "with 2 balls and a crate",
              drench::bullet::CoupledWorld::thread_count(), options.seconds);

  std::vector<Stage> stages = {{"emit", {}},     {"fluid", {}}, {"cloth", {}}, {"rigid", {}},
                               {"coupling", {}}, {"other", {}}, {"total", {}}};
  const auto steps = static_cast<long long>(std::llround(options.seconds / playground::kDt));
  std::uint64_t leaks = 0;
  bool failed = false;
  std::string failure;
  const auto start = std::chrono::steady_clock::now();
  for (long long n = 1; n <= steps; ++n) {
    const drench::bullet::CoupledStepReport report = coupled.step();  // instead of world.stepSimulation
    const auto& s = report.seconds;
    const double other = s.total - (s.emit + s.fluid + s.cloth + s.rigid + s.coupling);
    const double values[] = {s.emit, s.fluid, s.cloth, s.rigid, s.coupling, other, s.total};
    for (std::size_t k = 0; k < stages.size(); ++k)
      stages[k].seconds.push_back(values[k]);
    leaks += report.leak_stats.leaks;
    std::printf(
        "frame %4lld  t %.3f s  particles %5zu  contacts %5llu  ms: fluid %6.1f  cloth %5.1f  rigid %5.1f  "
        "coupling %6.1f  total %6.1f",
        n, coupled.time(), coupled.particles().size(),
        static_cast<unsigned long long>(report.coupling_stats.contacts), 1e3 * s.fluid, 1e3 * s.cloth,
        1e3 * s.rigid, 1e3 * s.coupling, 1e3 * s.total);
    if (game.ball) {
      const btVector3 ball = game.ball->getCenterOfMassPosition(),
                      light = game.light_ball->getCenterOfMassPosition();
      std::printf("  balls at (%.2f, %.2f, %.2f) (%.2f, %.2f, %.2f)", ball.x(), ball.y(), ball.z(), light.x(),
                  light.y(), light.z());
    }
    std::printf("\n");
    if (files && n % options.frames_every == 0) write_frame(out, n / options.frames_every, coupled);
    if (report.failed()) {
      failed = true;
      failure = report.fluid.describe();
      if (!report.ok()) break;  // the state is no longer worth stepping
    }
  }

  // ---- The summary ---------------------------------------------------------------------------------------
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const drench::Simulation& sim = coupled.simulation();
  std::printf("\nms per frame   median      p99\n");
  json ms;
  for (const Stage& stage : stages) {
    const double median = 1e3 * quantile(stage.seconds, 0.5), p99 = 1e3 * quantile(stage.seconds, 0.99);
    std::printf("  %-9s %8.2f %8.2f\n", stage.name, median, p99);
    ms[stage.name] = {{"median", median}, {"p99", p99}};
  }
  std::printf(
      "particles %zu (created %lld, removed %lld); leaks %llu; fastest particle %.2f m/s, node %.2f m/s\n",
      coupled.particles().size(), static_cast<long long>(coupled.created()),
      static_cast<long long>(coupled.removed()), static_cast<unsigned long long>(leaks),
      sim.max_particle_speed(), sim.max_node_speed());
  std::printf("water held: hammock %.3f kg, curtain %.3f kg", coupled.water_held(0), coupled.water_held(1));
  if (game.ball)
    std::printf("; the 3 kg ball's centre at y = %.3f m", game.ball->getCenterOfMassPosition().y());
  std::printf("\n");
  if (failed) std::printf("status: %s\n", failure.c_str());

  if (files) {
    const json summary = {
        {"status", failed ? failure : std::string("ok")},
        {"rigid_bodies", !options.no_rigid},
        {"steps", coupled.steps()},
        {"sim_time_s", coupled.time()},
        {"frames", coupled.steps() / options.frames_every + 1},
        {"threads", drench::bullet::CoupledWorld::thread_count()},
        {"wall_s", wall},
        {"particles", coupled.particles().size()},
        {"created", coupled.created()},
        {"removed", coupled.removed()},
        {"leaks", leaks},
        {"max_speed_mps", {{"particle", sim.max_particle_speed()}, {"node", sim.max_node_speed()}}},
        {"water_held_kg", {{"hammock", coupled.water_held(0)}, {"curtain", coupled.water_held(1)}}},
        {"ms_per_frame", ms},
    };
    drench::write_file_atomic((out / "summary.json").string(), summary.dump(2) + "\n");
  }
  return failed || leaks > 0 ? 2 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"water in a game's Bullet world: a hammock, a curtain, balls and a crate under two jets"};
  app.add_option("--out", options.out,
                 "folder for the frames drench render draws (new or empty); none: no files");
  app.add_option("--seconds", options.seconds, "simulated time (unit: s)")
      ->check(drench::cli::finite_positive());
  app.add_option("--threads", options.threads, "threads of drench's loops (default: the CPUs)")
      ->check(CLI::Range(1, drench::kMaxThreadCount));
  app.add_flag("--no-rigid", options.no_rigid,
               "leave out the balls and the crate (the ground and table stay)");
  app.add_option("--frames-every", options.frames_every, "write a frame every N steps")
      ->check(CLI::Range(1, 1000000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;
  }
  try {
    return run(options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bullet_playground: %s\n", e.what());
    return 1;
  }
}
