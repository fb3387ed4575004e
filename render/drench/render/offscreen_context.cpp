#include <drench/render/offscreen_context.hpp>

#define EGL_EGLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#include <drench/render/render_error.hpp>

namespace drench::render {

namespace {

std::string egl_error_text(const char* call) {
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", static_cast<unsigned>(eglGetError()));
  return std::string(call) + " failed (EGL error " + code +
         "); a headless OpenGL 3.3 needs Mesa's EGL and drivers (Debian: libegl-mesa0 libgl1-mesa-dri)";
}

}  // namespace

struct OffscreenContext::State {
  /// Frees whatever exists so far: the destructor's work, and the constructor's when it fails halfway.
  void release();

  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  int width = 0, height = 0;
  GLuint multisampled = 0, resolved = 0;  // framebuffers
  GLuint renderbuffers[3] = {0, 0, 0};    // multisampled colour and depth, resolved colour
};

void OffscreenContext::State::release() {
  if (display == EGL_NO_DISPLAY) return;
  if (context != EGL_NO_CONTEXT) {
    if (eglGetCurrentContext() == context) {
      glDeleteFramebuffers(1, &multisampled);
      glDeleteFramebuffers(1, &resolved);
      glDeleteRenderbuffers(3, renderbuffers);
    }
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display, context);
  }
  eglTerminate(display);
  display = EGL_NO_DISPLAY;
  context = EGL_NO_CONTEXT;
}

OffscreenContext::OffscreenContext(int width, int height, int samples) : m_state(std::make_unique<State>()) {
  State& s = *m_state;
  // Every failure below frees what was made before it throws.
  const auto fail = [&s](const std::string& message) {
    s.release();
    return RenderError(message);
  };
  if (width < 1 || height < 1 || samples < 1) {
    throw RenderError("an offscreen image of " + std::to_string(width) + " x " + std::to_string(height) +
                      " pixels with " + std::to_string(samples) + " samples; each must be >= 1");
  }
  s.width = width;
  s.height = height;
  // The surfaceless platform needs neither X11 nor Wayland nor a GPU device node.
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display == nullptr)
    throw RenderError(egl_error_text("eglGetProcAddress(eglGetPlatformDisplayEXT)"));
  s.display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (s.display == EGL_NO_DISPLAY)
    throw RenderError(egl_error_text("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)"));
  EGLint major = 0, minor = 0;
  if (!eglInitialize(s.display, &major, &minor)) throw RenderError(egl_error_text("eglInitialize"));
  if (!eglBindAPI(EGL_OPENGL_API)) throw fail(egl_error_text("eglBindAPI(EGL_OPENGL_API)"));
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                       3,
                                       EGL_CONTEXT_MINOR_VERSION,
                                       3,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                       EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  // No config: the context draws only into framebuffer objects (EGL_KHR_no_config_context).
  s.context = eglCreateContext(s.display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attributes);
  if (s.context == EGL_NO_CONTEXT) throw fail(egl_error_text("eglCreateContext(OpenGL 3.3 core)"));
  if (!eglMakeCurrent(s.display, EGL_NO_SURFACE, EGL_NO_SURFACE, s.context))
    throw fail(egl_error_text("eglMakeCurrent"));

  GLint max_size = 0, max_samples = 1;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  if (width > max_size || height > max_size) {
    throw fail("an image of " + std::to_string(width) + " x " + std::to_string(height) +
               " pixels is larger than this OpenGL allows (" + std::to_string(max_size) + " on a side)");
  }
  samples = std::min(samples, static_cast<int>(max_samples));

  glGenRenderbuffers(3, s.renderbuffers);
  glBindRenderbuffer(GL_RENDERBUFFER, s.renderbuffers[0]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, s.renderbuffers[1]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, s.renderbuffers[2]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glGenFramebuffers(1, &s.multisampled);
  glBindFramebuffer(GL_FRAMEBUFFER, s.multisampled);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, s.renderbuffers[0]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, s.renderbuffers[1]);
  const GLenum multisampled_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glGenFramebuffers(1, &s.resolved);
  glBindFramebuffer(GL_FRAMEBUFFER, s.resolved);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, s.renderbuffers[2]);
  const GLenum resolved_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (multisampled_status != GL_FRAMEBUFFER_COMPLETE || resolved_status != GL_FRAMEBUFFER_COMPLETE) {
    char text[96];
    std::snprintf(text, sizeof text, "framebuffer incomplete (status 0x%04x, 0x%04x)", multisampled_status,
                  resolved_status);
    throw fail("an image of " + std::to_string(width) + " x " + std::to_string(height) + " pixels with " +
               std::to_string(samples) + " samples: " + text +
               "; this OpenGL could not allocate it: choose a smaller size (drench render --size)");
  }
  bind();
}

OffscreenContext::~OffscreenContext() {
  m_state->release();
}

int OffscreenContext::width() const {
  return m_state->width;
}

int OffscreenContext::height() const {
  return m_state->height;
}

std::string OffscreenContext::description() const {
  const auto text = [](GLenum name) {
    const GLubyte* value = glGetString(name);
    return value == nullptr ? std::string("?") : std::string(reinterpret_cast<const char*>(value));
  };
  return text(GL_RENDERER) + ", " + text(GL_VERSION);
}

void OffscreenContext::bind() {
  glBindFramebuffer(GL_FRAMEBUFFER, m_state->multisampled);
  glViewport(0, 0, m_state->width, m_state->height);
}

Image OffscreenContext::read_image() {
  const State& s = *m_state;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, s.multisampled);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, s.resolved);
  glBlitFramebuffer(0, 0, s.width, s.height, 0, 0, s.width, s.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, s.resolved);
  Image image;
  image.width = s.width;
  image.height = s.height;
  image.rgb.resize(3 * static_cast<std::size_t>(s.width) * s.height);
  std::vector<std::uint8_t> rgba(4 * static_cast<std::size_t>(s.width) * s.height);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, s.width, s.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char text[64];
    std::snprintf(text, sizeof text, "OpenGL error 0x%04x while drawing a frame", error);
    throw RenderError(text);
  }
  // OpenGL's rows start at the bottom, PNG's at the top.
  for (int y = 0; y < s.height; ++y) {
    const std::uint8_t* from = rgba.data() + 4 * static_cast<std::size_t>(s.height - 1 - y) * s.width;
    std::uint8_t* to = image.rgb.data() + 3 * static_cast<std::size_t>(y) * s.width;
    for (int x = 0; x < s.width; ++x) {
      to[3 * x] = from[4 * x];
      to[3 * x + 1] = from[4 * x + 1];
      to[3 * x + 2] = from[4 * x + 2];
    }
  }
  bind();
  return image;
}

}  // namespace drench::render
