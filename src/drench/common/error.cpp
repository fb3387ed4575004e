#include <drench/common/error.hpp>

#include <cstdio>
#include <cstdlib>

namespace drench {

std::string format_number(double value) {
  // The shortest of 15 to 17 digits that reads back as `value`: 0.1, not 0.10000000000000001.
  char buffer[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
    if (std::strtod(buffer, nullptr) == value || !(value == value)) break;
  }
  return buffer;
}

std::string format_vec3(const Vec3& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + ")";
}

void require_setting(bool ok, const std::string& key, const std::string& range, double value) {
  if (!ok) throw SceneError(key + " must be " + range + ", got " + format_number(value));
}

}  // namespace drench
