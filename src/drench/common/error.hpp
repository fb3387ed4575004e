#pragma once
/// Error types. Loading and set-up code throws; code inside a time step never throws for numerical trouble
/// but reports it through a StepStatus (see sph/fluid_solver.hpp).

#include <stdexcept>
#include <string>

#include <drench/common/types.hpp>

namespace drench {

/// Base of every exception drench throws. The message always names the culprit (file, JSON path, particle or
/// triangle index) and the offending value.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A scene file, a --set override or a scene built in code is invalid. The message has the form
/// `<json.path> <problem>, got <value> (<file>)`.
class SceneError : public Error {
 public:
  using Error::Error;
};

/// Reading or writing a file failed (the message names the file and the system's reason).
class IoError : public Error {
 public:
  using Error::Error;
};

/// Formats a double for error messages in the fewest digits (15 to 17) that read back as the same double.
std::string format_number(double value);

/// A vector as "(x, y, z)", each as format_number writes it.
std::string format_vec3(const Vec3& v);

/// Throws SceneError("<key> must be <range>, got <value>") unless `ok`: a setting built in code held to the
/// range the scene loader gives its key (e.g. require_setting(v > 0, "fluid.cfl", "in (0, 1]", v)).
void require_setting(bool ok, const std::string& key, const std::string& range, double value);

}  // namespace drench
