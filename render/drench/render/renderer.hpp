#pragma once
/// Draws one frame of a run with OpenGL 3.3 core: the cloth shaded on both sides, the fluid as its
/// reconstructed surface or as particles coloured by speed, the static obstacles in grey, over a grey
/// backdrop. The same code draws `drench render`'s offscreen images (offscreen_context.hpp) and the viewer's
/// window (viewer.hpp): it draws into whatever framebuffer is bound in the current context.

#include <memory>

#include <drench/common/triangle_mesh.hpp>
#include <drench/common/types.hpp>
#include <drench/render/camera.hpp>

namespace drench::render {

/// What one frame shows. Each part is optional (nullptr or empty) and not owned.
struct FrameGeometry {
  const TriangleMesh* cloth = nullptr;      ///< drawn two-sided (unit: m)
  const TriangleMesh* surface = nullptr;    ///< the fluid's surface; when given, particles are not drawn
  const Vec3Array* particles = nullptr;     ///< N particle centres (unit: m)
  const Vec3Array* velocities = nullptr;    ///< N velocities (unit: m/s) or nullptr: all drawn as at rest
  const TriangleMesh* obstacles = nullptr;  ///< static obstacles (unit: m)
  bool cloth_wireframe = false;             ///< the cloth's edges only, in its colours (the viewer's `w`)
  Eigen::AlignedBox3d bounds;               ///< the scene's box (unit: m): sets the depth range; not empty
};

/// How particles are drawn.
struct ParticleStyle {
  Scalar radius = 0.0025;    ///< drawn sphere radius (unit: m), > 0; half the particle spacing
  Scalar speed_scale = 1.0;  ///< speed drawn in the fastest colour (unit: m/s), > 0
};

/// The colours (linear RGB in [0, 1]) the renderer draws with, for tests that classify pixels and for docs.
/// Shading darkens and highlights them, but keeps each family apart: the cloth's red exceeds its blue, the
/// water's blue exceeds its red, and the backdrop and obstacles are grey (channels within a few percent).
struct Palette {
  static constexpr float kClothFront[3] = {0.86f, 0.40f, 0.18f};
  static constexpr float kClothBack[3] = {0.72f, 0.30f, 0.14f};
  static constexpr float kWater[3] = {0.12f, 0.42f, 0.86f};      ///< the surface
  static constexpr float kSlowWater[3] = {0.08f, 0.30f, 0.80f};  ///< particles at rest
  static constexpr float kFastWater[3] = {0.50f, 0.85f, 1.00f};  ///< particles at `speed_scale` and above
  static constexpr float kObstacle[3] = {0.58f, 0.58f, 0.60f};
  static constexpr float kBackdropTop[3] = {0.96f, 0.96f, 0.97f};
  static constexpr float kBackdropBottom[3] = {0.80f, 0.80f, 0.82f};
};

/// The shaders and buffers of the drawing; needs a current OpenGL 3.3 core context for its whole life.
class Renderer {
 public:
  /// Compiles the shaders. @throws RenderError with the driver's log when a shader does not compile or link.
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Clears the bound framebuffer and draws `frame` as `camera` sees it into a `width` x `height` viewport
  /// (the caller's viewport; project_to_pixel gives where a point lands). Triangles with an index out of
  /// range are the caller's error (asserted, not checked).
  void draw(const FrameGeometry& frame, const Camera& camera, const ParticleStyle& style, int width,
            int height);

 private:
  struct State;
  std::unique_ptr<State> m_state;
};

}  // namespace drench::render
