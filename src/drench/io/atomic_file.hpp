#pragma once
/// Output files appear whole or not at all: written to a temporary name beside the target, then renamed.

#include <string>

namespace drench {

/// Writes `bytes` to `path` through `path.tmp-<pid>` and an atomic rename, so that a reader (or a crash)
/// never sees a half-written file and an existing file is replaced only by a complete one.
/// @throws IoError naming the path and the system's reason.
void write_file_atomic(const std::string& path, const std::string& bytes);

}  // namespace drench
