#include <drench/common/error.hpp>

#include <cstdio>

namespace drench {

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

void require_setting(bool ok, const std::string& key, const std::string& range, double value) {
  if (!ok) throw SceneError(key + " must be " + range + ", got " + format_number(value));
}

}  // namespace drench
