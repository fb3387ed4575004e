#pragma once
/// Scene files: JSON in SI units -> SceneConfig, with every key validated. The schema is documented key by
/// key in docs/scenes.md; every error names the file, the JSON path and the value.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include <drench/scene/scene_config.hpp>

namespace drench {

/// Largest scene file read (unit: bytes): the demo scenes take 1-3 KB, so 16 MiB leaves room for any scene
/// written by hand or by a program, while /dev/zero or a runaway generator is refused before it is read.
inline constexpr std::uint64_t kMaxSceneFileBytes = 16u << 20;

/// Reads a scene file, applies `overrides` and validates the result.
/// @param path  scene file (JSON)
/// @param overrides  assignments `json.path=value` (the `--set` flag), applied in order before validation;
///        `value` is parsed as JSON and taken as a string when it is not valid JSON; paths use dots for
///        object keys and `[i]` (or `.i`) for array elements, e.g. `time.dt=0.004`, `emitters[0].speed=5`.
/// @throws IoError when the file cannot be read; SceneError for malformed JSON (with line and column), an
///         unknown key, a wrong type, a value out of range, or an override whose path does not exist. The
///         message names the file (and the override), the JSON path and the value.
SceneConfig load_scene_file(const std::string& path, const std::vector<std::string>& overrides = {});

/// How errors name a scene read from `path` with `overrides`: `<path> with --set a=1 --set b=2`.
std::string scene_source(const std::string& path, const std::vector<std::string>& overrides);

/// Validates an already parsed scene document. `source` names it in error messages.
/// @param supplied  meshes a program gives beside the document's `cloth` and `obstacles`, which meet the
///        effects' needs (a CoupledWorld's Bullet cloths and bodies); a file has none
/// @throws SceneError as load_scene_file.
SceneConfig parse_scene(const nlohmann::json& document, const std::string& source,
                        const SuppliedMeshes& supplied = {});

/// Validates a `camera` object given apart from a scene (`drench render --camera`), as parse_scene validates
/// a scene's `camera` key; errors name it `camera.<key>` and `source`.
/// @throws SceneError for a value that is not an object, an unknown key, a malformed vector, a field of view
///         outside (0, 180) degrees, a position without a target (or the reverse), or a target at the
///         position.
CameraSettings parse_camera(const nlohmann::json& camera, const std::string& source);

/// Applies one `json.path=value` assignment to `document` in place.
/// @throws SceneError when the assignment has no `=`, the path is empty or malformed, an intermediate element
///         is missing or not an object/array, or an array index is out of range.
void apply_override(nlohmann::json& document, const std::string& assignment);

/// The effective scene document after overrides, serialised canonically (sorted keys, no spaces): the text
/// whose SHA-256 the summary reports as `scene_sha256`.
std::string canonical_scene_text(const nlohmann::json& document);

/// Reads a scene file and applies overrides without validating (for `scene_sha256`). The file must be a
/// regular file of at most kMaxSceneFileBytes, nested at most loader::kMaxJsonDepth (64) levels, with no key
/// twice in an object; `--set` values are held to the same. The file paths the scene names (`cloth.mesh`,
/// `obstacles[i].mesh`) come back absolute: a relative one in the file against the file's folder, one an
/// override names against the working directory.
/// @throws IoError (missing, a folder, a FIFO or device, unreadable), SceneError (too large, malformed
///         JSON, too deep, a duplicate key, a bad override); each names the file
nlohmann::json read_scene_document(const std::string& path, const std::vector<std::string>& overrides = {});

/// Lowercase hex SHA-256 of `bytes` (OpenSSL's EVP digest).
std::string sha256_hex(const std::string& bytes);

}  // namespace drench
