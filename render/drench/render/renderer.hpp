#pragma once
/// Draws one frame of a run with OpenGL 3.3 core: the cloth shaded on both sides, the fluid as its
/// reconstructed surface (opaque blue, or transparent water as the paper's Fig. 7) or as particles coloured
/// by speed, the static obstacles in grey, over a grey backdrop. The same code draws `drench render`'s
/// offscreen images (offscreen_context.hpp) and the viewer's window (viewer.hpp): it draws into whatever
/// framebuffer is bound in the current context.

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

/// How the fluid's surface is drawn.
enum class WaterShading {
  OPAQUE,       ///< a blue solid: its shape reads, what lies behind it does not
  TRANSPARENT,  ///< water: reflects a sky, shows what lies behind it refracted and tinted (WaterStyle)
};

/// The optics of the transparent surface (Huber et al. 2013 Fig. 7 is such a rendering). Per pixel: the
/// Fresnel reflectance F (Schlick's approximation for `refractive_index`) of a sky, plus (1 - F) times the
/// scene behind the water, seen where the refracted ray leaves it and attenuated by Beer-Lambert's
/// exp(-absorption * thickness), thickness being the length of the view ray inside the water.
struct WaterStyle {
  WaterShading shading = WaterShading::OPAQUE;
  Scalar refractive_index = 1.33;  ///< of water against air, > 1: F = 2 % head on, refraction's bend
  /// Beer-Lambert absorption of red, green and blue (unit: 1/m), each >= 0. Pure water's at 650, 550 and
  /// 450 nm (0.34, 0.057, 0.0092 1/m; Pope & Fry 1997) times 30, so that the centimetres of water at cloth
  /// scale show a tint (real water that thin looks as clear as glass), while a jet still shows the cloth
  /// behind it in its own colour (times 100 turned a 4 cm jet over the cloth nearly black). Water absorbs
  /// red most: 1 cm keeps 90 % of red, 98 % of green, 99.7 % of blue; a 4 cm jet 66 %, 93 %, 99 %.
  Vec3 absorption = Vec3(10.2, 1.7, 0.28);
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
  /// What transparent water reflects, by the reflected ray's world direction: the horizon's colour level,
  /// blending to the zenith's straight up and to the ground's straight down (by the square root of the
  /// direction's height).
  static constexpr float kSkyZenith[3] = {0.30f, 0.50f, 0.82f};
  static constexpr float kSkyHorizon[3] = {0.86f, 0.90f, 0.95f};
  static constexpr float kGround[3] = {0.40f, 0.39f, 0.37f};
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
  ///
  /// With `water.shading` TRANSPARENT and a surface, the opaque scene is drawn first into textures of the
  /// viewport's size (colour and depth, kept for the next frame of that size), then the surface's thickness
  /// along each view ray, then the surface shaded as water over the opaque scene in the bound framebuffer.
  /// The thickness adds the distance of every face a ray leaves the water through and subtracts that of
  /// every face it enters through, each cut at what is opaque behind: exact for any number of layers of a
  /// closed surface wound consistently (drench's surfaces are closed, counter-clockwise from outside).
  /// Without a surface the particles are drawn as with OPAQUE.
  void draw(const FrameGeometry& frame, const Camera& camera, const ParticleStyle& style, int width,
            int height, const WaterStyle& water = {});

 private:
  struct State;
  std::unique_ptr<State> m_state;
};

}  // namespace drench::render
