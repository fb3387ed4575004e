/// libFuzzer target: scene files. The input bytes are JSON text; what nlohmann::json parses goes through
/// drench::parse_scene. A document nlohmann rejects (parse_error, or out_of_range for a number like 1e999) is
/// skipped, as read_scene_document turns those into SceneError itself; parse_scene may reject a
/// scene only with drench::Error (SceneError, or IoError); any other exception aborts after printing it, and
/// ASan/UBSan abort on memory errors and undefined behaviour.
/// Run it with scripts/fuzz; scripts/test replays fuzz/corpus/scene_loader and fuzz/regressions/scene_loader.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include <drench/common/error.hpp>
#include <drench/scene/scene_loader.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(data, data + size);
  } catch (const nlohmann::json::exception&) {
    return 0;  // not JSON: nothing of ours ran
  }
  try {
    drench::parse_scene(document, "fuzz.json");
  } catch (const drench::Error&) {
    // The documented rejection (SceneError, or IoError).
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\nfuzz_scene_loader: parse_scene threw a non-drench exception: %s\n", e.what());
    std::fflush(stderr);
    std::abort();
  }
  return 0;
}
