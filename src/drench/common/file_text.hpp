#pragma once
/// Whole-file reads for the inputs a user names (scene files, OBJ meshes, CCD query files), bounded so that a
/// device, a FIFO or a huge file is refused at once instead of read forever.

#include <cstdint>
#include <string>

#include <drench/common/error.hpp>

namespace drench {

/// Why read_file_text refused a file; the reader that called it names the file in its own words.
class FileTextError : public IoError {
 public:
  /// What was wrong with the file.
  enum class Kind {
    UNREADABLE,   ///< missing, no permission or a read error (the system's reason)
    NOT_REGULAR,  ///< a folder, FIFO, device or socket
    TOO_LARGE,    ///< more bytes than the reader allows
  };
  FileTextError(Kind kind, const std::string& reason) : IoError(reason), m_kind(kind) {}
  Kind kind() const { return m_kind; }
  /// The reason alone, e.g. "not a regular file (a FIFO, device or socket)", to follow "cannot be read: ".
  const char* reason() const { return what(); }

 private:
  Kind m_kind;
};

/// The whole content of the regular file at `path`. Anything else is refused before it is opened, since
/// /dev/zero never ends and a FIFO blocks; the size is checked before the read and again during it, since
/// the file may grow meanwhile.
/// @param max_bytes  the largest size accepted (unit: bytes)
/// @param limit_name  that limit and the file's kind for a message, e.g. "16 MiB (16777216 bytes) a scene
///                    file": the reason then reads "<size> bytes, more than the <limit_name> may have"
/// @throws FileTextError saying why the file cannot be read, without its path
std::string read_file_text(const std::string& path, std::uint64_t max_bytes, const std::string& limit_name);

}  // namespace drench
