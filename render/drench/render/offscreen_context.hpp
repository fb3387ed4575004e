#pragma once
/// An OpenGL context without a display, for `drench render` on a server or in CI: EGL's surfaceless platform
/// (EGL_MESA_platform_surfaceless; Mesa's llvmpipe on the CPU, or the driver of a GPU when there is one),
/// drawing into framebuffer objects. EGL rather than OSMesa: the same Mesa packages give it, and Mesa drops
/// OSMesa after 25.0.

#include <memory>
#include <string>

#include <drench/render/png_image.hpp>

namespace drench::render {

/// An OpenGL 3.3 core context, current on the creating thread while the object lives, and a multisampled
/// `width` x `height` colour and depth target that the Renderer draws into. One per process at a time.
class OffscreenContext {
 public:
  /// @param width, height  the image's size in pixels, >= 1 and at most the driver's limit
  ///        (GL_MAX_RENDERBUFFER_SIZE, 16384 on llvmpipe)
  /// @param samples  multisampling per pixel, >= 1; clamped to the driver's GL_MAX_SAMPLES
  /// @throws RenderError when EGL has no surfaceless display or OpenGL 3.3 core context (naming the EGL call
  ///         and its error, and the Debian packages that provide one), or the size is out of range.
  OffscreenContext(int width, int height, int samples = 4);
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  int width() const;
  int height() const;
  /// GL_RENDERER and GL_VERSION, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core Profile) Mesa 22.3.6".
  std::string description() const;

  /// Binds the multisampled target for drawing, with the viewport set to the whole image.
  void bind();
  /// Resolves the samples and reads the image back (rows from the top, as PNG stores them); waits for the
  /// drawing to finish. @throws RenderError when OpenGL reports an error.
  Image read_image();

 private:
  struct State;
  std::unique_ptr<State> m_state;
};

}  // namespace drench::render
