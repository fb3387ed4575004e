#include <drench/io/atomic_file.hpp>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <drench/common/error.hpp>

namespace drench {

void write_file_atomic(const std::string& path, const std::string& bytes) {
  const std::string temporary = path + ".tmp-" + std::to_string(::getpid());
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if (!file) throw IoError("cannot write " + temporary + ": " + std::strerror(errno));
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size();
  const int saved_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) {
    std::remove(temporary.c_str());
    throw IoError("cannot write " + temporary + ": " + std::strerror(written ? errno : saved_errno));
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const int rename_errno = errno;
    std::remove(temporary.c_str());
    throw IoError("cannot rename " + temporary + " to " + path + ": " + std::strerror(rename_errno));
  }
}

}  // namespace drench
