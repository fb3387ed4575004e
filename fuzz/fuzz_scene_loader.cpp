/// libFuzzer target: scene files. The input bytes are JSON text; what the scene loader's JSON parser accepts
/// (loader::parse_json_strict: nlohmann's, at most 64 levels, no duplicate keys) goes through
/// drench::parse_scene. A document nlohmann rejects (parse_error, or out_of_range for a number like 1e999) is
/// skipped, as read_scene_document turns those into SceneError itself; parse_scene may reject a
/// scene only with drench::Error (SceneError, or IoError); any other exception aborts after printing it, and
/// ASan/UBSan abort on memory errors and undefined behaviour.
/// An accepted scene whose resource estimate (scene_resources.hpp) is small is then built as a Simulation and
/// stepped a few times: scripts/fuzz runs this target under libFuzzer's -malloc_limit_mb and -rss_limit_mb,
/// so a scene the estimate underrates (a refusal that is missing) shows up as an allocation failure. A scene
/// with a cloth is refused by the Simulation here (this target has no Bullet cloth engine).
/// Run it with scripts/fuzz; scripts/test replays fuzz/corpus/scene_loader and fuzz/regressions/scene_loader.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include <drench/common/error.hpp>
#include <drench/scene/json_reader.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_resources.hpp>
#include <drench/scene/simulation.hpp>

namespace {

/// The scenes simulated: an estimate of at most this much memory (unit: bytes), far below the malloc and
/// RSS limits of scripts/fuzz (512 MB, 2 GB), and few enough particles that a step takes milliseconds.
constexpr double kSimulatedMemoryBytes = 96e6;
constexpr double kSimulatedParticles = 3000;
constexpr int kSimulatedSteps = 3;

/// Builds and steps an accepted scene whose estimate is small. The steps are a tenth of the CFL limit at the
/// speed of sound or fluid.max_speed, whichever is faster, so that the fluid takes about one sub-step each
/// until a particle passes fluid.max_speed and stops the run: no input can make this hang. (A scene without
/// fluid.max_speed is not stepped for that reason.)
void simulate(const drench::SceneConfig& config) {
  const drench::ResourceEstimate estimate = drench::estimate_resources(config);
  if (!(estimate.memory_bytes.value <= kSimulatedMemoryBytes) ||
      !(estimate.particles.value + estimate.boundary_particles.value <= kSimulatedParticles))
    return;
  drench::Simulation simulation(config);
  if (!config.fluid.max_speed) return;
  const double fastest = std::max({simulation.speed_of_sound(), *config.fluid.max_speed, 1.0});
  const double dt =
      std::min(config.time.dt, 0.1 * config.fluid.cfl * config.fluid.particle_spacing / fastest);
  for (int step = 0; step < kSimulatedSteps && !simulation.finished(); ++step) {
    if (!simulation.step(dt).ok()) break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  nlohmann::json document;
  try {
    // As read_scene_document parses a file: at most 64 levels deep, no duplicate keys.
    document =
        drench::loader::parse_json_strict(std::string(data, data + size), drench::loader::kMaxJsonDepth);
  } catch (const nlohmann::json::exception&) {
    return 0;  // not JSON: nothing of ours ran
  } catch (const drench::SceneError&) {
    return 0;  // too deep, or a duplicate key: the documented rejection
  }
  try {
    simulate(drench::parse_scene(document, "fuzz.json"));
  } catch (const drench::Error&) {
    // The documented rejection (SceneError, or IoError).
  } catch (const std::exception& e) {
    std::fprintf(stderr,
                 "\nfuzz_scene_loader: parse_scene or the simulation threw a non-drench exception: %s\n",
                 e.what());
    std::fflush(stderr);
    std::abort();
  }
  return 0;
}
