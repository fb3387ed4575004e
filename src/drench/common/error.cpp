#include <drench/common/error.hpp>

#include <cstdio>

namespace drench {

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

}  // namespace drench
