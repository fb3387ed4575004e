#pragma once
/// The error of the renderer: no OpenGL context to be had, a shader the driver refuses, an image size the
/// driver cannot hold.

#include <drench/common/error.hpp>

namespace drench::render {

/// OpenGL or EGL failed; the message says which call and, where there is one, the driver's reason.
class RenderError : public Error {
 public:
  using Error::Error;
};

}  // namespace drench::render
