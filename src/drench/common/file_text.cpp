#include <drench/common/file_text.hpp>

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace drench {

std::string read_file_text(const std::string& path, std::uint64_t max_bytes, const std::string& limit_name) {
  using Kind = FileTextError::Kind;
  const auto too_large = [&](std::uint64_t bytes) {
    return FileTextError(Kind::TOO_LARGE,
                         std::to_string(bytes) + " bytes, more than the " + limit_name + " may have");
  };
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) throw FileTextError(Kind::UNREADABLE, std::strerror(errno));
  if (S_ISDIR(info.st_mode)) throw FileTextError(Kind::NOT_REGULAR, "it is a folder");
  if (!S_ISREG(info.st_mode))
    throw FileTextError(Kind::NOT_REGULAR, "not a regular file (a FIFO, device or socket)");
  if (static_cast<std::uint64_t>(info.st_size) > max_bytes) throw too_large(info.st_size);

  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw FileTextError(Kind::UNREADABLE, std::strerror(errno));
  std::string text;
  text.reserve(static_cast<std::size_t>(info.st_size));
  char buffer[65536];
  std::size_t count = 0;
  while (text.size() <= max_bytes && (count = std::fread(buffer, 1, sizeof buffer, file)) > 0)
    text.append(buffer, count);
  const bool failed = std::ferror(file) != 0;
  const int error = errno;  // fclose may overwrite errno
  std::fclose(file);
  if (failed) throw FileTextError(Kind::UNREADABLE, std::strerror(error));
  if (text.size() > max_bytes) throw too_large(text.size());
  return text;
}

}  // namespace drench
